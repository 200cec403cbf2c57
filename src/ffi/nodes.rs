//! The tree's nodes as C sees them ([`crate::KdTree::nodes`], [`crate::KdTree::node_weights`],
//! [`crate::KdTree::tree_order`]): what scipy's `cKDTreeNode` objects and `_build_weights`
//! describe, copied into the caller's buffers with the size-query convention of every buffer
//! of this layer (too small: BUFFER_TOO_SMALL, the size needed in `*count`).

use super::args::{copy_counted, deref, init_out, read_slice};
use super::status::{guard, nbhd_status, FfiError};
use super::tree::nbhd_tree;
use crate::handle::AnyIndex;
use crate::tree::NodeInfo;

/// One node of a tree, as nbhd_tree_nodes lists them: in preorder (a node, its left subtree,
/// its right subtree; the root at position 0). A split sends coordinates `<= split` left and
/// `>= split` right, so points equal to the split value may lie on both sides; identical
/// points are split by index like any others, so every leaf holds at most the build's
/// `leaf_size` points.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_node {
    /// Edges from the root (the root is level 0).
    pub level: usize,
    /// An internal node's splitting dimension; 0 for a leaf.
    pub split_dim: usize,
    /// An internal node's splitting value, as a double whatever the tree's scalar type; 0 for
    /// a leaf.
    pub split: f64,
    /// The node's points are the tree positions `start .. end - 1`: entries of
    /// nbhd_tree_order, which names their caller indices.
    pub start: usize,
    /// One past the node's last tree position.
    pub end: usize,
    /// An internal node's children: their positions in the list (`left` is the node's own
    /// position plus one); 0 for a leaf (the root, position 0, is no node's child).
    pub left: usize,
    /// See `left`.
    pub right: usize,
    /// Whether the node is a leaf.
    pub leaf: bool,
}

impl From<&NodeInfo<f64>> for nbhd_node {
    fn from(n: &NodeInfo<f64>) -> Self {
        let (left, right) = n.children.unwrap_or((0, 0));
        Self {
            level: n.level,
            split_dim: n.split_dim.unwrap_or(0),
            split: n.split,
            start: n.start,
            end: n.end,
            left,
            right,
            leaf: n.children.is_none(),
        }
    }
}

/// The index behind an nbhd_tree, which is always a static tree (a growing tree,
/// nbhd_dynamic_tree, is a forest that merges as it grows and has no one node list).
///
/// # Safety
/// `tree` must be NULL or a live handle.
unsafe fn static_tree<'a>(tree: *const nbhd_tree) -> Result<&'a AnyIndex, FfiError> {
    // SAFETY: forwarded from the caller.
    let tree = unsafe { deref(tree, "tree") }?;
    Ok(&tree.inner)
}

/// The error of a growing tree where a static one is needed (never reached through an
/// nbhd_tree, which always holds a static tree).
fn not_static() -> FfiError {
    FfiError::InvalidArgument("a growing tree has no single node list".into())
}

/// Copies the tree's nodes in preorder into `nodes`: `*count` of them, nbhd_stats.nodes
/// (a tree of no point is one empty leaf). If `capacity` is smaller, nothing is written to
/// `nodes`, `*count` receives the number needed and the status is
/// NBHD_STATUS_BUFFER_TOO_SMALL; `nodes` may be NULL with capacity 0 to ask for the size.
///
/// Errors: NULL_POINTER (`tree`, `count`, `nodes` when needed), MISALIGNED_POINTER,
/// BUFFER_TOO_SMALL, OUT_OF_MEMORY. On any other error `*count` is 0.
///
/// # Safety
/// `tree` must be NULL or a live handle; `nodes` NULL or writable for `capacity` structs;
/// `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_nodes(
    tree: *const nbhd_tree,
    nodes: *mut nbhd_node,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    guard("nbhd_tree_nodes", || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(count, "count", 0) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let index = unsafe { static_tree(tree) }?;
        let list: Vec<nbhd_node> = index
            .nodes()
            .ok_or_else(not_static)?
            .iter()
            .map(nbhd_node::from)
            .collect();
        let what = "nodes (the size needed is in *count)";
        // SAFETY: `nodes` is NULL or writable for `capacity` structs (caller); `count` was
        // checked by init_out.
        unsafe { copy_counted(&list, nodes, capacity, count, what) }
    })
}

/// Copies the caller indices of the tree's points in tree order into `indices`: `*count` of
/// them, nbhd_stats.points (the points of a node, nbhd_node's `start .. end - 1`, are
/// adjacent; skipped points are absent). Too small a `capacity` is BUFFER_TOO_SMALL with the
/// size needed in `*count`, as for nbhd_tree_nodes.
///
/// Errors: NULL_POINTER (`tree`, `count`, `indices` when needed), MISALIGNED_POINTER,
/// BUFFER_TOO_SMALL. On any other error `*count` is 0.
///
/// # Safety
/// `tree` must be NULL or a live handle; `indices` NULL or writable for `capacity` values;
/// `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_order(
    tree: *const nbhd_tree,
    indices: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    guard("nbhd_tree_order", || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(count, "count", 0) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let order = unsafe { static_tree(tree) }?
            .tree_order()
            .ok_or_else(not_static)?;
        let what = "indices (the size needed is in *count)";
        // SAFETY: `indices` is NULL or writable for `capacity` values (caller); `count` was
        // checked by init_out.
        unsafe { copy_counted(order, indices, capacity, count, what) }
    })
}

/// The sum of `weights` over each node's points, in the order of nbhd_tree_nodes (scipy's
/// `_build_weights`), into `sums`: `*count` values, nbhd_stats.nodes. `weights` holds one
/// finite value per point given to the build (`weight_count` = nbhd_stats.source_points,
/// skipped points included and never counted). A leaf sums its points in tree order, an
/// internal node adds its left child's sum and its right child's, so the values are the same
/// bits on every run. Too small a `capacity` is BUFFER_TOO_SMALL with the size needed in
/// `*count`, as for nbhd_tree_nodes.
///
/// Errors: NULL_POINTER (`tree`, `count`, `weights` with a count above 0, `sums` when
/// needed), MISALIGNED_POINTER, INVALID_ARGUMENT (`weight_count` overflowing the address
/// space), INVALID_OPTION (`weight_count` other than nbhd_stats.source_points, a NaN or
/// infinite weight: the message names the point), BUFFER_TOO_SMALL, OUT_OF_MEMORY. On any
/// other error `*count` is 0 and nothing is written.
///
/// # Safety
/// `tree` must be NULL or a live handle; `weights` NULL or readable for `weight_count`
/// values; `sums` NULL or writable for `capacity` values; `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_node_weights(
    tree: *const nbhd_tree,
    weights: *const f64,
    weight_count: usize,
    sums: *mut f64,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    guard("nbhd_tree_node_weights", || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(count, "count", 0) }?;
        // SAFETY: `tree` is NULL or a live handle; `weights` NULL or readable for
        // `weight_count` values (caller).
        let (index, weights) = unsafe {
            (
                static_tree(tree)?,
                read_slice(weights, weight_count, "weights")?,
            )
        };
        let node_sums = index.node_weights(weights).ok_or_else(not_static)??;
        let what = "sums (the size needed is in *count)";
        // SAFETY: `sums` is NULL or writable for `capacity` values (caller); `count` was
        // checked by init_out.
        unsafe { copy_counted(&node_sums, sums, capacity, count, what) }
    })
}
