//! The brute-force baseline (thesis Algorithm 7): every point is a candidate. O(n) per query;
//! the oracle of the tests.

use super::{Neighbor, NeighborHeap, NeighborSearch, Neighborhood, Query, QueryOptions};
use crate::error::Result;
use crate::metric::{Norm, NormUser};
use crate::packed::{NonFinitePolicy, PackedPoints};
use crate::points::PointsView;
use crate::query::resolve_query;
use crate::scalar::Scalar;

/// Answers every query by scanning all points.
#[derive(Clone, Debug)]
pub struct BruteForce<T> {
    packed: PackedPoints<T>,
    slot_of: Vec<u32>,
}

impl<T: Scalar> BruteForce<T> {
    /// Copies the points of `view` (non-finite points handled by `policy`).
    pub fn new(view: &PointsView<'_>, policy: NonFinitePolicy) -> Result<Self> {
        let packed = PackedPoints::from_view(view, policy)?;
        let slot_of = packed.slots_by_caller_index();
        Ok(Self { packed, slot_of })
    }
}

/// Squared Euclidean distance.
#[inline]
pub(crate) fn sq_dist<T: Scalar>(a: &[T], b: &[T]) -> T {
    a.iter().zip(b).fold(T::ZERO, |acc, (&x, &y)| {
        let d = x - y;
        acc + d * d
    })
}

impl<T: Scalar> NeighborSearch<T> for BruteForce<T> {
    fn dim(&self) -> usize {
        self.packed.dim
    }

    fn source_len(&self) -> usize {
        self.packed.source_len
    }

    fn search(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        nbhd.validate()?;
        let packed = &self.packed;
        let (q, exclude) =
            resolve_query(query, packed.dim, packed.source_len, &self.slot_of, |s| {
                packed.point(s)
            })?;
        let (k, sq_radius) = nbhd.limits();
        let mut heap = NeighborHeap::new(out, k, sq_radius);
        for slot in 0..packed.len() {
            let id = packed.ids[slot];
            if Some(id) != exclude {
                heap.push(id, sq_dist(q, packed.point(slot)));
            }
        }
        if nbhd.is_sorted() {
            heap.finish();
        }
        Ok(())
    }
}

impl<T: Scalar> BruteForce<T> {
    /// The exact neighbourhood of `query` under `options`' metric and strictness, ordered by
    /// `(sq_dist, index)` unless an unsorted radius query was asked for: the reference of
    /// `NeighborIndex::search_with` (`src/index/`). Every key is folded
    /// over the axes in order, as the tree folds it, so keys are bit-identical. `eps` is
    /// checked but not used (the exact answer is within every approximation), except that a
    /// radius admits keys up to that of `r · (1 + eps)`, as an approximate tree search does.
    pub fn search_with(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        options: &QueryOptions,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        let plan = options.plan(nbhd)?;
        let packed = &self.packed;
        let (q, exclude) =
            resolve_query(query, packed.dim, packed.source_len, &self.slot_of, |s| {
                packed.point(s)
            })?;
        struct Scan<'a, T> {
            packed: &'a PackedPoints<T>,
            q: &'a [T],
            exclude: Option<u32>,
            heap: NeighborHeap<'a, T>,
        }
        impl<T: Scalar> NormUser<T> for Scan<'_, T> {
            type Out = ();
            fn with<N: Norm<T>>(mut self, norm: N) {
                let d = self.packed.dim;
                for slot in 0..self.packed.len() {
                    let id = self.packed.ids[slot];
                    if Some(id) != self.exclude {
                        let key = norm.key(self.q, self.packed.point(slot), d);
                        self.heap.push(id, key);
                    }
                }
            }
        }
        plan.measure.apply(Scan {
            packed,
            q,
            exclude,
            heap: NeighborHeap::new(out, plan.k, plan.bound),
        });
        if plan.nbhd.is_sorted() {
            out.sort_unstable_by(|a, b| a.cmp_by_distance(b));
        }
        Ok(())
    }

    /// The caller's indices of all points in the closed box `min ≤ x ≤ max`, ascending (the
    /// convention of `src/query/in_box.rs`), by testing every point: the reference of the
    /// tree's box query.
    pub fn in_box(&self, min: &[T], max: &[T], out: &mut Vec<u32>) -> Result<()> {
        super::in_box::check_box(min, max, self.packed.dim, None)?;
        out.clear();
        for slot in 0..self.packed.len() {
            if super::in_box::in_closed_box(self.packed.point(slot), min, max) {
                out.push(self.packed.ids[slot]);
            }
        }
        out.sort_unstable();
        Ok(())
    }
}
