//! Grouped all-point search: the neighbourhood table of a tree's own points, answered one
//! small group of consecutive tree-order points at a time.
//!
//! Points of one leaf have nearly the same neighbourhood (the "leaf-to-leaf" sharing of
//! dual-tree search, Gray & Moore, *'N-Body' Problems in Statistical Learning*, NIPS 2000, and
//! of bucketed all-kNN, Vaidya 1989). So instead of one
//! descent per query (thesis Algorithm 9), the tree is descended once per group: a cell is
//! visited if its tight bounding box may hold a point of some member's answer, i.e. if its
//! squared distance to the group's bounding box does not exceed the largest current bound of
//! the members. Each visited leaf is then scanned for every member whose own point-to-box
//! distance admits it, with a bounded heap per member. Every member therefore sees every
//! point that could enter its answer, with the exact squared distance the single-query search
//! computes, so the rows are the single-query rows byte for byte.
//!
//! Ties in `(sq_dist, index)` order also prune: once a member holds `k` candidates whose worst
//! is `(b, w)`, a cell at distance exactly `b` whose smallest caller index is ≥ `w` cannot
//! improve it. This stops duplicate-heavy sets from scanning every copy of a point.
//!
//! k-nearest rows up to [`SORTED_MAX_K`] take a faster path first (`group_search/gather.rs`):
//! the group gathers every point within a guessed radius once, and each member orders its
//! candidates within it once instead of inserting them one by one; where the guess does not
//! settle a row, the group is searched as above. The rows are the same either way.
//!
//! Lower bounds are exact in floating point: the gaps, squares and sums are evaluated in the
//! order of the point distance, and rounding is monotone, so a cell's bound never exceeds the
//! computed squared distance of any of its points to any member.

#[cfg(all(target_arch = "x86_64", rustc_1_89))]
#[clippy::msrv = "1.89"]
mod avx512;
mod gather;

use std::ops::Range;

use rayon::prelude::*;

use gather::Gather;

use super::kernel::{below_mask, sq_dists_by_dim};
use super::node::Node;
use super::search::TreeView;
use crate::error::Result;
use crate::query::result_set::{Key32, ResultSet, RowEntry, WithinRadius};
use crate::query::{order, Neighbor, NeighborHeap, Neighborhood};
use crate::scalar::{Scalar, ScalarType};
use crate::table::{rows_in_chunks, NeighborTable, RowsChunk, CHUNK};

/// Most queries in one group.
const GROUP: usize = 16;

/// Tight bounding box and smallest caller index of every node.
struct Boxes<'a, T, const D: usize> {
    lo: Vec<[T; D]>,
    hi: Vec<[T; D]>,
    /// The tree's own (`TreeView::min_id`).
    min_id: &'a [u32],
}

impl<'a, T: Scalar, const D: usize> Boxes<'a, T, D> {
    /// The leaves' boxes from their points in parallel (they read every point), then the
    /// internal nodes' bottom-up over the preorder node array (children follow their parent).
    fn new(tree: &TreeView<'a, T>) -> Self {
        let n = tree.nodes.len();
        let neg_inf = T::ZERO - T::INFINITY;
        let mut lo = vec![[T::INFINITY; D]; n];
        let mut hi = vec![[neg_inf; D]; n];
        lo.par_iter_mut()
            .zip(hi.par_iter_mut())
            .zip(tree.nodes.par_iter())
            .with_min_len(1024)
            .filter(|(_, nd)| nd.is_leaf())
            .for_each(|((l, h), nd)| {
                let points = &tree.coords[nd.a as usize * D..nd.b as usize * D];
                for p in points.chunks_exact(D) {
                    for j in 0..D {
                        l[j] = l[j].min_of(p[j]);
                        h[j] = h[j].max_of(p[j]);
                    }
                }
            });
        for i in (0..n).rev() {
            let nd = &tree.nodes[i];
            if !nd.is_leaf() {
                let (a, b) = (i + 1, nd.a as usize);
                for j in 0..D {
                    lo[i][j] = lo[a][j].min_of(lo[b][j]);
                    hi[i][j] = hi[a][j].max_of(hi[b][j]);
                }
            }
        }
        Self {
            lo,
            hi,
            min_id: tree.min_id,
        }
    }
}

/// The groups: subtrees of at most [`GROUP`] points, and pieces of larger leaves, as ranges of
/// tree positions in increasing order.
fn groups<T: Scalar>(nodes: &[Node<T>]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, start)) = stack.pop() {
        let nd = &nodes[i];
        let end = nd.b as usize;
        if nd.is_leaf() || end - start <= GROUP {
            let mut s = start;
            while s < end {
                let e = (s + GROUP).min(end);
                out.push(s..e);
                s = e;
            }
        } else {
            let left_end = nodes[i + 1].b as usize;
            stack.push((nd.a as usize, left_end));
            stack.push((i + 1, start));
        }
    }
    out
}

/// Points scanned at once: a leaf's squared distances to one query are computed a block at a
/// time, in straight-line code the compiler vectorises.
const BLOCK: usize = 16;

/// The coordinates in tree order as struct-of-arrays, dimension `j` at `v[j * stride..]`,
/// padded by a block so that a leaf's last block can be read whole.
struct Soa<T, const D: usize> {
    stride: usize,
    v: Vec<T>,
}

impl<T: Scalar, const D: usize> Soa<T, D> {
    fn new(coords: &[T]) -> Self {
        let n = coords.len() / D;
        let stride = n + BLOCK;
        let mut v = vec![T::ZERO; D * stride];
        // one dimension at a time, its points in parallel pieces
        for (j, dim) in v.chunks_exact_mut(stride).enumerate() {
            dim[..n]
                .par_chunks_mut(4096)
                .zip(coords.par_chunks(4096 * D))
                .for_each(|(out, c)| {
                    for (o, p) in out.iter_mut().zip(c.chunks_exact(D)) {
                        *o = p[j];
                    }
                });
        }
        Self { stride, v }
    }

    /// Squared distances from `q` to the points at tree positions `start..start + BLOCK`.
    #[inline(always)]
    fn block_sq_dists(&self, q: &[T; D], start: usize) -> [T; BLOCK] {
        sq_dists_by_dim(q, |j| &self.v[j * self.stride + start..][..BLOCK])
    }
}

/// Squared distance between the boxes `[alo, ahi]` and `[blo, bhi]` (0 where they overlap):
/// per dimension the gap `max(blo − ahi, alo − bhi, 0)`, without branches.
#[inline(always)]
pub(crate) fn box_dist<T: Scalar, const D: usize>(
    alo: &[T; D],
    ahi: &[T; D],
    blo: &[T; D],
    bhi: &[T; D],
) -> T {
    let mut s = T::ZERO;
    for j in 0..D {
        let g = (blo[j] - ahi[j]).max_of(alo[j] - bhi[j]).max_of(T::ZERO);
        s = s + g * g;
    }
    s
}

/// Whether a group descends into the left child before the right one, given each child's
/// `(lower bound, smallest index)`: the nearer first; between equally near ones the side of the
/// split the first member is on (`on_left`) — unless only ties at the bound can still enter
/// (`ties_only`), then the one holding the smallest index.
#[inline(always)]
pub(crate) fn left_first<T: Scalar>(
    left: (T, u32),
    right: (T, u32),
    ties_only: bool,
    on_left: bool,
) -> bool {
    if left.0 == right.0 {
        if ties_only {
            left.1 < right.1
        } else {
            on_left
        }
    } else {
        left.0 < right.0
    }
}

/// `true` if a cell at squared distance `lb` whose smallest caller index is `min_id` may
/// improve a row whose worst admissible key is `(b, w)` (`w == u32::MAX` while the row is not
/// full: caller indices are below it).
#[inline(always)]
pub(crate) fn admits<T: Scalar>(lb: T, min_id: u32, b: T, w: u32) -> bool {
    order::precedes((lb, min_id), (b, w))
}

/// One result set (`src/query/result_set.rs`) per member of a group, and how their rows are
/// written.
trait RowSets<T: Scalar> {
    /// The result set of one member.
    type Set<'a>: ResultSet<T>
    where
        Self: 'a;
    /// Empties the first `m` rows.
    fn clear(&mut self, m: usize);
    /// The result set of member `i`.
    fn set(&mut self, i: usize) -> Self::Set<'_>;
    /// Adds a candidate to member `i`'s set (it must precede the set's worst key, see
    /// [`admits`]); returns the set's new worst key.
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let mut set = self.set(i);
        set.insert(index, sq_dist);
        set.worst_key()
    }
    /// Whether keys change as candidates arrive (k-nearest) or stay the radius (radius).
    const TIGHTENS: bool;

    /// Appends the first `m` rows, in `(sq_dist, index)` order where asked, to `out`.
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>);
    /// Appends, for every id of `self_ids`, row 0 without that id: the rows of a group of
    /// copies of one point, searched once (radius rows only; see [`Search::group`]).
    fn write_copies(&mut self, _self_ids: &[u32], _out: &mut RowsChunk<'_, T>) {
        unreachable!("only radius rows are shared by copies")
    }
}

/// `k` up to [`SORTED_MAX_K`]: each row sorted by insertion in a fixed slice of `k + 1` entries
/// of a flat buffer, so a candidate costs a short shift and the row needs no final sort. Entries
/// `E` are [`Neighbor`]s, or for `f32` the packed keys [`Key32`], so the insertion compares one
/// integer instead of two floats and an index. Slot 0 of each row is a guard that no candidate precedes
/// (`(0, 0)`: distances are never negative), so the shift stops there without testing the
/// position; the row's entries are slots `1..=len`.
struct SortedRows<T, E> {
    k: usize,
    sq_radius: T,
    len: [usize; GROUP],
    buf: Vec<E>,
}

impl<T: Scalar, E: RowEntry<T>> SortedRows<T, E> {
    fn new(k: usize, sq_radius: T) -> Self {
        Self {
            k,
            sq_radius,
            len: [0; GROUP],
            buf: vec![E::of(0, T::ZERO); GROUP * (k + 1)],
        }
    }
}

/// Rows up to this `k` are kept sorted by insertion; larger ones in heaps of packed keys
/// ([`KeyHeapRows`]) up to [`KEY_HEAP_MAX_K`], in growing heaps of neighbours beyond. Measured
/// on the 77k torus (README "Single queries, the floor, and copies of a point", round 4): with
/// the guard slot, sorted rows take 17 % fewer instructions than the key heaps for k = 30 and
/// 11 % fewer for k = 52 (each point left out), and 10–20 % less time.
const SORTED_MAX_K: usize = 64;

/// Rows up to this `k` are heaps of packed keys: `GROUP · k` keys of scratch per thread.
const KEY_HEAP_MAX_K: usize = 4096;

impl<T: Scalar, E: RowEntry<T>> RowSets<T> for SortedRows<T, E> {
    type Set<'a>
        = NoSet
    where
        Self: 'a;
    const TIGHTENS: bool = true;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.len[..m].fill(0);
    }
    fn set(&mut self, _i: usize) -> NoSet {
        NoSet
    }
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let k = self.k;
        let row = &mut self.buf[i * (k + 1)..(i + 1) * (k + 1)];
        let cand = E::of(index, sq_dist);
        let held = self.len[i];
        // the slot the candidate's entry ends in; the worst entry falls off a full row
        let mut j = if held < k {
            self.len[i] = held + 1;
            held + 1
        } else {
            k
        };
        // SAFETY: `1 ≤ j ≤ k < row.len()` on entry, and no candidate precedes the guard
        // `row[0]`, so the loop leaves at `j = 1` at the latest: `j - 1` and `j` stay in
        // `row`.
        unsafe {
            while cand.precedes(*row.get_unchecked(j - 1)) {
                *row.get_unchecked_mut(j) = *row.get_unchecked(j - 1);
                j -= 1;
            }
            *row.get_unchecked_mut(j) = cand;
        }
        if held + 1 < k {
            (self.sq_radius, u32::MAX)
        } else {
            row[k].pair()
        }
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        let k = self.k;
        for i in 0..m {
            let row = &self.buf[i * (k + 1) + 1..i * (k + 1) + 1 + self.len[i]];
            out.push_row(row.len(), row.iter().map(|&e| e.pair()));
        }
    }
}

/// A neighbour packed into one integer key that orders as `(sq_dist, index)`
/// (`src/query/order.rs`): a `u64` for `f32` ([`order::key32`]), a `u128` for any scalar
/// ([`order::key64`]).
trait PackedKey<T>: Copy + Ord + Default + gather::Rank + 'static {
    /// The key of a candidate.
    fn of(index: u32, sq_dist: T) -> Self;
    /// Its `(sq_dist, index)`.
    fn pair(self) -> (T, u32);
}

impl<T: Scalar> PackedKey<T> for u64 {
    #[inline(always)]
    fn of(index: u32, sq_dist: T) -> Self {
        order::key32(sq_dist, index)
    }
    #[inline(always)]
    fn pair(self) -> (T, u32) {
        order::unkey32(self)
    }
}

impl<T: Scalar> PackedKey<T> for u128 {
    #[inline(always)]
    fn of(index: u32, sq_dist: T) -> Self {
        order::key64(sq_dist, index)
    }
    #[inline(always)]
    fn pair(self) -> (T, u32) {
        order::unkey64(self)
    }
}

/// Larger `k`: each row a binary max-heap of packed keys in a fixed slice of a flat buffer, so
/// a candidate costs `log k` integer compares and moves (a sorted row shifts or moves about
/// `k / 2` entries) and the worst key is always exact; sorted once, when written.
struct KeyHeapRows<T, K> {
    k: usize,
    sq_radius: T,
    len: [usize; GROUP],
    buf: Vec<K>,
}

impl<T: Scalar, K: PackedKey<T>> KeyHeapRows<T, K> {
    fn new(k: usize, sq_radius: T) -> Self {
        Self {
            k,
            sq_radius,
            len: [0; GROUP],
            buf: vec![K::default(); GROUP * k],
        }
    }
}

/// [`KeyHeapRows`]' rows are never asked for as [`ResultSet`]s: the search inserts through
/// [`RowSets::insert`]. This set only satisfies the trait.
struct NoSet;

impl<T: Scalar> ResultSet<T> for NoSet {
    fn worst_key(&self) -> (T, u32) {
        unreachable!("heap rows insert directly")
    }
    fn insert(&mut self, _index: u32, _sq_dist: T) {
        unreachable!("heap rows insert directly")
    }
}

impl<T: Scalar, K: PackedKey<T>> RowSets<T> for KeyHeapRows<T, K> {
    type Set<'a>
        = NoSet
    where
        Self: 'a;
    const TIGHTENS: bool = true;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.len[..m].fill(0);
    }
    fn set(&mut self, _i: usize) -> NoSet {
        NoSet
    }
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let k = self.k;
        let heap = &mut self.buf[i * k..i * k + k];
        let key = K::of(index, sq_dist);
        let len = self.len[i];
        if len < k {
            // sift up from the new leaf
            let mut c = len;
            while c > 0 {
                let p = (c - 1) / 2;
                if heap[p] >= key {
                    break;
                }
                heap[c] = heap[p];
                c = p;
            }
            heap[c] = key;
            self.len[i] = len + 1;
            if len + 1 < k {
                return (self.sq_radius, u32::MAX);
            }
        } else {
            // the worst (the root) falls off: sift the candidate down from the root
            let mut c = 0;
            loop {
                let l = 2 * c + 1;
                if l >= k {
                    break;
                }
                let r = l + 1;
                let big = if r < k && heap[r] > heap[l] { r } else { l };
                if heap[big] <= key {
                    break;
                }
                heap[c] = heap[big];
                c = big;
            }
            heap[c] = key;
        }
        heap[0].pair()
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        let k = self.k;
        for i in 0..m {
            let row = &mut self.buf[i * k..i * k + self.len[i]];
            row.sort_unstable();
            out.push_row(row.len(), row.iter().map(|&e| e.pair()));
        }
    }
}

/// Appends one row of neighbours to the chunk.
#[inline]
fn write_neighbors<T: Scalar>(row: &[Neighbor<T>], out: &mut RowsChunk<'_, T>) {
    out.push_row(row.len(), row.iter().map(|nb| (nb.sq_dist, nb.index)));
}

/// Sorts a row by `(sq_dist, index)` through the packed keys of `src/query/order.rs`; every key
/// is distinct, so an unstable sort gives the one order.
fn sort_row<T: Scalar>(row: &mut [Neighbor<T>], keys: &mut Keys) {
    if T::TYPE == ScalarType::F32 {
        // f32 bits fit in 32: one u64 key (the f64 round trip of an f32 is exact).
        let keys = &mut keys.narrow;
        keys.clear();
        keys.extend(row.iter().map(|nb| order::key32(nb.sq_dist, nb.index)));
        keys.sort_unstable();
        for (nb, &key) in row.iter_mut().zip(keys.iter()) {
            (nb.sq_dist, nb.index) = order::unkey32(key);
        }
    } else {
        let keys = &mut keys.wide;
        keys.clear();
        keys.extend(row.iter().map(|nb| order::key64(nb.sq_dist, nb.index)));
        keys.sort_unstable();
        for (nb, &key) in row.iter_mut().zip(keys.iter()) {
            (nb.sq_dist, nb.index) = order::unkey64(key);
        }
    }
}

/// Scratch keys of [`sort_row`].
#[derive(Default)]
struct Keys {
    narrow: Vec<u64>,
    wide: Vec<u128>,
}

/// Large `k`: a bounded heap per row ([`NeighborHeap`]), sorted at the end.
struct HeapRows<T> {
    k: usize,
    sq_radius: T,
    rows: Vec<Vec<Neighbor<T>>>,
    keys: Keys,
}

impl<T: Scalar> RowSets<T> for HeapRows<T> {
    type Set<'a>
        = NeighborHeap<'a, T>
    where
        Self: 'a;
    const TIGHTENS: bool = true;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.rows[..m].iter_mut().for_each(Vec::clear);
    }
    #[inline]
    fn set(&mut self, i: usize) -> NeighborHeap<'_, T> {
        NeighborHeap::resume(&mut self.rows[i], self.k, self.sq_radius)
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        for r in &mut self.rows[..m] {
            sort_row(r, &mut self.keys);
            write_neighbors(r, out);
        }
    }
}

/// Radius: every candidate within the radius ([`WithinRadius`]), sorted at the end if asked.
struct RadiusRows<T> {
    sq_radius: T,
    sorted: bool,
    rows: Vec<Vec<Neighbor<T>>>,
    keys: Keys,
}

impl<T: Scalar> RowSets<T> for RadiusRows<T> {
    type Set<'a>
        = WithinRadius<'a, T>
    where
        Self: 'a;
    const TIGHTENS: bool = false;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.rows[..m].iter_mut().for_each(Vec::clear);
    }
    #[inline(always)]
    fn set(&mut self, i: usize) -> WithinRadius<'_, T> {
        WithinRadius {
            out: &mut self.rows[i],
            sq_radius: self.sq_radius,
        }
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        for r in &mut self.rows[..m] {
            if self.sorted {
                sort_row(r, &mut self.keys);
            }
            write_neighbors(r, out);
        }
    }
    fn write_copies(&mut self, self_ids: &[u32], out: &mut RowsChunk<'_, T>) {
        let r = &mut self.rows[0];
        if self.sorted {
            sort_row(r, &mut self.keys);
        }
        // The shared row as two flat arrays, stored once; each member's row (the shared one
        // less the member itself) is written only into the final table.
        let ids: Vec<u32> = r.iter().map(|nb| nb.index).collect();
        let dists: Vec<T> = r.iter().map(|nb| nb.sq_dist).collect();
        out.push_shared(&ids, &dists, self_ids);
    }
}

/// The all-point table of `tree` (dimension `D`), rows in the caller's index order.
pub(crate) fn table<T: Scalar, const D: usize>(
    tree: &TreeView<'_, T>,
    source_len: usize,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
) -> Result<NeighborTable<T>> {
    let plan = Plan::<T, D>::new(tree, nbhd, exclude_self);
    plan.rows(0..plan.chunks(), source_len, |pos| tree.ids[pos] as usize)
}

/// The grouped search of one tree and one neighbourhood, prepared once (cell boxes, groups,
/// coordinates by dimension) and run over any run of its chunks: the whole table, or a block of
/// tree positions at a time when the table of every point would not fit in memory.
pub(crate) struct Plan<'a, T, const D: usize> {
    tree: &'a TreeView<'a, T>,
    boxes: Boxes<'a, T, D>,
    soa: Soa<T, D>,
    groups: Vec<Range<usize>>,
    /// Chunk `c` holds the groups `chunk_groups[c]..chunk_groups[c + 1]`.
    chunk_groups: Vec<usize>,
    /// Chunk `c` holds the tree positions `work_bounds[c]..work_bounds[c + 1]`.
    work_bounds: Vec<usize>,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
}

impl<'a, T: Scalar, const D: usize> Plan<'a, T, D> {
    pub(crate) fn new(
        tree: &'a TreeView<'a, T>,
        nbhd: Neighborhood<T>,
        exclude_self: bool,
    ) -> Self {
        let boxes = Boxes::<T, D>::new(tree);
        let groups = groups(tree.nodes);
        // Chunks of whole groups, about CHUNK points each: fixed by the tree, not the threads.
        let mut chunk_groups = vec![0usize];
        let mut work_bounds = vec![0usize];
        let mut acc = 0;
        for (g, r) in groups.iter().enumerate() {
            acc += r.len();
            if acc >= CHUNK || g + 1 == groups.len() {
                chunk_groups.push(g + 1);
                work_bounds.push(r.end);
                acc = 0;
            }
        }
        Self {
            tree,
            boxes,
            soa: Soa::<T, D>::new(tree.coords),
            groups,
            chunk_groups,
            work_bounds,
            nbhd,
            exclude_self,
        }
    }

    /// Empty radius rows of a group, within `sq_radius`.
    fn radius_rows(&self, sq_radius: T) -> RadiusRows<T> {
        RadiusRows {
            sq_radius,
            sorted: self.nbhd.is_sorted(),
            rows: (0..GROUP).map(|_| Vec::new()).collect(),
            keys: Keys::default(),
        }
    }

    /// How many chunks the tree's positions are cut into.
    pub(crate) fn chunks(&self) -> usize {
        self.work_bounds.len() - 1
    }

    /// The tree positions of the chunks `chunks`.
    pub(crate) fn positions(&self, chunks: Range<usize>) -> Range<usize> {
        self.work_bounds[chunks.start]..self.work_bounds[chunks.end]
    }

    /// The rows of the points at the tree positions of `chunks`, computed in parallel, as a
    /// table of `rows` rows in which the row of position `pos` is `row_of(pos)`.
    pub(crate) fn rows(
        &self,
        chunks: Range<usize>,
        rows: usize,
        row_of: impl Fn(usize) -> usize + Sync,
    ) -> Result<NeighborTable<T>> {
        let (k, sq_radius) = self.nbhd.limits();
        let search = Search {
            tree: self.tree,
            boxes: &self.boxes,
            soa: &self.soa,
            sq_radius,
            exclude_self: self.exclude_self,
        };
        let first = chunks.start;
        let run = |c: usize, rows: &mut GroupAnswer<'_, T, D>| {
            let c = first + c;
            for g in &self.groups[self.chunk_groups[c]..self.chunk_groups[c + 1]] {
                rows(&search, g.clone());
            }
        };
        // Every row of a k-nearest table (no radius) holds k of the tree's other points, or
        // all of them: its place in the table is known before the search.
        let row_len = match self.nbhd {
            Neighborhood::Knn { k } => Some(k.min(
                self.tree.ids.len() - usize::from(self.exclude_self).min(self.tree.ids.len()),
            )),
            _ => None,
        };
        rows_in_chunks(
            rows,
            &self.work_bounds[chunks.start..=chunks.end],
            row_of,
            row_len,
            |c, out| {
                let groups = |each: &mut GroupAnswer<'_, T, D>| run(c, each);
                let sorted = self.nbhd.is_sorted();
                let f32 = T::TYPE == ScalarType::F32;
                if k == usize::MAX && f32 {
                    let gather = Gather::<T, u64, D>::within(sorted);
                    answer_groups(&groups, self.radius_rows(sq_radius), Some(gather), out);
                } else if k == usize::MAX {
                    let gather = Gather::<T, u128, D>::within(sorted);
                    answer_groups(&groups, self.radius_rows(sq_radius), Some(gather), out);
                } else if k <= SORTED_MAX_K && f32 {
                    let rows = SortedRows::<T, Key32>::new(k, sq_radius);
                    answer_groups(&groups, rows, Some(Gather::<T, u64, D>::nearest(k)), out);
                } else if k <= SORTED_MAX_K {
                    let rows = SortedRows::<T, Neighbor<T>>::new(k, sq_radius);
                    answer_groups(&groups, rows, Some(Gather::<T, u128, D>::nearest(k)), out);
                } else if k <= KEY_HEAP_MAX_K && f32 {
                    let rows = KeyHeapRows::<T, u64>::new(k, sq_radius);
                    answer_groups(&groups, rows, None::<Gather<T, u64, D>>, out);
                } else if k <= KEY_HEAP_MAX_K {
                    let rows = KeyHeapRows::<T, u128>::new(k, sq_radius);
                    answer_groups(&groups, rows, None::<Gather<T, u128, D>>, out);
                } else {
                    let rows = HeapRows {
                        k,
                        sq_radius,
                        rows: (0..GROUP).map(|_| Vec::new()).collect(),
                        keys: Keys::default(),
                    };
                    answer_groups(&groups, rows, None::<Gather<T, u64, D>>, out);
                }
                Ok(())
            },
        )
    }
}

/// What answers one group: given the search and the group's tree positions.
type GroupAnswer<'f, T, const D: usize> = dyn FnMut(&Search<'_, T, D>, Range<usize>) + 'f;

/// Answers every group that `groups` hands out with the rows `rows`, each group first from a
/// gathered block where `gather` is given (`group_search/gather.rs`), and appends the rows to
/// `out`; once a chunk's rows did not fit, it takes no more (see `RowsChunk`).
fn answer_groups<T: Scalar, const D: usize, R: RowSets<T>, K: PackedKey<T>>(
    groups: &dyn Fn(&mut GroupAnswer<'_, T, D>),
    mut rows: R,
    mut gather: Option<Gather<T, K, D>>,
    out: &mut RowsChunk<'_, T>,
) {
    let mut stack = Vec::new();
    groups(&mut |s, g| {
        if out.is_done() {
            return;
        }
        // the group's rows go to slots scattered over the table: request them (and the next
        // group's offsets) before the search
        out.prefetch(g.len(), GROUP);
        match &mut gather {
            Some(gather) => s.gathered_group(g, gather, &mut rows, &mut stack, out),
            None => s.group(g, &mut rows, &mut stack, out),
        }
    });
}

/// What every group's search reads.
struct Search<'a, T, const D: usize> {
    tree: &'a TreeView<'a, T>,
    boxes: &'a Boxes<'a, T, D>,
    soa: &'a Soa<T, D>,
    sq_radius: T,
    exclude_self: bool,
}

/// The members of a group: their coordinates, the ids their rows leave out (`u32::MAX` for
/// none) and their bounding box.
struct Members<T, const D: usize> {
    q: [[T; D]; GROUP],
    self_id: [u32; GROUP],
    lo: [T; D],
    hi: [T; D],
}

impl<T: Scalar, const D: usize> Search<'_, T, D> {
    /// The members of the group of tree positions `g`.
    fn members(&self, g: Range<usize>) -> Members<T, D> {
        let tree = self.tree;
        let mut m = Members {
            q: [[T::ZERO; D]; GROUP],
            self_id: [u32::MAX; GROUP],
            lo: [T::INFINITY; D],
            hi: [T::ZERO - T::INFINITY; D],
        };
        for (i, p) in g.enumerate() {
            for j in 0..D {
                let c = tree.coords[p * D + j];
                m.q[i][j] = c;
                m.lo[j] = m.lo[j].min_of(c);
                m.hi[j] = m.hi[j].max_of(c);
            }
            if self.exclude_self {
                m.self_id[i] = tree.ids[p];
            }
        }
        m
    }

    /// Answers the group of tree positions `g` from one gathered block (`gather`), or by
    /// [`Search::group`] with the rows `rows` where the gather does not settle it; appends its
    /// rows, in position order, to `out`.
    fn gathered_group<R: RowSets<T>, K: PackedKey<T>>(
        &self,
        g: Range<usize>,
        gather: &mut Gather<T, K, D>,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<'_, T>,
    ) {
        let mb = self.members(g.clone());
        if !gather.group(self, &mb, g.len(), out) {
            let bound = self.group_of(g, mb, rows, stack, out);
            if R::TIGHTENS {
                gather.learn(bound, self.sq_radius);
            }
        }
    }

    /// Answers the group of tree positions `g` and appends its rows, in position order, to
    /// `out`.
    fn group<R: RowSets<T>>(
        &self,
        g: Range<usize>,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<'_, T>,
    ) {
        let mb = self.members(g.clone());
        self.group_of(g, mb, rows, stack, out);
    }

    /// [`Search::group`] of the group's members `mb`; returns the group's bound, the largest
    /// worst distance of its rows (the search's limit where a row is not full).
    fn group_of<R: RowSets<T>>(
        &self,
        g: Range<usize>,
        mb: Members<T, D>,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<'_, T>,
    ) -> T {
        let (tree, boxes) = (self.tree, self.boxes);
        let sse = crate::simd::sse();
        let m = g.len();
        let Members {
            q,
            mut self_id,
            lo: glo,
            hi: ghi,
        } = mb;
        // Worst admissible key of each row.
        let mut bound = [self.sq_radius; GROUP];
        let mut worst = [u32::MAX; GROUP];
        // Radius rows of a group of copies of one point (duplicate-heavy sets) are one row,
        // less each member itself: searched and sorted once. (`u32::MAX` excludes nothing.)
        let copies = !R::TIGHTENS && m > 1 && glo == ghi;
        let self_ids = self_id;
        let m = if copies {
            self_id[0] = u32::MAX;
            1
        } else {
            m
        };
        rows.clear(m);
        // The group's key: the largest worst key of its rows.
        let (mut gb, mut gw) = (self.sq_radius, u32::MAX);
        stack.clear();
        stack.push((0, box_dist(&glo, &ghi, &boxes.lo[0], &boxes.hi[0])));
        while let Some((mut node, lb)) = stack.pop() {
            if !admits(lb, boxes.min_id[node as usize], gb, gw) {
                continue;
            }
            loop {
                let ni = node as usize;
                // A cell of copies of one point (duplicate-heavy sets): its distance to each
                // member is exact, so test the members one by one; near a cluster of copies
                // the group's box would admit every cell of it for members that only need
                // smaller indices at a tie.
                if boxes.lo[ni] == boxes.hi[ni]
                    && !(0..m).any(|i| {
                        let lb = box_dist(&q[i], &q[i], &boxes.lo[ni], &boxes.hi[ni]);
                        admits(lb, boxes.min_id[ni], bound[i], worst[i])
                    })
                {
                    break;
                }
                let nd = &tree.nodes[ni];
                if nd.is_leaf() {
                    let (llo, lhi) = (&boxes.lo[node as usize], &boxes.hi[node as usize]);
                    let lmin = boxes.min_id[node as usize];
                    let (a, b) = (nd.a as usize, nd.b as usize);
                    for i in 0..m {
                        let qi = &q[i];
                        if !admits(box_dist(qi, qi, llo, lhi), lmin, bound[i], worst[i]) {
                            continue;
                        }
                        let mut start = a;
                        while start < b {
                            let d = self.soa.block_sq_dists(qi, start);
                            let mut hits = below_mask(&d, bound[i], sse);
                            if b - start < BLOCK {
                                hits &= (1 << (b - start)) - 1;
                            }
                            while hits != 0 {
                                let p = hits.trailing_zeros() as usize;
                                hits &= hits - 1;
                                let id = tree.ids[start + p];
                                if admits(d[p], id, bound[i], worst[i]) && id != self_id[i] {
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
                let lbl = box_dist(&glo, &ghi, &boxes.lo[l as usize], &boxes.hi[l as usize]);
                let lbr = box_dist(&glo, &ghi, &boxes.lo[r as usize], &boxes.hi[r as usize]);
                // Nearer cell first; between equally near cells, the one holding the group
                // (the side of the split its first point is on) — unless they can only offer
                // ties at the bound (e.g. copies of the members' point once every row holds k
                // of them): then only smaller indices help, so the cell holding the smallest
                // first, which soon leaves every other cell pruned by its smallest index.
                let left_first = left_first(
                    (lbl, boxes.min_id[l as usize]),
                    (lbr, boxes.min_id[r as usize]),
                    R::TIGHTENS && lbl == gb,
                    q[0][nd.dim as usize] < nd.split,
                );
                let (near, lbn, far, lbf) = if left_first {
                    (l, lbl, r, lbr)
                } else {
                    (r, lbr, l, lbl)
                };
                if admits(lbf, boxes.min_id[far as usize], gb, gw) {
                    stack.push((far, lbf));
                }
                if !admits(lbn, boxes.min_id[near as usize], gb, gw) {
                    break;
                }
                node = near;
            }
        }
        if copies {
            rows.write_copies(&self_ids[..g.len()], out);
        } else {
            rows.write(m, out);
        }
        gb
    }
}
