//! Statistical and radius outlier removal.

use crate::error::{NbhdError, Result};
use crate::index::NeighborIndex;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::sum::ExactSum;
use crate::table::TableOptions;

/// The points a filter keeps.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Kept {
    /// The caller's indices of the kept points, ascending.
    pub indices: Vec<u32>,
    /// Number of points the caller passed in (the length of [`Kept::mask`]).
    pub source_len: usize,
}

impl Kept {
    /// One flag per point the caller passed in: `true` if it is kept.
    pub fn mask(&self) -> Vec<bool> {
        let mut m = vec![false; self.source_len];
        for &i in &self.indices {
            m[i as usize] = true;
        }
        m
    }
}

/// Options of [`statistical_outlier_removal`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StatisticalOutlierOptions {
    /// Number of nearest *other* points whose distances are averaged (≥ 1). The same number as
    /// PCL's `setMeanK` (PCL searches `k + 1` and skips the point itself) and Open3D's
    /// `nb_neighbors`.
    pub k: usize,
    /// α: a point is kept when its mean distance is at most `mean + α · σ` (PCL's
    /// `setStddevMulThresh`, Open3D's `std_ratio`). Finite; may be negative.
    pub std_ratio: f64,
    /// Worker threads (0: the current pool).
    pub threads: usize,
}

impl Default for StatisticalOutlierOptions {
    /// PCL's tutorial values: k = 50, α = 1.
    fn default() -> Self {
        Self {
            k: 50,
            std_ratio: 1.0,
            threads: 0,
        }
    }
}

/// Statistical outlier removal. For every point `i` its mean distance to its `k` nearest other
/// points, `d_i = (1/k) Σ_{j ∈ N_k(i)} ‖x_i − x_j‖` ([`mean_distance`]); over all `n` points
/// the mean `μ` and the sample standard deviation `σ = √(Σ (d_i − μ)² / (n − 1))` (PCL's
/// definition; σ = 0 when n = 1); point `i` is kept when `d_i ≤ μ + α σ`
/// ([`outlier_threshold`]). Distances are taken in `f64` from the tree's squared distances;
/// both sums over the points are exact and rounded once ([`ExactSum`]), so they do not depend
/// on the order of the points and a tiled run reduces them to the same bits (PCL sums in
/// order, which can differ in the last bits).
///
/// Errors: `k` = 0 ([`NbhdError::ZeroK`]); `k` not below the number of points, or a
/// non-finite `std_ratio`, or too many threads ([`NbhdError::InvalidOption`]).
///
/// ```
/// use nbhd::filter::{statistical_outlier_removal, StatisticalOutlierOptions};
/// use nbhd::{BuildOptions, KdTree, PointsView};
///
/// // a row of points one apart, and one far away
/// let mut pts: Vec<f32> = (0..20).flat_map(|i| [i as f32, 0.0]).collect();
/// pts.extend([5.0, 40.0]);
/// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
/// let options = StatisticalOutlierOptions { k: 2, std_ratio: 1.0, threads: 0 };
/// let kept = statistical_outlier_removal(&tree, &options)?;
/// assert_eq!(kept.indices, (0..20).collect::<Vec<u32>>());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn statistical_outlier_removal<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    options: &StatisticalOutlierOptions,
) -> Result<Kept> {
    let k = options.k;
    if k == 0 {
        return Err(NbhdError::ZeroK);
    }
    if !options.std_ratio.is_finite() {
        return Err(NbhdError::InvalidOption {
            name: "std_ratio",
            reason: format!("{} is not finite", options.std_ratio),
        });
    }
    if k >= index.len() {
        return Err(NbhdError::InvalidOption {
            name: "k",
            reason: format!(
                "{k} nearest other points need more than {k} points; the tree holds {}",
                index.len()
            ),
        });
    }
    let table = index.neighborhoods(
        Neighborhood::Knn { k },
        &TableOptions {
            exclude_self: true,
            threads: options.threads,
            ..Default::default()
        },
    )?;
    // d_i for the points the tree holds, in the caller's order
    let (kept_rows, d): (Vec<u32>, Vec<f64>) = (0..table.len())
        .filter(|&i| !table.sq_dists_of(i).is_empty())
        .map(|i| (i as u32, mean_distance(table.sq_dists_of(i))))
        .unzip();
    let mean = ExactSum::from_iter(d.iter().copied()).value() / d.len() as f64;
    let threshold = outlier_threshold(
        mean,
        &squared_deviation_sum(&d, mean),
        d.len(),
        options.std_ratio,
    );
    Ok(Kept {
        indices: kept_rows
            .into_iter()
            .zip(d)
            .filter(|&(_, x)| x <= threshold)
            .map(|(i, _)| i)
            .collect(),
        source_len: index.source_len(),
    })
}

/// A point's mean distance to its nearest other points, `d_i = (1/k) Σ_j ‖x_i − x_j‖`, from
/// the `k` squared distances of its row: each root taken in `f64`, summed in the row's order
/// (nearest first), divided by `k`. The step a tiled run (`python/nbhd/dask.py`) takes for
/// each of its tile's points, as [`statistical_outlier_removal`] takes it for every point.
pub fn mean_distance<T: Scalar>(sq_dists: &[T]) -> f64 {
    let s: f64 = sq_dists
        .iter()
        .fold(0.0, |acc, d2| acc + d2.to_f64().sqrt());
    s / sq_dists.len() as f64
}

/// `Σ (d_i − μ)²` over some of the points' mean distances `d`, exactly summed
/// ([`ExactSum`]): the parts of a tiled run merge to the one-machine sum bit for bit.
pub fn squared_deviation_sum(d: &[f64], mean: f64) -> ExactSum {
    d.iter().map(|&x| (x - mean) * (x - mean)).collect()
}

/// The statistical outlier threshold `μ + α σ` of `n` points whose mean distances average to
/// `mean` (their exact sum, rounded once, divided by `n`) and deviate from it by `spread`
/// ([`squared_deviation_sum`]), with the sample deviation `σ = √(spread / (n − 1))` (PCL's; 0
/// for one point). A point is kept when its mean distance is at most the threshold.
pub fn outlier_threshold(mean: f64, spread: &ExactSum, n: usize, std_ratio: f64) -> f64 {
    let sigma = if n > 1 {
        (spread.value() / (n as f64 - 1.0)).sqrt()
    } else {
        0.0
    };
    mean + std_ratio * sigma
}

/// Options of [`radius_outlier_removal`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusOutlierOptions {
    /// Plain Euclidean radius, inclusive (`‖x_j − x_i‖ ≤ radius`), finite and ≥ 0.
    pub radius: f64,
    /// A point is kept when at least this many *other* points lie within `radius`. PCL's
    /// `setMinNeighborsInRadius(m)` keeps a point when its radius search, which counts the
    /// point itself, finds more than `m`: the same `m`. 0 keeps every point.
    pub min_neighbors: usize,
    /// Worker threads (0: the current pool).
    pub threads: usize,
}

impl RadiusOutlierOptions {
    /// Radius `radius`, at least 2 other points within it (the CLI's default; PCL's is 1), the
    /// current pool.
    pub fn within(radius: f64) -> Self {
        Self {
            radius,
            min_neighbors: 2,
            threads: 0,
        }
    }
}

/// Radius outlier removal: keeps point `i` when `|{j ≠ i : ‖x_j − x_i‖ ≤ radius}| ≥
/// min_neighbors` (duplicates count). Each point's search stops at `min_neighbors` (an
/// ε-k-neighbourhood, Section 2.1.1), so a large radius costs no more than a small one.
///
/// Errors: a negative, NaN or infinite radius ([`NbhdError::InvalidRadius`]), one too large
/// for the tree's type ([`NbhdError::RadiusOutOfRange`]), too many threads.
///
/// ```
/// use nbhd::filter::{radius_outlier_removal, RadiusOutlierOptions};
/// use nbhd::{BuildOptions, KdTree, PointsView};
///
/// let pts = [0.0f64, 0.0, 1.0, 0.0, 2.0, 0.0, 9.0, 9.0];
/// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
/// let options = RadiusOutlierOptions { radius: 1.0, min_neighbors: 1, threads: 0 };
/// assert_eq!(radius_outlier_removal(&tree, &options)?.indices, [0, 1, 2]);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn radius_outlier_removal<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    options: &RadiusOutlierOptions,
) -> Result<Kept> {
    let r = options.radius;
    if !(r.is_finite() && r >= 0.0) {
        return Err(NbhdError::InvalidRadius(r));
    }
    let radius = T::from_f64(r);
    if !radius.is_finite() {
        return Err(crate::query::radius_out_of_range::<T>(r));
    }
    let m = options.min_neighbors;
    if m == 0 {
        crate::parallel::check_threads(options.threads)?;
        return Ok(Kept {
            indices: index.indices(),
            source_len: index.source_len(),
        });
    }
    let nbhd = Neighborhood::KnnRadius { k: m, radius };
    nbhd.validate()?;
    let table = index.neighborhoods(
        nbhd,
        &TableOptions {
            exclude_self: true,
            threads: options.threads,
            ..Default::default()
        },
    )?;
    Ok(Kept {
        indices: (0..table.len())
            .filter(|&i| table.indices_of(i).len() >= m)
            .map(|i| i as u32)
            .collect(),
        source_len: index.source_len(),
    })
}
