//! The tree's fast path for the table of its own points
//! ([`NeighborIndex::neighborhoods`](crate::index::NeighborIndex::neighborhoods) of a
//! [`KdTree`], `src/index/tables.rs`): in one to three dimensions, one descent per group of
//! consecutive tree-order points, shared by the group (`group_search.rs`); the same rows as the
//! single-query search.

use super::search::TreeView;
use super::{group_search, KdTree};
use crate::error::Result;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::table::NeighborTable;

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
}
