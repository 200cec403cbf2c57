//! The table driver: the neighbourhoods of all stored points ([`KdTree::neighborhoods`]) or of a
//! batch of query points ([`KdTree::neighborhoods_of`]) as a [`NeighborTable`], computed in
//! parallel in an order that keeps the cache warm and written back in the caller's order.

use rayon::prelude::*;

use super::search::TreeView;
use super::{group_search, KdTree};
use crate::error::{NbhdError, Result};
use crate::parallel::with_threads;
use crate::points::PointsView;
use crate::query::{NeighborSearch, Neighborhood, Query};
use crate::scalar::Scalar;
use crate::table::{check_knn_total, rows_in_work_order, NeighborTable, TableOptions};

impl<T: Scalar> KdTree<T> {
    /// The neighbourhood of every point of the tree, as compressed rows in the caller's
    /// index order (row `i` for point `i`; points skipped at build time get empty rows),
    /// computed in parallel; identical bytes for any thread count.
    pub fn neighborhoods(
        &self,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        nbhd.validate()?;
        check_knn_total(self.len(), self.len(), nbhd, options.exclude_self)?;
        // Low dimensions: one descent per group of consecutive tree-order points, shared by
        // the group (see `group_search`); the same rows as the single-query search.
        let grouped = |f: fn(&TreeView<'_, T>, usize, Neighborhood<T>, bool) -> _| {
            with_threads(options.threads, || {
                f(&self.view(), self.source_len, nbhd, options.exclude_self)
            })?
        };
        match self.dim {
            _ if self.is_empty() => {} // no point: `source_len` empty rows, below
            3 => return grouped(group_search::table::<T, 3>),
            2 => return grouped(group_search::table::<T, 2>),
            1 => return grouped(group_search::table::<T, 1>),
            _ => {}
        }
        // Any dimension: answered in tree order (neighbouring queries touch the same nodes and
        // leaves, so they hit the cache), written back in the caller's order.
        with_threads(options.threads, || {
            rows_in_work_order(
                self.source_len,
                self.len(),
                |pos| self.ids[pos] as usize,
                |pos, row, _| {
                    let exclude = options.exclude_self.then_some(self.ids[pos]);
                    self.search_resolved(self.point_at(pos), exclude, nbhd, row);
                    Ok(())
                },
            )
        })?
    }

    /// The neighbourhoods of a batch of query points (row `i` for query `i`), computed in
    /// parallel. `options.exclude_self` does not apply (the queries are not stored points).
    /// A batch of no query gives a table of no row.
    ///
    /// The queries are answered in the order of the leaves they fall into, so that consecutive
    /// queries walk the same nodes and leaves (a scan's points arrive in no useful order, and a
    /// query in random order misses the cache at almost every leaf); the rows come back in the
    /// queries' order, identical for any number of threads.
    pub fn neighborhoods_of(
        &self,
        queries: &PointsView<'_>,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        nbhd.validate()?;
        if queries.dim() != self.dim {
            return Err(NbhdError::DimensionMismatch {
                expected: self.dim,
                got: queries.dim(),
            });
        }
        check_knn_total(queries.len(), self.len(), nbhd, false)?;
        with_threads(options.threads, || {
            let order = self.leaf_order(queries);
            rows_in_work_order(
                queries.len(),
                queries.len(),
                |w| order[w] as usize,
                |w, row, q| {
                    q.resize(self.dim, T::ZERO);
                    queries.read_point(order[w] as usize, q);
                    self.search(Query::point(q), nbhd, row)
                        .map_err(|e| e.for_query(order[w] as usize))
                },
            )
        })?
    }

    /// The query indices of `queries` ordered by the first tree position of the leaf each falls
    /// into, ties by index (a counting sort: two passes over the queries).
    fn leaf_order(&self, queries: &PointsView<'_>) -> Vec<u32> {
        if self.is_empty() {
            return (0..queries.len() as u32).collect(); // one leaf, of no point
        }
        let leaf_of: Vec<u32> = (0..queries.len())
            .into_par_iter()
            .map_init(Vec::new, |q, i| {
                q.resize(self.dim, T::ZERO);
                queries.read_point(i, q);
                self.leaf_start(q)
            })
            .collect();
        let mut starts = vec![0u32; self.len() + 1];
        for &l in &leaf_of {
            starts[l as usize + 1] += 1;
        }
        for p in 0..self.len() {
            starts[p + 1] += starts[p];
        }
        let mut order = vec![0u32; queries.len()];
        for (i, &l) in leaf_of.iter().enumerate() {
            order[starts[l as usize] as usize] = i as u32;
            starts[l as usize] += 1;
        }
        order
    }

    /// The first tree position of the leaf `q` descends to (a non-finite coordinate takes
    /// some path; such a query is refused when it is answered).
    fn leaf_start(&self, q: &[T]) -> u32 {
        let mut node = 0;
        loop {
            let n = &self.nodes[node];
            if n.is_leaf() {
                return n.a;
            }
            node = if q[n.dim as usize] < n.split {
                node + 1
            } else {
                n.a as usize
            };
        }
    }
}
