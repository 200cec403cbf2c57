//! The pairs of a tree's own points within a bound of each other (scipy's `query_pairs`, the
//! fast path of [`NeighborIndex::pairs`](crate::NeighborIndex::pairs)): a self-join over the
//! leaves, each unordered pair of leaves visited once, where one search per point finds every
//! pair twice (once from each end) and throws one half away.
//!
//! Every node gets the tight bounding box of its points. Each leaf `A` then runs one descent
//! from the root with its box, entering only subtrees that hold a leaf at or after `A` in tree
//! order (`b > A.start`) and whose box may come within the bound of `A`'s; at a leaf `B` after
//! `A` every point of `A` is measured against every point of `B`, at `A` itself every pair of
//! its points once. A box pair's bound is the fold of the metric's terms over the gaps between
//! the boxes (nearest images on a periodic axis), which never exceeds the key of a pair of their
//! points: rounding is monotone, so each computed gap is at most the computed difference of
//! any two points across it ([`Period::boxes_key`]). A pair's key is the metric's key of the
//! difference of its points, the bits a single search computes for either end (a difference
//! and its negation have the same magnitude), so the pairs, and their keys, are exactly the
//! single searches'.
//!
//! Output: row `i` (caller index) holds the `j > i` paired with it, ascending, with their keys.
//! The pairs are collected per chunk of leaves into buckets of rows, each bucket then counted,
//! scattered and sorted on its own in parallel: the table is the same for any thread count (a
//! row's `j` are distinct, so sorting by them leaves one order).

use rayon::prelude::*;

use super::node::Node;
use super::KdTree;
use crate::error::{NbhdError, Result};
use crate::metric::{interval_gap, Measure, Norm, NormUser, Period};
use crate::scalar::Scalar;
use crate::table::{try_filled, NeighborTable};

/// One pair found: the smaller caller index, the larger, the key.
type Pair<T> = (u32, u32, T);

/// Leaves per chunk of work (each chunk collects its pairs on its own).
const LEAVES_PER_CHUNK: usize = 512;

/// Rows per bucket (a power of two): a bucket's pairs are counted, scattered and sorted
/// together, in a block that stays in the cache.
const ROWS_PER_BUCKET_LOG2: u32 = 13;

impl<T: Scalar> KdTree<T> {
    /// Every pair `(i, j)`, `i < j`, of held points whose key under `measure` is at most
    /// `bound`, as the table whose row `i` holds those `j` ascending (`source_len` rows), on the
    /// current rayon pool.
    pub(crate) fn self_join(&self, bound: T, measure: &Measure) -> Result<NeighborTable<T>> {
        struct Join<'a, T: Scalar> {
            tree: &'a KdTree<T>,
            bound: T,
        }
        impl<T: Scalar> NormUser<T> for Join<'_, T> {
            type Out = Result<NeighborTable<T>>;
            fn with<N: Norm<T>>(self, norm: N) -> Self::Out {
                match self.tree.period() {
                    Some(period) => join_in(self.tree, Torus { period, norm }, self.bound),
                    None => join_in(self.tree, Open(norm), self.bound),
                }
            }
        }
        measure.apply(Join { tree: self, bound })
    }
}

/// How the join measures (the norm, in an open space or a periodic box): the key of a pair of
/// points, and lower bounds of the keys between a point and a box and between two boxes.
trait PairMeasure<T: Scalar>: Copy + Send + Sync {
    /// The key of `x − y`, the bits a single search from either point computes.
    fn key(self, x: &[T], y: &[T]) -> T;
    /// At most the key from `x` to any point of the box `[lo, hi]`.
    fn point_box(self, x: &[T], lo: &[T], hi: &[T]) -> T;
    /// At most the key between any point of `[la, ha]` and any point of `[lb, hb]`.
    fn box_box(self, la: &[T], ha: &[T], lb: &[T], hb: &[T]) -> T;
}

/// A norm in open space.
#[derive(Clone, Copy)]
struct Open<N>(N);

impl<T: Scalar, N: Norm<T>> PairMeasure<T> for Open<N> {
    #[inline(always)]
    fn key(self, x: &[T], y: &[T]) -> T {
        self.0.key(x, y, x.len())
    }

    #[inline(always)]
    fn point_box(self, x: &[T], lo: &[T], hi: &[T]) -> T {
        let mut s = T::ZERO;
        for j in 0..x.len() {
            // a point is an interval of one point
            let gap = interval_gap(x[j], x[j], lo[j], hi[j]);
            s = self.0.fold(s, self.0.term(gap));
        }
        self.0.lower(s)
    }

    #[inline(always)]
    fn box_box(self, la: &[T], ha: &[T], lb: &[T], hb: &[T]) -> T {
        let mut s = T::ZERO;
        for j in 0..la.len() {
            let gap = interval_gap(la[j], ha[j], lb[j], hb[j]);
            s = self.0.fold(s, self.0.term(gap));
        }
        self.0.lower(s)
    }
}

/// A norm in a periodic box: nearest images ([`Period`]).
#[derive(Clone, Copy)]
struct Torus<'a, T, N> {
    period: &'a Period<T>,
    norm: N,
}

impl<T: Scalar, N: Norm<T>> PairMeasure<T> for Torus<'_, T, N> {
    #[inline(always)]
    fn key(self, x: &[T], y: &[T]) -> T {
        self.period.key(self.norm, x, y)
    }

    #[inline(always)]
    fn point_box(self, x: &[T], lo: &[T], hi: &[T]) -> T {
        self.period.box_key(self.norm, x, lo, hi)
    }

    #[inline(always)]
    fn box_box(self, la: &[T], ha: &[T], lb: &[T], hb: &[T]) -> T {
        self.period.boxes_key(self.norm, la, ha, lb, hb)
    }
}

/// The join under `measure`, dispatched to a dimension fixed at compile time (1–3).
fn join_in<T: Scalar, M: PairMeasure<T>>(
    tree: &KdTree<T>,
    measure: M,
    bound: T,
) -> Result<NeighborTable<T>> {
    match tree.dim {
        3 => join::<T, M, 3>(tree, measure, bound),
        2 => join::<T, M, 2>(tree, measure, bound),
        1 => join::<T, M, 1>(tree, measure, bound),
        _ => join::<T, M, 0>(tree, measure, bound),
    }
}

/// What the join reads of a tree: its nodes, points and caller indices, every node's box
/// (`boxes[2 d node..]`: the lows, then the highs), the measure, the bound.
struct JoinView<'a, T, M> {
    nodes: &'a [Node<T>],
    coords: &'a [T],
    ids: &'a [u32],
    boxes: Vec<T>,
    dim: usize,
    measure: M,
    bound: T,
    /// `ROWS_PER_BUCKET_LOG2`, or less so that a small table still has several buckets.
    bucket_shift: u32,
    buckets: usize,
}

/// [`KdTree::self_join`] under `measure`; `D > 0` fixes the dimension at compile time.
fn join<T: Scalar, M: PairMeasure<T>, const D: usize>(
    tree: &KdTree<T>,
    measure: M,
    bound: T,
) -> Result<NeighborTable<T>> {
    let rows = tree.source_len;
    let bucket_shift = ROWS_PER_BUCKET_LOG2.min(rows.max(1).ilog2().saturating_sub(4));
    let view = JoinView {
        nodes: &tree.nodes,
        coords: &tree.coords,
        ids: &tree.ids,
        boxes: node_boxes(&tree.nodes, &tree.coords, tree.dim)?,
        dim: tree.dim,
        measure,
        bound,
        bucket_shift,
        buckets: (rows >> bucket_shift) + 1,
    };
    let leaves: Vec<usize> = (0..tree.nodes.len())
        .filter(|&i| tree.nodes[i].is_leaf())
        .collect();
    let chunks: Vec<Vec<Vec<Pair<T>>>> = leaves
        .par_chunks(LEAVES_PER_CHUNK)
        .map(|chunk| view.pairs_of_leaves::<D>(chunk))
        .collect::<Result<_>>()?;
    assemble(&chunks, rows, bucket_shift)
}

/// The tight bounding box of every node's points (an empty leaf's is empty: lows +∞, highs
/// −∞), children before parents (a child's index is larger than its parent's in preorder).
fn node_boxes<T: Scalar>(nodes: &[Node<T>], coords: &[T], dim: usize) -> Result<Vec<T>> {
    let mut boxes = try_filled(nodes.len() * 2 * dim, T::ZERO, "the boxes of the nodes")?;
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        let (head, tail) = boxes.split_at_mut((i + 1) * 2 * dim);
        let own = &mut head[i * 2 * dim..];
        let (lo, hi) = own.split_at_mut(dim);
        if n.is_leaf() {
            lo.fill(T::INFINITY);
            hi.fill(T::ZERO - T::INFINITY);
            for p in coords[n.a as usize * dim..n.b as usize * dim].chunks_exact(dim) {
                for j in 0..dim {
                    lo[j] = lo[j].min_of(p[j]);
                    hi[j] = hi[j].max_of(p[j]);
                }
            }
        } else {
            // the left child is i + 1 (the first box of `tail`), the right one n.a
            let right = (n.a as usize - i - 1) * 2 * dim;
            for j in 0..dim {
                lo[j] = tail[j].min_of(tail[right + j]);
                hi[j] = tail[dim + j].max_of(tail[right + dim + j]);
            }
        }
    }
    Ok(boxes)
}

/// Tree positions of the points of a leaf near the other leaf's box (scratch of a chunk).
#[derive(Default)]
struct Near {
    a: Vec<u32>,
    b: Vec<u32>,
}

impl<T: Scalar, M: PairMeasure<T>> JoinView<'_, T, M> {
    /// The lows and highs of node `i`'s box.
    #[inline(always)]
    fn box_of(&self, i: usize) -> (&[T], &[T]) {
        self.boxes[i * 2 * self.dim..(i + 1) * 2 * self.dim].split_at(self.dim)
    }

    /// The coordinates of the point at tree position `p`.
    #[inline(always)]
    fn point<const D: usize>(&self, p: usize) -> &[T] {
        let d = if D > 0 { D } else { self.dim };
        &self.coords[p * d..p * d + d]
    }

    /// The pairs of the leaves `chunk` (node indices) with themselves and the leaves after
    /// them, by bucket of their smaller caller index.
    fn pairs_of_leaves<const D: usize>(&self, chunk: &[usize]) -> Result<Vec<Vec<Pair<T>>>> {
        let mut out: Vec<Vec<Pair<T>>> = (0..self.buckets).map(|_| Vec::new()).collect();
        let mut stack: Vec<usize> = Vec::new();
        let mut near = Near::default();
        for &a in chunk {
            let start = self.nodes[a].a;
            let (la, ha) = self.box_of(a);
            stack.clear();
            stack.push(0);
            while let Some(node) = stack.pop() {
                let n = &self.nodes[node];
                if n.b <= start {
                    continue; // every leaf of it comes before `a`
                }
                let (lb, hb) = self.box_of(node);
                if self.measure.box_box(la, ha, lb, hb) > self.bound {
                    continue;
                }
                if node == a {
                    self.pairs_within::<D>(a, &mut out)?;
                } else if n.is_leaf() {
                    self.pairs_across::<D>(a, node, &mut near, &mut out)?;
                } else {
                    stack.push(n.a as usize);
                    stack.push(node + 1);
                }
            }
        }
        Ok(out)
    }

    /// The pairs within the bound of two points of leaf `a`, each once, into `out` by bucket.
    fn pairs_within<const D: usize>(&self, a: usize, out: &mut [Vec<Pair<T>>]) -> Result<()> {
        let n = &self.nodes[a];
        for q in n.a as usize..n.b as usize {
            let y = self.point::<D>(q);
            for p in q + 1..n.b as usize {
                self.offer(p, q, self.measure.key(self.point::<D>(p), y), out)?;
            }
        }
        Ok(())
    }

    /// The pairs within the bound of a point of leaf `a` and a point of leaf `b`, into `out`
    /// by bucket: only the points of each leaf near the other leaf's box are paired.
    fn pairs_across<const D: usize>(
        &self,
        a: usize,
        b: usize,
        near: &mut Near,
        out: &mut [Vec<Pair<T>>],
    ) -> Result<()> {
        let (na, nb) = (&self.nodes[a], &self.nodes[b]);
        let (la, ha) = self.box_of(a);
        let (lb, hb) = self.box_of(b);
        let near_box = |range: std::ops::Range<u32>, lo: &[T], hi: &[T], list: &mut Vec<u32>| {
            list.clear();
            for p in range {
                let x = self.point::<D>(p as usize);
                if self.measure.point_box(x, lo, hi) <= self.bound {
                    list.push(p);
                }
            }
        };
        near_box(na.a..na.b, lb, hb, &mut near.a);
        if near.a.is_empty() {
            return Ok(());
        }
        near_box(nb.a..nb.b, la, ha, &mut near.b);
        for &q in &near.b {
            let y = self.point::<D>(q as usize);
            for &p in &near.a {
                let key = self.measure.key(self.point::<D>(p as usize), y);
                self.offer(p as usize, q as usize, key, out)?;
            }
        }
        Ok(())
    }

    /// Keeps the pair of the points at tree positions `p` and `q` if `key` is within the bound.
    #[inline(always)]
    fn offer(&self, p: usize, q: usize, key: T, out: &mut [Vec<Pair<T>>]) -> Result<()> {
        if key <= self.bound {
            let (i, j) = (self.ids[p], self.ids[q]);
            let pair = if i < j { (i, j, key) } else { (j, i, key) };
            push(&mut out[(pair.0 >> self.bucket_shift) as usize], pair)?;
        }
        Ok(())
    }
}

/// Appends `pair`, the memory reserved fallibly.
#[inline(always)]
fn push<T: Scalar>(v: &mut Vec<Pair<T>>, pair: Pair<T>) -> Result<()> {
    if v.len() == v.capacity() {
        let more = v.capacity().max(64);
        v.try_reserve(more).map_err(|_| NbhdError::OutOfMemory {
            what: "the table of pairs",
            bytes: (v.len() + more) as u128 * std::mem::size_of::<Pair<T>>() as u128,
        })?;
    }
    v.push(pair);
    Ok(())
}

/// The table of `rows` rows from the pairs of every chunk by bucket: row `i` the `j` of the
/// pairs `(i, j)`, ascending, with their keys.
fn assemble<T: Scalar>(
    chunks: &[Vec<Vec<Pair<T>>>],
    rows: usize,
    shift: u32,
) -> Result<NeighborTable<T>> {
    let buckets = (rows >> shift) + 1;
    let rows_of = |b: usize| (b << shift).min(rows)..((b + 1) << shift).min(rows);
    // the length of every row, bucket by bucket
    let lens: Vec<Vec<usize>> = (0..buckets)
        .into_par_iter()
        .map(|b| {
            let first = b << shift;
            let mut lens = vec![0usize; rows_of(b).len()];
            for chunk in chunks {
                for &(i, _, _) in &chunk[b] {
                    lens[i as usize - first] += 1;
                }
            }
            lens
        })
        .collect();
    let mut offsets = try_filled(rows + 1, 0usize, "the offsets of the table of pairs")?;
    for (i, len) in lens.iter().flatten().enumerate() {
        offsets[i + 1] = offsets[i] + len;
    }
    let total = offsets[rows];
    let mut indices = try_filled(total, 0u32, "the table of pairs")?;
    let mut keys = try_filled(total, T::ZERO, "the table of pairs")?;
    // the buckets' disjoint parts of the entries
    let mut parts = Vec::with_capacity(buckets);
    let (mut rest_i, mut rest_k) = (&mut indices[..], &mut keys[..]);
    for b in 0..buckets {
        let r = rows_of(b);
        let len = offsets[r.end] - offsets[r.start];
        let (part_i, next_i) = rest_i.split_at_mut(len);
        let (part_k, next_k) = rest_k.split_at_mut(len);
        parts.push((b, &offsets[r.start..=r.end], part_i, part_k));
        (rest_i, rest_k) = (next_i, next_k);
    }
    parts
        .into_par_iter()
        .for_each(|(b, starts, part_i, part_k)| {
            let first = b << shift;
            let mut next: Vec<usize> = starts[..starts.len() - 1]
                .iter()
                .map(|&s| s - starts[0])
                .collect();
            let mut row: Vec<(u32, T)> = vec![(0, T::ZERO); part_i.len()];
            for chunk in chunks {
                for &(i, j, key) in &chunk[b] {
                    let at = &mut next[i as usize - first];
                    row[*at] = (j, key);
                    *at += 1;
                }
            }
            for w in starts.windows(2) {
                let (a, e) = (w[0] - starts[0], w[1] - starts[0]);
                row[a..e].sort_unstable_by_key(|&(j, _)| j);
            }
            for ((oi, ok), &(j, key)) in part_i.iter_mut().zip(part_k.iter_mut()).zip(&row) {
                (*oi, *ok) = (j, key);
            }
        });
    Ok(NeighborTable::from_parts(offsets, indices, keys).expect("offsets made from the rows"))
}
