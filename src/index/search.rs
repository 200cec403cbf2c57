//! The single search of every index (thesis Algorithm 9): the query's checks, then the result
//! set the neighbourhood asks for, filled by the flavour's one traversal
//! ([`NeighborIndex::visit`]). Which set serves which query, and how its contents become the
//! caller's vector, is decided here for both flavours.

use super::NeighborIndex;
use crate::error::Result;
use crate::query::order::PackedKey;
use crate::query::result_set::{KnnBuf, KnnRow, RowKey, WithinRadius};
use crate::query::{Neighbor, NeighborHeap, Neighborhood, Plan, Query, QueryOptions};
use crate::scalar::{Scalar, ScalarType};

/// [`NeighborIndex::search_with`]: the neighbourhood of `query` under `options`.
pub(crate) fn search_with<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    query: Query<'_, T>,
    nbhd: Neighborhood<T>,
    options: &QueryOptions,
    out: &mut Vec<Neighbor<T>>,
) -> Result<()> {
    let plan = options.plan(nbhd)?;
    let (q, exclude) = index.resolve(query)?;
    answer_with(index, q, exclude, &plan, out);
    Ok(())
}

/// The search proper under a plan ([`QueryOptions`] resolved): the plain queries' paths for the
/// default options on an index without a period, else a heap (k nearest) or a list (radius)
/// filled by the flavour's traversal under the plan's measure ([`NeighborIndex::visit_with`]),
/// the query wrapped into the index's box first if it has one.
#[inline]
pub(crate) fn answer_with<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    q: &[T],
    exclude: Option<u32>,
    plan: &Plan<T>,
    out: &mut Vec<Neighbor<T>>,
) {
    if plan.plain && index.period().is_none() {
        return answer(index, q, exclude, plan.nbhd, out);
    }
    answer_measured(index, q, exclude, plan, out);
}

/// The measured search of [`answer_with`], `q` wrapped into the index's box if it has one. Kept
/// out of line: inlined, its body made `answer_with` too large to inline into the tables' row
/// loops, which cost the default path a call per row (callgrind, docs/speed-log.md).
#[inline(never)]
fn answer_measured<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    q: &[T],
    exclude: Option<u32>,
    plan: &Plan<T>,
    out: &mut Vec<Neighbor<T>>,
) {
    match index.period() {
        None => measured(index, q, exclude, plan, out),
        Some(period) if q.len() <= 8 => {
            let mut w = [T::ZERO; 8];
            period.wrap(q, &mut w[..q.len()]);
            measured(index, &w[..q.len()], exclude, plan, out)
        }
        Some(period) => {
            let mut w = vec![T::ZERO; q.len()];
            period.wrap(q, &mut w);
            measured(index, &w, exclude, plan, out)
        }
    }
}

/// A heap (k nearest) or a list (radius) filled by the flavour's traversal under the plan's
/// measure, for `q` (wrapped into the index's box if it has one).
fn measured<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    q: &[T],
    exclude: Option<u32>,
    plan: &Plan<T>,
    out: &mut Vec<Neighbor<T>>,
) {
    if plan.k == usize::MAX {
        out.clear();
        let mut within = WithinRadius {
            out,
            sq_radius: plan.bound,
        };
        index.visit_with(q, exclude, &plan.measure, &mut within);
        if plan.nbhd.is_sorted() {
            out.sort_unstable_by(|a, b| a.cmp_by_distance(b));
        }
    } else {
        let mut heap = NeighborHeap::new(out, plan.k, plan.bound);
        index.visit_with(q, exclude, &plan.measure, &mut heap);
        heap.finish();
    }
}

/// Writes the neighbourhood of `query` into `out` (cleared first), ordered by
/// `(sq_dist, index)` unless an unsorted radius query was asked for: the body of
/// `NeighborSearch::search` for every flavour.
pub(crate) fn search<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    query: Query<'_, T>,
    nbhd: Neighborhood<T>,
    out: &mut Vec<Neighbor<T>>,
) -> Result<()> {
    if index.period().is_some() {
        return search_with(index, query, nbhd, &QueryOptions::DEFAULT, out);
    }
    nbhd.validate()?;
    let (q, exclude) = index.resolve(query)?;
    answer(index, q, exclude, nbhd, out);
    Ok(())
}

/// The search proper, on a validated neighbourhood and a resolved query: `q` of the index's
/// dimension, finite.
#[inline]
pub(crate) fn answer<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    q: &[T],
    exclude: Option<u32>,
    nbhd: Neighborhood<T>,
    out: &mut Vec<Neighbor<T>>,
) {
    let (k, sq_radius) = nbhd.limits();
    if k == usize::MAX {
        out.clear();
        index.visit(q, exclude, &mut WithinRadius { out, sq_radius });
        if nbhd.is_sorted() {
            out.sort_unstable_by(|a, b| a.cmp_by_distance(b));
        }
    } else if k <= SORTED_MAX_K {
        match T::TYPE {
            ScalarType::F32 => search_packed::<T, u64, I>(index, q, exclude, k, sq_radius, out),
            ScalarType::F64 => search_packed::<T, u128, I>(index, q, exclude, k, sq_radius, out),
        }
    } else {
        let mut heap = NeighborHeap::new(out, k, sq_radius);
        index.visit(q, exclude, &mut heap);
        heap.finish();
    }
}

/// Single kNN queries up to this `k` keep their candidates on the call stack, as packed keys
/// (`src/query/order.rs`: `u64` for `f32`, `u128` for `f64`), sorted in a [`KnnRow`] up to
/// [`RowKey::ROW_MAX_K`], unsorted in a [`KnnBuf`] above; larger ones in a heap in the result
/// vector.
const SORTED_MAX_K: usize = 32;

/// A kNN search (`k ≤ SORTED_MAX_K`) into a [`KnnRow`] or a [`KnnBuf`] of packed keys `K` on
/// the call stack, copied to `out` at the end: a candidate costs one-integer compares and a
/// short shift or a store, and the result needs no sort.
fn search_packed<T: Scalar, K: RowKey + PackedKey<T>, I: NeighborIndex<T>>(
    index: &I,
    q: &[T],
    exclude: Option<u32>,
    k: usize,
    sq_radius: T,
    out: &mut Vec<Neighbor<T>>,
) {
    let pair = |e: &K| {
        let (sq_dist, index) = e.pair();
        Neighbor { index, sq_dist }
    };
    if k <= K::ROW_MAX_K {
        let mut buf = [K::default(); SORTED_MAX_K];
        let mut row = KnnRow::new(&mut buf[..k], sq_radius);
        index.visit(q, exclude, &mut row);
        out.clear();
        out.extend(row.held().map(|e| pair(&e)));
    } else {
        let mut buf = [K::default(); 2 * SORTED_MAX_K];
        let mut set = KnnBuf::new(&mut buf[..2 * k], k, sq_radius);
        index.visit(q, exclude, &mut set);
        out.clear();
        out.extend(set.finish().iter().map(pair));
    }
}
