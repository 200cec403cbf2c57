//! What a structure made of several trees (the dynamic forest, `src/dynamic/`) reads from one
//! of them: its cells for the grouped search of a batch over the forest, the single-query
//! descent into a result set of its own (so that one result set collects over every tree of the
//! forest), the leaf a query falls into (to order a batch of queries for the cache), and the
//! bounding box of the points.

use super::group_search::{CellView, Cells};
use super::search;
use super::KdTree;
use crate::metric::{Measure, Norm, NormUser};
use crate::query::result_set::ResultSet;
use crate::scalar::Scalar;

impl<T: Scalar> KdTree<T> {
    /// Runs the exact search of `src/tree/search.rs` (of `periodic.rs` for a periodic tree,
    /// `q` then wrapped into its box) under the norm `norm` (`src/metric.rs`;
    /// [`L2`](crate::metric::L2) for the plain Euclidean search) for the point `q` (of the
    /// tree's dimension, finite), offering every point of every visited leaf except the caller
    /// index `exclude` to `out`; the cells visited depend only on `out`'s bound.
    pub(crate) fn search_into_norm<C: ResultSet<T>, N: Norm<T>>(
        &self,
        q: &[T],
        exclude: Option<u32>,
        norm: N,
        out: &mut C,
    ) {
        match &self.periodic {
            Some(periodic) => {
                super::periodic::search_periodic(&self.view(), periodic, q, exclude, norm, out)
            }
            None => search::search_norm(&self.view(), q, exclude, norm, out),
        }
    }

    /// The single search under `measure` (the preorder descent, the compact one being
    /// Euclidean): the norm chosen once, then [`KdTree::search_into_norm`].
    pub(crate) fn search_measured<C: ResultSet<T>>(
        &self,
        q: &[T],
        exclude: Option<u32>,
        measure: &Measure,
        out: &mut C,
    ) {
        struct Descend<'a, T: Scalar, C> {
            tree: &'a KdTree<T>,
            q: &'a [T],
            exclude: Option<u32>,
            out: &'a mut C,
        }
        impl<T: Scalar, C: ResultSet<T>> NormUser<T> for Descend<'_, T, C> {
            type Out = ();
            fn with<N: Norm<T>>(self, norm: N) {
                self.tree
                    .search_into_norm(self.q, self.exclude, norm, self.out);
            }
        }
        measure.apply(Descend {
            tree: self,
            q,
            exclude,
            out,
        });
    }

    /// The first tree position of the leaf `q` descends to.
    pub(crate) fn leaf_position(&self, q: &[T]) -> u32 {
        let mut node = 0;
        loop {
            let n = &self.nodes[node];
            if n.is_leaf() {
                return n.a;
            }
            // without a branch: which side a query takes is a coin toss the predictor loses
            // at every level (queries come in spatial order, so the nodes are in the cache)
            let right = usize::from(q[n.dim as usize] >= n.split);
            node = (node + 1) * (1 - right) + n.a as usize * right;
        }
    }

    /// The tree prepared for the grouped search of a forest (`group_search.rs`), its caller
    /// indices shifted by `shift` to the forest's.
    pub(crate) fn group_cells<const D: usize>(&self, shift: u32) -> Cells<T, D> {
        Cells::new(&self.view(), shift)
    }

    /// What the grouped search reads of this tree, with its prepared `cells`; `not_live` marks
    /// the forest's indices it skips.
    pub(crate) fn cell_view<'a, const D: usize>(
        &'a self,
        cells: &'a Cells<T, D>,
        not_live: Option<&'a [u64]>,
    ) -> CellView<'a, T, D> {
        cells.view(&self.view(), not_live)
    }

    /// The smallest and largest coordinate of the points in every dimension.
    pub(crate) fn bounding_box(&self) -> (Vec<T>, Vec<T>) {
        let mut lo = vec![T::INFINITY; self.dim];
        let mut hi = vec![T::ZERO - T::INFINITY; self.dim];
        for p in self.coords.chunks_exact(self.dim) {
            for j in 0..self.dim {
                lo[j] = lo[j].min_of(p[j]);
                hi[j] = hi[j].max_of(p[j]);
            }
        }
        (lo, hi)
    }
}
