//! Building the node array by selection (thesis Algorithm 4 with the median algorithms of
//! Section 3.3.4 / Chapter 6): at every node the policy picks a dimension and a rank, and a
//! selection algorithm partitions the node's points around the point of that rank in the
//! composite order. Iterative (an explicit work stack), so trees thousands of levels deep
//! (closest-to-middle on surfaces, thesis Fig. 8.7) cannot overflow the call stack. Above a
//! size threshold the two children of a well-balanced split are built in parallel and
//! concatenated, which gives exactly the serial tree.

use super::node::Node;
use super::options::{BuildOptions, MedianAlgorithm};
use super::split::{choose_split, lex_less, NodeFacts, Split};
use crate::scalar::Scalar;

/// Children smaller than this are built serially.
const PARALLEL_MIN: usize = 16 * 1024;

/// The points and options a build reads.
pub(crate) struct BuildInput<'a, T> {
    /// Packed coordinates of the points, by slot.
    pub coords: &'a [T],
    /// Dimension.
    pub dim: usize,
    /// Options.
    pub options: BuildOptions,
}

/// Nodes of a subtree (child links relative to its first node) and its depth.
pub(crate) struct Subtree<T> {
    pub nodes: Vec<Node<T>>,
    pub depth: usize,
}

/// Facts about the slots of one node, found by scanning them.
struct ScanFacts<'a, T> {
    coords: &'a [T],
    dim: usize,
    slots: &'a [u32],
}

impl<T: Scalar> ScanFacts<'_, T> {
    #[inline]
    fn coord(&self, slot: u32, j: usize) -> T {
        self.coords[slot as usize * self.dim + j]
    }
}

impl<T: Scalar> NodeFacts<T> for ScanFacts<'_, T> {
    fn len(&self) -> usize {
        self.slots.len()
    }

    fn range(&self, j: usize) -> (T, T) {
        let first = self.coord(self.slots[0], j);
        self.slots.iter().fold((first, first), |(lo, hi), &s| {
            let c = self.coord(s, j);
            (lo.min_of(c), hi.max_of(c))
        })
    }

    fn count_below(&self, j: usize, value: T) -> usize {
        self.slots
            .iter()
            .filter(|&&s| self.coord(s, j) < value)
            .count()
    }

    fn closest(&self, j: usize, target: T) -> T {
        let dist = |c: T| if c > target { c - target } else { target - c };
        let first = self.coord(self.slots[0], j);
        self.slots.iter().fold(first, |best, &s| {
            let c = self.coord(s, j);
            let (dc, db) = (dist(c), dist(best));
            if dc < db || (dc == db && c < best) {
                c
            } else {
                best
            }
        })
    }
}

/// Splits the node holding `slots`: decides the split and partitions `slots` so that the first
/// `rank` are the left child. Returns the split and its coordinate value.
fn split_node<T: Scalar>(input: &BuildInput<'_, T>, slots: &mut [u32], depth: usize) -> (Split, T) {
    let facts = ScanFacts {
        coords: input.coords,
        dim: input.dim,
        slots,
    };
    let split = choose_split(input.options.pivot, depth, input.dim, &facts);
    let (coords, d, j) = (input.coords, input.dim, split.dim);
    let mut less = |a: &u32, b: &u32| lex_less(coords, d, *a, *b, j);
    select(slots, split.rank, &mut less, input.options.median);
    let value = coords[slots[split.rank] as usize * d + j];
    (split, value)
}

/// Puts the element of rank `k` at `k`, smaller before, larger after.
fn select<F: FnMut(&u32, &u32) -> bool>(
    v: &mut [u32],
    k: usize,
    less: &mut F,
    algo: MedianAlgorithm,
) {
    let mut cmp = |a: &u32, b: &u32| {
        if less(a, b) {
            std::cmp::Ordering::Less
        } else if less(b, a) {
            std::cmp::Ordering::Greater
        } else {
            std::cmp::Ordering::Equal
        }
    };
    match algo {
        MedianAlgorithm::Sort | MedianAlgorithm::Presorted => v.sort_unstable_by(&mut cmp),
        _ => {
            v.select_nth_unstable_by(k, &mut cmp);
        }
    }
}

/// Builds the subtree over `slots` (tree positions `offset..offset + slots.len()`) at `depth`,
/// serially, with an explicit stack.
pub(crate) fn build_serial<T: Scalar>(
    input: &BuildInput<'_, T>,
    slots: &mut [u32],
    offset: usize,
    depth: usize,
) -> Subtree<T> {
    struct Task {
        start: usize,
        end: usize,
        depth: usize,
        parent: Option<usize>,
    }
    let leaf_size = input.options.leaf_size;
    let mut nodes: Vec<Node<T>> = Vec::with_capacity(2 * slots.len() / leaf_size.max(1) + 1);
    let mut max_depth = depth;
    let mut stack = vec![Task {
        start: 0,
        end: slots.len(),
        depth,
        parent: None,
    }];
    while let Some(t) = stack.pop() {
        let idx = nodes.len();
        if let Some(p) = t.parent {
            nodes[p].a = idx as u32;
        }
        max_depth = max_depth.max(t.depth);
        let node_slots = &mut slots[t.start..t.end];
        if node_slots.len() <= leaf_size {
            node_slots.sort_unstable();
            nodes.push(Node::leaf(offset + t.start, offset + t.end));
            continue;
        }
        let (split, value) = split_node(input, node_slots, t.depth);
        let mid = t.start + split.rank;
        nodes.push(Node::internal(split.dim, value, 0, offset + t.end));
        stack.push(Task {
            start: mid,
            end: t.end,
            depth: t.depth + 1,
            parent: Some(idx),
        });
        stack.push(Task {
            start: t.start,
            end: mid,
            depth: t.depth + 1,
            parent: None,
        });
    }
    Subtree {
        nodes,
        depth: max_depth,
    }
}

/// Builds the subtree over `slots` like [`build_serial`], building the children of balanced
/// splits of large nodes in parallel (rayon) and concatenating them in preorder.
pub(crate) fn build_parallel<T: Scalar>(
    input: &BuildInput<'_, T>,
    slots: &mut [u32],
    offset: usize,
    depth: usize,
) -> Subtree<T> {
    let n = slots.len();
    if n < 2 * PARALLEL_MIN || n <= input.options.leaf_size {
        return build_serial(input, slots, offset, depth);
    }
    let (split, value) = split_node(input, slots, depth);
    let rank = split.rank;
    let (left, right) = slots.split_at_mut(rank);
    let (l, r) = if rank >= PARALLEL_MIN && n - rank >= PARALLEL_MIN {
        rayon::join(
            || build_parallel(input, left, offset, depth + 1),
            || build_parallel(input, right, offset + rank, depth + 1),
        )
    } else {
        (
            build_serial(input, left, offset, depth + 1),
            build_serial(input, right, offset + rank, depth + 1),
        )
    };
    join_subtrees(Node::internal(split.dim, value, 0, offset + n), l, r)
}

/// `root` followed by the nodes of `left` and `right`, child links rebased.
pub(crate) fn join_subtrees<T: Scalar>(
    mut root: Node<T>,
    left: Subtree<T>,
    right: Subtree<T>,
) -> Subtree<T> {
    let right_start = 1 + left.nodes.len();
    root.a = right_start as u32;
    let mut nodes = Vec::with_capacity(right_start + right.nodes.len());
    nodes.push(root);
    for (base, part) in [(1, left.nodes), (right_start, right.nodes)] {
        nodes.extend(part.into_iter().map(|mut node| {
            if !node.is_leaf() {
                node.a += base as u32;
            }
            node
        }));
    }
    Subtree {
        nodes,
        depth: left.depth.max(right.depth),
    }
}
