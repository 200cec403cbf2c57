//! Periodic trees (a torus, scipy's `boxsize`): a tree whose points lie in a box `[0, L)` on
//! its periodic axes, searched by nearest images ([`Period`], `src/metric.rs`).
//!
//! The descent is that of `search.rs` (thesis Algorithm 9) with one change: a cell's lower
//! bound can no longer be grown from the split alone, because the nearest image of the far side
//! may lie across the box's edge. So every pending cell carries its box (scipy's `cKDTree` does
//! the same): the root's is the points' bounding box, a child's the parent's cut at the split
//! (`[lo, split]` left, `[split, hi]` right, valid as every point left of a split is at most
//! the split and every point right of it at least), and its bound is [`Period::box_key`] of
//! that box, which never exceeds the key of a point inside it. The nearer child is the one of
//! smaller bound. Pruning is by `(key, index)` as in `search.rs`, so the result is exact and
//! independent of the order cells are visited in.

use super::node::Node;
use super::search::{may_enter, TreeView};
use super::{BuildOptions, KdTree};
use crate::error::{NbhdError, Result};
use crate::metric::{Norm, Period};
use crate::points::PointsView;
use crate::query::result_set::ResultSet;
use crate::scalar::Scalar;

/// What a periodic tree adds to its arrays: the box, and the points' bounding box (the root
/// cell of a periodic search).
#[derive(Clone, Debug)]
pub(crate) struct Periodic<T> {
    pub period: Period<T>,
    pub lo: Vec<T>,
    pub hi: Vec<T>,
}

impl<T: Scalar> KdTree<T> {
    /// Builds a periodic tree (a torus, scipy's `cKDTree(boxsize=...)`) over the points of
    /// `view`: `boxsize` holds the box size of every axis (or one for all), 0 or +∞ for an
    /// open axis. Every query of the tree is then wrapped into the box and measures each axis
    /// difference at its nearest image (`min(t, L − t)`, [`Period`]), under any metric. With
    /// no periodic axis this is [`KdTree::build`].
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, Query};
    ///
    /// let pts = [0.05f64, 0.5, 0.97];
    /// let view = PointsView::from_flat(&pts, 1)?;
    /// let tree = KdTree::<f64>::build_periodic(&view, &BuildOptions::default(), &[1.0])?;
    /// let mut out = Vec::new();
    /// tree.knn(Query::point(&[0.0]), 2, &mut out)?; // 0.97 is 0.03 away across the edge
    /// assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), [2, 0]);
    /// tree.knn(Query::point(&[-3.0]), 1, &mut out)?; // queries are wrapped: -3 is 0
    /// assert_eq!(out[0].index, 2);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`KdTree::build`]; a size negative, NaN or rounding to 0 in `T`, or a
    /// `boxsize` of another length than 1 or the dimension ([`NbhdError::InvalidOption`]); a
    /// point outside `[0, L)` on a periodic axis ([`NbhdError::OutsidePeriod`], naming the
    /// smallest such caller index; points are not wrapped, as in scipy).
    pub fn build_periodic(
        view: &PointsView<'_>,
        options: &BuildOptions,
        boxsize: &[f64],
    ) -> Result<Self> {
        let period = Period::new(boxsize, view.dim())?;
        let tree = Self::build(view, options)?;
        match period {
            Some(period) => tree.with_period(period),
            None => Ok(tree),
        }
    }

    /// This tree made periodic: its points checked to lie in the box.
    pub(crate) fn with_period(mut self, period: Period<T>) -> Result<Self> {
        let outside = self
            .coords
            .chunks_exact(self.dim.max(1))
            .zip(&self.ids)
            .filter_map(|(p, &id)| period.outside(p).map(|j| (id, j)))
            .min();
        if let Some((id, coordinate)) = outside {
            return Err(NbhdError::OutsidePeriod {
                index: id as usize,
                coordinate,
                value: self.point(id).map_or(f64::NAN, |p| p[coordinate].to_f64()),
                size: period.sizes()[coordinate],
            });
        }
        let (lo, hi) = self.bounding_box();
        self.periodic = Some(Box::new(Periodic { period, lo, hi }));
        Ok(self)
    }

    /// The periodic box of the tree, if it has one ([`KdTree::build_periodic`]).
    pub fn period(&self) -> Option<&Period<T>> {
        self.periodic.as_ref().map(|p| &p.period)
    }
}

/// The periodic search: offers to `out` every point (except the caller index `exclude`) of
/// every cell whose bound may still enter, for the wrapped query `q`.
pub(crate) fn search_periodic<T: Scalar, C: ResultSet<T>, N: Norm<T>>(
    tree: &TreeView<'_, T>,
    periodic: &Periodic<T>,
    q: &[T],
    exclude: Option<u32>,
    norm: N,
    out: &mut C,
) {
    let (d, period) = (tree.dim, &periodic.period);
    let excluded = exclude.unwrap_or(u32::MAX);
    // the current cell's box, and the boxes of the pending cells (2·d values each, a stack)
    let (mut lo, mut hi) = (periodic.lo.clone(), periodic.hi.clone());
    let mut boxes: Vec<T> = Vec::new();
    let mut pending: Vec<(u32, T)> = vec![(0, period.box_key(norm, q, &lo, &hi))];
    boxes.extend_from_slice(&lo);
    boxes.extend_from_slice(&hi);
    while let Some((mut node, mut dist)) = pending.pop() {
        let at = boxes.len() - 2 * d;
        lo.copy_from_slice(&boxes[at..at + d]);
        hi.copy_from_slice(&boxes[at + d..]);
        boxes.truncate(at);
        while may_enter(out, dist, tree.min_id, node) {
            let n: &Node<T> = &tree.nodes[node as usize];
            if n.is_leaf() {
                let bound = out.bound();
                for i in n.a as usize..n.b as usize {
                    let key = period.key(norm, q, &tree.coords[i * d..i * d + d]);
                    let id = tree.ids[i];
                    if key <= bound && id != excluded {
                        out.offer(id, key);
                    }
                }
                break;
            }
            let (sd, split) = (n.dim as usize, n.split);
            let (low, high) = (lo[sd], hi[sd]);
            hi[sd] = split;
            let left_key = period.box_key(norm, q, &lo, &hi);
            (lo[sd], hi[sd]) = (split, high);
            let right_key = period.box_key(norm, q, &lo, &hi);
            lo[sd] = low;
            // the nearer child is entered, the other pushed with its box
            let right_first = right_key <= left_key;
            let (near, far) = if right_first {
                ((n.a, right_key), (node + 1, left_key))
            } else {
                ((node + 1, left_key), (n.a, right_key))
            };
            if may_enter(out, far.1, tree.min_id, far.0) {
                let at = boxes.len();
                boxes.extend_from_slice(&lo);
                boxes.extend_from_slice(&hi);
                boxes[if right_first { at + d + sd } else { at + sd }] = split;
                pending.push(far);
            }
            if right_first {
                lo[sd] = split;
            } else {
                hi[sd] = split;
            }
            (node, dist) = near;
        }
    }
}
