//! The Python package `nbhd` (module `nbhd._nbhd`): a thin binding of the Rust crate `nbhd`.
//! Every computation is the library's; this crate converts numpy arrays and keyword options to
//! the library's types and back, releases the GIL while the library runs, and turns the
//! library's errors into Python exceptions with its messages.

mod arrays;
mod dynamic;
mod errors;
mod filter;
mod geometry;
mod index;
mod io;
mod options;
mod robust_options;
mod robust_tiles;
mod shapes;
mod tree;

use pyo3::prelude::*;

/// Whether `points` (an (n, d) array) would be read in place by `KdTree` rather than copied:
/// for the tests of the zero-copy paths.
#[pyfunction]
fn _reads_in_place(points: &Bound<'_, PyAny>) -> PyResult<bool> {
    let (arr, dtype) = arrays::float_array(points, None)?;
    Ok(match dtype {
        arrays::Dtype::F32 => arrays::Points::<f32>::new(&arr)?.is_in_place(),
        arrays::Dtype::F64 => arrays::Points::<f64>::new(&arr)?.is_in_place(),
    })
}

#[pymodule]
fn _nbhd(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<tree::PyKdTree>()?;
    m.add_class::<tree::PyTable>()?;
    m.add_class::<dynamic::PyDynamicKdTree>()?;
    m.add_function(wrap_pyfunction!(geometry::normals, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::curvatures, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::smooth, m)?)?;
    m.add_function(wrap_pyfunction!(robust_options::smooth_robust, m)?)?;
    m.add_class::<robust_options::PyRobustOptions>()?;
    m.add_class::<robust_tiles::PyRobustRun>()?;
    m.add_class::<robust_tiles::PyRobustTile>()?;
    m.add_class::<robust_tiles::PyRankSearch>()?;
    m.add_class::<robust_tiles::PyDigitCounts>()?;
    m.add_class::<robust_tiles::PyExactSum>()?;
    m.add_function(wrap_pyfunction!(robust_tiles::_skipped_outputs, m)?)?;
    m.add_function(wrap_pyfunction!(filter::voxel_grid, m)?)?;
    m.add_function(wrap_pyfunction!(filter::mean_distances, m)?)?;
    m.add_function(wrap_pyfunction!(filter::squared_deviation_sum, m)?)?;
    m.add_function(wrap_pyfunction!(filter::outlier_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(shapes::aerial_tile, m)?)?;
    m.add_function(wrap_pyfunction!(io::read, m)?)?;
    m.add_function(wrap_pyfunction!(io::write, m)?)?;
    m.add_function(wrap_pyfunction!(_reads_in_place, m)?)?;
    m.add("MAX_THREADS", nbhd::MAX_THREADS)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
