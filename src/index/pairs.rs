//! Pair queries (scipy's `query_pairs`, `query_ball_tree`, `sparse_distance_matrix`,
//! `count_neighbors`): the pairs of points within a radius of each other, in one index or
//! between two, as tables or counted in bins of radii. Each is the index's single radius search
//! (`search.rs`) run once per point of the other side, under the [`QueryOptions`] of
//! [`TableOptions::query`] — every metric, eps, strict radii — and always measured by the index
//! the method is called on (`self`): its metric and its periodic box, as scipy measures by the
//! tree whose method is called.
//!
//! Results are deterministic and identical for any thread count: tables hold rows in the
//! caller's index order with the other side's indices ascending (not by distance), and counts
//! are exact (integers, or the correctly rounded sum of the weight products, `ExactSum`).
//!
//! Keys, as every query of the crate: `sq_dist` holds the metric's key (squared for Euclidean,
//! the distance for p = 1 and ∞, `Σ |x_j|^p` otherwise); scipy's plain distances are
//! [`Metric::distance_of`](crate::Metric::distance_of) of them.

use rayon::prelude::*;

use super::search::answer_with;
use super::tables::{region_order, search_each_held};
use super::NeighborIndex;
use crate::error::{NbhdError, Result};
use crate::metric::Measure;
use crate::parallel::with_threads;
use crate::query::{Neighborhood, Plan, QueryOptions};
use crate::scalar::Scalar;
use crate::sum::ExactSum;
use crate::table::{NeighborTable, TableOptions};

/// [`NeighborIndex::pairs`].
pub(super) fn pairs<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    radius: T,
    options: &TableOptions,
) -> Result<NeighborTable<T>> {
    let mut plan = options.query.plan(Neighborhood::Radius {
        radius,
        sorted: false,
    })?;
    // eps > 0: cells pruned at the key the pairs are accepted up to, r·(1 + eps), not at
    // r / (1 + eps) — every pair within r·(1 + eps) (`NeighborIndex::pairs`)
    plan.measure.scale = 1.0;
    with_threads(options.threads, || {
        // each pair of leaves once, where the flavour can (the static tree, `self_join.rs`)
        if let Some(table) = index.grouped_pairs(plan.bound, &plan.measure) {
            return table;
        }
        // (the grouped table of every point, halved, measured slower than this on the 1M
        // cube: it finds every pair twice; python/benchmarks/vs_scipy.py)
        search_each_held(index, index, &plan, true, |i, row| {
            row.retain(|nb| nb.index > i);
            row.sort_unstable_by_key(|nb| nb.index);
        })
    })?
}

/// `table` with every row ordered by index (ascending `j`; the keys move with their indices),
/// in place: the rows of the grouped paths come in their own order. One parallel pass on the
/// current pool, blocks of [`ROWS_PER_BLOCK`] rows each.
fn sorted_by_index<T: Scalar>(table: NeighborTable<T>) -> NeighborTable<T> {
    let (offsets, mut indices, mut keys) = table.into_parts();
    let rows = offsets.len() - 1;
    // the blocks' disjoint parts of the entries, cut in row order
    let mut parts = Vec::with_capacity(rows.div_ceil(ROWS_PER_BLOCK));
    let (mut rest_i, mut rest_k) = (&mut indices[..], &mut keys[..]);
    for lo in (0..rows).step_by(ROWS_PER_BLOCK) {
        let hi = (lo + ROWS_PER_BLOCK).min(rows);
        let (block_i, next_i) = rest_i.split_at_mut(offsets[hi] - offsets[lo]);
        let (block_k, next_k) = rest_k.split_at_mut(offsets[hi] - offsets[lo]);
        parts.push((&offsets[lo..=hi], block_i, block_k));
        (rest_i, rest_k) = (next_i, next_k);
    }
    parts
        .into_par_iter()
        .for_each(|(starts, block_i, block_k)| {
            let mut row: Vec<(u32, T)> = Vec::new();
            for w in starts.windows(2) {
                let (a, b) = (w[0] - starts[0], w[1] - starts[0]);
                row.clear();
                row.extend(
                    block_i[a..b]
                        .iter()
                        .copied()
                        .zip(block_k[a..b].iter().copied()),
                );
                row.sort_unstable_by_key(|&(j, _)| j);
                for (&(j, key), (oi, ok)) in row
                    .iter()
                    .zip(block_i[a..b].iter_mut().zip(&mut block_k[a..b]))
                {
                    (*oi, *ok) = (j, key);
                }
            }
        });
    NeighborTable::from_parts(offsets, indices, keys).expect("the same offsets")
}

/// Rows per parallel block of [`sorted_by_index`].
const ROWS_PER_BLOCK: usize = 4096;

/// [`NeighborIndex::pairs_with`].
pub(super) fn pairs_with<T: Scalar, I: NeighborIndex<T>, O: NeighborIndex<T>>(
    index: &I,
    other: &O,
    radius: T,
    options: &TableOptions,
) -> Result<NeighborTable<T>> {
    same_dim(index, other)?;
    let plan = options.query.plan(Neighborhood::Radius {
        radius,
        sorted: false,
    })?;
    with_threads(options.threads, || {
        if plan.plain && index.period().is_none() {
            // the index against itself (scipy's `sparse_distance_matrix(self, r)`): its own
            // grouped table, every point in its own row; a key is the same from either end
            // of a pair (each coordinate difference is negated exactly, then squared)
            if std::ptr::addr_eq(index, other) {
                if let Some(all) = index.grouped_table(plan.nbhd, false) {
                    return Ok(sorted_by_index(all?));
                }
            }
            if let Some(found) = grouped_of_held(index, other, plan.nbhd) {
                // row r: the points of `index` near the r-th held point of `other` (ids[r])
                let (ids, by_other) = found?;
                return transpose(&by_other, index.source_len(), |r| ids[r]);
            }
        }
        // row j: the points of `index` near point j of `other`, found by `index`'s own search
        let by_other = search_each_held(index, other, &plan, false, |_, _| {})?;
        transpose(&by_other, index.source_len(), |j| j as u32)
    })?
}

/// The neighbourhoods in `index` of the points held by `other`, by `index`'s grouped batch
/// path if it has one for them ([`NeighborIndex::grouped_batch`]): the caller indices of
/// `other`'s held points, ascending, and the table of their rows in that order. `None` when
/// there is no such path (or `other` holds no point). On the current pool.
fn grouped_of_held<T: Scalar, I: NeighborIndex<T>, O: NeighborIndex<T>>(
    index: &I,
    other: &O,
    nbhd: Neighborhood<T>,
) -> Option<Result<(Vec<u32>, NeighborTable<T>)>> {
    let d = other.dim();
    let (ids, packed) = other.with_stored(|stored| {
        // the held points by caller index: `at[j]` is j's stored position + 1 (0: not held)
        let mut at = vec![0u32; other.source_len()];
        for w in 0..stored.len {
            at[(stored.at)(w).0 as usize] = w as u32 + 1;
        }
        let ids: Vec<u32> = (0..at.len() as u32)
            .filter(|&j| at[j as usize] > 0)
            .collect();
        let mut packed = Vec::with_capacity(ids.len() * d);
        for &j in &ids {
            packed.extend_from_slice((stored.at)(at[j as usize] as usize - 1).1);
        }
        (ids, packed)
    });
    if ids.is_empty() {
        return None;
    }
    let (order, keys) = region_order(index, &packed);
    let table = index.grouped_batch(&packed, &order, &keys, nbhd)?;
    Some(table.map(|t| (ids, t)))
}

/// The table whose row `i` holds `(j_of(r), key)` for every entry `(i, key)` of row `r` of
/// `table`, `rows` rows (every index of `table` below it); `j_of` ascending in `r`, so each row
/// comes out ordered by `j` (a counting sort).
fn transpose<T: Scalar>(
    table: &NeighborTable<T>,
    rows: usize,
    j_of: impl Fn(usize) -> u32,
) -> Result<NeighborTable<T>> {
    let total = table.total();
    let mut offsets = vec![0usize; rows + 1];
    for &i in table.indices() {
        offsets[i as usize + 1] += 1;
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    let oom = |_| NbhdError::OutOfMemory {
        what: "the table of pairs",
        bytes: total as u128 * (4 + std::mem::size_of::<T>() as u128),
    };
    let mut indices: Vec<u32> = Vec::new();
    indices.try_reserve_exact(total).map_err(oom)?;
    indices.resize(total, 0);
    let mut keys: Vec<T> = Vec::new();
    keys.try_reserve_exact(total).map_err(oom)?;
    keys.resize(total, T::ZERO);
    let mut next = offsets[..rows].to_vec();
    for r in 0..table.len() {
        let j = j_of(r);
        for (&i, &key) in table.indices_of(r).iter().zip(table.sq_dists_of(r)) {
            let at = &mut next[i as usize];
            indices[*at] = j;
            keys[*at] = key;
            *at += 1;
        }
    }
    Ok(NeighborTable::from_parts(offsets, indices, keys).expect("offsets made from the rows"))
}

fn same_dim<T: Scalar, I: NeighborIndex<T>, O: NeighborIndex<T>>(
    index: &I,
    other: &O,
) -> Result<()> {
    if index.dim() != other.dim() {
        return Err(NbhdError::DimensionMismatch {
            expected: index.dim(),
            got: other.dim(),
        });
    }
    Ok(())
}

/// The weights of [`NeighborIndex::weigh_pairs_with`]: per caller index of each side (the
/// length of each is that side's `source_len`), `None` for a weight of 1 on every point.
#[derive(Clone, Copy, Debug, Default)]
pub struct PairWeights<'a> {
    /// The weights of the points of the index the method is called on.
    pub this: Option<&'a [f64]>,
    /// The weights of the points of the other index.
    pub other: Option<&'a [f64]>,
}

/// The radii of a count resolved to keys: `keys` ascending (a copy of the radii's keys sorted),
/// each pair counted in the bin of the first key it does not exceed (scipy's `lower_bound`).
struct Bins<T> {
    keys: Vec<T>,
}

impl<T: Scalar> Bins<T> {
    /// The keys of `radii` under `options` (a negative radius counts no pair, +∞ every pair;
    /// strict: below the radius), checked: no NaN, non-decreasing unless `cumulative`, no eps.
    fn new(radii: &[T], cumulative: bool, options: &QueryOptions) -> Result<(Self, Vec<T>)> {
        options.validate()?;
        if options.eps != 0.0 {
            return Err(NbhdError::InvalidOption {
                name: "eps",
                reason: "pair counts are exact (scipy's count_neighbors has no eps)".into(),
            });
        }
        let metric = options.metric.canonical()?;
        let mut of_radius = Vec::with_capacity(radii.len());
        for &r in radii {
            if r.to_f64().is_nan() {
                return Err(NbhdError::InvalidRadius(f64::NAN));
            }
            let key = if r < T::ZERO {
                T::ZERO - T::INFINITY
            } else {
                metric.key_of(r)
            };
            of_radius.push(if options.strict { key.next_down() } else { key });
        }
        if !cumulative && of_radius.windows(2).any(|w| w[1] < w[0]) {
            return Err(NbhdError::InvalidOption {
                name: "radii",
                reason: "non-cumulative counts need non-decreasing radii".into(),
            });
        }
        let mut keys = of_radius.clone();
        keys.sort_unstable_by(|a, b| a.partial_cmp(b).expect("no NaN key"));
        Ok((Self { keys }, of_radius))
    }

    /// The bin of a pair's key, `None` beyond the largest radius.
    #[inline]
    fn of(&self, key: T) -> Option<usize> {
        let b = self.keys.partition_point(|&k| k < key);
        (b < self.keys.len()).then_some(b)
    }

    /// The per-radius answer from the per-bin sums: for radius `k` (key `of_radius[k]`) the
    /// sum of the bins up to its key (cumulative), or its own bin — the first of equal radii
    /// holds the count, the others 0, as scipy (`of_radius` is then non-decreasing).
    fn per_radius<S: Clone>(
        &self,
        of_radius: &[T],
        bins: &[S],
        cumulative: bool,
        zero: S,
        add: impl Fn(&mut S, &S),
    ) -> Vec<S> {
        let mut prefix = vec![zero.clone()];
        for b in bins {
            let mut next = prefix.last().expect("prefix starts with zero").clone();
            add(&mut next, b);
            prefix.push(next);
        }
        let mut out = Vec::with_capacity(of_radius.len());
        for (k, &key) in of_radius.iter().enumerate() {
            let first = self.keys.partition_point(|&s| s < key);
            out.push(if cumulative {
                prefix[self.keys.partition_point(|&s| s <= key)].clone()
            } else if k > 0 && of_radius[k - 1] == key {
                zero.clone()
            } else {
                bins[first].clone()
            });
        }
        out
    }
}

/// Runs `index`'s search of every point of `other` out to the largest key of `bins` and hands
/// each pair `(i of index, j of other, bin)` to `add` on a per-worker accumulator made by
/// `zero`; the accumulators are merged by `merge` (order-independent sums: the result is the
/// same for any thread count).
fn binned<T, I, O, A>(
    index: &I,
    other: &O,
    bins: &Bins<T>,
    options: &TableOptions,
    zero: impl Fn() -> A + Sync + Send,
    add: impl Fn(&mut A, u32, u32, usize) + Sync + Send,
    merge: impl Fn(A, A) -> A + Sync + Send,
) -> Result<A>
where
    T: Scalar,
    I: NeighborIndex<T>,
    O: NeighborIndex<T>,
    A: Send,
{
    same_dim(index, other)?;
    let Some(&bound) = bins.keys.last().filter(|&&b| b >= T::ZERO) else {
        return Ok(zero());
    };
    let plan = Plan {
        nbhd: Neighborhood::Radius {
            radius: T::ZERO,
            sorted: false,
        },
        plain: false,
        k: usize::MAX,
        bound,
        measure: Measure {
            metric: options.query.metric.canonical()?,
            scale: 1.0,
        },
    };
    with_threads(options.threads, || {
        other.with_stored(|stored| {
            (0..stored.len)
                .into_par_iter()
                .fold(
                    || (zero(), Vec::new()),
                    |(mut acc, mut row), w| {
                        let (j, q) = (stored.at)(w);
                        answer_with(index, q, None, &plan, &mut row);
                        for nb in &row {
                            if let Some(b) = bins.of(nb.sq_dist) {
                                add(&mut acc, nb.index, j, b);
                            }
                        }
                        (acc, row)
                    },
                )
                .map(|(acc, _)| acc)
                .reduce(&zero, &merge)
        })
    })
}

/// [`NeighborIndex::count_pairs_with`].
pub(super) fn count_pairs_with<T: Scalar, I: NeighborIndex<T>, O: NeighborIndex<T>>(
    index: &I,
    other: &O,
    radii: &[T],
    cumulative: bool,
    options: &TableOptions,
) -> Result<Vec<u64>> {
    let (bins, of_radius) = Bins::new(radii, cumulative, &options.query)?;
    let n = bins.keys.len();
    let counts = binned(
        index,
        other,
        &bins,
        options,
        || vec![0u64; n],
        |acc, _, _, b| acc[b] += 1,
        |mut a, b| {
            a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
            a
        },
    )?;
    Ok(bins.per_radius(&of_radius, &counts, cumulative, 0, |a, b| *a += b))
}

/// [`NeighborIndex::weigh_pairs_with`].
pub(super) fn weigh_pairs_with<T: Scalar, I: NeighborIndex<T>, O: NeighborIndex<T>>(
    index: &I,
    other: &O,
    radii: &[T],
    weights: PairWeights<'_>,
    cumulative: bool,
    options: &TableOptions,
) -> Result<Vec<f64>> {
    let w_this = check_weights(weights.this, index.source_len(), "weights of this index")?;
    let w_other = check_weights(weights.other, other.source_len(), "weights of the other")?;
    let (bins, of_radius) = Bins::new(radii, cumulative, &options.query)?;
    let n = bins.keys.len();
    let weight = |w: Option<&[f64]>, i: u32| w.map_or(1.0, |w| w[i as usize]);
    let sums = binned(
        index,
        other,
        &bins,
        options,
        || vec![ExactSum::new(); n],
        |acc, i, j, b| acc[b].add(weight(w_this, i) * weight(w_other, j)),
        |mut a, b| {
            a.iter_mut().zip(&b).for_each(|(x, y)| x.merge(y));
            a
        },
    )?;
    let sums = bins.per_radius(&of_radius, &sums, cumulative, ExactSum::new(), |a, b| {
        a.merge(b)
    });
    Ok(sums.iter().map(ExactSum::value).collect())
}

/// `weights` checked: one per caller index (`len`), each finite.
fn check_weights<'a>(
    weights: Option<&'a [f64]>,
    len: usize,
    name: &'static str,
) -> Result<Option<&'a [f64]>> {
    let Some(w) = weights else { return Ok(None) };
    if w.len() != len {
        return Err(NbhdError::InvalidOption {
            name,
            reason: format!("{} weights for {len} points (one per index)", w.len()),
        });
    }
    if let Some(at) = w.iter().position(|x| !x.is_finite()) {
        return Err(NbhdError::InvalidOption {
            name,
            reason: format!("the weight of point {at} is {}, not finite", w[at]),
        });
    }
    Ok(Some(w))
}
