//! Normals, curvatures and point-set smoothing (thesis Chapter 2) for C: an options struct
//! with a defaults initializer, a progress callback that can cancel, and outputs in caller
//! buffers. Each export converts its arguments and calls [`crate::smooth::smooth_with_progress`]
//! or [`crate::smooth::analyze`]; nothing is computed here.

use std::ffi::{c_int, c_void};

use glam::DVec3;

use super::args::{check_aligned, check_optional, check_ptr};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::types::{c_bool_field, c_enum, c_enum_field, c_field, CEnum, PointsArg};
use super::types::{nbhd_non_finite_policy, nbhd_points};
use crate::geometry::Orientation;
use crate::points::PointsView;
use crate::scalar::ScalarType;
use crate::smooth::{
    self, Curvature, FeatureCriterion, Length, PointOutput, SmoothOptions, SmoothResult, Stage,
    Weighting,
};

/// Whether a length or curvature option is absolute or relative to the mean spacing `h` of
/// the input (the mean distance of a point to its nearest other point, estimated by nbhd).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_units {
    /// A length in multiples of `h`, a curvature in multiples of `1/h`: the same settings suit
    /// a metre and a millimetre scan. The default.
    Relative = 0,
    /// In the points' own units (a curvature in inverse units).
    Absolute = 1,
}
c_enum!(nbhd_units, [Relative, Absolute]);

/// The weights `g_ij` of the smoothing step (thesis eq. 2.30–2.32).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_weighting {
    /// `g = 1`: isotropic Laplacian fairing (eq. 2.16).
    Isotropic = 0,
    /// `g_sharp` (eq. 2.31): 1 where the directional curvature `|κ_ij|` is below `lambda`, 0
    /// from it on. The default.
    Sharp = 1,
    /// `g_cont` (eq. 2.32): 1 below `lambda`, `λ²/(λ² + 10(|κ| − λ)²)` from it on.
    Continuous = 2,
}
c_enum!(nbhd_weighting, [Isotropic, Sharp, Continuous]);

/// Which points are smoothed anisotropically (thesis eq. 2.33–2.35); the others are smoothed
/// isotropically.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_feature_criterion {
    /// Every point. The default.
    AllPoints = 0,
    /// Edge quotient Q (eq. 2.33): `min(|k1|,|k2|) / max(|k1|,|k2|) < feature_threshold`.
    EdgeQuotient = 1,
    /// Principal curvature K (eq. 2.34): `max(|k1|,|k2|) > feature_threshold`.
    PrincipalCurvature = 2,
    /// Directional curvature D (eq. 2.35): some neighbour has `|κ_ij| > feature_threshold`.
    DirectionalCurvature = 3,
}
c_enum!(
    nbhd_feature_criterion,
    [
        AllPoints,
        EdgeQuotient,
        PrincipalCurvature,
        DirectionalCurvature
    ]
);

/// How the sign-free covariance normals are oriented in the outputs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_orientation {
    /// The eigen-solver's sign: arbitrary but deterministic. The default.
    Unoriented = 0,
    /// Every normal points toward `orientation_point` (a scanner's viewpoint).
    TowardPoint = 1,
    /// Every normal points away from `orientation_point` (outward for star-shaped surfaces).
    AwayFromPoint = 2,
    /// One consistent orientation spread over the neighbour graph along smooth paths
    /// (Hoppe et al. 1992); in each connected part the highest point's normal has `z >= 0`.
    Propagate = 3,
}
c_enum!(
    nbhd_orientation,
    [Unoriented, TowardPoint, AwayFromPoint, Propagate]
);

/// What a smoothing run is doing when it calls the progress callback.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_stage {
    /// Neighbourhood search and the spacing estimate.
    Neighbors = 0,
    /// Normals and curvatures of a step.
    Geometry = 1,
    /// Moving the points.
    Step = 2,
    /// Per-point geometry of the result.
    Outputs = 3,
    /// Finished (fraction 1).
    Done = 4,
}

impl From<Stage> for nbhd_stage {
    fn from(s: Stage) -> Self {
        match s {
            Stage::Neighbors => nbhd_stage::Neighbors,
            Stage::Geometry => nbhd_stage::Geometry,
            Stage::Step => nbhd_stage::Step,
            Stage::Outputs => nbhd_stage::Outputs,
            Stage::Done => nbhd_stage::Done,
        }
    }
}

/// A progress callback: `fraction` grows from 0 to 1 over the run; return `true` to go on,
/// `false` to stop the run, which then returns NBHD_STATUS_CANCELLED and writes no output.
/// It is called from the thread that runs the computation (the calling thread when
/// `threads` is 0, otherwise a worker of the call's own pool), never from two threads at
/// once, and must return normally (no longjmp, no C++ exception).
pub type nbhd_progress_fn =
    Option<unsafe extern "C" fn(fraction: f64, stage: nbhd_stage, user_data: *mut c_void) -> bool>;

/// Options of nbhd_smooth and nbhd_estimate_curvatures (nbhd_estimate_normals has its own,
/// nbhd_normal_options). Start from nbhd_smooth_options_default() and change what you need.
///
/// UNITS: `epsilon`, `lambda` and a curvature `feature_threshold` are RELATIVE by default —
/// multiples of the mean spacing h of the points (or of 1/h) — not lengths in the points'
/// units. `epsilon = 0.01` means 0.01 h, far below any neighbour, and is refused with
/// NBHD_STATUS_DEGENERATE; for 1 cm in metre coordinates set `epsilon = 0.01` AND
/// `epsilon_units = NBHD_UNITS_ABSOLUTE`. nbhd_smooth_summary reports h and ε resolved.
///
/// Neighbourhoods are the thesis' ε-k-neighbourhoods (Section 2.1.1): the `k` nearest other
/// points within `epsilon`, computed once on the input and cached (Section 2.1.3) unless
/// `update_neighbors` is set. One step moves every point at once by
/// `p_i += tau * (1/|N_i|) Σ_j g_ij (x_j − p_i)` (eq. 2.16, 2.18, 2.30).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_smooth_options {
    /// Maximum valence k (>= 1). Default 15.
    pub k: usize,
    /// Influence radius ε (> 0), plain (not squared), inclusive. Default 6 (relative: 6h).
    pub epsilon: f64,
    /// Units of `epsilon`. Default relative.
    pub epsilon_units: nbhd_units,
    /// Number of smoothing steps (0 only analyses). Default 3.
    pub steps: usize,
    /// Step size τ = λ·∂t of eq. 2.18 (finite, >= 0). Default 0.5.
    pub tau: f64,
    /// The weights g_ij. Default NBHD_WEIGHTING_SHARP.
    pub weighting: nbhd_weighting,
    /// Curvature threshold λ of g_sharp / g_cont (> 0). Default 0.2 (relative: 0.2/h).
    pub lambda: f64,
    /// Units of `lambda`. Default relative.
    pub lambda_units: nbhd_units,
    /// Which points are smoothed anisotropically. Default all points.
    pub feature: nbhd_feature_criterion,
    /// Threshold of the feature criterion: the quotient Q (a plain number) for
    /// EDGE_QUOTIENT, a curvature for PRINCIPAL_CURVATURE and DIRECTIONAL_CURVATURE.
    /// Ignored for ALL_POINTS. Default 0.5.
    pub feature_threshold: f64,
    /// Units of a curvature `feature_threshold`. Default relative.
    pub feature_units: nbhd_units,
    /// 'Constrain interior' (thesis Section 7.3): points whose covariance quotient
    /// λ0/(λ0 + λ1 + λ2) is below `interior_threshold` are held fixed. Default false.
    pub constrain_interior: bool,
    /// The covariance-quotient threshold of `constrain_interior` (finite). Default 0.01.
    pub interior_threshold: f64,
    /// 'Update Neighbors' (Section 7.3): recompute the neighbourhoods before every step.
    /// Default false.
    pub update_neighbors: bool,
    /// Orientation of the normals written to the outputs (smoothing itself uses |κ| and does
    /// not depend on it). Default unoriented.
    pub orientation: nbhd_orientation,
    /// The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite).
    pub orientation_point: [f64; 3],
    /// Worker threads: 0 the shared pool with a thread per core, n >= 1 a pool of n threads
    /// made for this call (at most NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results
    /// are identical for every value. Default 0.
    pub threads: usize,
    /// Called with the progress of the run; NULL for none. Default NULL.
    pub progress: nbhd_progress_fn,
    /// Passed to `progress` unchanged. Default NULL.
    pub progress_user_data: *mut c_void,
    /// Points with a NaN or infinite coordinate (the holes of organized scans), as in
    /// nbhd_build_options: REJECT (the default) refuses the input with NON_FINITE; SKIP
    /// computes on the finite points only, and a skipped point keeps its index, is left
    /// unmoved (its coordinates are copied to `out_coords` as they are) and gets NaN geometry
    /// with `normal_flags` 8.
    pub non_finite: nbhd_non_finite_policy,
}

/// The per-point geometry the thesis' program colours by (Section 7.3), on the final points.
/// Curvatures are signed relative to the reported normal.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_point_geometry {
    /// Unit normal (eq. 2.10), oriented as the options ask.
    pub normal: [f64; 3],
    /// Larger principal curvature k1 (Weingarten estimate, eq. 2.25–2.29).
    pub k1: f64,
    /// Smaller principal curvature k2.
    pub k2: f64,
    /// Unit principal direction of k1.
    pub dir1: [f64; 3],
    /// Unit principal direction of k2.
    pub dir2: [f64; 3],
    /// 'Mean': (k1 + k2) / 2.
    pub mean_curvature: f64,
    /// 'Max Princ': max(|k1|, |k2|).
    pub max_principal_curvature: f64,
    /// 'CovQuotient': λ0/(λ0 + λ1 + λ2) of the covariance (0 flat, at most 1/3).
    pub covariance_quotient: f64,
    /// 'MeanAni': Σ g κ / Σ g over the neighbours, with the chosen weights (0 if all vanish).
    pub anisotropic_mean_curvature: f64,
    /// 'PrincQuotient': min(|k1|,|k2|) / max(|k1|,|k2|) in [0, 1].
    pub principal_curvature_quotient: f64,
    /// 'MaxCov': the largest covariance eigenvalue over the neighbourhood size.
    pub max_covariance: f64,
    /// Why the normal is not to be trusted, 0 if it is: 1 fewer than 3 points, 2 collinear or
    /// coincident points, 4 the normal is not unique (isotropic neighbourhood), 8 the point
    /// was skipped for a NaN or infinite coordinate (everything else is NaN then).
    pub normal_flags: u8,
    /// Whether the feature criterion selects the point.
    pub feature: bool,
    /// Whether 'constrain interior' holds the point fixed.
    pub interior: bool,
}

/// Scalars a run resolved: the spacing estimate and the absolute thresholds it used.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_smooth_summary {
    /// Mean nearest-neighbour spacing h of the input.
    pub spacing: f64,
    /// The absolute ε used.
    pub epsilon: f64,
    /// The absolute λ used.
    pub lambda: f64,
    /// 'Min Neighbors': the smallest neighbourhood size |N_i| of the input.
    pub min_neighbors: usize,
}

/// The core's length for a C value and its units.
pub(super) fn length(u: nbhd_units, v: f64) -> Length {
    match u {
        nbhd_units::Relative => Length::Relative(v),
        nbhd_units::Absolute => Length::Absolute(v),
    }
}

/// The C units and value of the core's length.
pub(super) fn units_of_length(l: Length) -> (nbhd_units, f64) {
    match l {
        Length::Relative(v) => (nbhd_units::Relative, v),
        Length::Absolute(v) => (nbhd_units::Absolute, v),
    }
}

fn curvature(u: nbhd_units, v: f64) -> Curvature {
    match u {
        nbhd_units::Relative => Curvature::Relative(v),
        nbhd_units::Absolute => Curvature::Absolute(v),
    }
}

fn units_of_curvature(c: Curvature) -> (nbhd_units, f64) {
    match c {
        Curvature::Relative(v) => (nbhd_units::Relative, v),
        Curvature::Absolute(v) => (nbhd_units::Absolute, v),
    }
}

/// The C defaults: the core's [`SmoothOptions::default`].
fn default_options() -> nbhd_smooth_options {
    let d = SmoothOptions::default();
    let (epsilon_units, epsilon) = units_of_length(d.epsilon);
    let (lambda_units, lambda) = units_of_curvature(d.lambda);
    let (feature, feature_threshold, feature_units) = match d.feature {
        FeatureCriterion::AllPoints => {
            (nbhd_feature_criterion::AllPoints, 0.5, nbhd_units::Relative)
        }
        FeatureCriterion::EdgeQuotient(q) => (
            nbhd_feature_criterion::EdgeQuotient,
            q,
            nbhd_units::Relative,
        ),
        FeatureCriterion::PrincipalCurvature(c) => {
            let (u, v) = units_of_curvature(c);
            (nbhd_feature_criterion::PrincipalCurvature, v, u)
        }
        FeatureCriterion::DirectionalCurvature(c) => {
            let (u, v) = units_of_curvature(c);
            (nbhd_feature_criterion::DirectionalCurvature, v, u)
        }
    };
    let (orientation, orientation_point) = orientation_to_c(d.orientation);
    nbhd_smooth_options {
        k: d.k,
        epsilon,
        epsilon_units,
        steps: d.steps,
        tau: d.tau,
        weighting: match d.weighting {
            Weighting::Isotropic => nbhd_weighting::Isotropic,
            Weighting::Sharp => nbhd_weighting::Sharp,
            Weighting::Continuous => nbhd_weighting::Continuous,
        },
        lambda,
        lambda_units,
        feature,
        feature_threshold,
        feature_units,
        constrain_interior: d.constrain_interior.is_some(),
        interior_threshold: d.constrain_interior.unwrap_or(0.01),
        update_neighbors: d.update_neighbors,
        orientation,
        orientation_point,
        threads: 0,
        progress: None,
        progress_user_data: std::ptr::null_mut(),
        non_finite: d.non_finite.into(),
    }
}

/// The default smoothing options: the thesis' anisotropic flow with g_sharp at λ = 0.2/h on
/// all points, 3 steps of τ = 0.5, the 15 nearest other points within 6h, no progress
/// callback, the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_smooth_options_default() -> nbhd_smooth_options {
    guard_value(
        "nbhd_smooth_options_default",
        default_options(),
        default_options,
    )
}

/// The core's orientation for a C orientation and its point (which must be finite when used).
pub(super) fn read_orientation(
    o: nbhd_orientation,
    point: [f64; 3],
) -> Result<Orientation, FfiError> {
    Ok(match o {
        nbhd_orientation::Unoriented => Orientation::Unoriented,
        nbhd_orientation::Propagate => Orientation::Propagate,
        o @ (nbhd_orientation::TowardPoint | nbhd_orientation::AwayFromPoint) => {
            if !point.iter().all(|c| c.is_finite()) {
                return Err(crate::NbhdError::InvalidOption {
                    name: "orientation_point",
                    reason: format!("{point:?} must be finite"),
                }
                .into());
            }
            let p = DVec3::from_array(point);
            if o == nbhd_orientation::TowardPoint {
                Orientation::TowardViewpoint(p)
            } else {
                Orientation::AwayFrom(p)
            }
        }
    })
}

/// The C form of the core's orientation.
pub(super) fn orientation_to_c(o: Orientation) -> (nbhd_orientation, [f64; 3]) {
    match o {
        Orientation::Unoriented => (nbhd_orientation::Unoriented, [0.0; 3]),
        Orientation::TowardViewpoint(p) => (nbhd_orientation::TowardPoint, p.to_array()),
        Orientation::AwayFrom(p) => (nbhd_orientation::AwayFromPoint, p.to_array()),
        Orientation::Propagate => (nbhd_orientation::Propagate, [0.0; 3]),
    }
}

/// The options of one call after reading them from C.
pub(super) struct SmoothArgs {
    pub(super) core: SmoothOptions,
    pub(super) threads: usize,
    pub(super) progress: nbhd_progress_fn,
    pub(super) user_data: *mut c_void,
}

/// Reads `*options` field by field (NULL gives the defaults); enum fields are read as `int`
/// and checked, bools as bytes.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_smooth_options`.
pub(super) unsafe fn read_options(
    options: *const nbhd_smooth_options,
) -> Result<SmoothArgs, FfiError> {
    let defaults = default_options();
    let o: *const nbhd_smooth_options = if options.is_null() {
        &defaults
    } else {
        check_ptr(options, "options")?;
        options
    };
    let epsilon_units = c_enum_field!(o, epsilon_units, nbhd_units);
    let lambda_units = c_enum_field!(o, lambda_units, nbhd_units);
    let feature_units = c_enum_field!(o, feature_units, nbhd_units);
    let weighting = match c_enum_field!(o, weighting, nbhd_weighting) {
        nbhd_weighting::Isotropic => Weighting::Isotropic,
        nbhd_weighting::Sharp => Weighting::Sharp,
        nbhd_weighting::Continuous => Weighting::Continuous,
    };
    let threshold: f64 = c_field!(o, feature_threshold);
    let feature = match c_enum_field!(o, feature, nbhd_feature_criterion) {
        nbhd_feature_criterion::AllPoints => FeatureCriterion::AllPoints,
        nbhd_feature_criterion::EdgeQuotient => FeatureCriterion::EdgeQuotient(threshold),
        nbhd_feature_criterion::PrincipalCurvature => {
            FeatureCriterion::PrincipalCurvature(curvature(feature_units, threshold))
        }
        nbhd_feature_criterion::DirectionalCurvature => {
            FeatureCriterion::DirectionalCurvature(curvature(feature_units, threshold))
        }
    };
    let orientation = read_orientation(
        c_enum_field!(o, orientation, nbhd_orientation),
        c_field!(o, orientation_point),
    )?;
    let constrain_interior =
        c_bool_field!(o, constrain_interior).then(|| c_field!(o, interior_threshold));
    let core = SmoothOptions {
        k: c_field!(o, k),
        epsilon: length(epsilon_units, c_field!(o, epsilon)),
        steps: c_field!(o, steps),
        tau: c_field!(o, tau),
        weighting,
        lambda: curvature(lambda_units, c_field!(o, lambda)),
        feature,
        constrain_interior,
        update_neighbors: c_bool_field!(o, update_neighbors),
        orientation,
        non_finite: c_enum_field!(o, non_finite, nbhd_non_finite_policy).into(),
        ..SmoothOptions::default()
    };
    Ok(SmoothArgs {
        core,
        threads: c_field!(o, threads),
        progress: c_field!(o, progress),
        user_data: c_field!(o, progress_user_data),
    })
}

/// Reads the caller's points into 3-D double positions (the smoothing computes in double).
///
/// # Safety
/// `points` must be NULL or describe readable memory (see nbhd_points).
pub(super) unsafe fn read_points(
    points: *const nbhd_points,
) -> Result<(PointsArg, Vec<DVec3>), FfiError> {
    // SAFETY: forwarded from the caller.
    let arg = unsafe { PointsArg::read(points, "points") }?;
    // SAFETY: the caller's description of the point memory is true (contract above); the
    // view is dropped before this function returns, so later writes to an aliasing output
    // buffer never overlap a live borrow.
    let view: PointsView<'_> = unsafe { arg.view() }?;
    if view.dim() != 3 {
        return Err(FfiError::InvalidArgument(format!(
            "points->dim is {}; normals, curvatures and smoothing need 3-D points",
            view.dim()
        )));
    }
    let mut xyz = [0.0f64; 3];
    let pts = (0..view.len())
        .map(|i| {
            view.read_point(i, &mut xyz);
            DVec3::from_array(xyz)
        })
        .collect();
    Ok((arg, pts))
}

/// Runs `core` on `threads` workers, handing it a progress closure that calls the C callback
/// (if any) with `user_data`.
pub(super) fn run_with_progress<R: Send>(
    threads: usize,
    callback: nbhd_progress_fn,
    user_data: *mut c_void,
    core: impl FnOnce(&mut dyn FnMut(f64, Stage) -> bool) -> crate::Result<R> + Send,
) -> Result<R, FfiError> {
    struct Callback(nbhd_progress_fn, *mut c_void);
    // SAFETY: the callback and its user data are the caller's; the header tells C that the
    // callback may run on a worker thread of the call (never on two threads at once), which
    // is all that moving them to that thread needs.
    unsafe impl Send for Callback {}
    let cb = Callback(callback, user_data);
    let result = crate::parallel::with_threads(threads, move || {
        let cb = cb;
        let mut progress = |fraction: f64, stage: Stage| match cb.0 {
            // SAFETY: a C function pointer the caller gave for this purpose, called with the
            // user data it gave and plain values.
            Some(f) => unsafe { f(fraction, stage.into(), cb.1) },
            None => true,
        };
        core(&mut progress)
    })?;
    Ok(result?)
}

/// Runs the faithful method (or only its analysis) with the options' threads and callback.
fn run(points: &[DVec3], args: &SmoothArgs, analyze_only: bool) -> Result<SmoothResult, FfiError> {
    let opts = if analyze_only {
        SmoothOptions {
            steps: 0,
            outputs: true,
            ..args.core
        }
    } else {
        args.core
    };
    run_with_progress(args.threads, args.progress, args.user_data, |progress| {
        smooth::smooth_with_progress(points, &opts, progress)
    })
}

/// Writes the smoothed `points` to `out` with the input's layout (`arg`).
///
/// # Safety
/// `out` must be non-NULL and writable for the layout `arg` describes (checked by
/// [`read_points`]), and no Rust borrow of that memory may be live.
pub(super) unsafe fn write_coords(arg: &PointsArg, points: &[DVec3], out: *mut c_void) {
    let size = arg.scalar.size();
    for (i, p) in points.iter().enumerate() {
        for (c, v) in p.to_array().into_iter().enumerate() {
            let offset = i * arg.stride + c * size;
            // SAFETY: `out` is writable with the input's layout (caller), whose size
            // `read_points` checked, and `offset` stays inside it; the writes are unaligned;
            // no borrow of the memory is live (caller).
            unsafe {
                let at = out.cast::<u8>().add(offset);
                match arg.scalar {
                    ScalarType::F32 => at.cast::<f32>().write_unaligned(v as f32),
                    ScalarType::F64 => at.cast::<f64>().write_unaligned(v),
                }
            }
        }
    }
}

impl From<&PointOutput> for nbhd_point_geometry {
    fn from(o: &PointOutput) -> Self {
        Self {
            normal: o.normal.to_array(),
            k1: o.principal.k1,
            k2: o.principal.k2,
            dir1: o.principal.dir1.to_array(),
            dir2: o.principal.dir2.to_array(),
            mean_curvature: o.mean_curvature,
            max_principal_curvature: o.max_principal_curvature,
            covariance_quotient: o.covariance_quotient,
            anisotropic_mean_curvature: o.anisotropic_mean_curvature,
            principal_curvature_quotient: o.principal_curvature_quotient,
            max_covariance: o.max_covariance,
            normal_flags: o.normal_flags,
            feature: o.feature,
            interior: o.interior,
        }
    }
}

impl From<&SmoothResult> for nbhd_smooth_summary {
    fn from(r: &SmoothResult) -> Self {
        Self {
            spacing: r.spacing,
            epsilon: r.epsilon,
            lambda: r.lambda,
            min_neighbors: r.min_neighbors,
        }
    }
}

/// Writes `values` to `out[0..values.len()]`.
///
/// # Safety
/// `out` must be NULL or point to `values.len()` writable `T`s; it is checked for NULL and
/// alignment here.
unsafe fn write_all<T: Copy>(out: *mut T, values: &[T], arg: &str) -> Result<(), FfiError> {
    check_ptr(out.cast_const(), arg)?;
    // SAFETY: `out` is non-NULL and aligned (checked above) and holds `values.len()` writable
    // elements (caller); it cannot overlap `values`, which is nbhd's own memory.
    unsafe { std::ptr::copy_nonoverlapping(values.as_ptr(), out, values.len()) };
    Ok(())
}

/// Writes `geometry` (if not NULL) and `summary` (if not NULL) from a result.
///
/// # Safety
/// Each pointer must be NULL or writable for `result.outputs.len()` / one element.
pub(super) unsafe fn write_outputs(
    result: &SmoothResult,
    geometry: *mut nbhd_point_geometry,
    summary: *mut nbhd_smooth_summary,
) -> Result<(), FfiError> {
    if !geometry.is_null() {
        let g: Vec<nbhd_point_geometry> = result.outputs.iter().map(Into::into).collect();
        // SAFETY: forwarded from the caller.
        unsafe { write_all(geometry, &g, "out_geometry") }?;
    }
    if !summary.is_null() {
        // SAFETY: forwarded from the caller.
        unsafe { write_all(summary, &[nbhd_smooth_summary::from(result)], "out_summary") }?;
    }
    Ok(())
}

/// Smooths 3-D points (thesis Chapter 2) and writes the smoothed coordinates to `out_coords`.
///
/// `out_coords` is laid out like the input: `points->count` points `points->stride` bytes
/// apart (a stride of 0 means packed), three coordinates of `points->scalar_type` each; only
/// the coordinates are written, other bytes in a strided layout are left alone. It may be
/// `points->data` itself, to smooth in place (the input is read completely first).
/// `out_geometry` (`points->count` elements) receives the per-point geometry of the smoothed
/// points and `out_summary` the spacing and thresholds used; either may be NULL, and leaving
/// `out_geometry` NULL skips that work. `options` may be NULL for the defaults.
///
/// Nothing is written unless the call succeeds. Results are identical for any number of
/// threads.
///
/// Errors: NULL_POINTER (`points`, `points->data`, `out_coords`), MISALIGNED_POINTER,
/// INVALID_ARGUMENT (dimension other than 3, an enum field out of range, a buffer size that
/// overflows), ZERO_DIMENSION (dimension 0), EMPTY_INPUT (also: no finite point left to SKIP),
/// STRIDE_TOO_SMALL, TOO_MANY_POINTS, NON_FINITE (with `non_finite` REJECT; the message names the point),
/// INVALID_K, INVALID_OPTION (ε or λ not > 0, τ negative, relative units on a set without two
/// distinct points, ...), DEGENERATE (no neighbourhood reached 3 points: ε far below the
/// spacing — check `epsilon_units`; the message gives ε in the points' units), OUT_OF_MEMORY
/// (the neighbourhoods of `k` do not fit in memory, e.g. k = SIZE_MAX on a large set),
/// THREAD_POOL, CANCELLED (the progress callback returned false).
///
/// # Safety
/// `points` must describe readable memory (see nbhd_points); `out_coords` must be writable
/// with the same layout; `out_geometry` and `out_summary` must be NULL or writable for
/// `points->count` elements / one element; `options` must be NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth(
    points: *const nbhd_points,
    options: *const nbhd_smooth_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth", || {
        // SAFETY: forwarded from the caller.
        let (arg, pts) = unsafe { read_points(points) }?;
        // Coordinates are written unaligned, as the input is read: only NULL is refused.
        check_aligned(out_coords.cast_const(), 1, "out_coords")?;
        check_optional(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        // SAFETY: forwarded from the caller.
        let mut args = unsafe { read_options(options) }?;
        args.core.outputs = !out_geometry.is_null();
        let result = run(&pts, &args, false)?;
        // SAFETY: `out_coords` is non-NULL (checked above) and writable with the input's
        // layout (caller); the input view was dropped in `read_points`, so writing in place
        // overlaps no live borrow.
        unsafe { write_coords(&arg, &result.points, out_coords) };
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

/// Estimates normals and curvatures of every point without moving it: the normal, the
/// principal curvatures and directions of the Weingarten estimate (thesis eq. 2.26–2.29 with
/// 2.25) and the other per-point values of nbhd_point_geometry, over the ε-k-neighbourhoods
/// of `options`. `out_geometry` receives `points->count` elements; `out_summary` (may be NULL)
/// the spacing and thresholds used.
///
/// Errors: as nbhd_smooth; DEGENERATE also when every normal is flagged degenerate.
///
/// # Safety
/// `points` must describe readable memory; `out_geometry` must be writable for
/// `points->count` elements; `out_summary` NULL or writable; `options` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_estimate_curvatures(
    points: *const nbhd_points,
    options: *const nbhd_smooth_options,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_estimate_curvatures", || {
        // SAFETY: forwarded from the caller.
        let (_, pts) = unsafe { read_points(points) }?;
        check_ptr(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        // SAFETY: forwarded from the caller.
        let args = unsafe { read_options(options) }?;
        let result = run(&pts, &args, true)?;
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffi::nbhd_scalar_type;
    use crate::shapes::{sample, Sphere};

    fn sphere_points() -> Vec<f32> {
        sample(&Sphere::new(1.0), 600, 3)
            .points
            .iter()
            .flat_map(|p| p.as_vec3().to_array())
            .collect()
    }

    fn desc(data: &[f32]) -> nbhd_points {
        nbhd_points {
            data: data.as_ptr().cast(),
            count: data.len() / 3,
            dim: 3,
            stride: 12,
            scalar_type: nbhd_scalar_type::F32,
        }
    }

    #[test]
    fn defaults_mirror_the_core() {
        // SAFETY: NULL asks for the defaults.
        let args = unsafe { read_options(std::ptr::null()) }.unwrap();
        assert_eq!(args.core, SmoothOptions::default());
        let c = nbhd_smooth_options_default();
        // SAFETY: a live, initialised options struct.
        let args = unsafe { read_options(&c) }.unwrap();
        assert_eq!(args.core, SmoothOptions::default());
        assert_eq!(args.threads, 0);
    }

    #[test]
    fn smoothing_through_the_abi_equals_the_core() {
        let data = sphere_points();
        let pts: Vec<DVec3> = data
            .chunks(3)
            .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect();
        let core = smooth::smooth(&pts, &SmoothOptions::default()).unwrap();
        let mut out = vec![0f32; data.len()];
        let mut geo = vec![nbhd_point_geometry::default(); pts.len()];
        let mut summary = nbhd_smooth_summary::default();
        // SAFETY: the descriptor matches `data`; the outputs hold `count` elements.
        let s = unsafe {
            nbhd_smooth(
                &desc(&data),
                std::ptr::null(),
                out.as_mut_ptr().cast(),
                geo.as_mut_ptr(),
                &mut summary,
            )
        };
        assert_eq!(s, nbhd_status::Ok);
        for (i, p) in core.points.iter().enumerate() {
            assert_eq!(&out[3 * i..3 * i + 3], &p.as_vec3().to_array());
            assert_eq!(geo[i], nbhd_point_geometry::from(&core.outputs[i]));
        }
        assert_eq!(summary, nbhd_smooth_summary::from(&core));
    }

    unsafe extern "C" fn stop_at_half(f: f64, _: nbhd_stage, seen: *mut c_void) -> bool {
        // SAFETY: the test passes a pointer to its usize counter.
        unsafe { *seen.cast::<usize>() += 1 };
        f < 0.5
    }

    #[test]
    fn a_callback_that_returns_false_cancels_and_writes_nothing() {
        let data = sphere_points();
        let mut seen = 0usize;
        let mut o = nbhd_smooth_options_default();
        o.progress = Some(stop_at_half);
        o.progress_user_data = (&mut seen as *mut usize).cast();
        let mut out = vec![7f32; data.len()];
        // SAFETY: the descriptor matches `data`; `out` has its layout; `seen` outlives the call.
        let s = unsafe {
            nbhd_smooth(
                &desc(&data),
                &o,
                out.as_mut_ptr().cast(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(s, nbhd_status::Cancelled);
        assert!(seen >= 2);
        assert!(out.iter().all(|&v| v == 7.0));
    }

    #[test]
    fn bad_options_are_named() {
        let data = sphere_points();
        let mut geo = vec![nbhd_point_geometry::default(); data.len() / 3];
        let mut o = nbhd_smooth_options_default();
        o.k = 0;
        // SAFETY: the descriptor matches `data`; `geo` holds one element per point.
        let s = unsafe {
            nbhd_estimate_curvatures(&desc(&data), &o, geo.as_mut_ptr(), std::ptr::null_mut())
        };
        assert_eq!(s, nbhd_status::InvalidK);
        let mut o = nbhd_smooth_options_default();
        // SAFETY: writes an int into the int-sized enum field, as C may.
        unsafe {
            std::ptr::addr_of_mut!(o.weighting)
                .cast::<std::ffi::c_int>()
                .write(9)
        };
        // SAFETY: as above.
        let s = unsafe {
            nbhd_estimate_curvatures(&desc(&data), &o, geo.as_mut_ptr(), std::ptr::null_mut())
        };
        assert_eq!(s, nbhd_status::InvalidArgument);
    }
}
