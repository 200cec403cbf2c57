//! Robust smoothing: the thesis' anisotropic flow with the neighbourhood, the normals and the
//! feature threshold chosen by the data instead of by hand (the directions named in
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
//! 0. **Noise scale** (`robust/scales.rs`): before the first iteration, and before each later
//!    one while it reads so, the cloud's local dimension (the median over the points of how
//!    their neighbour distances grow: 2 on a surface, 3 in a ball of noise) says whether the
//!    neighbourhoods below see the surface through the noise. Where they do not (noise of
//!    about two spacings and more), `k` and `k_plane` are tripled until the proxy reads as a
//!    surface (the stopping rule waits for it); then the rows are cut back and the iterations go on as below. Clouds with noise
//!    up to about 1.5 spacings are never widened.
//! 1. **Neighbourhoods** (Section 2.1.1): each point's candidates are the `k_plane` nearest
//!    other points of the **input**, with no radius limit, searched once; every iteration
//!    re-measures and re-sorts them on the proxy and keeps those within ε ('Update Neighbors',
//!    Section 7.3, without a second search: points move across the surface by a fraction of a
//!    spacing, so their nearest neighbours stay among the first search's candidates; see
//!    `robust/rows.rs`). A candidate beyond ε in the input can move inside it later. The first
//!    `k` of each row form the umbrella neighbourhood `N_i`.
//! 2. **Noise estimate** σ̂: the median absolute distance of a point to the covariance plane
//!    (eq. 2.8–2.10) of its wide neighbourhood, times 1.4826 (the median absolute deviation of a
//!    normal distribution). The median ignores the minority of points at edges and creases.
//!    Every threshold below is a multiple of σ̂, so nothing is tuned by hand and the thresholds
//!    shrink as the proxy gets smoother.
//! 3. **Feature-aware normals by plane selection** ('better neighbourhoods'): the covariance
//!    normal of a point near an edge is a blend of both faces, because its neighbourhood
//!    straddles the edge. Instead each point considers the covariance planes (eq. 2.10, through
//!    the barycentre, eq. 2.3) of its own wide neighbourhood and of those of the farthest
//!    quarter of its wide neighbours (the most shifted ones; nearer neighbours' planes repeat
//!    its own; of a row widened by the noise scale, every third of them), scores each plane by how many of the point's wide neighbours it explains —
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
//!    `feature_angle` apart (a Gaussian in the distance between the unit normals, `2 sin(θ/2)`,
//!    which is the angle θ to third order) *or* their chord is perpendicular to their
//!    mean normal within a quarter of the inlier width (the biweight of `⟨m, x_j − p_i⟩`,
//!    which holds on any smooth surface however curved, and fails for the blended normals
//!    next to an edge); `a_ij` is the larger of the two.
//! 5. **Stopping rule**: stop as soon as an iteration lowered the noise estimate σ̂ by less than
//!    the fraction `tolerance` (by less than a quarter while more than 0.4 of the first σ̂ is
//!    left on a cloud that did not start as a ball of noise: that spread is mostly the
//!    surface's own detail, see `stop_tolerance`), at most after `max_iterations`. The amount of smoothing thus
//!    grows with the noise instead of being a fixed step count (one count under-smooths strong
//!    noise and erodes weak noise; docs/smoothing-results.md), and a clean cloud stops after
//!    one iteration: its σ̂ is curvature, which smoothing does not lower, so it is not eroded
//!    step by step.
//!
//! Every per-point computation reads the previous iteration only and sums its neighbours in row
//! order; medians are exact selections of values collected per point. The result is
//! bit-identical for any number of rayon threads.
//!
//! **Driver and tiles.** A run is split in two (`robust/run.rs`, `robust/tile.rs`): the
//! [`RobustRun`] holds every decision that depends on the whole cloud (the noise scale, σ̂, the
//! stopping rule, λ) and no point, and asks for [`Round`]s; a [`RobustTile`] computes a round's
//! per-point values over the points it owns. [`smooth_robust`] is the run driven over one tile
//! that owns the whole cloud; a cloud split into tiles (larger than memory, or spread over a
//! cluster) runs the same code with many tiles and gets the same bits.
//!
//! **Global statistics and reach** (what a tiled run reduces and exchanges). Per iteration the
//! method uses exactly two quantities computed over all points, each an exact median (the
//! value of rank ⌊n/2⌋ in `total_cmp` order, so it can be selected exactly across tiles with
//! `select::radix`): σ̂ (over each point's distance to its covariance plane, `plane_distances`
//! in `robust/planes.rs`) and, while the rows are wide, the median distance ratio of the noise
//! scale (over each point's `d₄ₘ/dₘ`, `distance_ratios` in `robust/scales.rs`). The reported RMS
//! displacement sums the squared displacements in an [`crate::ExactSum`], which does not depend
//! on the order. The spacing h (a mean over the input's nearest distances, summed in caller
//! order) is computed once. Everything else is per point. A point's row is its candidates (the
//! `k_plane` nearest of the input, `WIDE`·`k_plane` = 3·`k_plane` while wide, not cut at ε),
//! and one iteration reaches **three hops** along rows: the step reads the neighbours'
//! normals, a neighbour's normal is chosen among the covariance planes of its own row's
//! farthest quarter, and each plane is fitted to that point's row. A hop is bounded by the
//! input's distance to its `k_plane`-th (or wide) nearest, not by ε, so no radius bounds the
//! reach next to outliers and holes: a tile checks per point whether its rows are the whole
//! cloud's and how many hops of them it holds (`robust/reach.rs`). The points are stored in the
//! k-d tree's order while the iterations run, so that a point's neighbours lie close in memory.
//!
//! Speed (docs/smoothing-results.md#speed): one search instead of one per iteration, a quarter of
//! the candidate planes, the scoring in eight `f32` lanes, and no arc cosine or square root in
//! the step took the 80k torus of `cpp_examples/bench_smoothing` from 5.3 s to about 0.8 s on one
//! thread; the figures of `tests/smoothing_quality.rs` held or improved. Since then the plane
//! fits and the step run in four `f64` lanes, and a point whose own plane already explains
//! nine tenths of its wide neighbourhood skips the other candidates (73–98 % of the points of
//! the analytic shapes; quality within 0.002h).

mod planes;
mod reach;
mod row_file;
mod rows;
mod run;
pub(super) mod scales;
mod step;
mod tile;

pub use reach::Region;
pub use run::{median, median_rank, Reduced, RobustRun, Round, RowSet};
pub use tile::{reduce, RobustTile, TilePart};

/// The exact selection across tiles that a driver running the tiles elsewhere reduces the
/// medians with (`select/radix.rs`; [`reduce`] runs it in one process).
pub use crate::select::radix::{DigitCounts, RankSearch, RankStep};

/// The factor of `k` and `k_plane` while the cloud reads as a ball of noise
/// ([`RobustOptions::noise_scale`], `robust/scales.rs`).
pub use scales::WIDE as NOISE_SCALE_FACTOR;

/// The local dimension of the input from which the neighbourhoods are widened
/// ([`RobustOptions::noise_scale`], `robust/scales.rs`).
pub use scales::BALL_DIMENSION as NOISE_SCALE_DIMENSION;

use super::source::{Neighbors, SearchMethod};
use super::{point_outputs, progress_in_units, Criteria, Length};
use super::{FeatureCriterion, SmoothResult, Stage, Weighting};
use crate::error::{NbhdError, Result};
use crate::geometry::normals::Orientation;
use glam::DVec3;

/// Settings of [`smooth_robust`]. The defaults are one setting for every shape and noise level:
/// all thresholds are multiples of the estimated noise σ̂ or dimensionless, and the
/// neighbourhoods grow with the noise by themselves (`noise_scale`). Every front door (CLI,
/// C ABI, Python, MeshLab) starts from [`RobustOptions::default`].
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
    /// Scale from the noise (`robust/scales.rs`): while the cloud's neighbourhoods read as
    /// balls of noise (noise of about two spacings or more), iterate with `k` and `k_plane`
    /// tripled. Clouds with noise up to about 1.5 spacings are smoothed as without it. Not
    /// applied to a caller's table. Default true.
    pub noise_scale: bool,
    /// Orientation of the normals reported in the outputs.
    pub orientation: Orientation,
    /// Compute the per-point outputs of the result (as [`super::smooth`] does, with the robust
    /// normals in place of the covariance normals).
    pub outputs: bool,
    /// Points with a NaN or infinite coordinate: rejected, or skipped (left unmoved, NaN
    /// outputs and normals), as [`super::SmoothOptions::non_finite`].
    pub non_finite: crate::packed::NonFinitePolicy,
    /// Worker threads: 0 uses the current rayon pool, n ≥ 1 a pool of n threads; at most
    /// [`crate::MAX_THREADS`], as [`super::SmoothOptions::threads`]. The result is
    /// bit-identical for every value. Default 0.
    pub threads: usize,
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
            noise_scale: true,
            orientation: Orientation::Unoriented,
            outputs: true,
            non_finite: crate::packed::NonFinitePolicy::Reject,
            threads: 0,
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
    /// The noise scale (`robust/scales.rs`): the local dimension of the cloud (2 a surface, 3
    /// a ball of noise) as measured before the first iteration and, while it read as a ball of
    /// noise, before each later one (empty with `noise_scale: false`; a caller's table is
    /// measured but never widened).
    pub dimension: Vec<f64>,
    /// How many of the iterations used the wide neighbourhoods (`k` and `k_plane` tripled).
    pub wide_iterations: usize,
}

/// Smooths `points` robustly with `options` (see the module documentation).
pub fn smooth_robust(points: &[DVec3], options: &RobustOptions) -> Result<SmoothResult> {
    smooth_robust_with_progress(points, options, &mut |_, _| true)
}

/// [`smooth_robust`] with a progress callback, called with the fraction done (0 to 1, counted
/// against `max_iterations`) and the stage on the thread that runs the computation (the
/// calling thread, or with `options.threads` ≥ 1 a worker of the call's pool); returning
/// `false` stops the run with [`NbhdError::Cancelled`].
pub fn smooth_robust_with_progress(
    points: &[DVec3],
    options: &RobustOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
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
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<RobustReport> {
    smooth_robust_from(points, Neighbors::default(), options, progress)
}

/// [`smooth_robust_report`] with the neighbourhoods from `neighbors`: a search of the call's
/// own (k-d tree, PCA sweep or brute force: the same result from each) or a table the caller
/// already has, of which the first `k_plane` of each row are taken (see
/// [`super::source`]). Runs on the pool of `options.threads`.
pub fn smooth_robust_from(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &RobustOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<RobustReport> {
    crate::parallel::with_threads(options.threads, || {
        robust_on_pool(points, neighbors, options, progress)
    })?
}

/// [`smooth_robust_from`] on the pool it runs on.
fn robust_on_pool(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &RobustOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<RobustReport> {
    options.validate()?;
    match super::finite_subset(points, options.non_finite)? {
        None => robust_finite(points, neighbors, options, progress),
        Some((index, finite)) => {
            let mut holder = None;
            let neighbors =
                super::source::for_finite_subset(neighbors, &index, points.len(), &mut holder)?;
            let r = robust_finite(&finite, neighbors, options, progress)?;
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

/// [`smooth_robust_from`] on finite points (nonempty, every coordinate finite:
/// [`super::finite_subset`] checked or chose them, so they are not scanned again): the run
/// (`robust/run.rs`) driven over the whole cloud as one tile (`robust/tile.rs`).
fn robust_finite(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &RobustOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<RobustReport> {
    let wide_first = options.noise_scale
        && matches!(neighbors, Neighbors::Search(SearchMethod::KdTree))
        && scales::input_reads_as_ball(points, options.k_plane);
    robust_whole(points, neighbors, options, progress, wide_first)
}

/// [`robust_finite`] with the first search finding the wide rows when `wide_first`
/// ([`RobustTile::search_wide_first`]; the same bits either way, a search saved where the run
/// widens).
pub(super) fn robust_whole(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &RobustOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
    wide_first: bool,
) -> Result<RobustReport> {
    let total = options.max_iterations as f64 + 1.0;
    let mut report = progress_in_units(total, progress);
    report(0.0, Stage::Neighbors)?;
    let mut tile = RobustTile::whole(points, neighbors);
    if wide_first {
        tile.search_wide_first();
    }
    let h = RobustRun::spacing_of_nearest(tile.nearest(options)?.0);
    let mut run = RobustRun::new(options, h, neighbors)?;
    let eps = run.epsilon();
    // the generation whose rows were last re-measured, for the progress of 'Neighbors'
    let mut measured = 0;
    loop {
        let round = run.round();
        match round {
            Round::Ratio { generation } | Round::Measure { generation, .. }
                if generation > measured =>
            {
                report(generation as f64, Stage::Neighbors)?;
                measured = generation;
            }
            _ => {}
        }
        match round {
            Round::Measure { generation, .. } => report(generation as f64 + 0.2, Stage::Geometry)?,
            Round::Step { generation, .. } => report(generation as f64 + 0.6, Stage::Step)?,
            Round::Finish { .. } => break,
            _ => {}
        }
        let mut part = [tile.round(&round, options, eps)?];
        run.feed(&reduce(&round, &mut part)?)?;
    }
    if options.outputs {
        report(options.max_iterations as f64 + 0.2, Stage::Outputs)?;
    }
    let (points, normals, outputs, _) = tile.finish(&run.round(), options, eps)?;
    report(options.max_iterations as f64 + 1.0, Stage::Done)?;
    let r = run.report();
    Ok(RobustReport {
        result: SmoothResult {
            points,
            outputs,
            ..r.result
        },
        normals,
        ..r
    })
}

/// The per-point outputs of the faithful method's defaults with the noise-adapted threshold
/// `lambda`, and the robust `normals` (on the side the oriented covariance normal points to).
fn robust_outputs(
    points: &[DVec3],
    narrow: &crate::table::NeighborTable<f64>,
    normals: &[DVec3],
    lambda: f64,
    options: &RobustOptions,
) -> Result<Vec<super::PointOutput>> {
    let defaults = super::SmoothOptions::default();
    let criteria = Criteria {
        weighting: Weighting::Sharp,
        lambda: lambda.max(f64::MIN_POSITIVE),
        feature: FeatureCriterion::AllPoints,
        constrain_interior: None,
        density: defaults.density,
        formula: defaults.formula,
    };
    let mut out = point_outputs(points, narrow, &criteria, options.orientation, &mut |_| {
        true
    })?;
    for (o, &n) in out.iter_mut().zip(normals) {
        o.normal = if n.dot(o.normal) < 0.0 { -n } else { n };
    }
    Ok(out)
}

/// Values stored in tree order (`order[s]` is the caller's index of the value at `s`), in the
/// caller's order.
fn in_input_order(stored: &[DVec3], order: &[u32]) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; stored.len()];
    super::unpermute(stored, order, &mut out);
    out
}
