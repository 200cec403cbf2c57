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
//! single gap, a weaker bound with the same guarantee.)
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

use super::node::Node;
use crate::query::result_set::ResultSet;
use crate::scalar::Scalar;

/// The tree's arrays a search reads.
pub(crate) struct TreeView<'a, T> {
    pub nodes: &'a [Node<T>],
    pub coords: &'a [T],
    pub ids: &'a [u32],
    /// Smallest caller index of every node's subtree (`min_ids`).
    pub min_id: &'a [u32],
    pub dim: usize,
}

/// The smallest caller index of every node's subtree, bottom-up over the preorder node array
/// (children follow their parent).
pub(crate) fn min_ids<T: Copy + Default>(nodes: &[Node<T>], ids: &[u32]) -> Vec<u32> {
    let mut m = vec![u32::MAX; nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        m[i] = if n.is_leaf() {
            ids[n.a as usize..n.b as usize]
                .iter()
                .copied()
                .min()
                .unwrap_or(u32::MAX)
        } else {
            m[i + 1].min(m[n.a as usize])
        };
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

/// Squared distance from `q` to the point at tree position `i`; `D > 0` fixes the dimension at
/// compile time (the 3-D hot path), `D == 0` reads it from `dim`.
#[inline(always)]
fn sq_dist_at<T: Scalar, const D: usize>(q: &[T], coords: &[T], i: usize, dim: usize) -> T {
    let d = if D > 0 { D } else { dim };
    let p = &coords[i * d..i * d + d];
    let mut s = T::ZERO;
    for j in 0..d {
        let t = q[j] - p[j];
        s = s + t * t;
    }
    s
}

/// Whether a cell with lower bound `dist` and smallest caller index `min_id` may still hold a
/// candidate that enters `out`: `(dist, min_id)` precedes the worst admissible key. The index
/// is read only on a tie in distance.
#[inline(always)]
fn may_enter<T: Scalar, C: ResultSet<T>>(out: &C, dist: T, min_id: &[u32], node: u32) -> bool {
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
    match tree.dim {
        3 => search_d::<T, C, 3, 3>(tree, q, exclude, out),
        2 => search_d::<T, C, 2, 2>(tree, q, exclude, out),
        1 => search_d::<T, C, 1, 1>(tree, q, exclude, out),
        _ => search_d::<T, C, 0, 0>(tree, q, exclude, out),
    }
}

/// `D` the dimension (0: read from the tree), `G` the gaps kept per cell (`D`, or 0 for the
/// largest-gap bound of any dimension).
fn search_d<T: Scalar, C: ResultSet<T>, const D: usize, const G: usize>(
    tree: &TreeView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
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
                    let d2 = sq_dist_at::<T, D>(q, tree.coords, i, tree.dim);
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
                    s = s + x * x;
                }
                Cell {
                    node: far,
                    dist: s,
                    gaps: g,
                }
            } else {
                Cell {
                    node: far,
                    dist: dist.max_of(diff * diff),
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
