//! Exact search on the k-d tree (thesis Section 5.2, Algorithm 9): descend to the leaf of the
//! query, then visit the far side of every split whose cell may still hold a point within the
//! current bound (the radius, or the k-th best distance once k candidates are held). Cells are
//! kept on an explicit stack with a lower bound of their squared distance to the query, so
//! deep, unbalanced trees cannot overflow the call stack and nothing is allocated per query.
//! A cell is skipped only if its bound is *strictly* larger, so a point at exactly the k-th
//! distance with a smaller index is still found: ties are resolved by index.

use super::node::Node;
use crate::query::result_set::ResultSet;
use crate::scalar::Scalar;

/// The tree's arrays a search reads.
pub(crate) struct TreeView<'a, T> {
    pub nodes: &'a [Node<T>],
    pub coords: &'a [T],
    pub ids: &'a [u32],
    pub dim: usize,
}

/// Pending cells: a fixed array on the call stack, spilling to the heap only for trees deeper
/// than it (unbalanced closest-to-middle trees).
struct CellStack<T> {
    inline: [(u32, T); 64],
    len: usize,
    spill: Vec<(u32, T)>,
}

impl<T: Scalar> CellStack<T> {
    #[inline]
    fn new() -> Self {
        Self {
            inline: [(0, T::ZERO); 64],
            len: 0,
            spill: Vec::new(),
        }
    }
    #[inline]
    fn push(&mut self, cell: (u32, T)) {
        if self.len < self.inline.len() {
            self.inline[self.len] = cell;
            self.len += 1;
        } else {
            self.spill.push(cell);
        }
    }
    #[inline]
    fn pop(&mut self) -> Option<(u32, T)> {
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

/// Runs the search, offering every point of every visited leaf except `exclude` to the result
/// set `out` (`src/query/result_set.rs`), which decides what it keeps.
pub(crate) fn search<T: Scalar, C: ResultSet<T>>(
    tree: &TreeView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    out: &mut C,
) {
    match tree.dim {
        3 => search_d::<T, C, 3>(tree, q, exclude, out),
        2 => search_d::<T, C, 2>(tree, q, exclude, out),
        1 => search_d::<T, C, 1>(tree, q, exclude, out),
        _ => search_d::<T, C, 0>(tree, q, exclude, out),
    }
}

fn search_d<T: Scalar, C: ResultSet<T>, const D: usize>(
    tree: &TreeView<'_, T>,
    q: &[T],
    exclude: Option<u32>,
    out: &mut C,
) {
    let excluded = exclude.unwrap_or(u32::MAX);
    let mut stack = CellStack::new();
    stack.push((0, T::ZERO));
    while let Some((mut node, cell_dist)) = stack.pop() {
        if cell_dist > out.bound() {
            continue;
        }
        loop {
            let n = &tree.nodes[node as usize];
            if n.is_leaf() {
                for i in n.a as usize..n.b as usize {
                    let id = tree.ids[i];
                    let d2 = sq_dist_at::<T, D>(q, tree.coords, i, tree.dim);
                    // Caller indices are below u32::MAX, so MAX excludes nothing.
                    if id != excluded {
                        out.offer(id, d2);
                    }
                }
                break;
            }
            let diff = q[n.dim as usize] - n.split;
            let (near, far) = if diff < T::ZERO {
                (node + 1, n.a)
            } else {
                (n.a, node + 1)
            };
            let far_dist = cell_dist.max_of(diff * diff);
            if far_dist <= out.bound() {
                stack.push((far, far_dist));
            }
            node = near;
        }
    }
}
