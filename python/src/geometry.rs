//! Normals, curvatures and smoothing (`nbhd::smooth`, thesis Chapter 2) on an (n, 3) array:
//! the options of `SmoothOptions` as keyword arguments (those of `RobustOptions` are in
//! `robust_options.rs`), the per-point outputs (`PointOutput`) as numpy arrays. The points are
//! read as float64 (the library computes the geometry in f64); the GIL is released while the
//! library runs.

use glam::DVec3;
use nbhd::geometry::{estimate_normals, NormalOptions};
use nbhd::smooth as core;
use nbhd::smooth::{Curvature, PointOutput, RobustOptions, SmoothOptions, SmoothResult};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{dvec3_array, dvec3s, vec1};
use crate::errors::OrRaise;
use crate::options;

/// The per-point outputs as a dict of arrays (names as in `nbhd::smooth::PointOutput`).
pub(crate) fn outputs_dict<'py>(
    py: Python<'py>,
    out: &[PointOutput],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col = |f: fn(&PointOutput) -> f64| vec1(py, out.iter().map(f).collect::<Vec<f64>>());
    let vecs =
        |f: fn(&PointOutput) -> DVec3| dvec3_array(py, &out.iter().map(f).collect::<Vec<DVec3>>());
    d.set_item("normals", vecs(|o| o.normal)?)?;
    d.set_item("mean_curvature", col(|o| o.mean_curvature))?;
    d.set_item(
        "max_principal_curvature",
        col(|o| o.max_principal_curvature),
    )?;
    d.set_item("surface_variation", col(|o| o.covariance_quotient))?;
    d.set_item(
        "anisotropic_mean_curvature",
        col(|o| o.anisotropic_mean_curvature),
    )?;
    d.set_item(
        "principal_curvature_quotient",
        col(|o| o.principal_curvature_quotient),
    )?;
    d.set_item("max_covariance", col(|o| o.max_covariance))?;
    d.set_item("k1", col(|o| o.principal.k1))?;
    d.set_item("k2", col(|o| o.principal.k2))?;
    d.set_item("dir1", vecs(|o| o.principal.dir1)?)?;
    d.set_item("dir2", vecs(|o| o.principal.dir2)?)?;
    d.set_item(
        "flags",
        vec1(py, out.iter().map(|o| o.normal_flags).collect::<Vec<u8>>()),
    )?;
    d.set_item(
        "feature",
        vec1(py, out.iter().map(|o| o.feature).collect::<Vec<bool>>()),
    )?;
    d.set_item(
        "interior",
        vec1(py, out.iter().map(|o| o.interior).collect::<Vec<bool>>()),
    )?;
    Ok(d)
}

/// The scalars of a result (spacing h, ε and λ resolved to the points' units, the smallest
/// neighbourhood) and its points and outputs.
fn result_dict<'py>(
    py: Python<'py>,
    r: &SmoothResult,
    with_points: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if with_points {
        d.set_item("points", dvec3_array(py, &r.points)?)?;
    }
    d.set_item("spacing", r.spacing)?;
    d.set_item("epsilon", r.epsilon)?;
    d.set_item("lambda", r.lambda)?;
    d.set_item("min_neighbors", r.min_neighbors)?;
    if r.outputs.is_empty() {
        d.set_item("outputs", py.None())?;
    } else {
        d.set_item("outputs", outputs_dict(py, &r.outputs)?)?;
    }
    Ok(d)
}

/// The options of an analysis without steps (the curvatures; λ is not read).
#[allow(clippy::too_many_arguments)]
fn analysis_options(
    k: usize,
    epsilon: f64,
    epsilon_units: &str,
    orientation: &str,
    orientation_point: [f64; 3],
    non_finite: &str,
    density: &str,
    formula: &str,
    threads: usize,
) -> PyResult<SmoothOptions> {
    Ok(SmoothOptions {
        k,
        epsilon: options::length(epsilon, epsilon_units)?,
        // `analyze` sets no step and every output itself; the normals and curvatures do not
        // read λ, and an absolute λ needs no spacing
        lambda: Curvature::Absolute(1.0),
        orientation: options::orientation(orientation, orientation_point)?,
        non_finite: options::non_finite(non_finite)?,
        density: options::density(density)?,
        formula: options::formula(formula)?,
        threads,
        ..SmoothOptions::default()
    })
}

/// Normals of an (n, 3) point array: the eigenvector of the smallest eigenvalue of the
/// covariance of each point's ε-k-neighbourhood (the `k` nearest other points within
/// `epsilon`; eq. 2.8–2.10), as PCL's NormalEstimation computes it.
///
/// Returns `(normals (n, 3), curvature (n,), flags (n,))`: `curvature` is PCL's, the surface
/// variation λ0/(λ0+λ1+λ2); `flags` are 0 for a well-defined normal (1 too few neighbours,
/// 2 collinear, 4 ambiguous, 8 skipped as non-finite: NaN normal).
///
/// epsilon is RELATIVE by default (multiples of the mean spacing h); pass
/// `epsilon_units="absolute"` for a length in the points' units. orientation: "unoriented",
/// "toward-point" (PCL's flipNormalTowardsViewpoint, with `orientation_point`),
/// "away-from-point", "propagate" (consistent over the neighbour graph).
#[pyfunction]
#[pyo3(signature = (points, *, k = 15, epsilon = 6.0, epsilon_units = "relative",
                    orientation = "unoriented", orientation_point = [0.0, 0.0, 0.0],
                    non_finite = "reject", threads = 0))]
#[allow(clippy::too_many_arguments)]
pub fn normals<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: usize,
    epsilon: f64,
    epsilon_units: &str,
    orientation: &str,
    orientation_point: [f64; 3],
    non_finite: &str,
    threads: usize,
) -> PyResult<Bound<'py, PyTuple>> {
    let opts = NormalOptions {
        k,
        epsilon: options::length(epsilon, epsilon_units)?,
        orientation: options::orientation(orientation, orientation_point)?,
        non_finite: options::non_finite(non_finite)?,
        threads,
    };
    let pts = dvec3s(points)?;
    let r = py.detach(|| estimate_normals(&pts, &opts)).or_raise()?;
    let o = &r.normals;
    let n: Vec<DVec3> = o.iter().map(|o| o.normal).collect();
    let c: Vec<f64> = o.iter().map(|o| o.surface_variation).collect();
    let f: Vec<u8> = o.iter().map(|o| o.flags).collect();
    PyTuple::new(
        py,
        [
            dvec3_array(py, &n)?.into_any(),
            vec1(py, c).into_any(),
            vec1(py, f).into_any(),
        ],
    )
}

/// Normals and curvatures of an (n, 3) point array (thesis Section 2.2): every per-point output
/// of the thesis' program on the points as they are, without smoothing.
///
/// Returns a dict: `normals`, `k1`, `k2` (principal curvatures, eq. 2.25 or the exact moments,
/// signed relative to the normal), `dir1`, `dir2`, `mean_curvature`, `max_principal_curvature`,
/// `surface_variation` (λ0/(λ0+λ1+λ2)), `principal_curvature_quotient`, `max_covariance`,
/// `anisotropic_mean_curvature`, `flags`, `feature`, `interior` (arrays), and `spacing`,
/// `epsilon` (resolved to the points' units), `min_neighbors`.
#[pyfunction]
#[pyo3(signature = (points, *, k = 15, epsilon = 6.0, epsilon_units = "relative",
                    orientation = "unoriented", orientation_point = [0.0, 0.0, 0.0],
                    density = "abs-linear", formula = "eq2.25", non_finite = "reject",
                    threads = 0))]
#[allow(clippy::too_many_arguments)]
pub fn curvatures<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: usize,
    epsilon: f64,
    epsilon_units: &str,
    orientation: &str,
    orientation_point: [f64; 3],
    density: &str,
    formula: &str,
    non_finite: &str,
    threads: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = analysis_options(
        k,
        epsilon,
        epsilon_units,
        orientation,
        orientation_point,
        non_finite,
        density,
        formula,
        threads,
    )?;
    let pts = dvec3s(points)?;
    let r = py.detach(|| core::analyze(&pts, &opts)).or_raise()?;
    let d = outputs_dict(py, &r.outputs)?;
    d.set_item("spacing", r.spacing)?;
    d.set_item("epsilon", r.epsilon)?;
    d.set_item("min_neighbors", r.min_neighbors)?;
    Ok(d)
}

/// Smooths an (n, 3) point array with the thesis' method (Chapter 2, `nbhd.smooth.smooth`):
/// `steps` explicit steps p ← p + τΔ (eq. 2.18) of the uniform-umbrella Laplacian over the
/// ε-k-neighbourhoods, weighted anisotropically by the directional curvatures (g_sharp eq. 2.31
/// or g_cont eq. 2.32 at threshold λ) on the points the feature criterion selects.
///
/// `method="isotropic"` is Gaussian fairing (g = 1, 2 steps by default), `"anisotropic"` the
/// default (g_sharp, λ = 0.2/h, 3 steps). Lengths are relative to the mean spacing h unless
/// their units say "absolute"; curvatures relative to 1/h.
///
/// Returns a dict: `points` (n, 3), `spacing` h, `epsilon` and `lambda` resolved,
/// `min_neighbors`, and `outputs` (the dict of `curvatures()` on the smoothed points) when
/// `outputs=True`, else None.
#[pyfunction]
#[pyo3(signature = (points, *, method = "anisotropic", k = 15, epsilon = 6.0,
                    epsilon_units = "relative", steps = None, tau = 0.5, weighting = None,
                    lambda_ = 0.2, lambda_units = "relative", feature = "all",
                    feature_threshold = None, feature_units = "relative",
                    constrain_interior = None, update_neighbors = false,
                    orientation = "unoriented", orientation_point = [0.0, 0.0, 0.0],
                    non_finite = "reject", outputs = false, threads = 0))]
#[allow(clippy::too_many_arguments)]
pub fn smooth<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    method: &str,
    k: usize,
    epsilon: f64,
    epsilon_units: &str,
    steps: Option<usize>,
    tau: f64,
    weighting: Option<&str>,
    lambda_: f64,
    lambda_units: &str,
    feature: &str,
    feature_threshold: Option<f64>,
    feature_units: &str,
    constrain_interior: Option<f64>,
    update_neighbors: bool,
    orientation: &str,
    orientation_point: [f64; 3],
    non_finite: &str,
    outputs: bool,
    threads: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let base = match method {
        "anisotropic" => SmoothOptions::default(),
        "isotropic" => SmoothOptions::isotropic(),
        _ => {
            return Err(crate::errors::value_err(format!(
                "unknown method {method:?}; expected \"anisotropic\" or \"isotropic\" \
                 (the robust mode is smooth_robust)"
            )))
        }
    };
    let opts = SmoothOptions {
        k,
        epsilon: options::length(epsilon, epsilon_units)?,
        steps: steps.unwrap_or(base.steps),
        tau,
        weighting: match weighting {
            Some(w) => options::weighting(w)?,
            None => base.weighting,
        },
        lambda: options::curvature(lambda_, lambda_units)?,
        feature: options::feature(feature, feature_threshold, feature_units)?,
        constrain_interior,
        update_neighbors,
        orientation: options::orientation(orientation, orientation_point)?,
        non_finite: options::non_finite(non_finite)?,
        outputs,
        threads,
        ..base
    };
    let pts = dvec3s(points)?;
    let r = py.detach(|| core::smooth(&pts, &opts)).or_raise()?;
    result_dict(py, &r, true)
}

/// `nbhd::smooth::smooth_robust` on an (n, 3) point array: the dict `smooth_robust` returns
/// (its keywords are parsed in `robust_options.rs`).
pub(crate) fn smooth_robust_dict<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    opts: &RobustOptions,
) -> PyResult<Bound<'py, PyDict>> {
    let pts = dvec3s(points)?;
    let r = py
        .detach(|| core::smooth_robust_report(&pts, opts, &mut |_, _| true))
        .or_raise()?;
    let d = result_dict(py, &r.result, true)?;
    d.set_item("normals", dvec3_array(py, &r.normals)?)?;
    d.set_item("noise", vec1(py, r.noise.clone()))?;
    d.set_item("moved", vec1(py, r.moved.clone()))?;
    d.set_item("dimension", vec1(py, r.dimension.clone()))?;
    d.set_item("wide_iterations", r.wide_iterations)?;
    Ok(d)
}
