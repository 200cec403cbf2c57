//! Robust smoothing: the thesis' anisotropic flow with the neighbourhood, the normals and the
//! feature threshold chosen by the data instead of by hand (issue 5 §4; the directions named in
//! Fig. 2.7 and Chapter 9 of the thesis — better neighbourhoods, automatic feature detection).
//!
//! The faithful method (the parent module) stops helping once the noise reaches about one
//! spacing: the directional curvatures κ_ij (eq. 2.20) of noise and of edges are then
//! distributed alike, and no fixed threshold λ separates them. The robust mode keeps the shape
//! of the method — an explicit step `p_i ← p_i + τ Δ^A_i` of a weighted umbrella operator over
//! the ε-k-neighbourhood (eq. 2.18, 2.30) — and changes three of its ingredients. Every
//! iteration of [`smooth_robust`] does, on the current points (the *proxy*: the cloud as
//! smoothed so far, so that later iterations classify and choose on a less noisy cloud):
//!
//! 1. **Neighbourhoods** (Section 2.1.1): the `k_plane` nearest other points within ε, computed
//!    anew on the proxy ('Update Neighbors', Section 7.3 — safe here, since points only move
//!    along normals and cannot cluster tangentially). The first `k` of each row form the
//!    umbrella neighbourhood `N_i`.
//! 2. **Noise estimate** σ̂: the median absolute distance of a point to the covariance plane
//!    (eq. 2.8–2.10) of its wide neighbourhood, times 1.4826 (the median absolute deviation of a
//!    normal distribution). The median ignores the minority of points at edges and creases.
//!    Every threshold below is a multiple of σ̂, so nothing is tuned by hand and the thresholds
//!    shrink as the proxy gets smoother.
//! 3. **Feature-aware normals by plane selection** ('better neighbourhoods'): the covariance
//!    normal of a point near an edge is a blend of both faces, because its neighbourhood
//!    straddles the edge. Instead each point considers the covariance planes (eq. 2.10, through
//!    the barycentre, eq. 2.3) of its own and of its `k_plane` nearest neighbours' wide
//!    neighbourhoods, scores each plane by how many of the point's wide neighbours it explains —
//!    a robust (Tukey biweight) count of the points within `inlier_width`·σ̂ of it — and keeps
//!    the best. A neighbourhood shifted off the edge fits one face and explains that face's
//!    points; a straddling one explains only the points near the edge. The normal is then
//!    refitted as the weighted covariance normal over the inliers of the chosen plane. On a
//!    smooth surface every candidate explains about the same points, and the result is a
//!    covariance normal as in eq. 2.10.
//! 4. **Normal-projected anisotropic umbrella** (eq. 2.30 with normal-based weights): the
//!    step is `Δ_i = Σ_j g_ij m_ij m_ijᵀ (x_j − p_i) / Σ_j g_ij`, the umbrella of eq. 2.16
//!    projected onto a normal direction `m_ij`, so points move only across the surface and
//!    never cluster tangentially. The weight `g_ij` is the biweight of the distance
//!    `d_ij = ⟨n_j, p_i − x_j⟩` of `p_i` to the neighbour's tangent plane, in units of
//!    `inlier_width`·σ̂: a neighbour on another face of an edge has a tangent plane far from
//!    `p_i` and drops out, like `g_sharp` (2.31) with a noise-adapted threshold — by eq. 2.20,
//!    `d_ij = κ_ji ‖x_j − p_i‖²/2`, so the test is a directional-curvature test whose
//!    threshold is set by the noise. A point beyond an edge is close to both faces' planes and
//!    is pulled onto their intersection, which keeps edges sharp. The direction `m_ij` is the
//!    mean normal `(n_i + n_j)/‖n_i + n_j‖` for neighbours on the same smooth patch: the chord
//!    between two points of a circle is exactly perpendicular to the sum of their normals, and
//!    of a smooth surface up to third order, so the curvature term that makes the umbrella
//!    shrink (Fig. 2.5) and the tangent-plane projection inflate cancels. Across a feature
//!    `m_ij` turns to the neighbour's own normal `n_j`, a projection onto its plane:
//!    `m_ij ∝ a_ij n_i + n_j` with `a_ij` = 1 on one smooth patch and → 0 across a feature.
//!    Two points count as one smooth patch when their normals are less than about
//!    `feature_angle` apart (a Gaussian in the angle) *or* their chord is perpendicular to their
//!    mean normal within a quarter of the inlier width (the biweight of `⟨m, x_j − p_i⟩`,
//!    which holds on any smooth surface however curved, and fails for the blended normals
//!    next to an edge); `a_ij` is the larger of the two.
//! 5. **Stopping rule**: stop as soon as an iteration lowered the noise estimate σ̂ by less than
//!    the fraction `tolerance`, at most after `max_iterations`. The amount of smoothing thus
//!    grows with the noise instead of being a fixed step count (the notes' first lesson), and a
//!    clean cloud stops after one iteration: its σ̂ is curvature, which smoothing does not
//!    lower, so it is not eroded step by step.
//!
//! Every per-point computation reads the previous iteration only and sums its neighbours in row
//! order; medians are taken over vectors collected in point order. The result is bit-identical
//! for any number of rayon threads.

use super::{check_points, point_outputs_with, progress_in_units, within, Length, Resolved};
use super::{FeatureCriterion, Weighting};
use super::{SmoothOptions, SmoothResult, Stage};
use crate::error::{NbhdError, Result};
use crate::geometry::neighbors::{mean_spacing_of, neighbor_table};
use crate::geometry::normals::{local_frames, LocalFrame, Orientation};
use crate::geometry::robust_plane::{biweight, weighted_plane_normal};
use crate::query::Neighborhood;
use crate::table::NeighborTable;
use glam::DVec3;
use rayon::prelude::*;

/// Settings of [`smooth_robust`]. The defaults are one setting for every shape and noise level:
/// all thresholds are multiples of the estimated noise σ̂ or dimensionless.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobustOptions {
    /// Size `k` of the umbrella neighbourhood `N_i` (≥ 1). Default 24.
    pub k: usize,
    /// Size of the wide neighbourhood the planes are fitted and scored on (≥ `k`). Default 48:
    /// at noise of one spacing, a plane needs neighbourhoods of a radius of about 4h to tell a
    /// face from the chamfer across an edge.
    pub k_plane: usize,
    /// Influence radius ε (> 0), cuts both neighbourhoods. Default 12h.
    pub epsilon: Length,
    /// Upper bound on the number of iterations. Default 10.
    pub max_iterations: usize,
    /// The stopping rule: stop once an iteration lowered the noise estimate σ̂ by less than
    /// this fraction (it then mostly moves points along the surface's own curvature, not
    /// noise). Default 0.05. 0 runs `max_iterations` unless the noise estimate rises.
    pub tolerance: f64,
    /// Width of the biweight of plane distances in units of σ̂ (> 0): a point farther than
    /// this from a plane is no inlier of it. Default 5 (the biweight's core is narrower than
    /// its support: near 0 it falls like a Gaussian of standard deviation width/2 = 2.5σ̂, and
    /// σ̂ itself underestimates the noise of the input by about a quarter, since the covariance
    /// plane absorbs part of it).
    pub inlier_width: f64,
    /// Angle in degrees at which the direction `m_ij` turns from the mean normal (one smooth
    /// patch) to the neighbour's normal (a feature between them); Gaussian in the angle.
    /// Default 20°. Smaller values keep edges sharper but let curved surfaces drift outward
    /// slightly (a tangent-plane projection inflates by `κ‖x_j − p_i‖²/2`, eq. 2.20).
    pub feature_angle: f64,
    /// Step size τ of eq. 2.18 (finite, in (0, 1]). Default 1: each step moves a point onto the
    /// weighted mean of its neighbours' planes.
    pub tau: f64,
    /// Orientation of the normals reported in the outputs.
    pub orientation: Orientation,
    /// Compute the per-point outputs of the result (as [`super::smooth`] does, with the robust
    /// normals in place of the covariance normals).
    pub outputs: bool,
    /// Points with a NaN or infinite coordinate: rejected, or skipped (left unmoved, NaN
    /// outputs and normals), as [`SmoothOptions::non_finite`].
    pub non_finite: crate::NonFinitePolicy,
}

impl Default for RobustOptions {
    fn default() -> Self {
        Self {
            k: 24,
            k_plane: 48,
            epsilon: Length::Relative(12.0),
            max_iterations: 10,
            tolerance: 0.05,
            inlier_width: 5.0,
            feature_angle: 20.0,
            tau: 1.0,
            orientation: Orientation::Unoriented,
            outputs: true,
            non_finite: crate::NonFinitePolicy::Reject,
        }
    }
}

impl RobustOptions {
    fn validate(&self) -> Result<()> {
        let bad = |name, reason: String| Err(NbhdError::InvalidOption { name, reason });
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if self.k == 0 {
            return Err(NbhdError::ZeroK);
        }
        if self.k_plane < self.k {
            return bad(
                "k_plane",
                format!("{} must be at least k = {}", self.k_plane, self.k),
            );
        }
        let eps = match self.epsilon {
            Length::Absolute(v) | Length::Relative(v) => v,
        };
        if !pos(eps) {
            return bad("epsilon", format!("{eps} must be finite and > 0"));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return bad(
                "tolerance",
                format!("{} must be finite and >= 0", self.tolerance),
            );
        }
        if !pos(self.inlier_width) {
            return bad(
                "inlier_width",
                format!("{} must be finite and > 0", self.inlier_width),
            );
        }
        if !pos(self.feature_angle) {
            return bad(
                "feature_angle",
                format!("{} must be finite and > 0", self.feature_angle),
            );
        }
        if !(pos(self.tau) && self.tau <= 1.0) {
            return bad("tau", format!("{} must be in (0, 1]", self.tau));
        }
        Ok(())
    }
}

/// What [`smooth_robust_report`] adds to the result.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustReport {
    /// The smoothed points and outputs. `lambda` holds the noise-adapted threshold of the
    /// first iteration as a directional curvature (eq. 2.20) over one spacing,
    /// `2·inlier_width·σ̂₀/h²`: a neighbour at distance h whose tangent plane is that far from
    /// the point is cut off.
    pub result: SmoothResult,
    /// The robust normals (unit, unoriented) the last step used, in input order (the
    /// covariance normals of the input if no step was taken).
    pub normals: Vec<DVec3>,
    /// Noise estimate σ̂ of each iteration's input, in units of h (the first is the input's).
    pub noise: Vec<f64>,
    /// RMS displacement of each iteration, in units of h.
    pub moved: Vec<f64>,
}

/// Smooths `points` robustly with `options` (see the module documentation).
pub fn smooth_robust(points: &[DVec3], options: &RobustOptions) -> Result<SmoothResult> {
    smooth_robust_with_progress(points, options, &mut |_, _| true)
}

/// [`smooth_robust`] with a progress callback, called on the calling thread with the fraction
/// done (0 to 1, counted against `max_iterations`) and the stage; returning `false` stops the
/// run with [`NbhdError::Cancelled`].
pub fn smooth_robust_with_progress(
    points: &[DVec3],
    options: &RobustOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<SmoothResult> {
    smooth_robust_report(points, options, progress).map(|r| r.result)
}

/// [`smooth_robust_with_progress`] that also returns the normals, the noise estimates and the
/// displacement of each iteration.
///
/// Non-finite points are refused or skipped as `options.non_finite` says (skipped points keep
/// their index, are left unmoved and get NaN outputs and normals);
/// [`NbhdError::Degenerate`] when no neighbourhood reaches 3 points.
pub fn smooth_robust_report(
    points: &[DVec3],
    options: &RobustOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<RobustReport> {
    options.validate()?;
    match super::finite_subset(points, options.non_finite)? {
        None => robust_finite(points, options, progress),
        Some((index, finite)) => {
            let r = robust_finite(&finite, options, progress)?;
            let mut normals = vec![DVec3::splat(f64::NAN); points.len()];
            for (&i, &n) in index.iter().zip(&r.normals) {
                normals[i] = n;
            }
            Ok(RobustReport {
                result: super::scatter_result(r.result, points, &index),
                normals,
                ..r
            })
        }
    }
}

/// [`smooth_robust_report`] on finite points.
fn robust_finite(
    points: &[DVec3],
    options: &RobustOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<RobustReport> {
    check_points(points)?;
    let total = options.max_iterations as f64 + 1.0;
    let mut report = progress_in_units(total, progress);
    report(0.0, Stage::Neighbors)?;
    let wide_of = |pts: &[DVec3]| -> Result<NeighborTable<f64>> {
        neighbor_table(pts, Neighborhood::Knn { k: options.k_plane }, true)
    };
    let knn = wide_of(points)?;
    let h = mean_spacing_of(&knn);
    let relative = matches!(options.epsilon, Length::Relative(_));
    if relative && !(h > 0.0 && h.is_finite()) {
        return Err(NbhdError::InvalidOption {
            name: "epsilon",
            reason: "relative parameters need a mean spacing > 0 (at least two distinct points)"
                .into(),
        });
    }
    let eps = options.epsilon.resolve(h);
    let mut wide = within(&knn, eps);
    super::check_not_degenerate(&wide, None, eps, h, relative)?;
    let min_neighbors = truncate(&wide, options.k).min_row_len();
    let mut cur = points.to_vec();
    let mut normals: Vec<DVec3> = Vec::new();
    let (mut noise, mut moved) = (Vec::new(), Vec::new());
    let mut sigma0 = 0.0;
    let mut prev_sigma = f64::INFINITY;
    let hu = if h > 0.0 { h } else { 1.0 };
    for it in 0..options.max_iterations {
        let base = it as f64;
        if it > 0 {
            report(base, Stage::Neighbors)?;
            wide = within(&wide_of(&cur)?, eps);
        }
        let narrow = truncate(&wide, options.k);
        report(base + 0.2, Stage::Geometry)?;
        let frames = local_frames(&cur, &wide)?;
        let bary = barycentres(&cur, &wide);
        let sigma = noise_estimate(&cur, &frames, &bary);
        if it == 0 {
            sigma0 = sigma;
        }
        noise.push(sigma / hu);
        if it > 0 && sigma > (1.0 - options.tolerance) * prev_sigma {
            break;
        }
        prev_sigma = sigma;
        let width = options.inlier_width * sigma;
        normals = selected_normals(&cur, &wide, &frames, &bary, width);
        report(base + 0.6, Stage::Step)?;
        let next = step(&cur, &narrow, &normals, width, options);
        let rms = (next
            .iter()
            .zip(&cur)
            .map(|(a, b)| a.distance_squared(*b))
            .sum::<f64>()
            / cur.len() as f64)
            .sqrt();
        moved.push(rms / hu);
        cur = next;
        if rms == 0.0 {
            break;
        }
    }
    let lambda = 2.0 * options.inlier_width * sigma0 / (hu * hu);
    let outputs = if options.outputs {
        report(options.max_iterations as f64 + 0.2, Stage::Outputs)?;
        let narrow = truncate(&within(&wide_of(&cur)?, eps), options.k);
        let so = SmoothOptions {
            k: options.k,
            epsilon: Length::Absolute(eps.max(f64::MIN_POSITIVE)),
            weighting: Weighting::Sharp,
            lambda: super::Curvature::Absolute(lambda.max(f64::MIN_POSITIVE)),
            feature: FeatureCriterion::AllPoints,
            orientation: options.orientation,
            ..SmoothOptions::default()
        };
        let res = Resolved {
            lambda: lambda.max(f64::MIN_POSITIVE),
            feature: FeatureCriterion::AllPoints,
        };
        let mut out = point_outputs_with(&cur, &narrow, &so, &res)?;
        if normals.len() == out.len() {
            for (o, &n) in out.iter_mut().zip(&normals) {
                // the robust normal, on the side the oriented covariance normal points to
                o.normal = if n.dot(o.normal) < 0.0 { -n } else { n };
            }
        }
        out
    } else {
        Vec::new()
    };
    report(total, Stage::Done)?;
    if normals.is_empty() {
        normals = local_frames(&cur, &truncate(&wide, options.k))?
            .iter()
            .map(|f| f.normal)
            .collect();
    }
    Ok(RobustReport {
        result: SmoothResult {
            points: cur,
            outputs,
            spacing: h,
            epsilon: eps,
            lambda,
            min_neighbors,
        },
        normals,
        noise,
        moved,
    })
}

/// The first `k` entries of every row (rows are sorted by distance, so this is the k-nearest
/// table of the smaller k).
fn truncate(table: &NeighborTable<f64>, k: usize) -> NeighborTable<f64> {
    let mut offsets = Vec::with_capacity(table.len() + 1);
    offsets.push(0);
    let (mut idx, mut d2) = (Vec::new(), Vec::new());
    for i in 0..table.len() {
        let n = table.indices_of(i).len().min(k);
        idx.extend_from_slice(&table.indices_of(i)[..n]);
        d2.extend_from_slice(&table.sq_dists_of(i)[..n]);
        offsets.push(idx.len());
    }
    NeighborTable::from_parts(offsets, idx, d2).unwrap_or_default()
}

/// Barycentre of `N_i ∪ {p_i}` (eq. 2.3), the point the covariance plane passes through.
fn barycentres(cur: &[DVec3], table: &NeighborTable<f64>) -> Vec<DVec3> {
    (0..cur.len())
        .into_par_iter()
        .map(|i| {
            let row = table.indices_of(i);
            let sum = row
                .iter()
                .fold(DVec3::ZERO, |s, &j| s + (cur[j as usize] - cur[i]));
            cur[i] + sum / (row.len() + 1) as f64
        })
        .collect()
}

/// σ̂: 1.4826 × the median distance of a point to its own covariance plane.
fn noise_estimate(cur: &[DVec3], frames: &[LocalFrame], bary: &[DVec3]) -> f64 {
    let mut r: Vec<f64> = (0..cur.len())
        .into_par_iter()
        .map(|i| frames[i].normal.dot(cur[i] - bary[i]).abs())
        .collect();
    let m = r.len() / 2;
    r.select_nth_unstable_by(m, f64::total_cmp);
    1.4826 * r[m]
}

/// Step 3 of the module documentation: for each point the best-supported covariance plane among
/// its own and its wide neighbours', refitted over its inliers.
fn selected_normals(
    cur: &[DVec3],
    wide: &NeighborTable<f64>,
    frames: &[LocalFrame],
    bary: &[DVec3],
    width: f64,
) -> Vec<DVec3> {
    (0..cur.len())
        .into_par_iter()
        .map_init(Vec::new, |buf: &mut Vec<DVec3>, i| {
            buf.clear();
            buf.push(cur[i]);
            buf.extend(wide.indices_of(i).iter().map(|&l| cur[l as usize]));
            let score = |c: usize| -> f64 {
                let (n, b) = (frames[c].normal, bary[c]);
                buf.iter().map(|&x| biweight(n.dot(x - b), width)).sum()
            };
            let mut best = (score(i), i);
            for &j in wide.indices_of(i) {
                let s = score(j as usize);
                if s > best.0 {
                    best = (s, j as usize);
                }
            }
            let (n, b) = (frames[best.1].normal, bary[best.1]);
            weighted_plane_normal(buf, |x| biweight(n.dot(x - b), width)).unwrap_or(n)
        })
        .collect()
}

/// Fraction of the inlier width within which a chord counts as perpendicular to the mean normal
/// of its end points (step 4 of the module documentation).
const CHORD_WIDTH: f64 = 0.25;

/// Step 4 of the module documentation: one normal-projected anisotropic umbrella step.
fn step(
    cur: &[DVec3],
    narrow: &NeighborTable<f64>,
    normals: &[DVec3],
    width: f64,
    o: &RobustOptions,
) -> Vec<DVec3> {
    let angle = o.feature_angle.to_radians();
    (0..cur.len())
        .into_par_iter()
        .map(|i| {
            let (p, ni) = (cur[i], normals[i]);
            let (mut acc, mut ws) = (DVec3::ZERO, 0.0);
            for &j in narrow.indices_of(i) {
                let (x, nj) = (cur[j as usize], normals[j as usize]);
                let g = biweight(nj.dot(p - x), width);
                if g == 0.0 {
                    continue;
                }
                let c = ni.dot(nj);
                let nj = if c < 0.0 { -nj } else { nj };
                // one smooth patch: normals close, or the chord perpendicular to their mean
                let mean = (ni + nj).normalize_or_zero();
                let a = (-(c.abs().min(1.0).acos() / angle).powi(2))
                    .exp()
                    .max(biweight(mean.dot(x - p), CHORD_WIDTH * width));
                let m = (a * ni + nj).normalize_or_zero();
                acc += g * m * m.dot(x - p);
                ws += g;
            }
            if ws > 0.0 {
                p + o.tau * acc / ws
            } else {
                p
            }
        })
        .collect()
}
