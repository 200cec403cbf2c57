//! Batch queries on the forest, answered a small group of nearby queries at a time.
//!
//! A frame of query points is ordered along the leaves of the forest's largest tree (so that
//! consecutive queries are near each other) and cut into groups of at most [`GROUP`]. Each
//! group descends every tree of the forest once instead of once per query: a cell is visited
//! if its tight bounding box may hold a point of some member's answer — its squared distance
//! to the group's bounding box, with its smallest forest index, precedes the largest worst key
//! `(sq_dist, index)` of the members — and a visited leaf is scanned, a block of points at a
//! time from coordinates stored by dimension, for every member whose own point-to-box bound
//! admits it. The members' result sets are kept from tree to tree (largest first), so the
//! answers of the trees merge in `(sq_dist, index)` order as they arrive and every later tree
//! is searched with the bounds the earlier ones left. This is the grouped search the tree
//! uses for its own points (`src/tree/group_search.rs`, after Gray & Moore's leaf-to-leaf
//! sharing), for outside queries and across the trees of a forest.
//!
//! **Exactness.** Each member sees every live point that could enter its answer, with the
//! squared distance the single-query search computes (the same sum in the same order,
//! `((0 + t0²) + t1²) + …`): lower bounds are gaps between boxes evaluated in that order, and
//! rounding is monotone, so a cell's bound never exceeds the computed distance of any of its
//! points to any member. Rows are therefore the single-query rows, byte for byte, whatever the
//! groups, and so for any thread count.

use std::fmt;

use super::{bit, DynamicKdTree, Part};
use crate::error::Result;
use crate::index::answer;
use crate::query::result_set::{Key32, ResultSet, RowEntry, SortedRow, WithinRadius};
use crate::query::{order, Neighbor, NeighborHeap, NeighborSearch, Neighborhood};
use crate::scalar::{Scalar, ScalarType};
use crate::table::{rows_in_chunks, NeighborTable, RowsChunk, CHUNK};
use crate::tree::group_search::{admits, box_dist, left_first};

/// Most queries in one group (chosen by measurement, `benches/dynamic.rs`).
pub(super) const GROUP: usize = 8;

/// Points scanned at once: a leaf's squared distances to one query are computed a block at a
/// time, in straight-line code the compiler vectorises.
const BLOCK: usize = 8;

/// Queries in one group lie in leaves of the largest tree at most this many leaves (of the
/// build's leaf size) apart (chosen by measurement, `benches/dynamic.rs`).
const SPAN_LEAVES: usize = 4;

/// Rows up to this `k` are kept sorted by insertion; larger ones in a heap.
const SORTED_MAX_K: usize = 64;

/// `dim` of a leaf in [`Cell`].
const LEAF: u32 = u32::MAX;

/// One node of a tree as the grouped search reads it.
#[derive(Clone, Copy)]
struct Cell<T> {
    /// Internal: the split value.
    split: T,
    /// Internal: the split dimension; leaf: [`LEAF`].
    dim: u32,
    /// Internal: the right child; leaf: the first tree position.
    a: u32,
    /// One past the last tree position of the subtree.
    b: u32,
}

/// A tree of the forest prepared for the grouped search, made on the first batch query that
/// reaches it: its nodes with their tight boxes and smallest forest index, its points' forest
/// indices in tree order, and its coordinates by dimension.
pub(super) struct Cells<T> {
    nodes: Vec<Cell<T>>,
    /// Node `i`'s box is `lo[i * dim..][..dim]`, `hi[i * dim..][..dim]`.
    lo: Vec<T>,
    hi: Vec<T>,
    /// Smallest forest index of every node's subtree.
    min_gid: Vec<u32>,
    /// Forest index of every tree position.
    gids: Vec<u32>,
    /// Dimension `j` of tree position `p` at `soa[j * stride + p]`, padded by a block.
    stride: usize,
    soa: Vec<T>,
}

impl<T> fmt::Debug for Cells<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Cells")
            .field("nodes", &self.nodes.len())
            .field("points", &self.gids.len())
            .finish_non_exhaustive()
    }
}

impl<T: Scalar> Cells<T> {
    /// The cells of `part`'s tree.
    pub(super) fn new(part: &Part<T>) -> Self {
        let tree = &part.tree;
        let dim = tree.dim();
        let n = tree.len();
        let nodes: Vec<Cell<T>> = tree
            .nodes()
            .map(|(d, split, a, b)| Cell {
                split,
                dim: d.map_or(LEAF, |d| d as u32),
                a,
                b,
            })
            .collect();
        let gids: Vec<u32> = tree.tree_order().iter().map(|&i| i + part.lo).collect();
        let stride = n + BLOCK;
        let mut soa = vec![T::ZERO; dim * stride];
        for p in 0..n {
            for (j, &c) in tree.point_at(p).iter().enumerate() {
                soa[j * stride + p] = c;
            }
        }
        let m = nodes.len();
        let neg_inf = T::ZERO - T::INFINITY;
        let mut lo = vec![T::INFINITY; m * dim];
        let mut hi = vec![neg_inf; m * dim];
        let mut min_gid = vec![u32::MAX; m];
        for i in (0..m).rev() {
            let nd = nodes[i];
            if nd.dim == LEAF {
                for p in nd.a as usize..nd.b as usize {
                    for j in 0..dim {
                        let c = soa[j * stride + p];
                        lo[i * dim + j] = lo[i * dim + j].min_of(c);
                        hi[i * dim + j] = hi[i * dim + j].max_of(c);
                    }
                    min_gid[i] = min_gid[i].min(gids[p]);
                }
            } else {
                let (l, r) = (i + 1, nd.a as usize);
                for j in 0..dim {
                    lo[i * dim + j] = lo[l * dim + j].min_of(lo[r * dim + j]);
                    hi[i * dim + j] = hi[l * dim + j].max_of(hi[r * dim + j]);
                }
                min_gid[i] = min_gid[l].min(min_gid[r]);
            }
        }
        Self {
            nodes,
            lo,
            hi,
            min_gid,
            gids,
            stride,
            soa,
        }
    }

    #[inline(always)]
    fn lo<const D: usize>(&self, node: usize) -> &[T; D] {
        self.lo[node * D..node * D + D].try_into().unwrap()
    }

    #[inline(always)]
    fn hi<const D: usize>(&self, node: usize) -> &[T; D] {
        self.hi[node * D..node * D + D].try_into().unwrap()
    }

    /// Squared distances from `q` to the points at tree positions `start..start + BLOCK`, each
    /// summed over the dimensions in order as the single-query search does (`0 + x` is
    /// exact): the same bits.
    #[inline(always)]
    fn block_sq_dists<const D: usize>(&self, q: &[T; D], start: usize) -> [T; BLOCK] {
        let mut d = [T::ZERO; BLOCK];
        for (j, &qj) in q.iter().enumerate() {
            let at = j * self.stride + start;
            let c: &[T; BLOCK] = self.soa[at..at + BLOCK].try_into().unwrap();
            for p in 0..BLOCK {
                let t = qj - c[p];
                d[p] = d[p] + t * t;
            }
        }
        d
    }
}

/// One result set per member of a group, kept from tree to tree, and how rows are written.
trait Rows<T: Scalar> {
    /// Whether keys tighten as candidates arrive (k-nearest) or stay the radius (radius).
    const TIGHTENS: bool;
    /// Empties the first `m` rows.
    fn clear(&mut self, m: usize);
    /// Adds a candidate that precedes member `i`'s worst key; returns the new worst key.
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32);
    /// Appends the first `m` rows, in `(sq_dist, index)` order where asked, to `out`.
    fn write(&mut self, m: usize, out: &mut RowsChunk<T>);
}

/// Appends one row of `(sq_dist, index)` pairs to a chunk.
#[inline]
fn write_row<T: Scalar>(len: usize, row: impl Iterator<Item = (T, u32)>, out: &mut RowsChunk<T>) {
    out.push_row(len, row);
}

/// Small `k`: each row sorted by insertion in a fixed slice of a flat buffer.
struct SortedRows<T, E> {
    k: usize,
    sq_radius: T,
    len: [usize; GROUP],
    buf: Vec<E>,
}

impl<T: Scalar, E: RowEntry<T>> Rows<T> for SortedRows<T, E> {
    const TIGHTENS: bool = true;
    fn clear(&mut self, m: usize) {
        self.len[..m].fill(0);
    }
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let k = self.k;
        let mut set = SortedRow {
            row: &mut self.buf[i * k..i * k + k],
            len: &mut self.len[i],
            sq_radius: self.sq_radius,
        };
        set.insert(index, sq_dist);
        set.worst_key()
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<T>) {
        for i in 0..m {
            let row = &self.buf[i * self.k..i * self.k + self.len[i]];
            write_row(row.len(), row.iter().map(|&e| e.pair()), out);
        }
    }
}

/// Large `k`: a bounded heap per row, sorted at the end.
struct HeapRows<T> {
    k: usize,
    sq_radius: T,
    rows: Vec<Vec<Neighbor<T>>>,
}

impl<T: Scalar> Rows<T> for HeapRows<T> {
    const TIGHTENS: bool = true;
    fn clear(&mut self, m: usize) {
        self.rows[..m].iter_mut().for_each(Vec::clear);
    }
    #[inline]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let mut set = NeighborHeap::resume(&mut self.rows[i], self.k, self.sq_radius);
        set.insert(index, sq_dist);
        set.worst_key()
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<T>) {
        for r in &mut self.rows[..m] {
            r.sort_unstable_by(|a, b| a.cmp_by_distance(b));
            write_row(r.len(), r.iter().map(|nb| nb.key()), out);
        }
    }
}

/// Radius: every candidate within the radius, sorted at the end if asked.
struct RadiusRows<T> {
    sq_radius: T,
    sorted: bool,
    rows: Vec<Vec<Neighbor<T>>>,
}

impl<T: Scalar> Rows<T> for RadiusRows<T> {
    const TIGHTENS: bool = false;
    fn clear(&mut self, m: usize) {
        self.rows[..m].iter_mut().for_each(Vec::clear);
    }
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let mut set = WithinRadius {
            out: &mut self.rows[i],
            sq_radius: self.sq_radius,
        };
        set.insert(index, sq_dist);
        set.worst_key()
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<T>) {
        for r in &mut self.rows[..m] {
            if self.sorted {
                r.sort_unstable_by(|a, b| a.cmp_by_distance(b));
            }
            write_row(r.len(), r.iter().map(|nb| nb.key()), out);
        }
    }
}

impl<T: Scalar> DynamicKdTree<T> {
    /// The rows of the packed, finite `queries` (dimension `D`), row `i` for query `i`,
    /// answered in groups along `order` (a permutation of the queries); in parallel over
    /// fixed chunks of `order`, so identical for any thread count.
    ///
    /// `leaves[w]` is the first tree position, in the largest tree, of the leaf the query
    /// `order[w]` falls into (increasing): consecutive queries whose leaves lie within
    /// `span` positions form a group, and a query with no such neighbour is answered alone by
    /// the single-query descent (a group of far-apart queries would search the space between
    /// them).
    pub(super) fn grouped_rows<const D: usize>(
        &self,
        queries: &[T],
        order: &[u32],
        leaves: &[u32],
        nbhd: Neighborhood<T>,
    ) -> Result<NeighborTable<T>> {
        // Largest tree first: its bounds prune the smaller trees most.
        let mut parts: Vec<&Part<T>> = self.parts.iter().collect();
        parts.sort_by_key(|p| std::cmp::Reverse(p.tree.len()));
        let span = (SPAN_LEAVES * self.options.leaf_size) as u32;
        let n = order.len();
        let bounds: Vec<usize> = (0..n.div_ceil(CHUNK))
            .map(|c| c * CHUNK)
            .chain(std::iter::once(n))
            .collect();
        let (k, sq_radius) = nbhd.limits();
        let search = Group::<T, D> {
            forest: self,
            nbhd,
            parts: &parts,
            not_live: &self.not_live,
            sq_radius,
        };
        rows_in_chunks(
            n,
            &bounds,
            |w| order[w] as usize,
            None,
            |c, out| {
                let work = &order[bounds[c]..bounds[c + 1]];
                let leaves = &leaves[bounds[c]..bounds[c + 1]];
                let mut stack = Vec::new();
                let mut each = |rows: &mut GroupFn<'_, T>| {
                    let mut s = 0;
                    while s < work.len() {
                        let mut e = s + 1;
                        while e < work.len() && e - s < GROUP && leaves[e] - leaves[s] <= span {
                            e += 1;
                        }
                        rows(&work[s..e], &mut stack);
                        s = e;
                    }
                };
                if k == usize::MAX {
                    let mut rows = RadiusRows {
                        sq_radius,
                        sorted: nbhd.is_sorted(),
                        rows: (0..GROUP).map(|_| Vec::new()).collect(),
                    };
                    each(&mut |g, s| search.run(queries, g, &mut rows, s, out));
                } else if k <= SORTED_MAX_K && T::TYPE == ScalarType::F32 {
                    let mut rows = SortedRows {
                        k,
                        sq_radius,
                        len: [0; GROUP],
                        buf: vec![Key32::default(); GROUP * k],
                    };
                    each(&mut |g, s| search.run(queries, g, &mut rows, s, out));
                } else if k <= SORTED_MAX_K {
                    let mut rows = SortedRows {
                        k,
                        sq_radius,
                        len: [0; GROUP],
                        buf: vec![Neighbor::default(); GROUP * k],
                    };
                    each(&mut |g, s| search.run(queries, g, &mut rows, s, out));
                } else {
                    let mut rows = HeapRows {
                        k,
                        sq_radius,
                        rows: (0..GROUP).map(|_| Vec::new()).collect(),
                    };
                    each(&mut |g, s| search.run(queries, g, &mut rows, s, out));
                }
                Ok(())
            },
        )
    }
}

/// Answers one group (its members, a scratch stack of cells).
type GroupFn<'a, T> = dyn FnMut(&[u32], &mut Vec<(u32, T)>) + 'a;

/// What every group's search reads.
struct Group<'a, T, const D: usize> {
    forest: &'a DynamicKdTree<T>,
    nbhd: Neighborhood<T>,
    parts: &'a [&'a Part<T>],
    not_live: &'a [u64],
    sq_radius: T,
}

impl<T: Scalar, const D: usize> Group<'_, T, D> {
    /// Answers the queries `members` (indices into the packed `queries`) against every tree
    /// and appends their rows, in the members' order, to `out`.
    fn run<R: Rows<T>>(
        &self,
        queries: &[T],
        members: &[u32],
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<T>,
    ) {
        if out.is_done() {
            // a chunk whose rows did not fit takes no more (see `RowsChunk`)
            return;
        }
        let m = members.len();
        if m == 1 {
            let at = members[0] as usize * D;
            let mut row = Vec::new();
            answer(self.forest, &queries[at..at + D], None, self.nbhd, &mut row);
            write_row(row.len(), row.iter().map(|nb| nb.key()), out);
            return;
        }
        let mut q = [[T::ZERO; D]; GROUP];
        let mut glo = [T::INFINITY; D];
        let mut ghi = [T::ZERO - T::INFINITY; D];
        for (i, &w) in members.iter().enumerate() {
            let at = w as usize * D;
            q[i].copy_from_slice(&queries[at..at + D]);
            for j in 0..D {
                glo[j] = glo[j].min_of(q[i][j]);
                ghi[j] = ghi[j].max_of(q[i][j]);
            }
        }
        rows.clear(m);
        // Worst admissible key of each row, and the group's: the largest of them.
        let mut bound = [self.sq_radius; GROUP];
        let mut worst = [u32::MAX; GROUP];
        let (mut gb, mut gw) = (self.sq_radius, u32::MAX);
        for &part in self.parts {
            let (plo, phi): (&[T; D], &[T; D]) = (
                part.bbox_lo[..].try_into().unwrap(),
                part.bbox_hi[..].try_into().unwrap(),
            );
            let lb = box_dist(&glo, &ghi, plo, phi);
            if !order::precedes((lb, part.lo), (gb, gw)) {
                continue;
            }
            let cells = part.cells();
            let live_check = part.dead > 0;
            stack.clear();
            stack.push((0, lb));
            while let Some((mut node, lb)) = stack.pop() {
                if !admits(lb, cells.min_gid[node as usize], gb, gw) {
                    continue;
                }
                loop {
                    let ni = node as usize;
                    let (clo, chi) = (cells.lo::<D>(ni), cells.hi::<D>(ni));
                    let cmin = cells.min_gid[ni];
                    // A cell of copies of one point: its distance to each member is exact,
                    // so test the members one by one (near a cluster of copies the group's
                    // box would admit every cell of it for members that only need smaller
                    // indices at a tie).
                    if clo == chi
                        && !(0..m).any(|i| {
                            admits(box_dist(&q[i], &q[i], clo, chi), cmin, bound[i], worst[i])
                        })
                    {
                        break;
                    }
                    let nd = cells.nodes[ni];
                    if nd.dim == LEAF {
                        let (a, b) = (nd.a as usize, nd.b as usize);
                        for i in 0..m {
                            let qi = &q[i];
                            if !admits(box_dist(qi, qi, clo, chi), cmin, bound[i], worst[i]) {
                                continue;
                            }
                            let mut start = a;
                            while start < b {
                                let d = cells.block_sq_dists(qi, start);
                                let mut hits = 0u32;
                                for (p, &x) in d.iter().enumerate() {
                                    hits |= u32::from(x <= bound[i]) << p;
                                }
                                if b - start < BLOCK {
                                    hits &= (1 << (b - start)) - 1;
                                }
                                while hits != 0 {
                                    let p = hits.trailing_zeros() as usize;
                                    hits &= hits - 1;
                                    let id = cells.gids[start + p];
                                    if admits(d[p], id, bound[i], worst[i])
                                        && !(live_check && bit(self.not_live, id))
                                    {
                                        (bound[i], worst[i]) = rows.insert(i, id, d[p]);
                                    }
                                }
                                start += BLOCK;
                            }
                        }
                        if R::TIGHTENS {
                            (gb, gw) = (bound[0], worst[0]);
                            for i in 1..m {
                                if order::precedes((gb, gw), (bound[i], worst[i])) {
                                    (gb, gw) = (bound[i], worst[i]);
                                }
                            }
                        }
                        break;
                    }
                    let (l, r) = (node + 1, nd.a);
                    let lbl = box_dist(&glo, &ghi, cells.lo(l as usize), cells.hi(l as usize));
                    let lbr = box_dist(&glo, &ghi, cells.lo(r as usize), cells.hi(r as usize));
                    // Nearer cell first; between equally near ones, the side of the split the
                    // first member is on — unless only ties at the bound can still enter:
                    // then the cell holding the smallest index first.
                    let left_first = left_first(
                        (lbl, cells.min_gid[l as usize]),
                        (lbr, cells.min_gid[r as usize]),
                        R::TIGHTENS && lbl == gb,
                        q[0][nd.dim as usize] < nd.split,
                    );
                    let (near, lbn, far, lbf) = if left_first {
                        (l, lbl, r, lbr)
                    } else {
                        (r, lbr, l, lbl)
                    };
                    if admits(lbf, cells.min_gid[far as usize], gb, gw) {
                        stack.push((far, lbf));
                    }
                    if !admits(lbn, cells.min_gid[near as usize], gb, gw) {
                        break;
                    }
                    node = near;
                }
            }
        }
        rows.write(m, out);
    }
}
