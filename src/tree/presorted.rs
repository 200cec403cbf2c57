//! The presorted build (thesis Section 3.3.3, Algorithm 6): one list of all points per
//! dimension, each sorted once by the composite order starting at that dimension. A node's
//! points occupy the same range of every list; the split's dimension list is already split at
//! the pivot's rank, and every other list is split by a stable partition, which keeps both
//! halves sorted. Spreads and ranks come from the ends of the sorted lists and binary
//! searches instead of scans. Serial; gives the same tree as every selection build.

use super::build::{BuildInput, Subtree};
use super::layout::Layout;
use super::node::Node;
use super::split::{choose_split, resolve_below, Below, NodeFacts, Plan};
use crate::scalar::Scalar;

/// Facts about a node read from the presorted lists.
struct SortedFacts<'a, L: Layout<T>, T: Scalar> {
    layout: &'a L,
    /// The items in slot order.
    by_slot: &'a [L::Item],
    lists: &'a [Vec<u32>],
    start: usize,
    end: usize,
}

impl<L: Layout<T>, T: Scalar> SortedFacts<'_, L, T> {
    #[inline]
    fn coord(&self, list: usize, pos: usize) -> T {
        self.layout
            .coord(&self.by_slot[self.lists[list][pos] as usize], list)
    }

    /// Number of the node's points with coordinate `< value` in `j` (`<= value` if
    /// `or_equal`), by a binary search.
    fn count_below(&self, j: usize, value: T, or_equal: bool) -> usize {
        let list = &self.lists[j][self.start..self.end];
        list.partition_point(|&s| {
            let c = self.layout.coord(&self.by_slot[s as usize], j);
            c < value || (or_equal && c == value)
        })
    }
}

impl<L: Layout<T>, T: Scalar> NodeFacts<T> for SortedFacts<'_, L, T> {
    fn len(&self) -> usize {
        self.end - self.start
    }

    fn range(&self, j: usize) -> (T, T) {
        (self.coord(j, self.start), self.coord(j, self.end - 1))
    }

    fn closest(&self, j: usize, target: T) -> T {
        let r = self.start + self.count_below(j, target, false);
        match (r > self.start, r < self.end) {
            (true, true) => {
                let (below, above) = (self.coord(j, r - 1), self.coord(j, r));
                if target - below <= above - target {
                    below
                } else {
                    above
                }
            }
            (true, false) => self.coord(j, r - 1),
            _ => self.coord(j, r),
        }
    }
}

/// Builds the whole tree over `items` (given in slot order, rearranged into tree order).
pub(crate) fn build_presorted<T: Scalar, L: Layout<T>>(
    input: &BuildInput<L>,
    items: &mut [L::Item],
) -> Subtree<T> {
    let layout = &input.layout;
    let (n, d) = (items.len(), layout.dim());
    let by_slot: &[L::Item] = items;
    let mut lists: Vec<Vec<u32>> = (0..d)
        .map(|j| {
            let mut l: Vec<u32> = (0..n as u32).collect();
            l.sort_unstable_by(|&a, &b| {
                if layout.lex_less(&by_slot[a as usize], &by_slot[b as usize], j) {
                    std::cmp::Ordering::Less
                } else {
                    std::cmp::Ordering::Greater
                }
            });
            l
        })
        .collect();
    let mut in_left = vec![false; n];
    let mut scratch: Vec<u32> = Vec::with_capacity(n);
    let leaf_size = input.options.leaf_size;
    let mut nodes: Vec<Node<T>> = Vec::new();
    let mut max_depth = 0;
    // (start, end, depth, parent waiting for its right child)
    let mut stack = vec![(0usize, n, 0usize, None::<usize>)];
    while let Some((start, end, depth, parent)) = stack.pop() {
        let idx = nodes.len();
        if let Some(p) = parent {
            nodes[p].a = idx as u32;
        }
        max_depth = max_depth.max(depth);
        if end - start <= leaf_size {
            lists[0][start..end].sort_unstable();
            nodes.push(Node::leaf(start, end));
            continue;
        }
        let facts = SortedFacts {
            layout,
            by_slot,
            lists: &lists,
            start,
            end,
        };
        let plan = choose_split(input.options.pivot, depth, input.guard, d, &facts);
        let (j, rank, value) = match plan {
            Plan::Rank(split) | Plan::Coincident(split) => (split.dim, split.rank, None),
            Plan::Below { dim, value } => {
                match resolve_below(facts.count_below(dim, value, false), end - start) {
                    Below::Rank(rank) => (dim, rank, Some(value)),
                    // The copies of the smallest coordinate go left; the split value (read
                    // below) is the next coordinate, where the right side starts.
                    Below::SlideUp => (dim, facts.count_below(dim, value, true), None),
                    Below::Clamp(rank) => (dim, rank, None),
                }
            }
        };
        let mid = start + rank;
        let value = value.unwrap_or_else(|| facts.coord(j, mid));
        for &s in &lists[j][start..mid] {
            in_left[s as usize] = true;
        }
        for (i, list) in lists.iter_mut().enumerate() {
            if i != j {
                stable_partition(&mut list[start..end], &in_left, &mut scratch);
            }
        }
        for &s in &lists[j][start..mid] {
            in_left[s as usize] = false;
        }
        nodes.push(Node::internal(j, value, 0, end));
        stack.push((mid, end, depth + 1, Some(idx)));
        stack.push((start, mid, depth + 1, None));
    }
    let in_tree_order: Vec<L::Item> = lists[0].iter().map(|&s| by_slot[s as usize]).collect();
    items.copy_from_slice(&in_tree_order);
    Subtree {
        nodes,
        depth: max_depth,
    }
}

/// Moves the slots marked in `in_left` to the front, keeping the order within both parts
/// (the Partition procedure of Algorithm 6).
fn stable_partition(list: &mut [u32], in_left: &[bool], scratch: &mut Vec<u32>) {
    scratch.clear();
    let mut k = 0;
    for i in 0..list.len() {
        let s = list[i];
        if in_left[s as usize] {
            list[k] = s;
            k += 1;
        } else {
            scratch.push(s);
        }
    }
    list[k..].copy_from_slice(scratch);
}
