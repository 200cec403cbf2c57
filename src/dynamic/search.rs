//! Queries on the forest: one result set filled by the descents of every tree
//! (`src/tree/search.rs`, thesis Algorithm 9), the trees' caller indices shifted to the
//! forest's indices and removed points left out; the all-point tables and the batch tables
//! through the table writer of `src/table.rs`.

use rayon::prelude::*;

use super::{bit, DynamicKdTree};
use crate::error::{NbhdError, Result};
use crate::parallel::with_threads;
use crate::points::PointsView;
use crate::query::result_set::{ResultSet, WithinRadius};
use crate::query::{order, resolve_query, Neighbor, NeighborHeap, NeighborSearch};
use crate::query::{Neighborhood, Query};
use crate::scalar::Scalar;
use crate::table::{check_knn_total, rows_in_work_order, NeighborTable, TableOptions};

/// A tree's view of the forest-wide result set: the tree's caller index `i` is the forest's
/// index `lo + i` (an increasing map, so the `(sq_dist, index)` order is the same).
/// `worst_key` is in forest indices; `offer` and `insert` shift before comparing or storing.
struct Shift<'a, C> {
    set: &'a mut C,
    lo: u32,
}

impl<T: Scalar, C: ResultSet<T>> ResultSet<T> for Shift<'_, C> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        self.set.worst_key()
    }
    #[inline(always)]
    fn bound(&self) -> T {
        self.set.bound()
    }
    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        self.set.insert(index + self.lo, sq_dist)
    }
    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        self.set.offer(index + self.lo, sq_dist)
    }
}

/// [`Shift`] for a tree holding removed points: a candidate that would enter is dropped if it
/// is not live (the liveness bit is read only for candidates that would enter).
struct ShiftLive<'a, C> {
    set: &'a mut C,
    lo: u32,
    not_live: &'a [u64],
}

impl<T: Scalar, C: ResultSet<T>> ResultSet<T> for ShiftLive<'_, C> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        self.set.worst_key()
    }
    #[inline(always)]
    fn bound(&self) -> T {
        self.set.bound()
    }
    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        self.set.insert(index + self.lo, sq_dist)
    }
    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        let g = index + self.lo;
        if order::precedes((sq_dist, g), self.set.worst_key()) && !bit(self.not_live, g) {
            self.set.insert(g, sq_dist);
        }
    }
}

/// Squared distance from `q` to the box `[lo, hi]`, a lower bound of the squared distance the
/// search computes to any point in it: per dimension the gap is a difference of the query and
/// a box face, which rounds to at most the point's difference (rounding is monotone), and the
/// squares are summed in the same order as the point distance.
#[inline]
fn box_sq_dist<T: Scalar>(q: &[T], lo: &[T], hi: &[T]) -> T {
    let mut s = T::ZERO;
    for j in 0..q.len() {
        let t = if q[j] < lo[j] {
            lo[j] - q[j]
        } else if q[j] > hi[j] {
            q[j] - hi[j]
        } else {
            continue;
        };
        s = s + t * t;
    }
    s
}

impl<T: Scalar> DynamicKdTree<T> {
    /// Offers every live point that may enter `set` (except the index `exclude`): the trees in
    /// turn, oldest (largest) first, each skipped if its bounding box lies beyond the bound.
    fn collect<C: ResultSet<T>>(&self, q: &[T], exclude: Option<u32>, set: &mut C) {
        for part in &self.parts {
            if box_sq_dist(q, &part.bbox_lo, &part.bbox_hi) > set.bound() {
                continue;
            }
            let local = exclude
                .filter(|&e| e >= part.lo && e < part.hi)
                .map(|e| e - part.lo);
            if part.dead == 0 {
                let mut s = Shift { set, lo: part.lo };
                part.tree.search_into(q, local, &mut s);
            } else {
                let mut s = ShiftLive {
                    set,
                    lo: part.lo,
                    not_live: &self.not_live,
                };
                part.tree.search_into(q, local, &mut s);
            }
        }
    }

    /// The search proper, on a validated query.
    fn search_resolved(
        &self,
        q: &[T],
        exclude: Option<u32>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) {
        let (k, sq_radius) = nbhd.limits();
        if k == usize::MAX {
            out.clear();
            self.collect(q, exclude, &mut WithinRadius { out, sq_radius });
            if nbhd.is_sorted() {
                out.sort_unstable_by(|a, b| a.cmp_by_distance(b));
            }
        } else {
            let mut heap = NeighborHeap::new(out, k, sq_radius);
            self.collect(q, exclude, &mut heap);
            heap.finish();
        }
    }

    /// The `k` nearest live points to `query`, by `(sq_dist, index)`.
    pub fn knn(&self, query: Query<'_, T>, k: usize, out: &mut Vec<Neighbor<T>>) -> Result<()> {
        self.search(query, Neighborhood::Knn { k }, out)
    }

    /// All live points within `radius` (inclusive) of `query`, by `(sq_dist, index)`.
    pub fn radius(&self, query: Query<'_, T>, radius: T, out: &mut Vec<Neighbor<T>>) -> Result<()> {
        self.search(
            query,
            Neighborhood::Radius {
                radius,
                sorted: true,
            },
            out,
        )
    }

    /// The ε-k-neighbourhood: the `k` nearest among the live points within `radius`.
    pub fn knn_radius(
        &self,
        query: Query<'_, T>,
        k: usize,
        radius: T,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        self.search(query, Neighborhood::KnnRadius { k, radius }, out)
    }

    /// The neighbourhood of every live point, row `i` for index `i` (`next_index()` rows;
    /// points not live get empty rows), computed in parallel in tree order; identical bytes
    /// for any thread count, and those of a static tree over the live points.
    pub fn neighborhoods(
        &self,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        nbhd.validate()?;
        check_knn_total(self.live, self.live, nbhd, options.exclude_self)?;
        with_threads(options.threads, || {
            let work: Vec<u32> = self
                .parts
                .iter()
                .flat_map(|p| p.tree.tree_order().iter().map(move |&i| i + p.lo))
                .filter(|&g| !bit(&self.not_live, g))
                .collect();
            rows_in_work_order(
                self.next as usize,
                work.len(),
                |w| work[w] as usize,
                |w, row, _| {
                    let g = work[w];
                    let exclude = options.exclude_self.then_some(g);
                    self.search_resolved(self.stored(g), exclude, nbhd, row);
                    Ok(())
                },
            )
        })?
    }

    /// The neighbourhoods of a batch of query points (row `i` for query `i`), computed in
    /// parallel in the order of the leaves of the largest tree they fall into, written back in
    /// the queries' order; identical for any thread count. `options.exclude_self` does not
    /// apply.
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
        check_knn_total(queries.len(), self.live, nbhd, false)?;
        with_threads(options.threads, || {
            let order = self.query_order(queries);
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

    /// The query indices ordered by the first position of the leaf of the largest tree each
    /// falls into, ties by index (a counting sort).
    fn query_order(&self, queries: &PointsView<'_>) -> Vec<u32> {
        let Some(big) = self.parts.iter().max_by_key(|p| p.tree.len()) else {
            return (0..queries.len() as u32).collect();
        };
        let tree = &big.tree;
        let leaf_of: Vec<u32> = (0..queries.len())
            .into_par_iter()
            .map_init(Vec::new, |q, i| {
                q.resize(self.dim, T::ZERO);
                queries.read_point(i, q);
                tree.leaf_position(q)
            })
            .collect();
        let mut starts = vec![0u32; tree.len() + 1];
        for &l in &leaf_of {
            starts[l as usize + 1] += 1;
        }
        for p in 0..tree.len() {
            starts[p + 1] += starts[p];
        }
        let mut order = vec![0u32; queries.len()];
        for (i, &l) in leaf_of.iter().enumerate() {
            order[starts[l as usize] as usize] = i as u32;
            starts[l as usize] += 1;
        }
        order
    }
}

impl<T: Scalar> NeighborSearch<T> for DynamicKdTree<T> {
    fn dim(&self) -> usize {
        self.dim
    }

    /// The indices given so far (`next_index()`).
    fn source_len(&self) -> usize {
        self.next as usize
    }

    fn search(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        nbhd.validate()?;
        match query {
            Query::Point { .. } => {
                let (q, exclude) =
                    resolve_query(query, self.dim, self.next as usize, &[], |_| &[])?;
                self.search_resolved(q, exclude, nbhd, out);
            }
            Query::Stored {
                index,
                exclude_self,
            } => {
                self.check_live(index)?;
                let exclude = exclude_self.then_some(index);
                self.search_resolved(self.stored(index), exclude, nbhd, out);
            }
        }
        Ok(())
    }
}
