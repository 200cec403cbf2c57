//! Option names as Python passes them (strings, as scipy and Open3D do) to the library's enums.
//! The names and their parsing are the library's own (`nbhd::names`): the command line takes
//! the same words, and an unknown one is refused by the library with the words there are.

use glam::DVec3;
use nbhd::geometry::{DensityForm, Orientation, OrientationKind, PrincipalFormula};
use nbhd::smooth::{Curvature, FeatureCriterion, Length, Units, Weighting};
use nbhd::{BuildOptions, MedianAlgorithm, NonFinitePolicy, PivotPolicy};
use pyo3::prelude::*;

use crate::errors::{value_err, OrRaise};

/// The error for a name of the binding's own (the feature criterion, which the library takes
/// with its threshold).
fn unknown(what: &str, got: &str, names: &[&str]) -> PyErr {
    value_err(format!(
        "unknown {what} {got:?}; expected one of {}",
        names.join(", ")
    ))
}

/// The sizes of a periodic box as Python passes them (`boxsize=`: None, one number for every
/// axis, or one per axis, scipy's form); checked by the library when the tree is made.
pub fn boxsize(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<f64>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    if let Ok(l) = obj.extract::<f64>() {
        return Ok(Some(vec![l]));
    }
    obj.extract::<Vec<f64>>()
        .map(Some)
        .map_err(|_| value_err("boxsize: a number or a sequence of numbers, one per axis"))
}

/// A pivot policy by name (`cyclic-median`, `spread-median`, `closest-to-middle`,
/// `sliding-midpoint`; `_` may stand for `-`).
pub fn pivot(name: &str) -> PyResult<PivotPolicy> {
    name.parse::<PivotPolicy>().or_raise()
}

/// A median algorithm by name (`presorted`, `sort`, `quickselect`, `floyd-rivest`,
/// `median-of-medians`).
pub fn median(name: &str) -> PyResult<MedianAlgorithm> {
    name.parse::<MedianAlgorithm>().or_raise()
}

/// `reject` or `skip`.
pub fn non_finite(name: &str) -> PyResult<NonFinitePolicy> {
    name.parse::<NonFinitePolicy>().or_raise()
}

/// The build options of `KdTree` and `DynamicKdTree`, from the names Python passes.
pub fn build(
    pivot_name: &str,
    median_name: &str,
    leaf_size: usize,
    non_finite_name: &str,
    threads: usize,
) -> PyResult<BuildOptions> {
    Ok(BuildOptions {
        pivot: pivot(pivot_name)?,
        median: median(median_name)?,
        leaf_size,
        non_finite: non_finite(non_finite_name)?,
        threads,
    })
}

/// A length of `v` in `units` (`relative`: multiples of the mean spacing h; `absolute`: the
/// points' units).
pub fn length(v: f64, units: &str) -> PyResult<Length> {
    Ok(Length::new(v, units.parse::<Units>().or_raise()?))
}

/// A curvature of `v` in `units` (relative: multiples of 1/h).
pub fn curvature(v: f64, units: &str) -> PyResult<Curvature> {
    Ok(Curvature::new(v, units.parse::<Units>().or_raise()?))
}

/// `unoriented`, `toward-point` (PCL's flipNormalTowardsViewpoint), `away-from-point`,
/// `propagate` (consistent over the neighbour graph); `point` for the two with a point.
pub fn orientation(name: &str, point: [f64; 3]) -> PyResult<Orientation> {
    let kind = name.parse::<OrientationKind>().or_raise()?;
    Ok(Orientation::of_kind(kind, DVec3::from_array(point)))
}

/// `isotropic`, `sharp` (g_sharp, eq. 2.31) or `continuous` (g_cont, eq. 2.32).
pub fn weighting(name: &str) -> PyResult<Weighting> {
    name.parse::<Weighting>().or_raise()
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
    name.parse::<DensityForm>().or_raise()
}

/// `eq2.25` or `exact-moments`.
pub fn formula(name: &str) -> PyResult<PrincipalFormula> {
    name.parse::<PrincipalFormula>().or_raise()
}
