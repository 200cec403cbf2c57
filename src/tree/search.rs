//! Exact search on the k-d tree (thesis Section 5.2, Algorithm 9): descend to the leaf of the
//! query, then visit the far side of every split whose cell may still hold a point that enters
//! the result. Cells are kept on an explicit stack with a lower bound of their squared distance
//! to the query, so deep, unbalanced trees cannot overflow the call stack and nothing is
//! allocated per query.
//!
//! The lower bound of a cell is the sum of its squared per-dimension gaps to the query (the
//! incremental distance of Arya & Mount, *Algorithms for fast vector quantization*, 1993, as
//! nanoflann keeps it), evaluated in the order of the point distance, `((0 + g0²) + g1²) + …`:
//! rounding is monotone, so the bound never exceeds the computed squared distance of a point of
//! the cell, and pruning is exact in floating point. (Any dimension above 3 keeps the largest
//! single gap, a weaker bound with the same guarantee.) Under another norm (`src/metric.rs`,
//! [`search_norm`]) the keys and bounds are that norm's fold of its terms, in the same order and
//! with the same guarantee: the terms (`|t|`, `t²`) and folds (`+`, `max`) are monotone in
//! floating point; a general p's `pow` may not be, so its bounds are shrunk by a few ulps
//! (`Measure::apply`), and an approximate search's are scaled up by its factor.
//!
//! Cells are pruned in `(sq_dist, index)` order (`src/query/order.rs`): a cell whose bound is
//! `b` and whose smallest caller index is `m` can only hold candidates at or after `(b, m)`, so
//! it is skipped unless `(b, m)` precedes the result's worst admissible key. With distances
//! alone a cell at exactly the k-th distance must be visited (a point there may win on its
//! index); with the index too, the copies of a duplicated point stop being examined once the
//! result holds `k` of them with lower indices than any remaining cell. On a split whose value
//! equals the query's coordinate both sides are equally near; once only ties at the bound can
//! enter, the side with the smaller index is taken first (the build orders identical points by
//! caller index, `src/tree/layout.rs`), so the copies with the lowest indices are met first.

use super::kernel::sq_dists_below;
use super::node::{Descent, Node, DESCENT_LEAF};
use crate::metric::{Norm, L2};
use crate::prefetch::prefetch_range;
use crate::query::result_set::ResultSet;
use crate::scalar::{Scalar, ScalarType};
use rayon::prelude::*;

/// The tree's arrays a search reads.
pub(crate) struct TreeView<'a, T> {
    pub nodes: &'a [Node<T>],
    pub coords: &'a [T],
    pub ids: &'a [u32],
    /// Smallest caller index of every node's subtree (`min_ids`).
    pub min_id: &'a [u32],
    pub dim: usize,
}

/// The smallest caller index of every node's subtree: the leaves' from their indices (in
/// parallel on the current pool if `parallel`: they read every index), then the internal
/// nodes' bottom-up over the preorder node array (children follow their parent).
pub(crate) fn min_ids<T: Copy + Default + Sync>(
    nodes: &[Node<T>],
    ids: &[u32],
    parallel: bool,
) -> Vec<u32> {
    let leaf_min = |n: &Node<T>| {
        if n.is_leaf() {
            ids[n.a as usize..n.b as usize]
                .iter()
                .copied()
                .min()
                .unwrap_or(u32::MAX)
        } else {
            u32::MAX
        }
    };
    let mut m: Vec<u32> = if parallel {
        nodes.par_iter().with_min_len(1024).map(leaf_min).collect()
    } else {
        nodes.iter().map(leaf_min).collect()
    };
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        if !n.is_leaf() {
            m[i] = m[i + 1].min(m[n.a as usize]);
        }
    }
    m
}

/// A pending cell: its node, its per-dimension gaps to the query (3-D and below) and their
/// squared sum, the cell's lower bound.
#[derive(Clone, Copy)]
struct Cell<T, const G: usize> {
    node: u32,
    dist: T,
    gaps: [T; G],
}

/// Pending cells: a fixed array on the call stack, spilling to the heap only for trees deeper
/// than it (unbalanced closest-to-middle trees).
struct CellStack<T, const G: usize> {
    inline: [Cell<T, G>; 48],
    len: usize,
    spill: Vec<Cell<T, G>>,
}

impl<T: Scalar, const G: usize> CellStack<T, G> {
    #[inline(always)]
    fn new() -> Self {
        let empty = Cell {
            node: 0,
            dist: T::ZERO,
            gaps: [T::ZERO; G],
        };
        Self {
            inline: [empty; 48],
            len: 0,
            spill: Vec::new(),
        }
    }
    #[inline(always)]
    fn push(&mut self, cell: Cell<T, G>) {
        if self.len < self.inline.len() {
            self.inline[self.len] = cell;
            self.len += 1;
        } else {
            self.spill.push(cell);
        }
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<Cell<T, G>> {
        if let Some(c) = self.spill.pop() {
            return Some(c);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

/// The key (under `norm`; the squared distance for [`L2`]) from `q` to the point at tree
/// position `i`; `D > 0` fixes the dimension at compile time (the 3-D hot path), `D == 0`
/// reads it from `dim`.
#[inline(always)]
fn key_at<T: Scalar, N: Norm<T>, const D: usize>(
    norm: N,
    q: &[T],
    coords: &[T],
    i: usize,
    dim: usize,
) -> T {
    let d = if D > 0 { D } else { dim };
    norm.key(q, &coords[i * d..i * d + d], d)
}

/// Whether a cell with lower bound `dist` and smallest caller index `min_id` may still hold a
/// candidate that enters `out`: `(dist, min_id)` precedes the worst admissible key. The index
/// is read only on a tie in distance.
#[inline(always)]
pub(super) fn may_enter<T: Scalar, C: ResultSet<T>>(
    out: &C,
    dist: T,
    min_id: &[u32],
    node: u32,
) -> bool {
    let (wd, wi) = out.worst_key();
    dist < wd || (dist == wd && min_id[node as usize] < wi)
}

/// Runs the search, offering every point of every visited leaf except `exclude` to the result
/// set `out` (`src/query/result_set.rs`), which decides what it keeps.
pub(crate) fn search<T: Scalar, C: ResultSet<T>>(
    tree: &TreeView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    out: &mut C,
) {
    search_norm(tree, q, exclude, L2, out);
}

/// [`search`] under any norm (`src/metric.rs`): keys and cell bounds in the norm's form, the
/// bounds passed through its `lower` before every comparison.
pub(crate) fn search_norm<T: Scalar, C: ResultSet<T>, N: Norm<T>>(
    tree: &TreeView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    norm: N,
    out: &mut C,
) {
    match tree.dim {
        3 => search_d::<T, C, N, 3, 3>(tree, q, exclude, norm, out),
        2 => search_d::<T, C, N, 2, 2>(tree, q, exclude, norm, out),
        1 => search_d::<T, C, N, 1, 1>(tree, q, exclude, norm, out),
        _ => search_d::<T, C, N, 0, 0>(tree, q, exclude, norm, out),
    }
}

/// `D` the dimension (0: read from the tree), `G` the gaps kept per cell (`D`, or 0 for the
/// largest-gap bound of any dimension).
fn search_d<T: Scalar, C: ResultSet<T>, N: Norm<T>, const D: usize, const G: usize>(
    tree: &TreeView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    norm: N,
    out: &mut C,
) {
    let excluded = exclude.unwrap_or(u32::MAX);
    let mut stack = CellStack::<T, G>::new();
    stack.push(Cell {
        node: 0,
        dist: T::ZERO,
        gaps: [T::ZERO; G],
    });
    while let Some(Cell {
        mut node,
        dist,
        gaps,
    }) = stack.pop()
    {
        if !may_enter(out, dist, tree.min_id, node) {
            continue;
        }
        loop {
            let n = &tree.nodes[node as usize];
            if n.is_leaf() {
                let bound = out.bound();
                for i in n.a as usize..n.b as usize {
                    let d2 = key_at::<T, N, D>(norm, q, tree.coords, i, tree.dim);
                    // The index (another cache line) is read only for a candidate within the
                    // bound; caller indices are below u32::MAX, so MAX excludes nothing.
                    if d2 <= bound {
                        let id = tree.ids[i];
                        if id != excluded {
                            out.offer(id, d2);
                        }
                    }
                }
                break;
            }
            let sd = n.dim as usize;
            let diff = q[sd] - n.split;
            // On a tie both sides are equally near: the right one holds the query's own leaf
            // (points equal to a split value go right, as `leaf_start` in neighborhoods.rs
            // descends), unless only ties at the bound can still enter; then the side with the
            // smaller index first, which soon leaves the other pruned by its smallest index.
            let left_first = if diff == T::ZERO {
                dist == out.bound() && tree.min_id[node as usize + 1] < tree.min_id[n.a as usize]
            } else {
                diff < T::ZERO
            };
            let (near, far) = if left_first {
                (node + 1, n.a)
            } else {
                (n.a, node + 1)
            };
            let far_cell = if G > 0 {
                // The far side lies beyond the split: its gap in `sd` grows to |diff| (at
                // least the old gap, as the split lies inside the current cell).
                let mut g = gaps;
                g[sd] = diff;
                let mut s = T::ZERO;
                for x in g {
                    s = norm.fold(s, norm.term(x));
                }
                Cell {
                    node: far,
                    dist: norm.lower(s),
                    gaps: g,
                }
            } else {
                // One term bounds every norm's key from below (a sum or a maximum of terms).
                Cell {
                    node: far,
                    dist: dist.max_of(norm.lower(norm.term(diff))),
                    gaps,
                }
            };
            if may_enter(out, far_cell.dist, tree.min_id, far) {
                stack.push(far_cell);
            }
            node = near;
            // The near side keeps the cell's bound; on a tie it may still be passed by index.
            if !may_enter(out, dist, tree.min_id, node) {
                break;
            }
        }
    }
}

/// Points of a leaf scanned at once by the compact search: one mask of 32 bits, and a single
/// query's first block sorted whole. Blocks of 16 took 1.13x the time on the 1M cube at k = 10
/// (the half of a first leaf that is not sorted whole enters by insertions; docs/speed-log.md,
/// round 9).
const SCAN: usize = 32;

/// The lowest `n` bits (`n` ≤ 32).
#[inline(always)]
fn low_bits(n: usize) -> u32 {
    (u64::MAX >> (64 - n)) as u32
}

/// The tree's arrays a compact search reads.
pub(crate) struct DescentView<'a, T> {
    pub descent: &'a Descent<T>,
    pub coords: &'a [T],
    pub ids: &'a [u32],
    pub depth: usize,
}

/// A pending cell of the compact search: its step, its lower bound and its gaps (those above
/// the dimension stay zero).
#[derive(Clone, Copy)]
struct Pending<T> {
    step: u32,
    dist: T,
    gaps: [T; 3],
}

/// Pending cells fit the inline array when the tree is at most this deep (a depth-first
/// search holds at most one pending cell per level, plus the root).
const INLINE_DEPTH: usize = 38;

/// [`search`] over the compact descent array (`src/tree/node.rs`, [`Descent`]) of a tree of
/// dimension `D` ≤ 3: the same cells visited in the same order and pruned by the same exact
/// bounds, so the same result.
pub(crate) fn search_compact<T: Scalar, C: ResultSet<T>>(
    tree: &DescentView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    out: &mut C,
) {
    let empty = Pending {
        step: 0,
        dist: T::ZERO,
        gaps: [T::ZERO; 3],
    };
    if tree.depth < INLINE_DEPTH {
        let mut stack = [empty; INLINE_DEPTH + 2];
        compact_d(tree, q, exclude, out, &mut stack);
    } else {
        let mut stack = vec![empty; tree.depth + 2];
        compact_d(tree, q, exclude, out, &mut stack);
    }
}

#[inline(always)]
fn compact_d<T: Scalar, C: ResultSet<T>>(
    tree: &DescentView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    out: &mut C,
    stack: &mut [Pending<T>],
) {
    // The leaf kernel's form is chosen once, at compile time inside the search: a test of it
    // per leaf cost single queries 1.4 % of their instructions (callgrind, torus-77k, k = 10).
    // `f64` in 3-D takes four AVX lanes where the processor has them (`tree/kernel.rs`).
    let avx = T::TYPE == ScalarType::F64 && q.len() == 3 && crate::simd::avx();
    match (q.len(), crate::simd::sse()) {
        (3, true) if avx => compact_search::<T, C, 3, true, true>(tree, q, exclude, out, stack),
        (3, true) => compact_search::<T, C, 3, true, false>(tree, q, exclude, out, stack),
        (2, true) => compact_search::<T, C, 2, true, false>(tree, q, exclude, out, stack),
        (_, true) => compact_search::<T, C, 1, true, false>(tree, q, exclude, out, stack),
        (3, false) => compact_search::<T, C, 3, false, false>(tree, q, exclude, out, stack),
        (2, false) => compact_search::<T, C, 2, false, false>(tree, q, exclude, out, stack),
        (_, false) => compact_search::<T, C, 1, false, false>(tree, q, exclude, out, stack),
    }
}

/// `SSE`: the leaf masks by SSE compares; `AVX` (`f64`, 3-D, a processor with AVX): the leaf
/// distances and masks in four AVX lanes ([`sq_dists_below`]).
fn compact_search<T: Scalar, C: ResultSet<T>, const D: usize, const SSE: bool, const AVX: bool>(
    tree: &DescentView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    out: &mut C,
    stack: &mut [Pending<T>],
) {
    let excluded = exclude.unwrap_or(u32::MAX);
    let steps = &tree.descent.steps[..];
    let min_id = &tree.descent.min_id[..];
    let mut qa = [T::ZERO; 4];
    qa[..D].copy_from_slice(&q[..D]);
    stack[0] = Pending {
        step: 0,
        dist: T::ZERO,
        gaps: [T::ZERO; 3],
    };
    let mut len = 1usize;
    while len > 0 {
        len -= 1;
        let Pending {
            step: mut node,
            dist,
            gaps,
        } = stack[len];
        if !may_enter(out, dist, min_id, node) {
            continue;
        }
        loop {
            let s = steps[node as usize];
            let sd = (s.link & 3) as usize;
            if sd == DESCENT_LEAF as usize {
                scan_leaf::<T, C, D, SSE, AVX>(tree, &qa, s.leaf_range(), excluded, out);
                break;
            }
            let first = s.link >> 2;
            let diff = qa[sd] - s.split;
            // As in `search_d`: on a tie the right side first unless only ties at the bound
            // can still enter; then the side with the smaller index.
            let right_first = if diff == T::ZERO {
                !(dist == out.bound() && min_id[first as usize] < min_id[first as usize + 1])
            } else {
                diff > T::ZERO
            };
            let near = first + right_first as u32;
            let far = first + !right_first as u32;
            let mut g = gaps;
            g[sd] = diff;
            let mut fd = T::ZERO;
            for x in &g[..D] {
                fd = fd + *x * *x;
            }
            // Pushed unconditionally, kept only if it may enter (no branch on the test).
            stack[len] = Pending {
                step: far,
                dist: fd,
                gaps: g,
            };
            if may_enter(out, fd, min_id, far) {
                len += 1;
                // The far cell is visited after the near side's subtree: its first lines are
                // requested now (its step shares the near step's line, already read), so that
                // their misses overlap the near side's work. A leaf's indices too: on the 1M
                // cube k = 30 took 0.89-0.95x the time with them, k = 10 the same.
                let fs = steps[far as usize];
                if fs.link & 3 == DESCENT_LEAF {
                    let (a, b) = fs.leaf_range();
                    prefetch_range(&tree.coords[a * D..b * D]);
                    prefetch_range(&tree.ids[a..b]);
                } else {
                    let f = (fs.link >> 2) as usize;
                    prefetch_range(&steps[f..f + 1]);
                }
            }
            node = near;
            if !may_enter(out, dist, min_id, node) {
                break;
            }
        }
    }
}

/// Offers the points of the leaf at tree positions `a..b` to `out` (`qa`: the query, padded to
/// four coordinates; `SSE`, `AVX` as in [`compact_search`]).
#[inline(always)]
fn scan_leaf<T: Scalar, C: ResultSet<T>, const D: usize, const SSE: bool, const AVX: bool>(
    tree: &DescentView<'_, T>,
    qa: &[T; 4],
    (a, b): (usize, usize),
    excluded: u32,
    out: &mut C,
) {
    // The leaf's indices are another array: their lines are requested now, while the distances
    // are computed, instead of missing at the first offer (on the 1M cube the first index read
    // of a leaf held a fifth of the samples).
    prefetch_range(&tree.ids[a..b]);
    // The leaf's points and indices as slices: no bounds test per point.
    let points = &tree.coords[a * D..b * D];
    let ids = &tree.ids[a..b];
    // Blocks of up to `SCAN` points: every squared distance first (no branch, four points at a
    // time in vector arithmetic), the points within the bound as bits of a mask (vector
    // compares), then offers of those only, as one block (a single query's empty row sorts its
    // first block at once). The test per point was the search's most mispredicted branch
    // (README "Single queries, the floor, and copies of a point").
    for (points, ids) in points.chunks(SCAN * D).zip(ids.chunks(SCAN)) {
        let mut d = [T::ZERO; SCAN];
        let mask = sq_dists_below::<T, D, SCAN, SSE, AVX>(qa, points, &mut d, out.bound())
            & low_bits(ids.len());
        out.offer_block(ids, &d, mask, excluded);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::query::order::PackedKey;
    use crate::query::result_set::{KnnRow, RowKey, WithinRadius};
    use crate::query::{Neighbor, NeighborHeap};
    use crate::tree::node::{Descent, Step};
    use crate::tree::{BuildOptions, KdTree, PivotPolicy};

    /// Clouds with many ties: points on a coarse grid (queries on split values), copies of a
    /// few positions, and a sheared line (a deep tree for closest-to-middle).
    fn clouds(dim: usize) -> Vec<Vec<f32>> {
        let mut grid = Vec::new();
        for i in 0..700u32 {
            for j in 0..dim as u32 {
                grid.push(((i.wrapping_mul(2_654_435_761) >> (7 * j)) % 9) as f32 * 0.5);
            }
        }
        let mut copies = Vec::new();
        for i in 0..900u32 {
            for j in 0..dim as u32 {
                let c = if i % 2 == 0 {
                    (i / 2) % 3
                } else {
                    (i * 31 + j * 7) % 101
                };
                copies.push(c as f32 * 0.25);
            }
        }
        let mut line = Vec::new();
        for i in 0..600u32 {
            for j in 0..dim as u32 {
                line.push((1.5f32).powi((i % 40) as i32) * 1e-6 + (j * i) as f32);
            }
        }
        vec![grid, copies, line]
    }

    /// A single query's sorted row of packed keys `K` (its first leaf taken as one sorted
    /// block), as found by the compact descent.
    fn row_search<K: RowKey + PackedKey<f32>>(
        tree: &DescentView<'_, f32>,
        q: &[f32],
        exclude: Option<u32>,
        k: usize,
        r2: f32,
    ) -> Vec<Neighbor<f32>> {
        let mut keys = vec![K::default(); k];
        let mut row = KnnRow::new(&mut keys[..], r2);
        search_compact(tree, q, exclude, &mut row);
        row.held()
            .map(|e| {
                let (sq_dist, index) = e.pair();
                Neighbor { index, sq_dist }
            })
            .collect()
    }

    /// The compact descent gives what the preorder search gives, for every result set, on
    /// every pivot policy, at points of the cloud (ties everywhere) and between them.
    #[test]
    fn the_compact_descent_finds_what_the_preorder_search_finds() {
        for dim in 1..=3 {
            for coords in clouds(dim) {
                for pivot in PivotPolicy::ALL {
                    // both leaf sizes of the descent (`descent_bucket`), and an odd one
                    for (leaf_size, bucket) in [(1, 32), (5, 64), (12, 32), (12, 64), (5, 7)] {
                        let opts = BuildOptions {
                            pivot,
                            leaf_size,
                            threads: 1,
                            ..BuildOptions::default()
                        };
                        let tree = KdTree::from_flat(&coords, dim, &opts).unwrap();
                        let descent = Descent::new(&tree.nodes, &tree.min_id, dim, bucket)
                            .expect("dimension ≤ 3");
                        let compact = DescentView {
                            descent: &descent,
                            coords: &tree.coords,
                            ids: &tree.ids,
                            depth: tree.depth,
                        };
                        let n = coords.len() / dim;
                        for qi in (0..n).step_by(7) {
                            let mut q: Vec<f32> = coords[qi * dim..(qi + 1) * dim].to_vec();
                            if qi % 3 == 1 {
                                q[0] += 0.125;
                            }
                            let exclude = (qi % 2 == 0).then_some(qi as u32);
                            for (k, r2) in [(1, f32::INFINITY), (7, f32::INFINITY), (40, 0.3)] {
                                let (mut a, mut b) = (Vec::new(), Vec::new());
                                let mut ha = NeighborHeap::new(&mut a, k, r2);
                                search(&tree.view(), &q, exclude, &mut ha);
                                ha.finish();
                                let mut hb = NeighborHeap::new(&mut b, k, r2);
                                search_compact(&compact, &q, exclude, &mut hb);
                                hb.finish();
                                assert_eq!(
                                    a, b,
                                    "dim {dim} {pivot:?} leaf {leaf_size}/{bucket} q {qi} k {k}"
                                );
                                // The single queries' sorted rows of packed keys keep
                                // the same: `f32`'s `u64`, and `f64`'s `u128` (its first
                                // block sorted by rounded distances, then exactly).
                                let c = row_search::<u64>(&compact, &q, exclude, k, r2);
                                assert_eq!(a, c, "row: dim {dim} {pivot:?} q {qi} k {k}");
                                let c = row_search::<u128>(&compact, &q, exclude, k, r2);
                                assert_eq!(a, c, "u128 row: dim {dim} {pivot:?} q {qi} k {k}");
                            }
                            let (mut a, mut b): (Vec<Neighbor<f32>>, Vec<Neighbor<f32>>) =
                                (Vec::new(), Vec::new());
                            search(
                                &tree.view(),
                                &q,
                                exclude,
                                &mut WithinRadius {
                                    out: &mut a,
                                    sq_radius: 0.6,
                                },
                            );
                            search_compact(
                                &compact,
                                &q,
                                exclude,
                                &mut WithinRadius {
                                    out: &mut b,
                                    sq_radius: 0.6,
                                },
                            );
                            a.sort_by(|x, y| x.cmp_by_distance(y));
                            b.sort_by(|x, y| x.cmp_by_distance(y));
                            assert_eq!(a, b, "radius: dim {dim} {pivot:?} leaf {leaf_size} q {qi}");
                        }
                    }
                }
            }
        }
    }

    /// Every point of the tree is in exactly one leaf of the descent, the leaves in tree
    /// order cover the points, and the smallest indices agree with the leaves'.
    #[test]
    fn the_descent_covers_every_point_once() {
        for coords in clouds(3) {
            let tree = KdTree::from_flat(&coords, 3, &BuildOptions::default()).unwrap();
            let d = tree.descent.as_ref().unwrap();
            let mut leaves: Vec<(usize, usize)> = d
                .steps
                .iter()
                .filter(|s| s.link & 3 == DESCENT_LEAF)
                .map(Step::leaf_range)
                .collect();
            leaves.sort();
            let mut next = 0;
            for (a, b) in leaves {
                assert_eq!(a, next);
                assert!(b > a);
                next = b;
            }
            assert_eq!(next, tree.len());
            for (s, m) in d.steps.iter().zip(&d.min_id) {
                if s.link & 3 == DESCENT_LEAF {
                    let (a, b) = s.leaf_range();
                    assert_eq!(*m, *tree.ids[a..b].iter().min().unwrap());
                }
            }
        }
    }
}
