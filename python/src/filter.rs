//! Voxel-grid downsampling (`nbhd::filter::voxel_grid`) of an (n, d) array, computed in the
//! array's own float type as the C ABI and the CLI compute it. The outlier filters need an
//! index and are methods of `KdTree` and `DynamicKdTree` (`index.rs`); the steps of the
//! statistical one are here too, for a run over tiles (`nbhd.dask`), which reduces the sums of
//! its tiles exactly.

use nbhd::filter::{
    mean_distance, outlier_threshold as core_outlier_threshold,
    squared_deviation_sum as core_squared_deviation_sum, voxel_grid as core_voxel_grid, VoxelGrid,
    VoxelGridOptions,
};
use nbhd::Scalar;
use numpy::{Element, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{check_rows, float_array, vec1, vec2, Dtype, Points};
use crate::errors::{value_err, OrRaise};
use crate::robust_tiles::PyExactSum;

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
    d.set_item("cells", vec2(py, grid.cells, voxels, dim)?)?;
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
/// (Open3D's `voxel_down_sample_and_trace`), and `cells` ((v, d) int64: each voxel's numbers
/// ⌊x · (1/leaf)⌋ along each coordinate, which do not depend on the other points: voxels of
/// parts of a cloud line up by them).
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

/// Each row's mean distance of an (m, k) array of squared distances of type `T`.
fn row_means<T: Scalar + Element>(arr: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let ro = arr
        .cast::<PyArray2<T>>()
        .map_err(|e| value_err(e.to_string()))?
        .try_readonly()
        .map_err(|e| value_err(e.to_string()))?;
    let a = ro.as_array();
    let mut row = Vec::with_capacity(a.ncols());
    Ok(a.rows()
        .into_iter()
        .map(|r| {
            row.clear();
            row.extend(r.iter().copied());
            mean_distance(&row)
        })
        .collect())
}

/// The mean distance of every row of `sq_dists`, an (m, k) array (k ≥ 1) of a point's squared
/// distances to its k nearest other points, nearest first (float32 or float64, as a tree of
/// that type gives them): `(1/k) Σ √d²` in float64, summed in the row's order — the `d_i` of
/// `KdTree.remove_statistical_outliers` (`nbhd::filter::mean_distance`), for a run over tiles.
#[pyfunction]
pub fn mean_distances<'py>(
    py: Python<'py>,
    sq_dists: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (arr, dtype) = float_array(sq_dists, None)?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] == 0 {
        return Err(value_err(format!(
            "sq_dists must be an (m, k) array with k >= 1, not of shape {shape:?}"
        )));
    }
    let d = match dtype {
        Dtype::F32 => row_means::<f32>(&arr)?,
        Dtype::F64 => row_means::<f64>(&arr)?,
    };
    Ok(vec1(py, d))
}

/// `Σ (d_i − mean)²` over the mean distances `d` (1-D), as an exact `ExactSum`
/// (`nbhd::filter::squared_deviation_sum`): the parts of the tiles merge to the one-machine sum.
#[pyfunction]
pub fn squared_deviation_sum(d: PyReadonlyArray1<'_, f64>, mean: f64) -> PyResult<PyExactSum> {
    let d = d.as_slice().map_err(|e| value_err(e.to_string()))?;
    Ok(PyExactSum::of(core_squared_deviation_sum(d, mean)))
}

/// The statistical outlier threshold `mean + std_ratio · σ`, `σ = √(spread / (n − 1))` (0 for
/// one point; `nbhd::filter::outlier_threshold`): a point is kept when its mean distance is at
/// most this. `mean` is the exact sum of the n mean distances rounded once, divided by n.
#[pyfunction]
pub fn outlier_threshold(mean: f64, spread: &PyExactSum, n: usize, std_ratio: f64) -> f64 {
    core_outlier_threshold(mean, spread.sum(), n, std_ratio)
}
