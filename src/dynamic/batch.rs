//! Batch queries on the forest, answered a small group of nearby queries at a time by the
//! grouped search every tree uses (`src/tree/group_search.rs`): the forest's part is which
//! trees are searched, in which order, with which indices and tombstones.
//!
//! A frame of query points is ordered along the leaves of the forest's largest tree (so that
//! consecutive queries are near each other, `src/index/tables.rs`) and cut into groups of at
//! most [`GROUP`]. Each group descends every tree of the forest once instead of once per query,
//! largest tree first; the members' rows are kept from tree to tree, so the trees' answers
//! merge in `(sq_dist, index)` order as they arrive and every later tree is searched with the
//! bounds the earlier ones left. Each tree is prepared for this search once, on the first batch
//! that reaches it (its cells, with the tree's caller indices shifted to the forest's).
//!
//! **Exactness.** Each member sees every live point that could enter its answer, with the
//! squared distance the single-query search computes, so rows are the single-query rows, byte
//! for byte, whatever the groups, and so for any thread count (see the grouped search).

use std::any::Any;

use super::{DynamicKdTree, Part};
use crate::error::Result;
use crate::index::answer;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::table::NeighborTable;
use crate::tree::group_search::{batch_table, BatchGroups, Cells};

/// Most queries in one group (chosen by measurement, `benches/dynamic.rs`).
const GROUP: usize = 8;

/// Queries in one group lie in leaves of the largest tree at most this many leaves (of the
/// build's leaf size) apart (chosen by measurement, `benches/dynamic.rs`).
const SPAN_LEAVES: usize = 4;

impl<T: Scalar> Part<T> {
    /// The tree prepared for the grouped search of dimension `D`, made on first use.
    fn cells<const D: usize>(&self) -> &Cells<T, D> {
        let cells = self
            .cells
            .get_or_init(|| Box::new(self.tree.group_cells::<D>(self.lo)));
        (&**cells as &dyn Any)
            .downcast_ref()
            .expect("a forest's trees are searched in their one dimension")
    }
}

impl<T: Scalar> DynamicKdTree<T> {
    /// The rows of the packed, finite `queries` (dimension `D`), row `i` for query `i`,
    /// answered in groups along `order` (a permutation of the queries, `keys` the first tree
    /// positions of their leaves in the largest tree, increasing), on the current pool.
    pub(super) fn grouped_rows<const D: usize>(
        &self,
        queries: &[T],
        order: &[u32],
        keys: &[u32],
        nbhd: Neighborhood<T>,
    ) -> Result<NeighborTable<T>> {
        // Largest tree first: its bounds prune the smaller trees most.
        let mut parts: Vec<&Part<T>> = self.parts.iter().collect();
        parts.sort_by_key(|p| std::cmp::Reverse(p.tree.len()));
        let views: Vec<_> = parts
            .iter()
            .map(|p| {
                let tombstones = (p.dead > 0).then_some(&self.not_live[..]);
                p.tree.cell_view(p.cells::<D>(), tombstones)
            })
            .collect();
        let grouping = BatchGroups {
            span: (SPAN_LEAVES * self.options.leaf_size) as u32,
            max_group: GROUP,
            gather: false,
        };
        let single = |q: &[T], row: &mut Vec<_>| answer(self, q, None, nbhd, row);
        batch_table(&views, queries, (order, keys), grouping, nbhd, &single)
    }
}
