//! Voxel-grid downsampling (`nbhd::filter::voxel_grid`) of an (n, d) array, computed in the
//! array's own float type as the C ABI and the CLI compute it. The outlier filters need an
//! index and are methods of `KdTree` and `DynamicKdTree` (`index.rs`).

use nbhd::filter::{voxel_grid as core_voxel_grid, VoxelGrid, VoxelGridOptions};
use nbhd::Scalar;
use numpy::Element;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{check_rows, float_array, vec1, vec2, Dtype, Points};
use crate::errors::{value_err, OrRaise};

/// The edge lengths `leaf`: one number (a cube) or a sequence of one per coordinate.
fn leaf_lengths(leaf: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(edge) = leaf.extract::<f64>() {
        return Ok(vec![edge]);
    }
    leaf.extract::<Vec<f64>>().map_err(|_| {
        value_err("leaf must be a number or a sequence of numbers (one per coordinate)")
    })
}

/// The voxel grid of the rows of `arr` (of `T`) as the dict `voxel_grid` returns.
fn grid_dict<'py, T: Scalar + Element>(
    py: Python<'py>,
    arr: &Bound<'py, PyAny>,
    options: &VoxelGridOptions,
) -> PyResult<Bound<'py, PyDict>> {
    let pts = Points::<T>::new(arr)?;
    let view = pts.view().or_raise()?;
    let dim = view.dim();
    let grid: VoxelGrid<T> = py
        .detach(|| core_voxel_grid::<T>(&view, options))
        .or_raise()?;
    let voxels = grid.len();
    let d = PyDict::new(py);
    d.set_item("centroids", vec2(py, grid.centroids, voxels, dim)?)?;
    d.set_item("nearest", vec1(py, grid.nearest))?;
    let offsets: Vec<u64> = grid.offsets.iter().map(|&o| o as u64).collect();
    d.set_item("offsets", vec1(py, offsets))?;
    d.set_item("members", vec1(py, grid.members))?;
    Ok(d)
}

/// Voxel-grid downsampling (PCL's VoxelGrid, Open3D's `voxel_down_sample`) of the rows of
/// `points`, an (n, d) array of float32 or float64 (other types are converted to float64),
/// computed in that type with PCL's arithmetic (float32 points give PCL's voxels exactly).
/// Rows with a NaN or infinite coordinate are left out.
///
/// leaf: the voxel edge, one number (a cube) or one per coordinate, each finite and > 0.
/// min_points_per_voxel: voxels with fewer points are left out (0 and 1 keep every one).
/// threads: 0 for a thread per core, n ≥ 1 for n threads; the result is the same for any.
///
/// Returns a dict over the occupied voxels in ascending linear voxel index (x fastest):
/// `centroids` ((v, d), the points' dtype: Open3D's and PCL's output points), `nearest` ((v,)
/// uint32: each voxel's row nearest its centroid, ties by the smaller index — original rows,
/// whose attributes can be kept with `attrs[nearest]`), and `offsets` ((v + 1,) uint64) with
/// `members` (uint32): voxel i's rows are `members[offsets[i]:offsets[i + 1]]`, ascending
/// (Open3D's `voxel_down_sample_and_trace`).
#[pyfunction]
#[pyo3(signature = (points, leaf, *, min_points_per_voxel = 0, threads = 0))]
pub fn voxel_grid<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    leaf: &Bound<'py, PyAny>,
    min_points_per_voxel: usize,
    threads: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let options = VoxelGridOptions {
        leaf: leaf_lengths(leaf)?,
        min_points_per_voxel,
        threads,
    };
    let (arr, dtype) = float_array(points, None)?;
    check_rows(&arr, "d")?;
    match dtype {
        Dtype::F32 => grid_dict::<f32>(py, &arr, &options),
        Dtype::F64 => grid_dict::<f64>(py, &arr, &options),
    }
}
