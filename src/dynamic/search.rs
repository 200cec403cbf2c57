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
/// `worst_key` is in the tree's indices (the descent compares it with the tree's smallest
/// caller index of a cell to prune ties, `src/tree/search.rs`); `offer` and `insert` shift
/// before comparing or storing.
struct Shift<'a, C> {
    set: &'a mut C,
    lo: u32,
}

/// The forest's worst key `(b, w)` in the indices of a tree starting at `lo`: a candidate
/// `(b, lo + i)` precedes `(b, w)` exactly when `i < w - lo`; if `w < lo` none does, and
/// `(b, 0)` admits no tie either. `w = u32::MAX` (a set not full) maps above every index of
/// the tree (they are below `u32::MAX - lo`).
#[inline(always)]
fn local_key<T>((b, w): (T, u32), lo: u32) -> (T, u32) {
    (b, w.saturating_sub(lo))
}

impl<T: Scalar, C: ResultSet<T>> ResultSet<T> for Shift<'_, C> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        local_key(self.set.worst_key(), self.lo)
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

/// [`Shift`] for a tree holding removed points (`worst_key` in the tree's indices too): a
/// candidate that would enter is dropped if it is not live (the liveness bit is read only for candidates that would enter).
struct ShiftLive<'a, C> {
    set: &'a mut C,
    lo: u32,
    not_live: &'a [u64],
}

impl<T: Scalar, C: ResultSet<T>> ResultSet<T> for ShiftLive<'_, C> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        local_key(self.set.worst_key(), self.lo)
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

/// A batch is answered in groups when it holds at least 1/`DENSE` as many queries as there
/// are live points (a frame of 10k among 100k live points in the sliding-window benchmark was
/// slower grouped).
const DENSE: usize = 2;

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
    pub(super) fn search_resolved(
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

    /// The neighbourhoods of a batch of query points (row `i` for query `i`), identical for
    /// any thread count and the rows of single queries. In 1 to 3 dimensions a dense batch (at
    /// least half as many queries as live points) is answered in small
    /// groups of nearby queries, each group descending every tree once
    /// (`src/dynamic/batch.rs`); other batches one by one, in the order of the leaves of the
    /// largest tree they fall into. `options.exclude_self` does not apply.
    ///
    /// Errors: those of the neighbourhood, [`NbhdError::DimensionMismatch`],
    /// [`NbhdError::NonFiniteQuery`] naming the first query (by position) with a non-finite
    /// coordinate, [`NbhdError::OutOfMemory`], [`NbhdError::ThreadPool`].
    pub fn neighborhoods_of(
        &self,
        queries: &PointsView<'_>,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        nbhd.validate()?;
        let d = self.dim;
        if queries.dim() != d {
            return Err(NbhdError::DimensionMismatch {
                expected: d,
                got: queries.dim(),
            });
        }
        check_knn_total(queries.len(), self.live, nbhd, false)?;
        let n = queries.len();
        let mut packed: Vec<T> = Vec::new();
        packed
            .try_reserve_exact(n * d)
            .map_err(|_| NbhdError::OutOfMemory {
                what: "a copy of the query points",
                bytes: (n * d * std::mem::size_of::<T>()) as u128,
            })?;
        packed.resize(n * d, T::ZERO);
        for (i, q) in packed.chunks_exact_mut(d).enumerate() {
            queries.read_point(i, q);
            if let Some(coordinate) = q.iter().position(|c| !c.is_finite()) {
                return Err(NbhdError::NonFiniteQuery {
                    query: Some(i),
                    coordinate,
                });
            }
        }
        with_threads(options.threads, || {
            let (order, leaves) = self.query_order(&packed);
            if self.parts.is_empty() {
                return rows_in_work_order(n, 0, |w| w, |_, _, _| Ok(()));
            }
            // Grouped only for dense batches: measured (`benches/dynamic.rs`) 1.2x the static
            // tree's per-query batch with as many queries as points, but 1.9x for a frame of
            // 10k queries against 300k points, where groups are far apart and preparing the
            // trees' cells is not repaid; such batches take the single-query descents.
            let dense = n.saturating_mul(DENSE) >= self.live;
            match d {
                _ if !dense => {}
                3 => return self.grouped_rows::<3>(&packed, &order, &leaves, nbhd),
                2 => return self.grouped_rows::<2>(&packed, &order, &leaves, nbhd),
                1 => return self.grouped_rows::<1>(&packed, &order, &leaves, nbhd),
                _ => {}
            }
            rows_in_work_order(
                n,
                n,
                |w| order[w] as usize,
                |w, row, _| {
                    let at = order[w] as usize * d;
                    self.search_resolved(&packed[at..at + d], None, nbhd, row);
                    Ok(())
                },
            )
        })?
    }

    /// The indices of the packed `queries` ordered by the first position of the leaf of the
    /// largest tree each falls into, ties by index (a counting sort), and those positions in
    /// that order.
    fn query_order(&self, queries: &[T]) -> (Vec<u32>, Vec<u32>) {
        let n = queries.len() / self.dim;
        let Some(big) = self.parts.iter().max_by_key(|p| p.tree.len()) else {
            return ((0..n as u32).collect(), vec![0; n]);
        };
        let tree = &big.tree;
        let leaf_of: Vec<u32> = queries
            .par_chunks_exact(self.dim)
            .map(|q| tree.leaf_position(q))
            .collect();
        let mut starts = vec![0u32; tree.len() + 1];
        for &l in &leaf_of {
            starts[l as usize + 1] += 1;
        }
        for p in 0..tree.len() {
            starts[p + 1] += starts[p];
        }
        let mut order = vec![0u32; n];
        for (i, &l) in leaf_of.iter().enumerate() {
            order[starts[l as usize] as usize] = i as u32;
            starts[l as usize] += 1;
        }
        let leaves = order.iter().map(|&i| leaf_of[i as usize]).collect();
        (order, leaves)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::BuildOptions;

    /// Counts the candidates offered from the indices `from..` before passing them on.
    struct Counting<'a, C> {
        set: &'a mut C,
        from: u32,
        offered: usize,
    }

    impl<T: Scalar, C: ResultSet<T>> ResultSet<T> for Counting<'_, C> {
        fn worst_key(&self) -> (T, u32) {
            self.set.worst_key()
        }
        fn insert(&mut self, index: u32, sq_dist: T) {
            self.set.insert(index, sq_dist)
        }
        fn offer(&mut self, index: u32, sq_dist: T) {
            self.offered += usize::from(index >= self.from);
            self.set.offer(index, sq_dist)
        }
    }

    #[test]
    fn local_keys_map_forest_ties_to_tree_indices() {
        assert_eq!(local_key((1.0f32, 10), 4), (1.0, 6));
        assert_eq!(local_key((1.0f32, 3), 4), (1.0, 0));
        assert_eq!(local_key((1.0f32, u32::MAX), 7), (1.0, u32::MAX - 7));
    }

    /// Copies of one point in two trees: once the older tree has filled the result with
    /// copies of lower index, no copy of the newer tree can enter at the tie, and its search
    /// prunes the tree by index (nothing offered) — with the forest's key unshifted it would
    /// scan copies whose tree-local indices look small.
    #[test]
    fn index_ties_prune_across_trees() {
        for removed in [false, true] {
            let mut tree = DynamicKdTree::<f32>::new(3, &BuildOptions::default()).unwrap();
            tree.insert_flat(&[0.0; 3 * 2000]).unwrap();
            tree.insert_flat(&[0.0; 3 * 100]).unwrap();
            if removed {
                // a tombstone in the newer tree: its search goes through `ShiftLive`
                tree.remove(&[2050]).unwrap();
            }
            assert_eq!(tree.stats().trees.len(), 2, "two trees");
            let mut out = Vec::new();
            let mut heap = NeighborHeap::new(&mut out, 5, f32::INFINITY);
            let mut counting = Counting {
                set: &mut heap,
                from: 2000,
                offered: 0,
            };
            tree.collect(&[0.0; 3], None, &mut counting);
            let offered = counting.offered;
            heap.finish();
            let got: Vec<u32> = out.iter().map(|n| n.index).collect();
            assert_eq!(got, [0, 1, 2, 3, 4]);
            assert_eq!(offered, 0, "the newer tree is pruned by index");
        }
    }
}
