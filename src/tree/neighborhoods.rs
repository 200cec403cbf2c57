//! The tree's fast paths for tables: the table of its own points
//! ([`NeighborIndex::neighborhoods`](crate::index::NeighborIndex::neighborhoods) of a
//! [`KdTree`], one descent per group of consecutive tree-order points) and the table of a batch
//! of query points ([`NeighborIndex::neighborhoods_of`](crate::index::NeighborIndex::neighborhoods_of),
//! one descent per group of queries that fall into nearby leaves), in one to three dimensions,
//! shared by the group (`group_search.rs`; `src/index/tables.rs` chooses them); the same rows
//! as the single-query search.

use super::search::TreeView;
use super::{group_search, KdTree};
use crate::error::Result;
use crate::index::answer;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::table::NeighborTable;
use group_search::{batch_table, BatchGroups, Cells};

/// A batch is answered in groups when it holds at least 1/`DENSE` as many queries as the tree
/// holds points: the grouped search first prepares the tree's cells (every node's box, the
/// coordinates by dimension — a pass over every point), which a sparse batch does not repay.
const DENSE: usize = 4;

/// Queries in one group lie in leaves at most this many leaves (of the build's leaf size) apart.
const SPAN_LEAVES: usize = 2;

impl<T: Scalar> KdTree<T> {
    /// The grouped all-point table in dimensions 1 to 3 (`None` in others), on the current
    /// thread pool.
    pub(super) fn grouped_all(
        &self,
        nbhd: Neighborhood<T>,
        exclude_self: bool,
    ) -> Option<Result<NeighborTable<T>>> {
        let grouped = |f: fn(&TreeView<'_, T>, usize, Neighborhood<T>, bool) -> _| {
            Some(f(&self.view(), self.source_len, nbhd, exclude_self))
        };
        match self.dim {
            // no point: the index's own rows, every one empty
            _ if self.is_empty() => None,
            3 => grouped(group_search::table::<T, 3>),
            2 => grouped(group_search::table::<T, 2>),
            1 => grouped(group_search::table::<T, 1>),
            _ => None,
        }
    }

    /// The grouped table of the packed, finite `queries` (row `i` for query `i`) in dimensions
    /// 1 to 3, for a batch dense enough to repay the cells (`None` otherwise: one search per
    /// query), on the current thread pool. `order` lists the queries by the leaf they fall into,
    /// `keys` those leaves' first tree positions.
    pub(super) fn grouped_batch_of(
        &self,
        queries: &[T],
        order: &[u32],
        keys: &[u32],
        nbhd: Neighborhood<T>,
    ) -> Option<Result<NeighborTable<T>>> {
        if self.is_empty() || order.len().saturating_mul(DENSE) < self.len() {
            return None;
        }
        match self.dim {
            3 => Some(self.batch_rows::<3>(queries, order, keys, nbhd)),
            2 => Some(self.batch_rows::<2>(queries, order, keys, nbhd)),
            1 => Some(self.batch_rows::<1>(queries, order, keys, nbhd)),
            _ => None,
        }
    }

    /// [`KdTree::grouped_batch_of`] in dimension `D`.
    fn batch_rows<const D: usize>(
        &self,
        queries: &[T],
        order: &[u32],
        keys: &[u32],
        nbhd: Neighborhood<T>,
    ) -> Result<NeighborTable<T>> {
        let view = self.view();
        let cells = Cells::<T, D>::new(&view, 0);
        let grouping = BatchGroups {
            span: (SPAN_LEAVES * self.options.leaf_size).min(u32::MAX as usize) as u32,
            max_group: usize::MAX,
            gather: true,
        };
        let single = |q: &[T], row: &mut Vec<_>| answer(self, q, None, nbhd, row);
        batch_table(
            &[cells.view(&view, None)],
            queries,
            (order, keys),
            grouping,
            nbhd,
            &single,
        )
    }
}
