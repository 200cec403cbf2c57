//! Tables: the neighbourhoods of every held point, of a list of held points, or of a batch of
//! query points, as a [`NeighborTable`], computed in parallel in an order that keeps the cache
//! warm and written back in the caller's order (`src/table.rs`). A flavour's grouped search
//! answers where it has one ([`NeighborIndex::grouped_table`],
//! [`NeighborIndex::grouped_batch`]); otherwise each row is one single search, the rows the
//! grouped searches give too. Under non-default [`QueryOptions`](crate::QueryOptions)
//! (another metric, eps, a strict radius), and on a periodic index, every row is a single
//! search under them.

use rayon::prelude::*;

use super::search::answer_with;
use super::NeighborIndex;
use crate::error::{NbhdError, Result};
use crate::parallel::with_threads;
use crate::points::PointsView;
use crate::query::{Neighbor, Neighborhood, Plan, Query};
use crate::scalar::Scalar;
use crate::table::{check_knn_total, rows_in_work_order, NeighborTable, TableOptions};

/// [`NeighborIndex::neighborhoods`].
pub(super) fn neighborhoods<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    nbhd: Neighborhood<T>,
    options: &TableOptions,
) -> Result<NeighborTable<T>> {
    let plan = options.query.plan(nbhd)?;
    check_knn_total(index.len(), index.len(), nbhd, options.exclude_self)?;
    with_threads(options.threads, || {
        if plan.plain && index.period().is_none() {
            if let Some(table) = index.grouped_table(nbhd, options.exclude_self) {
                return table;
            }
        }
        search_each_held(index, index, &plan, options.exclude_self, |_, _| {})
    })?
}

/// One search of `index` per point held by `source` (`index` itself, or another index of the
/// same points' type), run in `source`'s stored order — neighbouring points touch the same
/// nodes and leaves, so they hit the cache — and written back as the rows of `source`'s caller
/// indices. `exclude_self` leaves each point out of its own row; `finish(i, row)` sees the row
/// of caller index `i` after its search. Runs on the current rayon pool.
pub(super) fn search_each_held<T: Scalar, I: NeighborIndex<T>, S: NeighborIndex<T>>(
    index: &I,
    source: &S,
    plan: &Plan<T>,
    exclude_self: bool,
    finish: impl Fn(u32, &mut Vec<Neighbor<T>>) + Sync,
) -> Result<NeighborTable<T>> {
    source.with_stored(|stored| {
        rows_in_work_order(
            source.source_len(),
            stored.len,
            |w| (stored.at)(w).0 as usize,
            |w, row, _| {
                let (i, q) = (stored.at)(w);
                answer_with(index, q, exclude_self.then_some(i), plan, row);
                finish(i, row);
                Ok(())
            },
        )
    })
}

/// [`NeighborIndex::neighborhoods_at`].
pub(super) fn neighborhoods_at<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    indices: &[u32],
    nbhd: Neighborhood<T>,
    options: &TableOptions,
) -> Result<NeighborTable<T>> {
    let plan = options.query.plan(nbhd)?;
    let query = |i: u32| Query::Stored {
        index: i,
        exclude_self: options.exclude_self,
    };
    for &i in indices {
        index.resolve(query(i))?;
    }
    check_knn_total(indices.len(), index.len(), nbhd, options.exclude_self)?;
    with_threads(options.threads, || {
        rows_in_work_order(
            indices.len(),
            indices.len(),
            |w| w,
            |w, row, _| {
                let (q, exclude) = index.resolve(query(indices[w]))?;
                answer_with(index, q, exclude, &plan, row);
                Ok(())
            },
        )
    })?
}

/// [`NeighborIndex::neighborhoods_of`].
pub(super) fn neighborhoods_of<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    queries: &PointsView<'_>,
    nbhd: Neighborhood<T>,
    options: &TableOptions,
) -> Result<NeighborTable<T>> {
    let plan = options.query.plan(nbhd)?;
    let d = index.dim();
    if queries.dim() != d {
        return Err(NbhdError::DimensionMismatch {
            expected: d,
            got: queries.dim(),
        });
    }
    check_knn_total(queries.len(), index.len(), nbhd, false)?;
    let packed = packed_queries(queries)?;
    let n = queries.len();
    with_threads(options.threads, || {
        let (order, keys) = region_order(index, &packed);
        if plan.plain && index.period().is_none() {
            if let Some(table) = index.grouped_batch(&packed, &order, &keys, nbhd) {
                return table;
            }
        }
        rows_in_work_order(
            n,
            n,
            |w| order[w] as usize,
            |w, row, _| {
                let at = order[w] as usize * d;
                answer_with(index, &packed[at..at + d], None, &plan, row);
                Ok(())
            },
        )
    })?
}

/// The queries as packed coordinates of the index's type, every one finite: the first
/// non-finite one (by position) is [`NbhdError::NonFiniteQuery`].
fn packed_queries<T: Scalar>(queries: &PointsView<'_>) -> Result<Vec<T>> {
    let (n, d) = (queries.len(), queries.dim());
    let mut packed: Vec<T> = Vec::new();
    packed
        .try_reserve_exact(n * d)
        .map_err(|_| NbhdError::OutOfMemory {
            what: "a copy of the query points",
            bytes: (n * d * std::mem::size_of::<T>()) as u128,
        })?;
    packed.resize(n * d, T::ZERO);
    for (i, q) in packed.chunks_exact_mut(d.max(1)).enumerate() {
        queries.read_point(i, q);
        if let Some(coordinate) = q.iter().position(|c| !c.is_finite()) {
            return Err(NbhdError::NonFiniteQuery {
                query: Some(i),
                coordinate,
            });
        }
    }
    Ok(packed)
}

/// The positions of the packed `queries` ordered by the region each falls into
/// ([`NeighborIndex::region_key`]), and those keys in that order. The keys are found in a
/// coarse spatial order of the queries ([`grid_order`]), so that consecutive descents share
/// their path and its nodes stay in the cache; then sorted by key with a counting sort, ties in
/// that spatial order. (In the caller's order, each descent of a large tree missed the cache at
/// its lower levels: the 1M torus' points as queries on their own tree, one thread, took
/// 0.65–0.85 s for their keys alone, 0.2–0.26 s in the grid order — wall times at a load of
/// 13–16 on 2 cores, 2026-11-29.)
pub(super) fn region_order<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    queries: &[T],
) -> (Vec<u32>, Vec<u32>) {
    let d = index.dim();
    let n = queries.len() / d;
    if index.is_empty() {
        return ((0..n as u32).collect(), vec![0; n]);
    }
    let visit = grid_order(queries, d);
    let key_of: Vec<u32> = visit
        .par_iter()
        .map(|&i| index.region_key(&queries[i as usize * d..][..d]))
        .collect();
    let by_key = counting_order(&key_of, index.region_keys());
    let order = by_key.iter().map(|&w| visit[w as usize]).collect();
    let sorted = by_key.iter().map(|&w| key_of[w as usize]).collect();
    (order, sorted)
}

/// Most bits per axis of [`grid_order`]'s cells.
const GRID_BITS: u32 = 10;

/// The positions of the packed `queries` (dimension `d`) in the Morton order of the cells of
/// a grid over their bounding box (in the first three axes), ties by position: about one cell
/// per query, at most [`GRID_BITS`] bits per axis.
fn grid_order<T: Scalar>(queries: &[T], d: usize) -> Vec<u32> {
    let n = queries.len() / d;
    let axes = d.min(3);
    let bits = ((usize::BITS - n.leading_zeros()) / axes as u32).clamp(1, GRID_BITS);
    let (lo, hi) = queries
        .par_chunks_exact(d)
        .fold(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(mut lo, mut hi), q| {
                for j in 0..axes {
                    lo[j] = lo[j].min(q[j].to_f64());
                    hi[j] = hi[j].max(q[j].to_f64());
                }
                (lo, hi)
            },
        )
        .reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(a, b), (c, e)| {
                (
                    std::array::from_fn(|j| a[j].min(c[j])),
                    std::array::from_fn(|j| b[j].max(e[j])),
                )
            },
        );
    let side = f64::from(1u32 << bits);
    // halves, so that no difference overflows; an axis of zero extent is one cell
    let scale: [f64; 3] = std::array::from_fn(|j| {
        let extent = hi[j] * 0.5 - lo[j] * 0.5;
        let s = 0.5 * side / extent;
        if extent > 0.0 && s.is_finite() {
            s
        } else {
            0.0
        }
    });
    let top = (1u32 << bits) - 1;
    let cell_of: Vec<u32> = queries
        .par_chunks_exact(d)
        .map(|q| {
            // the cell's coordinates (a NaN product, of an infinite extent, is cell 0)
            let c: [u32; 3] =
                std::array::from_fn(|j| ((q[j.min(axes - 1)].to_f64() - lo[j]) * scale[j]) as u32);
            let mut code = 0u32;
            for b in (0..bits).rev() {
                for &cj in &c[..axes] {
                    code = code << 1 | (cj.min(top) >> b & 1);
                }
            }
            code
        })
        .collect();
    counting_order(&cell_of, 1 << (bits as usize * axes))
}

/// The positions `0..keys.len()` ordered by their key (each below `buckets`), ties by position:
/// a counting sort, two passes over the keys.
fn counting_order(keys: &[u32], buckets: usize) -> Vec<u32> {
    let mut starts = vec![0u32; buckets + 1];
    for &l in keys {
        starts[l as usize + 1] += 1;
    }
    for p in 0..buckets {
        starts[p + 1] += starts[p];
    }
    let mut order = vec![0u32; keys.len()];
    for (i, &l) in keys.iter().enumerate() {
        order[starts[l as usize] as usize] = i as u32;
        starts[l as usize] += 1;
    }
    order
}
