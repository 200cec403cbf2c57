//! The seeded synthetic aerial LiDAR scene (`nbhd::shapes::aerial`), tile by tile, as numpy
//! arrays named like the LAS fields `nbhd.write` stores in a LAS/LAZ file's records.

use nbhd::shapes::aerial::AerialScene;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{dvec3_array, vec1};
use crate::errors::value_err;

/// The points of the synthetic aerial survey `seed` whose pulses' footprints lie in the box
/// `[x0, x1) × [y0, y1)` (metres): terrain, buildings with sharp roof edges, trees with several
/// returns per pulse, overlapping flight strips with zig-zag scan lines, range noise, a height
/// offset per strip and rare outliers. The same tile is the same points whether generated
/// alone or as part of a larger box. Returns a dict: `positions` (n, 3) float64 and the LAS
/// fields `classification`, `return_number`, `number_of_returns`, `gps_time`, `intensity`,
/// `point_source_id` (the strip) and `scan_angle` (as LAS 1.4 stores it: units of 0.006°),
/// each (n,).
#[pyfunction]
#[pyo3(signature = (x0, y0, x1, y1, *, seed = 39, density = 16.0, swath = 400.0,
                    overlap = 0.3, noise = 0.025, strip_offset = 0.03, outliers = 1e-5))]
#[allow(clippy::too_many_arguments)]
pub fn aerial_tile<'py>(
    py: Python<'py>,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    seed: u64,
    density: f64,
    swath: f64,
    overlap: f64,
    noise: f64,
    strip_offset: f64,
    outliers: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let finite = [x0, y0, x1, y1, density, swath, noise, strip_offset];
    if !finite.iter().all(|v| v.is_finite()) || density <= 0.0 || swath <= 0.0 {
        return Err(value_err(
            "the box, density and swath must be finite, density and swath > 0",
        ));
    }
    if !(0.0..1.0).contains(&overlap) || !(0.0..=1.0).contains(&outliers) {
        return Err(value_err(
            "overlap must be in [0, 1) and outliers in [0, 1]",
        ));
    }
    // at most about 2·10^8 pulses in one call: a tile, not a survey
    let pulses = (x1 - x0).max(0.0) * (y1 - y0).max(0.0) * density / (1.0 - overlap);
    if pulses > 2e8 {
        return Err(value_err(format!(
            "about {pulses:.3e} pulses in one tile: generate the survey in smaller tiles"
        )));
    }
    let scene = AerialScene {
        seed,
        density,
        swath,
        overlap,
        noise,
        strip_offset,
        outliers,
    };
    let p = py.detach(|| scene.tile(x0, y0, x1, y1));
    let d = PyDict::new(py);
    d.set_item("positions", dvec3_array(py, &p.positions)?)?;
    d.set_item("classification", vec1(py, p.classification))?;
    d.set_item("return_number", vec1(py, p.return_number))?;
    d.set_item("number_of_returns", vec1(py, p.number_of_returns))?;
    d.set_item("gps_time", vec1(py, p.gps_time))?;
    d.set_item("intensity", vec1(py, p.intensity))?;
    d.set_item("point_source_id", vec1(py, p.point_source_id))?;
    d.set_item("scan_angle", vec1(py, p.scan_angle))?;
    Ok(d)
}
