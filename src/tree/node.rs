//! The compact node array of a k-d tree, in preorder: the left child of internal node `i` is
//! `i + 1`, its right child is stored. Leaves are ranges of the tree-ordered points.

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
