//! Option names as Python passes them (strings, as scipy and Open3D do) to the library's enums.
//! The names are the library's own (`PivotPolicy::name`, `MedianAlgorithm::name`).

use glam::DVec3;
use nbhd::geometry::{DensityForm, Orientation, PrincipalFormula};
use nbhd::smooth::{Curvature, FeatureCriterion, Length, Weighting};
use nbhd::{MedianAlgorithm, NonFinitePolicy, PivotPolicy};
use pyo3::prelude::*;

use crate::errors::value_err;

fn unknown(what: &str, got: &str, names: &[&str]) -> PyErr {
    value_err(format!(
        "unknown {what} {got:?}; expected one of {}",
        names.join(", ")
    ))
}

/// A pivot policy by name (`cyclic-median`, `spread-median`, `closest-to-middle`,
/// `sliding-midpoint`; `_` may stand for `-`).
pub fn pivot(name: &str) -> PyResult<PivotPolicy> {
    let n = name.replace('_', "-");
    PivotPolicy::ALL
        .into_iter()
        .find(|p| p.name() == n)
        .ok_or_else(|| unknown("pivot", name, &PivotPolicy::ALL.map(|p| p.name())))
}

/// A median algorithm by name (`presorted`, `sort`, `quickselect`, `floyd-rivest`,
/// `median-of-medians`).
pub fn median(name: &str) -> PyResult<MedianAlgorithm> {
    let n = name.replace('_', "-");
    MedianAlgorithm::ALL
        .into_iter()
        .find(|p| p.name() == n)
        .ok_or_else(|| unknown("median", name, &MedianAlgorithm::ALL.map(|p| p.name())))
}

/// `reject` or `skip`.
pub fn non_finite(name: &str) -> PyResult<NonFinitePolicy> {
    match name {
        "reject" => Ok(NonFinitePolicy::Reject),
        "skip" => Ok(NonFinitePolicy::Skip),
        _ => Err(unknown("non_finite policy", name, &["reject", "skip"])),
    }
}

/// `relative` (multiples of the mean spacing h) or `absolute` (the points' units).
fn relative(units: &str) -> PyResult<bool> {
    match units {
        "relative" => Ok(true),
        "absolute" => Ok(false),
        _ => Err(unknown("units", units, &["relative", "absolute"])),
    }
}

/// A length in `units`.
pub fn length(v: f64, units: &str) -> PyResult<Length> {
    Ok(if relative(units)? {
        Length::Relative(v)
    } else {
        Length::Absolute(v)
    })
}

/// A curvature in `units` (relative: multiples of 1/h).
pub fn curvature(v: f64, units: &str) -> PyResult<Curvature> {
    Ok(if relative(units)? {
        Curvature::Relative(v)
    } else {
        Curvature::Absolute(v)
    })
}

/// `unoriented`, `toward-point` (PCL's flipNormalTowardsViewpoint), `away-from-point`,
/// `propagate` (consistent over the neighbour graph); `point` for the two with a point.
pub fn orientation(name: &str, point: [f64; 3]) -> PyResult<Orientation> {
    let p = DVec3::from_array(point);
    match name.replace('_', "-").as_str() {
        "unoriented" => Ok(Orientation::Unoriented),
        "toward-point" | "toward-viewpoint" => Ok(Orientation::TowardViewpoint(p)),
        "away-from-point" => Ok(Orientation::AwayFrom(p)),
        "propagate" => Ok(Orientation::Propagate),
        _ => Err(unknown(
            "orientation",
            name,
            &["unoriented", "toward-point", "away-from-point", "propagate"],
        )),
    }
}

/// `isotropic`, `sharp` (g_sharp, eq. 2.31) or `continuous` (g_cont, eq. 2.32).
pub fn weighting(name: &str) -> PyResult<Weighting> {
    match name {
        "isotropic" => Ok(Weighting::Isotropic),
        "sharp" => Ok(Weighting::Sharp),
        "continuous" => Ok(Weighting::Continuous),
        _ => Err(unknown(
            "weighting",
            name,
            &["isotropic", "sharp", "continuous"],
        )),
    }
}

/// The feature criterion: `all`, `edge-quotient` (Q, eq. 2.33), `principal` (K, eq. 2.34) or
/// `directional` (D, eq. 2.35) with its threshold (curvatures in `units`).
pub fn feature(name: &str, threshold: Option<f64>, units: &str) -> PyResult<FeatureCriterion> {
    let need =
        || threshold.ok_or_else(|| value_err(format!("feature {name:?} needs feature_threshold")));
    match name.replace('_', "-").as_str() {
        "all" => Ok(FeatureCriterion::AllPoints),
        "edge-quotient" => Ok(FeatureCriterion::EdgeQuotient(need()?)),
        "principal" => Ok(FeatureCriterion::PrincipalCurvature(curvature(
            need()?,
            units,
        )?)),
        "directional" => Ok(FeatureCriterion::DirectionalCurvature(curvature(
            need()?,
            units,
        )?)),
        _ => Err(unknown(
            "feature criterion",
            name,
            &["all", "edge-quotient", "principal", "directional"],
        )),
    }
}

/// `abs-linear` (eq. 2.27 as printed) or `quadratic`.
pub fn density(name: &str) -> PyResult<DensityForm> {
    match name.replace('_', "-").as_str() {
        "abs-linear" => Ok(DensityForm::AbsLinear),
        "quadratic" => Ok(DensityForm::Quadratic),
        _ => Err(unknown("density", name, &["abs-linear", "quadratic"])),
    }
}

/// `eq2.25` or `exact-moments`.
pub fn formula(name: &str) -> PyResult<PrincipalFormula> {
    match name.replace('_', "-").as_str() {
        "eq2.25" | "eq225" => Ok(PrincipalFormula::Eq225),
        "exact-moments" => Ok(PrincipalFormula::ExactMoments),
        _ => Err(unknown("formula", name, &["eq2.25", "exact-moments"])),
    }
}
