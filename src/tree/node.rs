//! The compact node array of a k-d tree, in preorder: the left child of internal node `i` is
//! `i + 1`, its right child is stored. Leaves are ranges of the tree-ordered points.

use crate::scalar::Scalar;

/// `dim` value marking a leaf.
pub(crate) const LEAF: u32 = u32::MAX;

/// One node: 16 bytes for `f32`, 24 for `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node<T> {
    /// Internal: the splitting coordinate value. Points of the left subtree have a
    /// coordinate ≤ `split` in dimension `dim`, points of the right one ≥ `split`.
    pub split: T,
    /// Internal: the splitting dimension; leaf: [`LEAF`].
    pub dim: u32,
    /// Internal: index of the right child; leaf: first point (tree order).
    pub a: u32,
    /// Internal and leaf: one past the last point of the subtree (tree order).
    pub b: u32,
}

impl<T: Copy + Default> Node<T> {
    pub(crate) fn leaf(start: usize, end: usize) -> Self {
        Self {
            split: T::default(),
            dim: LEAF,
            a: start as u32,
            b: end as u32,
        }
    }

    pub(crate) fn internal(dim: usize, split: T, right: usize, end: usize) -> Self {
        Self {
            split,
            dim: dim as u32,
            a: right as u32,
            b: end as u32,
        }
    }

    #[inline]
    pub(crate) fn is_leaf(&self) -> bool {
        self.dim == LEAF
    }
}

/// `link & 3` of a [`Descent`] leaf (internal nodes hold their splitting dimension, 0..=2).
pub(crate) const DESCENT_LEAF: u32 = 3;

/// One node of a [`Descent`]: 8 bytes for `f32`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Step<T> {
    /// Internal: the splitting value (as [`Node::split`]); leaf: its first point (tree order)
    /// as [`Scalar::from_index_bits`], so that a leaf's points are found without another read.
    pub split: T,
    /// Internal: `first_child << 2 | dim`, the two children adjacent (left, then right);
    /// leaf: `points << 2 | DESCENT_LEAF`, its number of points.
    pub link: u32,
}

impl<T: Scalar> Step<T> {
    /// A leaf's point range (tree order).
    #[inline(always)]
    pub(crate) fn leaf_range(&self) -> (usize, usize) {
        let a = self.split.index_bits() as usize;
        (a, a + (self.link >> 2) as usize)
    }
}

/// The descent array of a single query (`src/tree/search.rs`), derived from the preorder
/// [`Node`]s of a tree of dimension at most 3 and not saved: internal nodes of 8 bytes in
/// breadth-first order, the two children of a node side by side (the near child is the first
/// child plus the side of the split, one cache line for both), and every subtree of at most
/// `bucket` points collapsed into one leaf, so that the nodes of a 77k-point tree take about
/// 60 kB instead of the 300 kB of the preorder nodes a descent would otherwise walk. The
/// points of a leaf stay where the tree keeps them (tree order), a linear read; the leaf's
/// step holds their range itself (a separate array of ranges cost one more dependent cache
/// miss per leaf: 4 % of the samples of single queries on the 1M cube).
#[derive(Clone, Debug, Default)]
pub(crate) struct Descent<T> {
    pub steps: Vec<Step<T>>,
    /// Smallest caller index of every step's subtree.
    pub min_id: Vec<u32>,
}

impl<T: Scalar> Descent<T> {
    /// The descent of the preorder `nodes` with their smallest indices `min_id`, subtrees of
    /// at most `bucket` points as leaves; `None` above dimension 3, for more than 2^29 steps or
    /// 2^30 points.
    pub(crate) fn new(
        nodes: &[Node<T>],
        min_id: &[u32],
        dim: usize,
        bucket: usize,
    ) -> Option<Self> {
        if dim > 3 || nodes.len() >= 1 << 29 || nodes.is_empty() || nodes[0].b >= 1 << 30 {
            return None;
        }
        let mut d = Descent {
            steps: Vec::with_capacity(nodes.len()),
            min_id: Vec::with_capacity(nodes.len()),
        };
        // Breadth first: (preorder node, first point of its subtree) in step order.
        let mut queue = std::collections::VecDeque::new();
        queue.push_back((0usize, 0u32));
        d.steps.push(Step::default());
        d.min_id.push(min_id[0]);
        let mut at = 0usize;
        while let Some((i, start)) = queue.pop_front() {
            let n = &nodes[i];
            let end = n.b;
            if n.is_leaf() || (end - start) as usize <= bucket {
                // A build leaf may hold more than `bucket` points (its own limit), never 2^30.
                d.steps[at] = Step {
                    split: T::from_index_bits(start),
                    link: (end - start) << 2 | DESCENT_LEAF,
                };
            } else {
                let (left, right) = (i + 1, n.a as usize);
                let first = d.steps.len();
                d.steps[at] = Step {
                    split: n.split,
                    link: (first as u32) << 2 | n.dim,
                };
                d.steps.push(Step::default());
                d.steps.push(Step::default());
                d.min_id.push(min_id[left]);
                d.min_id.push(min_id[right]);
                queue.push_back((left, start));
                queue.push_back((right, nodes[left].b));
            }
            at += 1;
        }
        Some(d)
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.steps.len() * std::mem::size_of::<Step<T>>() + self.min_id.len() * 4
    }
}
