//! Point-set smoothing (thesis Section 2.1.3 and 2.3, program settings of Section 7.3).
//!
//! One step moves every point at once by `p_i ← p_i + τ Δ_i` (explicit Euler, eq. 2.18, with
//! `τ = λ·∂t`), where `Δ_i = (1/|N_i|) Σ_j g_ij (x_j − p_i)` is the uniform-umbrella form of the
//! Laplacian (eq. 2.16 with the factor `1/|N_i|`) and, anisotropically (eq. 2.30), `g_ij`
//! weighs each neighbour by its directional curvature `κ_ij` (eq. 2.20): `g_sharp` (2.31) or
//! `g_cont` (2.32), both in `|κ_ij|`. Only *feature* points — chosen by the edge quotient (2.33),
//! the principal curvature (2.34), the directional curvature (2.35), or all points — are
//! smoothed anisotropically; the others isotropically (`g = 1`).
//!
//! Neighbourhoods `N_i` are the `k` nearest *other* points within `ε` (Section 2.1.1),
//! computed once on the input and cached (Section 2.1.3), or recomputed every step
//! ('Update Neighbors', Section 7.3). Lengths and curvature thresholds are given absolutely or
//! relative to the mean nearest-neighbour spacing `h` of the input (the default), curvatures in
//! units of `1/h`, so the same settings suit a metre and a millimetre scan.
//!
//! Every per-point computation reads the previous positions only and sums its neighbours in
//! row order, so the result is bit-identical for any number of rayon threads.

use crate::error::{NbhdError, Result};
use crate::geometry::curvature::{
    all_principal_curvatures, offset_curvature, offsets_principal_curvatures, DensityForm,
    PrincipalCurvatures, PrincipalFormula,
};
use crate::geometry::neighbors::mean_spacing_of;
use crate::geometry::normals::{
    local_frames, offsets_frame, offsets_normal, orient_with_progress, Orientation,
};
use crate::packed::NonFinitePolicy;
use crate::table::NeighborTable;
use glam::DVec3;
use rayon::prelude::*;
use source::knn_rows;

use crate::geometry::neighbors::cut_to;
use crate::geometry::normals::quotient_of;
pub use crate::geometry::source;
pub use crate::geometry::{Neighbors, SearchMethod};
pub(crate) use crate::index::check_spacing;
pub use crate::index::{Length, Units};
use crate::named_option;
use crate::names::OptionName;
pub(crate) use crate::packed::finite_subset;
pub(crate) use crate::progress::progress_in_units;
pub use crate::progress::Stage;
/// The fast exact k-nearest table the robust smoothing's rows start from (`src/tree/`).
pub(crate) use crate::tree::exact_knn as nearest;
pub mod robust;
pub use robust::{
    smooth_robust, smooth_robust_report, smooth_robust_with_progress, RobustOptions, RobustReport,
};

/// A curvature (inverse length), absolute or in units of `1/h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Curvature {
    /// In inverse units of the points.
    Absolute(f64),
    /// Multiples of `1/h`.
    Relative(f64),
}

impl Curvature {
    /// The curvature `value` in `units` (relative: multiples of `1/h`).
    pub fn new(value: f64, units: Units) -> Self {
        match units {
            Units::Absolute => Curvature::Absolute(value),
            Units::Relative => Curvature::Relative(value),
        }
    }
}

impl Curvature {
    /// The absolute value for spacing `h`.
    pub fn resolve(self, h: f64) -> f64 {
        match self {
            Curvature::Absolute(v) => v,
            Curvature::Relative(v) => v / h,
        }
    }

    fn is_relative(self) -> bool {
        matches!(self, Curvature::Relative(_))
    }
}

/// The weights `g_ij` of the anisotropic Laplacian (eq. 2.30).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Weighting {
    /// `g = 1`: isotropic Gaussian fairing (eq. 2.16).
    Isotropic,
    /// `g_sharp` (2.31): 1 below the threshold λ, 0 from it on.
    #[default]
    Sharp,
    /// `g_cont` (2.32): 1 below λ, `λ²/(λ² + 10(|κ| − λ)²)` from it on.
    Continuous,
}

impl OptionName for Weighting {
    const OPTION: &'static str = "weighting";
    const WHAT: &'static str = "weighting";
    const NAMES: &'static [(Self, &'static str)] = &[
        (Weighting::Isotropic, "isotropic"),
        (Weighting::Sharp, "sharp"),
        (Weighting::Continuous, "continuous"),
    ];
    const ALIASES: &'static [(&'static str, Self)] = &[("cont", Weighting::Continuous)];
}
named_option!(Weighting);

impl Weighting {
    /// `g_ij` of the neighbour at offset `d = x_j − p_i` of a point with unit normal `n`, for
    /// the threshold `lambda`: 1 (eq. 2.16), `g_sharp` (eq. 2.31), or `g_cont` (eq. 2.32) in
    /// `|κ_ij|` of eq. 2.20.
    #[inline]
    pub fn weight(self, n: DVec3, d: DVec3, lambda: f64) -> f64 {
        match self {
            Weighting::Isotropic => 1.0,
            Weighting::Sharp if g_sharp(n, d, lambda) => 1.0,
            Weighting::Sharp => 0.0,
            Weighting::Continuous => {
                let abs_kappa = offset_curvature(n, d).abs();
                if abs_kappa < lambda {
                    1.0
                } else {
                    let l2 = lambda * lambda;
                    l2 / (l2 + 10.0 * (abs_kappa - lambda).powi(2))
                }
            }
        }
    }
}

/// `g_sharp` of eq. 2.31 as a keep/drop decision: whether the neighbour at offset
/// `d = x_j − p_i` of a point with unit normal `n` has `|κ_ij| < λ` (eq. 2.20), evaluated
/// without the division of eq. 2.20 as `2|⟨n, d⟩| < λ‖d‖²`; a neighbour at `d = 0` has
/// `κ_ij = 0` (as [`offset_curvature`] says) and is kept.
#[inline(always)]
pub(crate) fn g_sharp(n: DVec3, d: DVec3, lambda: f64) -> bool {
    let d2 = d.length_squared();
    2.0 * n.dot(d).abs() < lambda * d2 || d2 == 0.0
}

/// Which points are features, smoothed anisotropically (the others isotropically).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FeatureCriterion {
    /// Every point.
    AllPoints,
    /// Edge quotient (2.33): `min(|k1|,|k2|)/max(|k1|,|k2|) < Q` (principal curvatures
    /// compared by magnitude, since covariance normals carry no sign).
    EdgeQuotient(f64),
    /// Principal curvature (2.34): `max(|k1|, |k2|) > K`.
    PrincipalCurvature(Curvature),
    /// Directional curvature (2.35): some neighbour has `|κ_ij| > D`.
    DirectionalCurvature(Curvature),
}

/// Settings of [`smooth`]. `Default` gives the faithful anisotropic method with the settings
/// measured best for the thesis' method on the shapes of `docs/smoothing-results.md`: 15
/// nearest other points within 6h, computed once, 3 steps of τ = 0.5, `g_sharp` at λ = 0.2/h
/// on all points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothOptions {
    /// Maximum valence `k` (≥ 1).
    pub k: usize,
    /// Influence radius `ε` (> 0).
    pub epsilon: Length,
    /// Number of steps.
    pub steps: usize,
    /// Step size `τ = λ·∂t` of eq. 2.18 (finite, ≥ 0).
    pub tau: f64,
    /// The anisotropic weights `g_ij`.
    pub weighting: Weighting,
    /// Curvature threshold `λ` of (2.31)/(2.32) (> 0).
    pub lambda: Curvature,
    /// Which points are smoothed anisotropically.
    pub feature: FeatureCriterion,
    /// 'Constrain interior' (Section 7.3): points whose covariance quotient
    /// `λ0/(λ0 + λ1 + λ2)` is below this threshold count as interior points of a flat
    /// surface and are not moved. `None` moves every point.
    pub constrain_interior: Option<f64>,
    /// 'Update Neighbors': recompute the neighbourhoods before every step (with the same ε).
    pub update_neighbors: bool,
    /// Density form of eq. 2.27 for the principal curvatures.
    pub density: DensityForm,
    /// How principal curvatures are read off the Weingarten estimate.
    pub formula: PrincipalFormula,
    /// Orientation of the normals reported in the outputs (smoothing itself uses `|κ|`).
    pub orientation: Orientation,
    /// Compute the per-point outputs of the result.
    pub outputs: bool,
    /// Points with a NaN or infinite coordinate (the holes of organized scans):
    /// [`NonFinitePolicy::Reject`] refuses them ([`NbhdError::NonFinite`] names the first),
    /// [`NonFinitePolicy::Skip`] computes on the finite points only; a skipped point keeps its
    /// index, is left unmoved, and its outputs are NaN with
    /// [`crate::geometry::normals::FLAG_SKIPPED`].
    pub non_finite: NonFinitePolicy,
    /// Worker threads: 0 uses the current rayon pool (rayon's global pool has a thread per
    /// core), n ≥ 1 a pool of n threads (see `parallel.rs`); at most
    /// [`crate::parallel::MAX_THREADS`]. The result is bit-identical for every value.
    pub threads: usize,
}

impl Default for SmoothOptions {
    fn default() -> Self {
        Self {
            k: 15,
            epsilon: Length::Relative(6.0),
            steps: 3,
            tau: 0.5,
            weighting: Weighting::Sharp,
            lambda: Curvature::Relative(0.2),
            feature: FeatureCriterion::AllPoints,
            constrain_interior: None,
            update_neighbors: false,
            density: DensityForm::AbsLinear,
            formula: PrincipalFormula::Eq225,
            orientation: Orientation::Unoriented,
            outputs: true,
            non_finite: NonFinitePolicy::Reject,
            threads: 0,
        }
    }
}

impl SmoothOptions {
    /// The normals' part of these options (`k`, `epsilon`, `orientation`, `non_finite`,
    /// `threads`): [`crate::geometry::estimate_normals`] with them gives the normals this
    /// smoothing's analysis reports, bit for bit.
    pub fn normal_options(&self) -> crate::geometry::NormalOptions {
        crate::geometry::NormalOptions {
            k: self.k,
            epsilon: self.epsilon,
            orientation: self.orientation,
            non_finite: self.non_finite,
            threads: self.threads,
        }
    }

    /// Isotropic fairing with the settings of `docs/smoothing-results.md` (2 steps of τ = 0.5).
    pub fn isotropic() -> Self {
        Self {
            weighting: Weighting::Isotropic,
            steps: 2,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |name, reason: String| Err(NbhdError::InvalidOption { name, reason });
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if self.k == 0 {
            return Err(NbhdError::ZeroK);
        }
        let eps = match self.epsilon {
            Length::Absolute(v) | Length::Relative(v) => v,
        };
        if !pos(eps) {
            return bad("epsilon", format!("{eps} must be finite and > 0"));
        }
        if !(self.tau.is_finite() && self.tau >= 0.0) {
            return bad("tau", format!("{} must be finite and >= 0", self.tau));
        }
        let curv = |c: Curvature| match c {
            Curvature::Absolute(v) | Curvature::Relative(v) => v,
        };
        if !pos(curv(self.lambda)) {
            return bad(
                "lambda",
                format!("{} must be finite and > 0", curv(self.lambda)),
            );
        }
        match self.feature {
            FeatureCriterion::EdgeQuotient(q) if !q.is_finite() => {
                return bad("feature", format!("edge quotient {q} must be finite"))
            }
            FeatureCriterion::PrincipalCurvature(c) | FeatureCriterion::DirectionalCurvature(c)
                if !curv(c).is_finite() =>
            {
                return bad("feature", format!("threshold {} must be finite", curv(c)))
            }
            _ => {}
        }
        if let Some(t) = self.constrain_interior {
            if !t.is_finite() {
                return bad("constrain_interior", format!("{t} must be finite"));
            }
        }
        Ok(())
    }

    fn needs_relative(&self) -> bool {
        matches!(self.epsilon, Length::Relative(_))
            || self.lambda.is_relative()
            || matches!(
                self.feature,
                FeatureCriterion::PrincipalCurvature(c) | FeatureCriterion::DirectionalCurvature(c)
                    if c.is_relative()
            )
    }
}

/// The per-point values the thesis' program colours by (Section 7.3), on the final points.
/// Curvatures are signed relative to the reported normal (see
/// [`crate::geometry::curvature`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointOutput {
    /// Unit normal (eq. 2.10), oriented as `SmoothOptions::orientation` asks.
    pub normal: DVec3,
    /// 'Mean': `(k1 + k2)/2`.
    pub mean_curvature: f64,
    /// 'Max Princ': `max(|k1|, |k2|)`.
    pub max_principal_curvature: f64,
    /// 'CovQuotient': `λ0/(λ0 + λ1 + λ2)` of the covariance (0 = flat; at most 1/3).
    pub covariance_quotient: f64,
    /// 'MeanAni': mean of `κ_ij` weighted by `g_ij` of the chosen weighting,
    /// `Σ g κ / Σ g` (0 when every weight vanishes).
    pub anisotropic_mean_curvature: f64,
    /// 'PrincQuotient': `min(|k1|,|k2|)/max(|k1|,|k2|)` in `[0, 1]`.
    pub principal_curvature_quotient: f64,
    /// 'MaxCov': the largest covariance eigenvalue divided by `|N_i| + 1` (the variance along
    /// the main direction).
    pub max_covariance: f64,
    /// Principal curvatures and directions.
    pub principal: PrincipalCurvatures,
    /// Degeneracy flags of the normal (`geometry::normals::FLAG_*`).
    pub normal_flags: u8,
    /// Whether the feature criterion selects this point.
    pub feature: bool,
    /// Whether 'constrain interior' holds this point fixed.
    pub interior: bool,
}

/// What [`smooth`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothResult {
    /// The smoothed points, in input order.
    pub points: Vec<DVec3>,
    /// Per-point outputs on the smoothed points (empty unless `SmoothOptions::outputs`).
    pub outputs: Vec<PointOutput>,
    /// Mean nearest-neighbour spacing `h` of the input.
    pub spacing: f64,
    /// Absolute ε used.
    pub epsilon: f64,
    /// Absolute λ used.
    pub lambda: f64,
    /// 'Min Neighbors': the smallest `|N_i|` of the input neighbourhoods.
    pub min_neighbors: usize,
}

/// The weights and criteria of a run with every threshold absolute: what the step and the
/// per-point outputs read, from [`SmoothOptions`] or from the robust method
/// ([`robust::RobustOptions`]), which has no options of its own for them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Criteria {
    /// The anisotropic weights `g_ij` (eq. 2.30–2.32).
    pub(crate) weighting: Weighting,
    /// Curvature threshold λ of (2.31)/(2.32), absolute.
    pub(crate) lambda: f64,
    /// Feature criterion (2.33–2.35), thresholds absolute.
    pub(crate) feature: FeatureCriterion,
    /// 'Constrain interior' threshold of the covariance quotient (Section 7.3).
    pub(crate) constrain_interior: Option<f64>,
    /// Density form of eq. 2.27.
    pub(crate) density: DensityForm,
    /// How principal curvatures are read off the Weingarten estimate.
    pub(crate) formula: PrincipalFormula,
}

impl Criteria {
    /// The criteria of `options` for mean spacing `h`.
    fn of(options: &SmoothOptions, h: f64) -> Self {
        Self {
            weighting: options.weighting,
            lambda: options.lambda.resolve(h),
            feature: match options.feature {
                FeatureCriterion::PrincipalCurvature(c) => {
                    FeatureCriterion::PrincipalCurvature(Curvature::Absolute(c.resolve(h)))
                }
                FeatureCriterion::DirectionalCurvature(c) => {
                    FeatureCriterion::DirectionalCurvature(Curvature::Absolute(c.resolve(h)))
                }
                f => f,
            },
            constrain_interior: options.constrain_interior,
            density: options.density,
            formula: options.formula,
        }
    }

    /// Whether the feature criterion selects a point: the edge quotient (2.33)
    /// `min(|k1|,|k2|)/max(|k1|,|k2|) < Q` and the principal curvature (2.34)
    /// `max(|k1|,|k2|) > K` read its principal curvatures `principal`, the directional
    /// curvature (2.35) `|κ_ij| > D` for some neighbour reads `abs_kappas`, the `|κ_ij|` of its
    /// neighbours (eq. 2.20), as far as it needs them. Every point is a feature for
    /// [`FeatureCriterion::AllPoints`], and when the principal curvatures a criterion reads are
    /// not given.
    #[inline]
    fn is_feature(
        &self,
        principal: Option<&PrincipalCurvatures>,
        mut abs_kappas: impl Iterator<Item = f64>,
    ) -> bool {
        match (self.feature, principal) {
            (FeatureCriterion::EdgeQuotient(q), Some(pc)) => pc.quotient() < q,
            (FeatureCriterion::PrincipalCurvature(k), Some(pc)) => pc.max_abs() > k.resolve(1.0),
            (FeatureCriterion::DirectionalCurvature(d), _) => {
                let d = d.resolve(1.0);
                abs_kappas.any(|k| k > d)
            }
            _ => true,
        }
    }

    /// 'Constrain interior' (Section 7.3): whether a point whose covariance (eq. 2.8) has the
    /// ascending eigenvalues `values` is an interior point of a flat surface, held fixed: its
    /// covariance quotient `λ0/(λ0 + λ1 + λ2)` is below the threshold.
    #[inline]
    fn is_interior(&self, values: DVec3) -> bool {
        self.constrain_interior
            .is_some_and(|t| quotient_of(values) < t)
    }
}

impl PointOutput {
    /// The outputs of a point skipped for its non-finite coordinates: NaN everywhere, flagged
    /// [`crate::geometry::normals::FLAG_SKIPPED`].
    pub fn skipped() -> Self {
        let nan3 = DVec3::splat(f64::NAN);
        Self {
            normal: nan3,
            mean_curvature: f64::NAN,
            max_principal_curvature: f64::NAN,
            covariance_quotient: f64::NAN,
            anisotropic_mean_curvature: f64::NAN,
            principal_curvature_quotient: f64::NAN,
            max_covariance: f64::NAN,
            principal: PrincipalCurvatures {
                k1: f64::NAN,
                k2: f64::NAN,
                dir1: nan3,
                dir2: nan3,
            },
            normal_flags: crate::geometry::normals::FLAG_SKIPPED,
            feature: false,
            interior: false,
        }
    }
}

/// The result computed on the finite points `index` of `points` placed back at the original
/// indices: skipped points unmoved, with [`PointOutput::skipped`] outputs.
pub(crate) fn scatter_result(
    mut result: SmoothResult,
    points: &[DVec3],
    index: &[usize],
) -> SmoothResult {
    let mut all = points.to_vec();
    for (&i, &p) in index.iter().zip(&result.points) {
        all[i] = p;
    }
    result.points = all;
    if !result.outputs.is_empty() {
        let mut outputs = vec![PointOutput::skipped(); points.len()];
        for (&i, o) in index.iter().zip(&result.outputs) {
            outputs[i] = *o;
        }
        result.outputs = outputs;
    }
    result
}

/// Refuses results in which every neighbourhood is degenerate ([`NbhdError::Degenerate`]):
/// when no row of `table` reaches 3 points with the point itself, or (`flagged`, for
/// estimates of the geometry alone: how many of the rows' points carry a degeneracy flag) when
/// every point is flagged. `epsilon` (resolved) and `h` go into the message, with whether ε was relative.
pub(crate) fn check_not_degenerate(
    table: &NeighborTable<f64>,
    flagged: Option<usize>,
    epsilon: f64,
    h: f64,
    relative: bool,
) -> Result<()> {
    let largest = table.max_row_len() + 1;
    let all_flagged = flagged.is_some_and(|f| !table.is_empty() && f == table.len());
    let flagged = flagged.unwrap_or(0);
    if largest < 3 || all_flagged {
        return Err(NbhdError::Degenerate {
            points: table.len(),
            largest,
            flagged,
            epsilon,
            spacing: h,
            relative,
        });
    }
    Ok(())
}

/// Smooths `points` with `options` (see the module documentation).
///
/// ```
/// use glam::DVec3;
/// use nbhd::smooth::{smooth, SmoothOptions};
///
/// // a wavy patch of the plane z = 0: smoothing flattens it
/// let points: Vec<DVec3> = (0..900)
///     .map(|i| {
///         let (x, y) = ((i % 30) as f64, (i / 30) as f64);
///         DVec3::new(x, y, 0.05 * ((x + y) * 2.0).sin())
///     })
///     .collect();
/// let result = smooth(&points, &SmoothOptions::isotropic())?;
/// let spread = |p: &[DVec3]| p.iter().map(|p| p.z.abs()).sum::<f64>();
/// assert!(spread(&result.points) < spread(&points));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn smooth(points: &[DVec3], options: &SmoothOptions) -> Result<SmoothResult> {
    smooth_with_progress(points, options, &mut |_, _| true)
}

/// [`smooth`] with a progress callback, called with the fraction done (0 to 1) and the stage
/// on the thread that runs the computation (the calling thread, or with `options.threads` ≥ 1
/// a worker of the call's pool), never on two at once; returning `false` stops the run with
/// [`NbhdError::Cancelled`].
///
/// Errors besides the options' own: [`NbhdError::NonFinite`] (unless
/// `options.non_finite` skips such points), [`NbhdError::EmptyInput`],
/// [`NbhdError::Degenerate`] when no neighbourhood reaches 3 points — or, with `steps == 0`
/// (an estimate of the geometry alone), when every normal is flagged degenerate —
/// [`NbhdError::OutOfMemory`] when the neighbourhoods of `k` do not fit in memory.
pub fn smooth_with_progress(
    points: &[DVec3],
    options: &SmoothOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<SmoothResult> {
    smooth_from(points, Neighbors::default(), options, progress)
}

/// [`smooth_with_progress`] with the neighbourhoods from `neighbors`: a search of the call's own
/// (k-d tree, PCA sweep or brute force: the same result from each) or a table the caller
/// already has (see [`source`]). With `update_neighbors`, the later searches use the k-d tree
/// unless `neighbors` names another method. Runs on the pool of `options.threads`.
pub fn smooth_from(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &SmoothOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<SmoothResult> {
    crate::parallel::with_threads(options.threads, || {
        smooth_on_pool(points, neighbors, options, progress)
    })?
}

/// [`smooth_from`] on the pool it runs on.
fn smooth_on_pool(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &SmoothOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<SmoothResult> {
    options.validate()?;
    match finite_subset(points, options.non_finite)? {
        None => smooth_finite(points, neighbors, options, progress),
        Some((index, finite)) => {
            let mut holder = None;
            let neighbors =
                source::for_finite_subset(neighbors, &index, points.len(), &mut holder)?;
            Ok(scatter_result(
                smooth_finite(&finite, neighbors, options, progress)?,
                points,
                &index,
            ))
        }
    }
}

/// [`smooth_from`] on finite points (nonempty, every coordinate finite: [`finite_subset`]
/// checked or chose them, so they are not scanned again).
fn smooth_finite(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &SmoothOptions,
    progress: &mut dyn FnMut(f64, Stage) -> bool,
) -> Result<SmoothResult> {
    let total = options.steps as f64 + 1.0;
    let mut report = progress_in_units(total, progress);
    report(0.0, Stage::Neighbors)?;
    let (knn, order) = knn_rows(points, neighbors, options.k)?;
    let research = match neighbors {
        Neighbors::Search(method) => Neighbors::Search(method),
        Neighbors::Table(_) => Neighbors::default(),
    };
    let h = mean_spacing_of(&knn);
    check_spacing(h, options.needs_relative())?;
    let eps = options.epsilon.resolve(h);
    let criteria = Criteria::of(options, h);
    let mut table = cut_to(knn, eps);
    let relative_eps = matches!(options.epsilon, Length::Relative(_));
    check_not_degenerate(&table, None, eps, h, relative_eps)?;
    let min_neighbors = table.min_row_len();
    let mut cur = points.to_vec();
    if options.steps > 0 {
        // the steps run on the points stored in tree order, so that a point's neighbours lie
        // close in memory; each point's arithmetic is unchanged (rows keep their order)
        let mut rows = Rows::permuted(&table, &order);
        let mut stored: Vec<DVec3> = order.iter().map(|&o| points[o as usize]).collect();
        let mut next = vec![DVec3::ZERO; stored.len()];
        for step in 0..options.steps {
            let base = step as f64 + 0.2;
            if step > 0 && options.update_neighbors {
                report(base, Stage::Neighbors)?;
                unpermute(&stored, &order, &mut cur);
                table = cut_to(knn_rows(&cur, research, options.k)?.0, eps);
                rows = Rows::permuted(&table, &order);
            }
            report(base + 0.1, Stage::Geometry)?;
            report(base + 0.5, Stage::Step)?;
            step_into(&stored, &rows, &criteria, options.tau, &mut next);
            std::mem::swap(&mut stored, &mut next);
        }
        unpermute(&stored, &order, &mut cur);
    }
    let outputs = if options.outputs {
        report(options.steps as f64 + 0.2, Stage::Outputs)?;
        if options.update_neighbors && options.steps > 0 {
            table = cut_to(knn_rows(&cur, research, options.k)?.0, eps);
        }
        let base = options.steps as f64 + 0.2;
        let outputs = point_outputs(&cur, &table, &criteria, options.orientation, &mut |f| {
            report(base + 0.7 * f, Stage::Outputs).is_ok()
        })?;
        if options.steps == 0 {
            let flagged = outputs.iter().filter(|o| o.normal_flags != 0).count();
            check_not_degenerate(&table, Some(flagged), eps, h, relative_eps)?;
        }
        outputs
    } else {
        Vec::new()
    };
    report(total, Stage::Done)?;
    Ok(SmoothResult {
        points: cur,
        outputs,
        spacing: h,
        epsilon: eps,
        lambda: criteria.lambda,
        min_neighbors,
    })
}

/// The per-point outputs (Section 7.3) of `points` themselves, without smoothing: the
/// neighbourhoods, thresholds and orientation of `options` apply.
///
/// ```
/// use glam::DVec3;
/// use nbhd::smooth::{analyze, SmoothOptions};
///
/// let points: Vec<DVec3> = (0..400).map(|i| DVec3::new((i % 20) as f64, (i / 20) as f64, 0.0)).collect();
/// let result = analyze(&points, &SmoothOptions::default())?;
/// assert_eq!(result.points, points); // nothing moves
/// assert!(result.outputs.iter().all(|o| o.max_principal_curvature < 1e-9));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn analyze(points: &[DVec3], options: &SmoothOptions) -> Result<SmoothResult> {
    analyze_from(points, Neighbors::default(), options)
}

/// [`analyze`] with the neighbourhoods from `neighbors` (see [`smooth_from`]): normals and
/// curvatures of points whose neighbour table or tree the caller already has.
pub fn analyze_from(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &SmoothOptions,
) -> Result<SmoothResult> {
    analyze_with_progress(points, neighbors, options, &mut |_, _| true)
}

/// [`analyze_from`] with a progress callback (as [`smooth_with_progress`] calls it; returning
/// `false` stops with [`NbhdError::Cancelled`]): the one place that turns `options` into an
/// estimate of the geometry alone (no step, every output), which every front door calls.
///
/// ```
/// use glam::DVec3;
/// use nbhd::smooth::{analyze_with_progress, Neighbors, SmoothOptions, Stage};
/// use nbhd::NbhdError;
///
/// let points: Vec<DVec3> = (0..400).map(|i| DVec3::new((i % 20) as f64, (i / 20) as f64, 0.0)).collect();
/// let opts = SmoothOptions { steps: 5, outputs: false, ..SmoothOptions::default() };
/// let mut last = (0.0, Stage::Neighbors);
/// let result = analyze_with_progress(&points, Neighbors::default(), &opts, &mut |f, s| {
///     last = (f, s);
///     true
/// })?;
/// assert_eq!(result.points, points); // the steps of `opts` are not taken
/// assert_eq!(result.outputs.len(), points.len()); // the outputs are always computed
/// assert_eq!(last, (1.0, Stage::Done));
/// let stop = analyze_with_progress(&points, Neighbors::default(), &opts, &mut |_, _| false);
/// assert!(matches!(stop, Err(NbhdError::Cancelled)));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn analyze_with_progress(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &SmoothOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<SmoothResult> {
    let opts = SmoothOptions {
        steps: 0,
        outputs: true,
        ..*options
    };
    smooth_from(points, neighbors, &opts, progress)
}

/// The index rows of a neighbour table with the points stored in another order: row `s` holds
/// the stored positions of the neighbours of the point stored at `s`, in the table's row order.
struct Rows {
    offsets: Vec<usize>,
    indices: Vec<u32>,
}

impl Rows {
    /// `table` for the points stored as `order` says (`order[s]` is the index of the point
    /// stored at `s`; a permutation).
    fn permuted(table: &NeighborTable<f64>, order: &[u32]) -> Self {
        let position = positions_of(order);
        let mut offsets = Vec::with_capacity(order.len() + 1);
        let mut indices = Vec::with_capacity(table.total());
        offsets.push(0);
        for &o in order {
            indices.extend(
                table
                    .indices_of(o as usize)
                    .iter()
                    .map(|&j| position[j as usize]),
            );
            offsets.push(indices.len());
        }
        Self { offsets, indices }
    }

    #[inline]
    fn row(&self, s: usize) -> &[u32] {
        &self.indices[self.offsets[s]..self.offsets[s + 1]]
    }
}

/// Writes the points stored as `order` says back in index order.
/// The inverse of a storage order: `positions_of(order)[i]` is where the point of index `i` is
/// stored (`order[s]` is the index of the point stored at `s`; a permutation).
fn positions_of(order: &[u32]) -> Vec<u32> {
    let mut position = vec![0u32; order.len()];
    for (s, &o) in order.iter().enumerate() {
        position[o as usize] = s as u32;
    }
    position
}

fn unpermute(stored: &[DVec3], order: &[u32], out: &mut [DVec3]) {
    for (&p, &o) in stored.iter().zip(order) {
        out[o as usize] = p;
    }
}

/// One explicit Euler step `p_i ← p_i + τ Δ_i` (eq. 2.18) of every point of `cur` into `next`,
/// with the uniform-umbrella Laplacian `Δ_i = (1/|N_i|) Σ_j g_ij (x_j − p_i)` (eq. 2.16, and
/// eq. 2.30 with `g_ij` of eq. 2.31/2.32 in `|κ_ij|` of eq. 2.20 for feature points).
///
/// Each point's normal (eq. 2.8–2.10), its features (2.33–2.35) and its move are computed in
/// one pass over the offsets `x_j − p_i`, gathered once per point into a buffer of the worker
/// (no allocation per point). Only the point's own normal enters its move, so nothing else is
/// stored; principal curvatures (eq. 2.25–2.29) only for the criteria (2.33)/(2.34) that read
/// them. Every point reads `cur` only and sums in row order: bit-identical for any number of
/// threads.
fn step_into(cur: &[DVec3], rows: &Rows, criteria: &Criteria, tau: f64, next: &mut [DVec3]) {
    let aniso = criteria.weighting != Weighting::Isotropic;
    let needs_normal = aniso || criteria.constrain_interior.is_some();
    let needs_principal = aniso
        && matches!(
            criteria.feature,
            FeatureCriterion::EdgeQuotient(_) | FeatureCriterion::PrincipalCurvature(_)
        );
    next.par_iter_mut()
        .enumerate()
        .for_each_init(Vec::new, |buf: &mut Vec<DVec3>, (i, out)| {
            let p = cur[i];
            let row = rows.row(i);
            *out = p;
            if row.is_empty() {
                return;
            }
            if !needs_normal {
                let acc = row
                    .iter()
                    .fold(DVec3::ZERO, |acc, &j| acc + (cur[j as usize] - p));
                *out = p + tau * acc / row.len() as f64;
                return;
            }
            // rows never hold the point itself (`exclude_self`), so no filter is needed
            debug_assert!(row.iter().all(|&j| j as usize != i));
            buf.resize(row.len(), DVec3::ZERO);
            let mut sum = DVec3::ZERO;
            for (d, &j) in buf.iter_mut().zip(row) {
                *d = cur[j as usize] - p;
                sum += *d;
            }
            let (n, feature) = if needs_principal {
                let frame = offsets_frame(buf);
                if criteria.is_interior(frame.eigenvalues) {
                    return;
                }
                let pc = offsets_principal_curvatures(
                    &frame,
                    buf.iter().copied(),
                    criteria.density,
                    criteria.formula,
                );
                (
                    frame.normal,
                    criteria.is_feature(Some(&pc), std::iter::empty()),
                )
            } else {
                let (n, values, _) = offsets_normal(buf, sum);
                if criteria.is_interior(values) {
                    return;
                }
                let kappas = buf.iter().map(|&x| offset_curvature(n, x).abs());
                (n, aniso && criteria.is_feature(None, kappas))
            };
            let mut acc = DVec3::ZERO;
            if feature && criteria.weighting == Weighting::Sharp {
                for &d in buf.iter() {
                    acc += if g_sharp(n, d, criteria.lambda) {
                        d
                    } else {
                        DVec3::ZERO
                    };
                }
            } else if feature {
                for &d in buf.iter() {
                    acc += criteria.weighting.weight(n, d, criteria.lambda) * d;
                }
            } else {
                for &d in buf.iter() {
                    acc += d;
                }
            }
            *out = p + tau * acc / row.len() as f64;
        });
}

/// The per-point outputs (Section 7.3) of `points` with the neighbourhoods `table`: the
/// faithful method's and the robust method's (which replaces the normals afterwards).
/// `progress` gets the fraction of the outputs' work done, mostly the orientation (the part
/// that can take long, see [`orient_with_progress`]); `false` cancels.
pub(crate) fn point_outputs(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    criteria: &Criteria,
    orientation: Orientation,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<Vec<PointOutput>> {
    let mut frames = local_frames(points, table)?;
    if !progress(0.3) {
        return Err(NbhdError::Cancelled);
    }
    orient_with_progress(points, table, &mut frames, orientation, &mut |f| {
        progress(0.3 + 0.5 * f)
    })?;
    let principal =
        all_principal_curvatures(points, table, &frames, criteria.density, criteria.formula)?;
    Ok((0..points.len())
        .into_par_iter()
        .map(|i| {
            let (f, pc, p) = (&frames[i], principal[i], points[i]);
            let n = f.normal;
            let (mut gs, mut gk) = (0.0, 0.0);
            for &j in table.indices_of(i) {
                let d = points[j as usize] - p;
                let kappa = offset_curvature(n, d);
                let g = criteria.weighting.weight(n, d, criteria.lambda);
                gs += g;
                gk += g * kappa;
            }
            let kappas = table
                .indices_of(i)
                .iter()
                .map(|&j| offset_curvature(n, points[j as usize] - p).abs());
            PointOutput {
                normal: n,
                mean_curvature: pc.mean(),
                max_principal_curvature: pc.max_abs(),
                covariance_quotient: quotient_of(f.eigenvalues),
                anisotropic_mean_curvature: if gs > 0.0 { gk / gs } else { 0.0 },
                principal_curvature_quotient: pc.quotient(),
                max_covariance: f.eigenvalues.z / f.count as f64,
                principal: pc,
                normal_flags: f.flags,
                feature: criteria.is_feature(Some(&pc), kappas),
                interior: criteria.is_interior(f.eigenvalues),
            }
        })
        .collect())
}

#[cfg(test)]
mod tests;
