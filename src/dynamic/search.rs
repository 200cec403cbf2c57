//! The forest's traversals, its part of the one query family (`src/index/`): one result set
//! filled by the descents of every tree (`src/tree/search.rs`, thesis Algorithm 9), the trees'
//! caller indices shifted to the forest's indices and removed points left out; the box
//! descents of every tree likewise; the forest's points in its trees' orders for its tables.

use super::{bit, DynamicKdTree};
use crate::error::Result;
use crate::index::{self, NeighborIndex, StoredPoints};
use crate::metric::{Measure, Norm, NormUser, Period, L2};
use crate::query::result_set::ResultSet;
use crate::query::{order, resolve_query, Neighbor, NeighborSearch, Neighborhood, Query};
use crate::scalar::Scalar;
use crate::table::NeighborTable;
use crate::tree::KdTree;

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

/// The key (under `norm`; squared distance for [`L2`]) from `q` to the box `[lo, hi]`, a lower
/// bound of the key the search computes to any point in it: per dimension the gap is a
/// difference of the query and a box face, which rounds to at most the point's difference
/// (rounding is monotone), and the terms are folded in the same order as the point's key.
#[inline]
fn box_key<T: Scalar, N: Norm<T>>(norm: N, q: &[T], lo: &[T], hi: &[T]) -> T {
    let mut s = T::ZERO;
    for j in 0..q.len() {
        let t = if q[j] < lo[j] {
            lo[j] - q[j]
        } else if q[j] > hi[j] {
            q[j] - hi[j]
        } else {
            continue;
        };
        s = norm.fold(s, norm.term(t));
    }
    norm.lower(s)
}

/// A batch is answered in groups when it holds at least 1/`DENSE` as many queries as there
/// are live points (a frame of 10k among 100k live points in the sliding-window benchmark was
/// slower grouped).
const DENSE: usize = 2;

impl<T: Scalar> DynamicKdTree<T> {
    /// Offers every live point that may enter `set` (except the index `exclude`): the trees in
    /// turn, oldest (largest) first, each skipped if its bounding box lies beyond the bound.
    fn collect<C: ResultSet<T>>(&self, q: &[T], exclude: Option<u32>, set: &mut C) {
        self.collect_norm(q, exclude, L2, set);
    }

    /// [`DynamicKdTree::collect`] under the norm `norm` (`src/metric.rs`).
    fn collect_norm<C: ResultSet<T>, N: Norm<T>>(
        &self,
        q: &[T],
        exclude: Option<u32>,
        norm: N,
        set: &mut C,
    ) {
        for part in &self.parts {
            let key = match &self.period {
                None => box_key(norm, q, &part.bbox_lo, &part.bbox_hi),
                Some(period) => period.box_key(norm, q, &part.bbox_lo, &part.bbox_hi),
            };
            if key > set.bound() {
                continue;
            }
            let local = exclude
                .filter(|&e| e >= part.lo && e < part.hi)
                .map(|e| e - part.lo);
            if part.dead == 0 {
                let mut s = Shift { set, lo: part.lo };
                part.tree.search_into_norm(q, local, norm, &mut s);
            } else {
                let mut s = ShiftLive {
                    set,
                    lo: part.lo,
                    not_live: &self.not_live,
                };
                part.tree.search_into_norm(q, local, norm, &mut s);
            }
        }
    }

    /// The tree the regions of a batch of queries are taken from: the largest.
    fn largest(&self) -> Option<&KdTree<T>> {
        self.parts.iter().map(|p| &*p.tree).max_by_key(|t| t.len())
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
        index::search(self, query, nbhd, out)
    }
}

/// The forest's part of the one query family (`src/index/`): every query is the static tree's,
/// the forest's traversals visiting each of its trees; tables have one row per index given
/// (`next_index()` rows; points not live get empty rows), and a dense batch of queries is
/// answered in groups of nearby queries (`batch.rs`).
impl<T: Scalar> NeighborIndex<T> for DynamicKdTree<T> {
    fn len(&self) -> usize {
        self.live
    }

    fn resolve<'q>(&'q self, query: Query<'q, T>) -> Result<(&'q [T], Option<u32>)> {
        match query {
            Query::Point { .. } => resolve_query(query, self.dim, self.next as usize, &[], |_| &[]),
            Query::Stored {
                index,
                exclude_self,
            } => {
                self.check_live(index)?;
                Ok((self.stored(index), exclude_self.then_some(index)))
            }
        }
    }

    #[inline]
    fn visit<C: ResultSet<T>>(&self, q: &[T], exclude: Option<u32>, set: &mut C) {
        self.collect(q, exclude, set);
    }

    fn visit_with<C: ResultSet<T>>(
        &self,
        q: &[T],
        exclude: Option<u32>,
        measure: &Measure,
        set: &mut C,
    ) {
        struct Collect<'a, T, C> {
            forest: &'a DynamicKdTree<T>,
            q: &'a [T],
            exclude: Option<u32>,
            set: &'a mut C,
        }
        impl<T: Scalar, C: ResultSet<T>> NormUser<T> for Collect<'_, T, C> {
            type Out = ();
            fn with<N: Norm<T>>(self, norm: N) {
                self.forest
                    .collect_norm(self.q, self.exclude, norm, self.set);
            }
        }
        measure.apply(Collect {
            forest: self,
            q,
            exclude,
            set,
        });
    }

    fn period(&self) -> Option<&Period<T>> {
        self.period.as_ref()
    }

    fn visit_box(&self, min: &[T], max: &[T], scratch: &mut Vec<T>, out: &mut Vec<u32>) {
        for part in &self.parts {
            let outside =
                (0..self.dim).any(|j| part.bbox_hi[j] < min[j] || part.bbox_lo[j] > max[j]);
            if outside {
                continue;
            }
            let from = out.len();
            part.tree.collect_in_box(min, max, scratch, out);
            let mut kept = from;
            for i in from..out.len() {
                let g = out[i] + part.lo;
                if part.dead == 0 || !bit(&self.not_live, g) {
                    out[kept] = g;
                    kept += 1;
                }
            }
            out.truncate(kept);
        }
    }

    fn with_stored<R>(&self, f: impl FnOnce(&StoredPoints<'_, T>) -> R) -> R {
        let work: Vec<u32> = self
            .parts
            .iter()
            .flat_map(|p| p.tree.tree_order().iter().map(move |&i| i + p.lo))
            .filter(|&g| !bit(&self.not_live, g))
            .collect();
        f(&StoredPoints {
            len: work.len(),
            at: &|w| (work[w], self.stored(work[w])),
        })
    }

    fn region_key(&self, q: &[T]) -> u32 {
        self.largest().map_or(0, |t| t.leaf_position(q))
    }

    fn region_keys(&self) -> usize {
        self.largest().map_or(1, |t| t.len())
    }

    fn grouped_batch(
        &self,
        queries: &[T],
        order: &[u32],
        keys: &[u32],
        nbhd: Neighborhood<T>,
    ) -> Option<Result<NeighborTable<T>>> {
        // Grouped only for dense batches: measured (`benches/dynamic.rs`) 1.2x the static
        // tree's per-query batch with as many queries as points, but 1.9x for a frame of
        // 10k queries against 300k points, where groups are far apart and preparing the
        // trees' cells is not repaid; such batches take the single-query descents.
        let dense = order.len().saturating_mul(DENSE) >= self.live;
        if !dense || self.parts.is_empty() {
            return None;
        }
        match self.dim {
            3 => Some(self.grouped_rows::<3>(queries, order, keys, nbhd)),
            2 => Some(self.grouped_rows::<2>(queries, order, keys, nbhd)),
            1 => Some(self.grouped_rows::<1>(queries, order, keys, nbhd)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::query::NeighborHeap;
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
