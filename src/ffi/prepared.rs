//! Normals, curvatures and smoothing of what the caller already has: the points of a built
//! tree, or points with a neighbourhood table, without a second build. Each export converts
//! its arguments and calls `smooth::smooth_from` / `smooth::robust::smooth_robust_from` with
//! `Neighbors::Table`; the results are those of nbhd_smooth / nbhd_smooth_robust /
//! nbhd_estimate_curvatures on the same neighbourhoods.

use std::ffi::c_void;

use super::args::{check_aligned, check_optional, check_ptr, deref};
use super::smooth::{
    nbhd_point_geometry, nbhd_smooth_options, nbhd_smooth_summary, read_options, read_points,
    run_with_progress, write_coords, write_outputs,
};
use super::status::{guard, nbhd_status, FfiError};
use super::table::nbhd_neighborhoods;
use super::tree::{nbhd_tree, with_tree};
use super::types::nbhd_points;
use crate::scalar::ScalarType;
use crate::smooth::robust::{smooth_robust_from, RobustOptions};
use crate::smooth::source::tree_neighbors;
use crate::smooth::{smooth_from, Neighbors, SmoothOptions, SmoothResult};
use crate::table::NeighborTable;
use glam::DVec3;

/// Which smoothing a call runs.
enum Method {
    Faithful(*const nbhd_smooth_options, bool),
    Robust(*const super::robust::nbhd_robust_options),
}

impl Method {
    /// The size of the k-nearest table the method reads from a tree.
    ///
    /// # Safety
    /// The options pointer must be NULL or readable.
    unsafe fn table_k(&self) -> Result<usize, FfiError> {
        Ok(match *self {
            // SAFETY: forwarded from the caller.
            Method::Faithful(o, _) => unsafe { read_options(o) }?.core.k,
            // SAFETY: forwarded from the caller.
            Method::Robust(o) => unsafe { super::robust::read_options(o) }?.0.k_plane,
        })
    }

    /// Runs the method on `points` with the neighbourhoods `table`.
    ///
    /// # Safety
    /// The options pointer must be NULL or readable.
    unsafe fn run(
        &self,
        points: &[DVec3],
        table: &NeighborTable<f64>,
        outputs: bool,
    ) -> Result<SmoothResult, FfiError> {
        match *self {
            Method::Faithful(o, analyze_only) => {
                // SAFETY: forwarded from the caller.
                let args = unsafe { read_options(o) }?;
                let opts = SmoothOptions {
                    steps: if analyze_only { 0 } else { args.core.steps },
                    outputs: outputs || analyze_only,
                    ..args.core
                };
                run_with_progress(args.threads, args.progress, args.user_data, |progress| {
                    smooth_from(points, Neighbors::Table(table), &opts, progress)
                })
            }
            Method::Robust(o) => {
                // SAFETY: forwarded from the caller.
                let (core, threads, callback, user_data) =
                    unsafe { super::robust::read_options(o) }?;
                let opts = RobustOptions { outputs, ..core };
                run_with_progress(threads, callback, user_data, |progress| {
                    smooth_robust_from(points, Neighbors::Table(table), &opts, progress)
                        .map(|r| r.result)
                })
            }
        }
    }
}

/// The tree's points and their k-nearest table, then the method.
///
/// # Safety
/// `tree` must be NULL or a live tree; the options pointer NULL or readable.
unsafe fn on_tree(
    tree: *const nbhd_tree,
    method: &Method,
    outputs: bool,
) -> Result<(ScalarType, SmoothResult), FfiError> {
    // SAFETY: forwarded from the caller.
    let tree = unsafe { deref(tree, "tree") }?;
    // SAFETY: forwarded from the caller.
    let k = unsafe { method.table_k() }?;
    let (points, table) = with_tree!(&tree.inner, t => tree_neighbors(t, k))?;
    // SAFETY: forwarded from the caller.
    let result = unsafe { method.run(&points, &table, outputs) }?;
    Ok((tree.inner.scalar_type(), result))
}

/// The caller's points and table, then the method.
///
/// # Safety
/// `points` must describe readable memory; `table` NULL or a live table; the options pointer
/// NULL or readable.
unsafe fn on_table(
    points: *const nbhd_points,
    table: *const nbhd_neighborhoods,
    method: &Method,
    outputs: bool,
) -> Result<(super::types::PointsArg, SmoothResult), FfiError> {
    // SAFETY: forwarded from the caller.
    let (arg, pts) = unsafe { read_points(points) }?;
    // SAFETY: forwarded from the caller.
    let table = unsafe { deref(table, "table") }?;
    let rows = table.rows_in_f64(&pts)?;
    // SAFETY: forwarded from the caller.
    let result = unsafe { method.run(&pts, &rows, outputs) }?;
    Ok((arg, result))
}

/// Writes `points` packed, three coordinates of `scalar` each, to `out`.
///
/// # Safety
/// `out` must be non-NULL and writable for `3 * points.len()` values of `scalar`.
unsafe fn write_packed(scalar: ScalarType, points: &[DVec3], out: *mut c_void) {
    for (i, v) in points.iter().flat_map(|p| p.to_array()).enumerate() {
        // SAFETY: `out` holds 3 * points.len() values (caller); writes are unaligned.
        unsafe {
            match scalar {
                ScalarType::F32 => out.cast::<f32>().add(i).write_unaligned(v as f32),
                ScalarType::F64 => out.cast::<f64>().add(i).write_unaligned(v),
            }
        }
    }
}

/// nbhd_smooth on the points a built tree holds, with the tree's own search for the
/// neighbourhoods (no second build). `out_coords` receives the smoothed points packed in the
/// caller's index order, three values of the tree's scalar type each; `out_geometry` and
/// `out_summary` as in nbhd_smooth. The result is nbhd_smooth's on the same points.
///
/// Errors: as nbhd_smooth; NULL_POINTER (`tree`, `out_coords`); INVALID_OPTION when the tree
/// is not 3-D or skipped non-finite points (smooth the points themselves with a SKIP policy
/// instead).
///
/// # Safety
/// `tree` must be a live tree; `out_coords` writable for 3 × the tree's point count values;
/// `out_geometry`, `out_summary` NULL or writable; `options` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth_tree(
    tree: *const nbhd_tree,
    options: *const nbhd_smooth_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_tree", || {
        check_aligned(out_coords.cast_const(), 1, "out_coords")?;
        check_optional(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        let method = Method::Faithful(options, false);
        // SAFETY: forwarded from the caller.
        let (scalar, result) = unsafe { on_tree(tree, &method, !out_geometry.is_null()) }?;
        // SAFETY: `out_coords` is non-NULL and holds 3 × count values (caller).
        unsafe { write_packed(scalar, &result.points, out_coords) };
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

/// nbhd_estimate_curvatures on the points a built tree holds (normals, curvatures and the
/// other per-point geometry, without a second build). Errors: as nbhd_smooth_tree.
///
/// # Safety
/// `tree` must be a live tree; `out_geometry` writable for the tree's point count;
/// `out_summary` NULL or writable; `options` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_estimate_curvatures_tree(
    tree: *const nbhd_tree,
    options: *const nbhd_smooth_options,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_estimate_curvatures_tree", || {
        check_ptr(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        // SAFETY: forwarded from the caller.
        let (_, result) = unsafe { on_tree(tree, &Method::Faithful(options, true), true) }?;
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

/// nbhd_smooth_robust on the points a built tree holds (its `k_plane` nearest from the tree's
/// own search). Outputs and errors: as nbhd_smooth_tree.
///
/// # Safety
/// As nbhd_smooth_tree.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth_robust_tree(
    tree: *const nbhd_tree,
    options: *const super::robust::nbhd_robust_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_robust_tree", || {
        check_aligned(out_coords.cast_const(), 1, "out_coords")?;
        check_optional(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        let method = Method::Robust(options);
        // SAFETY: forwarded from the caller.
        let (scalar, result) = unsafe { on_tree(tree, &method, !out_geometry.is_null()) }?;
        // SAFETY: `out_coords` is non-NULL and holds 3 × count values (caller).
        unsafe { write_packed(scalar, &result.points, out_coords) };
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

/// nbhd_smooth with the neighbourhoods of `table` instead of a search: row i of `table`
/// (nbhd_tree_neighborhoods with each point left out of its own row, on the same points) gives
/// the candidates of point i, of which the first k within ε are taken, as from the call's own
/// search; a k-nearest table with at least `options->k` gives exactly nbhd_smooth's result.
/// A float table's rows are re-measured in double. Outputs as nbhd_smooth.
///
/// Errors: as nbhd_smooth; NULL_POINTER (`table`); INVALID_OPTION when the table does not fit
/// the points (row count, an index out of range, a point in its own row, rows out of order).
///
/// # Safety
/// As nbhd_smooth; `table` must be a live table.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth_table(
    points: *const nbhd_points,
    table: *const nbhd_neighborhoods,
    options: *const nbhd_smooth_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_table", || {
        check_aligned(out_coords.cast_const(), 1, "out_coords")?;
        check_optional(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        let method = Method::Faithful(options, false);
        // SAFETY: forwarded from the caller.
        let (arg, result) = unsafe { on_table(points, table, &method, !out_geometry.is_null()) }?;
        // SAFETY: `out_coords` is non-NULL and writable with the input's layout (caller); the
        // input view was dropped in `read_points`.
        unsafe { write_coords(&arg, &result.points, out_coords) };
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

/// nbhd_estimate_curvatures with the neighbourhoods of `table` (see nbhd_smooth_table).
///
/// # Safety
/// As nbhd_estimate_curvatures; `table` must be a live table.
#[no_mangle]
pub unsafe extern "C" fn nbhd_estimate_curvatures_table(
    points: *const nbhd_points,
    table: *const nbhd_neighborhoods,
    options: *const nbhd_smooth_options,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_estimate_curvatures_table", || {
        check_ptr(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        let method = Method::Faithful(options, true);
        // SAFETY: forwarded from the caller.
        let (_, result) = unsafe { on_table(points, table, &method, true) }?;
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}

/// nbhd_smooth_robust with the neighbourhoods of `table` (the first `k_plane` of each row; see
/// nbhd_smooth_table).
///
/// # Safety
/// As nbhd_smooth_robust; `table` must be a live table.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth_robust_table(
    points: *const nbhd_points,
    table: *const nbhd_neighborhoods,
    options: *const super::robust::nbhd_robust_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_robust_table", || {
        check_aligned(out_coords.cast_const(), 1, "out_coords")?;
        check_optional(out_geometry.cast_const(), "out_geometry")?;
        check_optional(out_summary.cast_const(), "out_summary")?;
        let method = Method::Robust(options);
        // SAFETY: forwarded from the caller.
        let (arg, result) = unsafe { on_table(points, table, &method, !out_geometry.is_null()) }?;
        // SAFETY: `out_coords` is non-NULL and writable with the input's layout (caller).
        unsafe { write_coords(&arg, &result.points, out_coords) };
        // SAFETY: forwarded from the caller.
        unsafe { write_outputs(&result, out_geometry, out_summary) }
    })
}
