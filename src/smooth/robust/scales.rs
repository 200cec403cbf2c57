//! The noise scale of the robust smoothing (item 0 of the parent module): wider
//! neighbourhoods while the noise is larger than the usual ones can see through.
//!
//! The `k_plane` nearest points of a point span about 4h (h the mean spacing). Where the noise
//! σ is several spacings (dense scans of noisy sensors, the 50K-point clouds of the denoising
//! protocol at 2–3 % noise), such a neighbourhood is a ball of noise: its covariance plane
//! follows the noise, the residuals to it measure the ball rather than the noise (σ̂ reads
//! 0.8h–1h whatever σ is), and the steps move points along noise.
//!
//! Which regime a cloud is in shows in how its neighbourhoods fill: the number of points within
//! a radius r grows like r² on a surface and like r³ inside a ball of noise. The *local
//! dimension* of a point at the scale of its wide neighbourhood is `ln 4 / ln(d₄ₘ / dₘ)`, with
//! `dₘ` the distance to its m-th nearest and `d₄ₘ` to its 4m-th (m = `k_plane`/4): 2 on a
//! surface, 3 in a volume, in between where the noise is comparable to the neighbourhood
//! (the correlation-dimension estimate of intrinsic dimension, Grassberger & Procaccia,
//! Physica D 9, 1983, applied per point). It does not read curvature (a curved surface is
//! two-dimensional at every scale below its radius) nor thin sheets (two sheets within reach
//! double the count at every radius). Measured on the meshes of the denoising protocol
//! (docs/smoothing-results.md), its median over the points rises with σ/h alone: 2.2–2.3 at
//! 10K points and 1 % noise (σ ≈ 0.45h), 2.4–2.6 at 50K and 1 % (σ ≈ h), 2.6–2.7 at 10K and
//! 3 % (σ ≈ 1.35h), 2.74–2.85 at 50K and 2 % (σ ≈ 2h), 2.86–2.93 at 50K and 3 % (σ ≈ 3h).
//!
//! The global statistic is the median over the points of the ratio `d₄ₘ / dₘ`
//! ([`distance_ratios`]), an exact selection. While it shows a dimension of at least
//! [`BALL_DIMENSION`], the iterations use [`WIDE`] times `k` and `k_plane`: radii √3 times as
//! large, which see the surface through noise of up to about three spacings (twice `k` left
//! the 50K clouds at 3 % noise about 1.5 times the Chamfer distance of three times, measured
//! on four meshes: 4.36 against 2.70). The ratio is measured again on the proxy before each
//! iteration, and once the smoothed cloud reads as a surface ([`KEEP_DIMENSION`]), the rows
//! are cut back to `k_plane` and the iterations continue as for any cloud. While the rows are
//! wide, σ̂ measures the ball and the stopping rule does not apply.
//! Clouds with noise up to about 1.5 spacings never widen (the choice of the neighbourhood from
//! the noise: Mitra & Nguyen, "Estimating surface normals in noisy point cloud data", SoCG
//! 2003, whose normal error grows with σ/r).

use super::rows::Rows;
use crate::index::NeighborIndex;
use crate::query::Query;
use crate::tree::{BuildOptions, KdTree};
use glam::DVec3;
use rayon::prelude::*;

/// Factor of `k` and `k_plane` while the cloud reads as a ball of noise (see the module
/// documentation for 2 against 3).
pub const WIDE: usize = 3;

/// The local dimension from which neighbourhoods are balls of noise (see the module
/// documentation for the values measured: 2.71 at most where widening did not help, 2.74 at
/// least where it did).
pub const BALL_DIMENSION: f64 = 2.75;

/// `d₄ₘ / dₘ` of every point of `points` (stored order) with the rows `rows` that has one
/// ([`distance_ratio_at`]), in stored order; the noise scale reads their median (an exact
/// selection, `robust/run.rs`).
pub(super) fn distance_ratios(points: &[DVec3], rows: &Rows, k_plane: usize) -> Vec<f64> {
    (0..points.len())
        .into_par_iter()
        .filter_map(|s| distance_ratio_at(points, rows, k_plane, s))
        .collect()
}

/// `d₄ₘ / dₘ` of the point stored at `s`, m = `k_plane`/4 (rows shorter than `k_plane` use
/// their own length); `None` for a point with fewer than four neighbours, or whose m-th nearest
/// coincides with it.
pub(super) fn distance_ratio_at(
    points: &[DVec3],
    rows: &Rows,
    k_plane: usize,
    s: usize,
) -> Option<f64> {
    let row = rows.wide(s);
    let far = row.len().min(k_plane);
    let near = far / 4;
    if near == 0 {
        return None;
    }
    let p = points[s];
    let d = |i: usize| points[row[i - 1] as usize].distance_squared(p);
    let (dn, df) = (d(near), d(far));
    (dn > 0.0).then(|| (df / dn).sqrt())
}

/// The local dimension of a median distance ratio `d₄ₘ / dₘ`: `ln 4 / ln ratio`.
pub(super) fn dimension(ratio: f64) -> f64 {
    4f64.ln() / ratio.ln()
}

/// The local dimension down to which a cloud that read as a ball of noise keeps the wide
/// neighbourhoods: after one wide iteration the clouds at 3 % noise read 2.55–2.7 and still
/// gain from a second (the smoothed proxy at 2 %: 2.3–2.45).
pub(super) const KEEP_DIMENSION: f64 = 2.55;

/// Whether a cloud whose median distance ratio is `ratio` reads as a ball of noise: a local
/// dimension of at least [`BALL_DIMENSION`], or of [`KEEP_DIMENSION`] where it already `was`.
pub(super) fn is_ball(ratio: Option<f64>, was: bool) -> bool {
    let from = if was { KEEP_DIMENSION } else { BALL_DIMENSION };
    ratio.is_some_and(|r| r > 1.0 && dimension(r) >= from)
}

/// Points of the input between two of the sample [`input_reads_as_ball`] measures.
const SAMPLE_STRIDE: usize = 32;

/// Fewest sampled points [`input_reads_as_ball`] reads a median from (fewer: no guess).
const MIN_SAMPLE: usize = 64;

/// Most sampled points of [`input_reads_as_ball`] (the stride grows on larger clouds).
const MAX_SAMPLE: usize = 4096;

/// The local dimension above [`BALL_DIMENSION`] from which the sample's median is trusted to
/// say that the whole cloud's will reach [`BALL_DIMENSION`].
const GUESS_MARGIN: f64 = 0.05;

/// A guess, before any row is searched, that the cloud will read as a ball of noise on the
/// input ([`is_ball`] of the median distance ratio of the rows of `k_plane`): the median local
/// dimension of every [`SAMPLE_STRIDE`]-th point (at most [`MAX_SAMPLE`] of them), each from
/// its `k_plane` nearest in a tree of every point, reads at least [`GUESS_MARGIN`] above
/// [`BALL_DIMENSION`]. It decides only which rows are searched first (`robust/tile.rs`: the
/// wide rows, whose first `k_plane` are the plain ones, instead of the plain rows and then the
/// wide ones), never a result: a wrong guess costs a search, not a bit. The sample ignores the
/// cut at ε (unknown before the spacing is) and the median is taken over a sample, hence the
/// margin; measured on the denoising protocol's clouds at 50K points and 3 % noise
/// (docs/smoothing-results.md, round 8), the sample's median reads 2.86–2.96, up to 0.04 below
/// the median over every fourth point. On a cloud that does not widen the guess is pure cost:
/// under 1 % of the run's instructions, about 5 % of its CPU time on the torus there. `false` on a cloud too small to sample, or whose tree or queries fail (the plain
/// rows are searched as always).
pub(crate) fn input_reads_as_ball(points: &[DVec3], k_plane: usize) -> bool {
    let stride = SAMPLE_STRIDE.max(points.len().div_ceil(MAX_SAMPLE));
    let sampled = points.len() / stride;
    if sampled < MIN_SAMPLE || k_plane / 4 == 0 || points.len() <= k_plane {
        return false;
    }
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    let Ok(tree) = KdTree::<f64>::from_flat(&flat, 3, &BuildOptions::default()) else {
        return false;
    };
    let mut ratios: Vec<f64> = (0..sampled)
        .into_par_iter()
        .map_init(Vec::new, |row, i| {
            let query = Query::stored_excluding_self((i * stride) as u32);
            tree.knn(query, k_plane, row).ok()?;
            let (near, far) = (row.get(k_plane / 4 - 1)?, row.get(k_plane - 1)?);
            (near.sq_dist > 0.0).then(|| (far.sq_dist / near.sq_dist).sqrt())
        })
        .flatten()
        .collect();
    let guess = super::run::median(&mut ratios);
    guess.is_some_and(|r| r > 1.0 && dimension(r) >= BALL_DIMENSION + GUESS_MARGIN)
}
