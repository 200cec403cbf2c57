//! Building the node array by selection (thesis Algorithm 4 with the median algorithms of
//! Section 3.3.4 / Chapter 6): at every node the policy picks a dimension and a rank (or a
//! threshold), and a selection algorithm (or one partition pass) splits the node's points in
//! the composite order. Iterative (an explicit work stack), so trees thousands of levels deep
//! (closest-to-middle on surfaces, thesis Fig. 8.7) cannot overflow the call stack. Above a
//! size threshold the two children of a well-balanced split are built in parallel and
//! concatenated, which gives exactly the serial tree.

use super::layout::Layout;
use super::node::Node;
use super::options::{BuildOptions, MedianAlgorithm};
use super::split::{choose_split, resolve_below, Below, NodeFacts, Plan, Split};
use crate::scalar::Scalar;
use crate::select::{select_nth, SelectAlgorithm};
use rayon::prelude::*;

/// Children smaller than this are built serially.
const PARALLEL_MIN: usize = 16 * 1024;

/// The layout and options a build reads.
pub(crate) struct BuildInput<L> {
    pub layout: L,
    pub options: BuildOptions,
    /// The depth from which every node splits at the median
    /// ([`super::options::max_unbalanced_depth`] of the points built over).
    pub guard: usize,
}

/// Nodes of a subtree (child links relative to its first node) and its depth.
pub(crate) struct Subtree<T> {
    pub nodes: Vec<Node<T>>,
    pub depth: usize,
}

/// Most dimensions whose ranges one pass over a node's items finds together.
const MAX_D: usize = 8;

/// Smallest and largest coordinate of the first `d` ≤ [`MAX_D`] dimensions.
#[derive(Clone, Copy)]
struct Ranges<T> {
    lo: [T; MAX_D],
    hi: [T; MAX_D],
}

impl<T: Scalar> Ranges<T> {
    /// The ranges of both (`self`'s values kept on ties, as a scan keeps the first).
    fn merge(mut self, other: Self, d: usize) -> Self {
        for j in 0..d {
            self.lo[j] = self.lo[j].min_of(other.lo[j]);
            self.hi[j] = self.hi[j].max_of(other.hi[j]);
        }
        self
    }

    /// The dimension of largest spread (the lowest on a tie) and its range.
    fn widest(&self, d: usize) -> (usize, T, T) {
        let mut best = 0;
        for j in 1..d {
            if self.hi[j] - self.lo[j] > self.hi[best] - self.lo[best] {
                best = j;
            }
        }
        (best, self.lo[best], self.hi[best])
    }
}

/// Of two coordinate values, the one closer to `target`, the lower on a tie, `a` if equal.
#[inline]
fn closer<T: Scalar>(a: T, b: T, target: T) -> T {
    let dist = |c: T| if c > target { c - target } else { target - c };
    let (da, db) = (dist(a), dist(b));
    if db < da || (db == da && b < a) {
        b
    } else {
        a
    }
}

/// Facts about the items of one node, found by scanning them.
struct ScanFacts<'a, L: Layout<T>, T: Scalar> {
    layout: &'a L,
    items: &'a [L::Item],
}

impl<L: Layout<T>, T: Scalar> ScanFacts<'_, L, T> {
    /// The ranges of the first `d` ≤ [`MAX_D`] dimensions, in one pass over the items.
    fn ranges(&self, d: usize) -> Ranges<T> {
        let mut r = Ranges {
            lo: [T::ZERO; MAX_D],
            hi: [T::ZERO; MAX_D],
        };
        for j in 0..d {
            r.lo[j] = self.layout.coord(&self.items[0], j);
            r.hi[j] = r.lo[j];
        }
        for it in self.items {
            for j in 0..d {
                let c = self.layout.coord(it, j);
                r.lo[j] = r.lo[j].min_of(c);
                r.hi[j] = r.hi[j].max_of(c);
            }
        }
        r
    }
}

impl<L: Layout<T>, T: Scalar> NodeFacts<T> for ScanFacts<'_, L, T> {
    fn len(&self) -> usize {
        self.items.len()
    }

    fn range(&self, j: usize) -> (T, T) {
        let first = self.layout.coord(&self.items[0], j);
        self.items.iter().fold((first, first), |(lo, hi), it| {
            let c = self.layout.coord(it, j);
            (lo.min_of(c), hi.max_of(c))
        })
    }

    fn widest(&self, d: usize) -> (usize, T, T) {
        if d > MAX_D {
            return (0..d).map(|j| (j, self.range(j))).fold(
                (0, T::ZERO, T::ZERO),
                |best, (j, (l, h))| {
                    if j == 0 || h - l > best.2 - best.1 {
                        (j, l, h)
                    } else {
                        best
                    }
                },
            );
        }
        self.ranges(d).widest(d)
    }

    fn closest(&self, j: usize, target: T) -> T {
        let first = self.layout.coord(&self.items[0], j);
        self.items.iter().fold(first, |best, it| {
            closer(best, self.layout.coord(it, j), target)
        })
    }
}

/// Facts about the items of a large node (the root's millions of points, which the build's
/// other threads would wait for), scanned in parallel pieces and merged in order: the values
/// [`ScanFacts`] finds, as minima, maxima and the closest value keep the first of equals
/// either way.
struct ParScanFacts<'a, L: Layout<T>, T: Scalar> {
    layout: &'a L,
    items: &'a [L::Item],
}

impl<'a, L: Layout<T>, T: Scalar> ParScanFacts<'a, L, T> {
    /// The facts of each piece, merged in item order.
    fn merged<R: Send>(
        &self,
        of: impl Fn(ScanFacts<'_, L, T>) -> R + Sync,
        merge: impl Fn(R, R) -> R + Sync + Send,
    ) -> R {
        let layout = self.layout;
        self.items
            .par_chunks(PARALLEL_MIN)
            .map(|items| of(ScanFacts { layout, items }))
            .reduce_with(merge)
            .expect("a node holds at least two items")
    }
}

impl<L: Layout<T>, T: Scalar> NodeFacts<T> for ParScanFacts<'_, L, T> {
    fn len(&self) -> usize {
        self.items.len()
    }

    fn range(&self, j: usize) -> (T, T) {
        self.merged(|f| f.range(j), |a, b| (a.0.min_of(b.0), a.1.max_of(b.1)))
    }

    fn widest(&self, d: usize) -> (usize, T, T) {
        if d > MAX_D {
            let whole = ScanFacts {
                layout: self.layout,
                items: self.items,
            };
            return whole.widest(d);
        }
        self.merged(|f| f.ranges(d), |a, b| a.merge(b, d)).widest(d)
    }

    fn closest(&self, j: usize, target: T) -> T {
        self.merged(|f| f.closest(j, target), |a, b| closer(a, b, target))
    }
}

/// How [`split_node`] scans a node's items: on this thread, or in parallel pieces (nodes of
/// [`build_parallel`], whose children wait for the split).
#[derive(Clone, Copy)]
enum Scan {
    Serial,
    Parallel,
}

/// Splits the node holding `items`: decides the split and moves the items so that the first
/// `rank` are the left child. Returns the split, its coordinate value and whether the node held
/// copies of one point (then its items are left sorted by slot; see [`split_copies`]).
fn split_node<T: Scalar, L: Layout<T>>(
    input: &BuildInput<L>,
    items: &mut [L::Item],
    depth: usize,
    scan: Scan,
) -> (Split, T, bool) {
    let layout = &input.layout;
    let (policy, guard, d) = (input.options.pivot, input.guard, layout.dim());
    let plan = match scan {
        Scan::Serial => choose_split(policy, depth, guard, d, &ScanFacts { layout, items }),
        Scan::Parallel => choose_split(policy, depth, guard, d, &ParScanFacts { layout, items }),
    };
    let (dim, rank) = match plan {
        Plan::Rank(split) => (split.dim, split.rank),
        Plan::Coincident(split) => {
            // Copies of one point (duplicate-heavy scans): sorted by index once, after which
            // every descendant is sorted too and splits without a selection or a scan.
            items.sort_unstable_by_key(|it| layout.slot(it));
            return (split, layout.coord(&items[split.rank], split.dim), true);
        }
        Plan::Below { dim, value } => {
            let below = partition_below(layout, items, dim, value, false);
            match resolve_below(below, items.len()) {
                Below::Rank(rank) => return (Split { dim, rank }, value, false),
                Below::SlideUp => {
                    // `value` is the smallest coordinate: its copies go left, and the split
                    // value is the smallest coordinate of the right side.
                    let rank = partition_below(layout, items, dim, value, true);
                    let next = items[rank..]
                        .iter()
                        .map(|it| layout.coord(it, dim))
                        .fold(layout.coord(&items[rank], dim), |m, c| m.min_of(c));
                    return (Split { dim, rank }, next, false);
                }
                Below::Clamp(rank) => (dim, rank),
            }
        }
    };
    select(layout, items, rank, dim, input.options.median);
    (Split { dim, rank }, layout.coord(&items[rank], dim), false)
}

/// The split of a node of copies of one point whose items are sorted by slot (a descendant of
/// a node [`split_node`] found coincident): what [`split_node`] would decide — halve by index
/// in dimension `depth mod d` — without scanning the items again.
fn split_copies<T: Scalar, L: Layout<T>>(
    layout: &L,
    items: &[L::Item],
    depth: usize,
) -> (Split, T) {
    let split = Split {
        dim: depth % layout.dim(),
        rank: items.len() / 2,
    };
    (split, layout.coord(&items[split.rank], split.dim))
}

/// Moves the items with coordinate `< value` in `dim` (`<= value` if `or_equal`) to the
/// front; returns their count.
///
/// Lomuto's scheme without branches on the data: every item is swapped with the first item not
/// yet known to be below, and the boundary advances by the comparison's outcome. Hoare's scheme
/// moves fewer items but mispredicts about every other comparison on the mixed nodes deep in
/// the tree: callgrind's branch simulation counted 0.6 million mispredictions for a 77k-point
/// build with it, 0.12 million with this loop.
fn partition_below<T: Scalar, L: Layout<T>>(
    layout: &L,
    items: &mut [L::Item],
    dim: usize,
    value: T,
    or_equal: bool,
) -> usize {
    let mut store = 0;
    for i in 0..items.len() {
        let x = items[i];
        let c = layout.coord(&x, dim);
        let below = c < value || (or_equal && c == value);
        items[i] = items[store];
        items[store] = x;
        store += usize::from(below);
    }
    store
}

/// Puts the item of rank `k` in the composite order of `dim` at `k`, smaller before, larger
/// after, with the chosen median algorithm.
fn select<T: Scalar, L: Layout<T>>(
    layout: &L,
    items: &mut [L::Item],
    k: usize,
    dim: usize,
    algo: MedianAlgorithm,
) {
    let mut less = |a: &L::Item, b: &L::Item| layout.lex_less(a, b, dim);
    let algo = match algo {
        MedianAlgorithm::Sort | MedianAlgorithm::Presorted => SelectAlgorithm::Sort,
        MedianAlgorithm::Quickselect => SelectAlgorithm::Quickselect,
        MedianAlgorithm::FloydRivest => SelectAlgorithm::FloydRivest,
        MedianAlgorithm::MedianOfMedians => SelectAlgorithm::MedianOfMedians,
    };
    select_nth(items, k, &mut less, algo);
}

/// Builds the subtree over `items` (tree positions `offset..offset + items.len()`) at
/// `depth`, serially, with an explicit stack.
pub(crate) fn build_serial<T: Scalar, L: Layout<T>>(
    input: &BuildInput<L>,
    items: &mut [L::Item],
    offset: usize,
    depth: usize,
) -> Subtree<T> {
    struct Task {
        start: usize,
        end: usize,
        depth: usize,
        parent: Option<usize>,
        /// Copies of one point, sorted by slot.
        copies: bool,
    }
    let leaf_size = input.options.leaf_size;
    let mut nodes: Vec<Node<T>> = Vec::with_capacity(2 * items.len() / leaf_size + 1);
    let mut max_depth = depth;
    let mut stack = vec![Task {
        start: 0,
        end: items.len(),
        depth,
        parent: None,
        copies: false,
    }];
    while let Some(t) = stack.pop() {
        let idx = nodes.len();
        if let Some(p) = t.parent {
            nodes[p].a = idx as u32;
        }
        max_depth = max_depth.max(t.depth);
        let node_items = &mut items[t.start..t.end];
        if node_items.len() <= leaf_size {
            sort_leaf_by_slot(&input.layout, node_items);
            nodes.push(Node::leaf(offset + t.start, offset + t.end));
            continue;
        }
        let (split, value, copies) = if t.copies {
            let (split, value) = split_copies(&input.layout, node_items, t.depth);
            (split, value, true)
        } else {
            split_node(input, node_items, t.depth, Scan::Serial)
        };
        let mid = t.start + split.rank;
        nodes.push(Node::internal(split.dim, value, 0, offset + t.end));
        stack.push(Task {
            start: mid,
            end: t.end,
            depth: t.depth + 1,
            parent: Some(idx),
            copies,
        });
        stack.push(Task {
            start: t.start,
            end: mid,
            depth: t.depth + 1,
            parent: None,
            copies,
        });
    }
    Subtree {
        nodes,
        depth: max_depth,
    }
}

/// Builds the subtree over `items` like [`build_serial`], building the children of balanced
/// splits of large nodes in parallel (rayon) and concatenating them in preorder.
pub(crate) fn build_parallel<T: Scalar, L: Layout<T>>(
    input: &BuildInput<L>,
    items: &mut [L::Item],
    offset: usize,
    depth: usize,
) -> Subtree<T> {
    let n = items.len();
    if n < 2 * PARALLEL_MIN || n <= input.options.leaf_size {
        return build_serial(input, items, offset, depth);
    }
    let (split, value, _) = split_node(input, items, depth, Scan::Parallel);
    let rank = split.rank;
    let (left, right) = items.split_at_mut(rank);
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

/// Puts the items of a leaf in slot order, so that a leaf's order does not depend on how its
/// points were partitioned (every median algorithm then gives the identical tree). Leaves of
/// up to 16 points are placed by rank (the number of smaller slots, counted over a fixed
/// 16-wide array without branches); comparison sorts of such short runs mispredicted about
/// every other comparison and cost a tenth of the build.
fn sort_leaf_by_slot<T: Scalar, L: Layout<T>>(layout: &L, items: &mut [L::Item]) {
    const WIDE: usize = 16;
    let m = items.len();
    if !(2..=WIDE).contains(&m) {
        items.sort_unstable_by_key(|it| layout.slot(it));
        return;
    }
    // Padding slots never count as smaller: slots are < u32::MAX (indices are u32 and a
    // tree holds fewer than u32::MAX points).
    let mut slots = [u32::MAX; WIDE];
    for (s, it) in slots.iter_mut().zip(items.iter()) {
        *s = layout.slot(it);
    }
    let mut placed = [items[0]; WIDE];
    for (i, it) in items.iter().enumerate() {
        let s = slots[i];
        let rank = slots.iter().map(|&t| usize::from(t < s)).sum::<usize>();
        placed[rank] = *it;
    }
    items.copy_from_slice(&placed[..m]);
}

/// `root` followed by the nodes of `left` and `right`, child links rebased.
fn join_subtrees<T: Scalar>(mut root: Node<T>, left: Subtree<T>, right: Subtree<T>) -> Subtree<T> {
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
