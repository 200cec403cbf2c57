//! The tree's nodes as a caller sees them: one [`NodeInfo`] per node in the tree's own preorder
//! (the order of its node array, `node.rs`), and per-node sums of per-point weights in that
//! order. This is what scipy's `cKDTreeNode` objects and `_build_weights` describe of scipy's
//! tree; here it describes nbhd's, which differs from scipy's in two honest ways:
//! - a split sends coordinates `≤ split` left and `≥ split` right (scipy: `< split` left), so
//!   points equal to the split value may lie on both sides;
//! - identical points are split by caller index like any others, so every leaf holds at most
//!   `leaf_size` points (scipy makes a node whose points all coincide a leaf of any size).

use super::KdTree;
use crate::error::{NbhdError, Result};
use crate::scalar::Scalar;

/// One node of a [`KdTree`], as [`KdTree::nodes`] lists them (preorder: a node, its left
/// subtree, its right subtree).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeInfo<T> {
    /// Edges from the root (the root is level 0).
    pub level: usize,
    /// The splitting dimension of an internal node; `None` for a leaf.
    pub split_dim: Option<usize>,
    /// The splitting value of an internal node: its left subtree's points have coordinate
    /// `≤ split` in `split_dim`, its right subtree's `≥ split`. Zero for a leaf.
    pub split: T,
    /// The node's points are tree positions `start..end` ([`KdTree::tree_order`] maps them to
    /// the caller's indices).
    pub start: usize,
    /// One past the node's last tree position.
    pub end: usize,
    /// Internal: the preorder positions of the left and the right child (the left one is the
    /// node's own position plus one); `None` for a leaf.
    pub children: Option<(usize, usize)>,
}

impl<T: Scalar> KdTree<T> {
    /// Every node of the tree in preorder (a tree of no point is one empty leaf). A node's
    /// position in the list is the one [`KdTree::node_weights`] uses.
    pub fn nodes(&self) -> Vec<NodeInfo<T>> {
        let mut out = Vec::with_capacity(self.nodes.len());
        // (node, level, start): a node's start is its parent's for a left child, the left
        // sibling's end for a right child
        let mut stack = vec![(0usize, 0usize, 0usize)];
        while let Some((i, level, start)) = stack.pop() {
            let n = self.nodes[i];
            let info = if n.is_leaf() {
                NodeInfo {
                    level,
                    split_dim: None,
                    split: T::ZERO,
                    start: n.a as usize,
                    end: n.b as usize,
                    children: None,
                }
            } else {
                let (left, right) = (i + 1, n.a as usize);
                let middle = self.nodes[left].b as usize;
                stack.push((right, level + 1, middle));
                stack.push((left, level + 1, start));
                NodeInfo {
                    level,
                    split_dim: Some(n.dim as usize),
                    split: n.split,
                    start,
                    end: n.b as usize,
                    children: Some((left, right)),
                }
            };
            debug_assert_eq!(out.len(), i, "the node array is in preorder");
            out.push(info);
        }
        out
    }

    /// The sum of `weights` over each node's points, in the preorder of [`KdTree::nodes`]
    /// (scipy's `_build_weights`): `weights` holds one finite value per caller index
    /// (skipped non-finite points included, never counted). A leaf sums its points in tree
    /// order, an internal node adds its left child's sum and its right child's, so the values
    /// are the same bits on every run.
    pub fn node_weights(&self, weights: &[f64]) -> Result<Vec<f64>> {
        if weights.len() != self.source_len {
            return Err(NbhdError::InvalidOption {
                name: "weights",
                reason: format!(
                    "{} weights for {} points (one per index)",
                    weights.len(),
                    self.source_len
                ),
            });
        }
        if let Some(at) = weights.iter().position(|w| !w.is_finite()) {
            return Err(NbhdError::InvalidOption {
                name: "weights",
                reason: format!("the weight of point {at} is {}, not finite", weights[at]),
            });
        }
        let mut sums = vec![0.0; self.nodes.len()];
        // children follow their parent in preorder: a backward sweep sees both before it
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            sums[i] = if n.is_leaf() {
                self.ids[n.a as usize..n.b as usize]
                    .iter()
                    .map(|&id| weights[id as usize])
                    .sum()
            } else {
                sums[i + 1] + sums[n.a as usize]
            };
        }
        Ok(sums)
    }
}

#[cfg(test)]
mod tests {
    use crate::tree::{BuildOptions, KdTree, PivotPolicy};
    use crate::PointsView;

    fn tree(coords: &[f64], dim: usize, pivot: PivotPolicy, leaf_size: usize) -> KdTree<f64> {
        let view = PointsView::from_flat(coords, dim).unwrap();
        let options = BuildOptions {
            pivot,
            leaf_size,
            ..BuildOptions::default()
        };
        KdTree::build(&view, &options).unwrap()
    }

    #[test]
    fn four_points_on_a_line_make_scipys_seven_nodes() {
        // the pivots of scipy's two build modes (median of the widest axis, sliding midpoint)
        for pivot in [PivotPolicy::SpreadMedian, PivotPolicy::SlidingMidpoint] {
            let t = tree(&[0.0, 1.0, 2.0, 3.0], 1, pivot, 1);
            let nodes = t.nodes();
            let levels: Vec<usize> = nodes.iter().map(|n| n.level).collect();
            assert_eq!(levels, [0, 1, 2, 2, 1, 2, 2], "{pivot:?}");
            let ranges: Vec<(usize, usize)> = nodes.iter().map(|n| (n.start, n.end)).collect();
            assert_eq!(
                ranges,
                [(0, 4), (0, 2), (0, 1), (1, 2), (2, 4), (2, 3), (3, 4)]
            );
            assert_eq!(nodes[0].children, Some((1, 4)));
            assert_eq!(nodes[2].split_dim, None);
            let w = t.node_weights(&[1.0; 4]).unwrap();
            assert_eq!(w, [4.0, 2.0, 1.0, 1.0, 2.0, 1.0, 1.0]);
        }
    }

    #[test]
    fn nodes_hold_their_points_on_the_sides_of_each_split() {
        let coords: Vec<f64> = (0..300).map(|i| ((i * 7919) % 101) as f64 / 7.0).collect();
        for pivot in PivotPolicy::ALL {
            let t = tree(&coords, 3, pivot, 4);
            let nodes = t.nodes();
            assert_eq!(nodes[0].start, 0);
            assert_eq!(nodes[0].end, 100);
            for n in &nodes {
                let Some((l, r)) = n.children else {
                    assert!(n.end - n.start <= 4);
                    continue;
                };
                let (dim, split) = (n.split_dim.unwrap(), n.split);
                assert_eq!((nodes[l].start, nodes[l].end), (n.start, nodes[r].start));
                assert_eq!(nodes[r].end, n.end);
                assert_eq!((nodes[l].level, nodes[r].level), (n.level + 1, n.level + 1));
                assert!((nodes[l].start..nodes[l].end).all(|p| t.point_at(p)[dim] <= split));
                assert!((nodes[r].start..nodes[r].end).all(|p| t.point_at(p)[dim] >= split));
            }
            let w: Vec<f64> = (0..100).map(f64::from).collect();
            let sums = t.node_weights(&w).unwrap();
            assert_eq!(sums[0], 4950.0);
            for (n, s) in nodes.iter().zip(&sums) {
                let direct: f64 = t.tree_order()[n.start..n.end]
                    .iter()
                    .map(|&i| w[i as usize])
                    .sum();
                assert_eq!(*s, direct);
            }
        }
    }

    #[test]
    fn an_empty_tree_is_one_empty_leaf_and_weights_are_checked() {
        let t = tree(&[], 2, PivotPolicy::default(), 8);
        let nodes = t.nodes();
        assert_eq!(nodes.len(), 1);
        assert_eq!(
            (nodes[0].start, nodes[0].end, nodes[0].children),
            (0, 0, None)
        );
        assert_eq!(t.node_weights(&[]).unwrap(), [0.0]);
        let t = tree(&[0.0, 1.0], 1, PivotPolicy::default(), 8);
        assert!(t.node_weights(&[1.0]).is_err());
        assert!(t.node_weights(&[1.0, f64::NAN]).is_err());
    }
}
