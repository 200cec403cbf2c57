//! The box query's descent on the k-d tree (thesis Section 3.2.3, Algorithms 2 and 3): the
//! descent keeps the cell of each node (the box its splits bound, starting from all of space);
//! a subtree whose cell lies inside the query box is reported whole (its points are one
//! contiguous range in tree order), a subtree whose cell misses the box is skipped, and the
//! points of the leaves in between are tested one by one. The queries themselves, their checks
//! and their rows are the index's (`src/index/in_box.rs`).

use super::KdTree;
use crate::query::in_box::in_closed_box;
use crate::scalar::Scalar;

impl<T: Scalar> KdTree<T> {
    /// Appends the caller's indices of the points in the box to `out`, unsorted. `cells` is
    /// scratch space: the pending subtrees' cells, `2 · dim` values each.
    pub(crate) fn collect_in_box(
        &self,
        min: &[T],
        max: &[T],
        cells: &mut Vec<T>,
        out: &mut Vec<u32>,
    ) {
        let d = self.dim;
        // pending subtrees: (node, first tree position); their cells on `cells`, lo then hi
        let mut stack: Vec<(u32, u32)> = vec![(0, 0)];
        cells.clear();
        cells.extend(std::iter::repeat_n(T::from_f64(f64::NEG_INFINITY), d));
        cells.extend(std::iter::repeat_n(T::INFINITY, d));
        while let Some((node, start)) = stack.pop() {
            let at = cells.len() - 2 * d;
            let n = self.nodes[node as usize];
            let (lo, hi) = cells[at..].split_at(d);
            if in_closed_box(lo, min, max) && in_closed_box(hi, min, max) {
                // the whole cell is inside: every point of the subtree (Algorithm 3's report)
                out.extend_from_slice(&self.ids[start as usize..n.b as usize]);
                cells.truncate(at);
                continue;
            }
            if n.is_leaf() {
                for i in n.a as usize..n.b as usize {
                    if in_closed_box(self.point_at(i), min, max) {
                        out.push(self.ids[i]);
                    }
                }
                cells.truncate(at);
                continue;
            }
            // left subtree: coordinates ≤ split; right subtree: coordinates ≥ split
            let (j, s) = (n.dim as usize, n.split);
            let (go_left, go_right) = (min[j] <= s, max[j] >= s);
            // the right child reuses the slot at `at`, the left one a copy above it (popped
            // first)
            match (go_left, go_right) {
                (true, true) => {
                    cells.extend_from_within(at..at + 2 * d);
                    cells[at + j] = cells[at + j].max_of(s);
                    stack.push((n.a, self.nodes[node as usize + 1].b));
                    let left = at + 2 * d;
                    cells[left + d + j] = cells[left + d + j].min_of(s);
                    stack.push((node + 1, start));
                }
                (false, true) => {
                    cells[at + j] = cells[at + j].max_of(s);
                    stack.push((n.a, self.nodes[node as usize + 1].b));
                }
                (true, false) => {
                    cells[at + d + j] = cells[at + d + j].min_of(s);
                    stack.push((node + 1, start));
                }
                (false, false) => cells.truncate(at),
            }
        }
    }
}
