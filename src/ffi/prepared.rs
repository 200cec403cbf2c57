//! Normals, curvatures and smoothing of what the caller already has: the points of a built
//! tree, or points with a neighbourhood table, without a second build. Each export converts
//! its arguments and calls `smooth::smooth_from`, `smooth::analyze_with_progress` (curvatures)
//! or `smooth::robust::smooth_robust_from` with `Neighbors::Table`; the results are those of
//! nbhd_smooth / nbhd_smooth_robust / nbhd_estimate_curvatures on the same neighbourhoods.

use std::ffi::c_void;

use glam::DVec3;

use super::args::deref;
use super::robust::nbhd_robust_options;
use super::smooth::nbhd_smooth_options;
use super::smoothing_io::{nbhd_point_geometry, nbhd_smooth_summary, read_points, Outputs};
use super::status::{guard, nbhd_status, FfiError};
use super::table::nbhd_neighborhoods;
use super::tree::nbhd_tree;
use super::types::nbhd_points;
use crate::handle::AnyIndex;
use crate::smooth::robust::{smooth_robust_from, RobustOptions};
use crate::smooth::source::tree_neighbors;
use crate::smooth::{analyze_with_progress, smooth_from, Neighbors, SmoothOptions, SmoothResult};
use crate::table::NeighborTable;

/// Which smoothing a call runs, with its options pointer.
enum Method {
    /// nbhd_smooth, or with `true` nbhd_estimate_curvatures (no step, all outputs).
    Faithful(*const nbhd_smooth_options, bool),
    Robust(*const nbhd_robust_options),
}

impl Method {
    /// The size of the k-nearest table the method reads from a tree.
    ///
    /// # Safety
    /// The options pointer must be NULL or readable.
    unsafe fn table_k(&self) -> Result<usize, FfiError> {
        Ok(match *self {
            // SAFETY: forwarded from the caller.
            Method::Faithful(o, _) => unsafe { super::smooth::read_options(o) }?.0.k,
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
        let rows = Neighbors::Table(table);
        match *self {
            Method::Faithful(o, analyze_only) => {
                // SAFETY: forwarded from the caller.
                let (core, mut progress) = unsafe { super::smooth::read_options(o) }?;
                let mut report = |f, s| progress.report(f, s);
                Ok(if analyze_only {
                    analyze_with_progress(points, rows, &core, &mut report)
                } else {
                    let opts = SmoothOptions { outputs, ..core };
                    smooth_from(points, rows, &opts, &mut report)
                }?)
            }
            Method::Robust(o) => {
                // SAFETY: forwarded from the caller.
                let (core, mut progress) = unsafe { super::robust::read_options(o) }?;
                let opts = RobustOptions { outputs, ..core };
                let report =
                    smooth_robust_from(points, rows, &opts, &mut |f, s| progress.report(f, s))?;
                Ok(report.result)
            }
        }
    }
}

/// The tree's points and their k-nearest table, then the method; writes `out` with the
/// coordinates packed in the tree's scalar type.
///
/// # Safety
/// `tree` must be NULL or a live tree; the options pointer NULL or readable; the outputs
/// writable for the tree's point count.
unsafe fn on_tree(tree: *const nbhd_tree, method: &Method, out: &Outputs) -> Result<(), FfiError> {
    // SAFETY: forwarded from the caller.
    let tree = unsafe { deref(tree, "tree") }?;
    // SAFETY: forwarded from the caller.
    let k = unsafe { method.table_k() }?;
    let (points, table) = match &tree.inner {
        AnyIndex::StaticF32(t) => tree_neighbors(t, k),
        AnyIndex::StaticF64(t) => tree_neighbors(t, k),
        _ => unreachable!("an nbhd_tree holds a static tree"),
    }?;
    // SAFETY: forwarded from the caller.
    let result = unsafe { method.run(&points, &table, out.wants_geometry()) }?;
    let scalar = tree.inner.scalar_type();
    // SAFETY: forwarded from the caller; packed: three values a point.
    unsafe { out.write(&result, scalar, 3 * scalar.size()) };
    Ok(())
}

/// The caller's points and table, then the method; writes `out` with the input's layout.
///
/// # Safety
/// `points` must describe readable memory; `table` NULL or a live table; the options pointer
/// NULL or readable; the outputs writable for `points->count` points.
unsafe fn on_table(
    points: *const nbhd_points,
    table: *const nbhd_neighborhoods,
    method: &Method,
    out: &Outputs,
) -> Result<(), FfiError> {
    // SAFETY: forwarded from the caller.
    let (arg, pts) = unsafe { read_points(points) }?;
    // SAFETY: forwarded from the caller.
    let table = unsafe { deref(table, "table") }?;
    let rows = table.rows_in_f64(&pts)?;
    // SAFETY: forwarded from the caller.
    let result = unsafe { method.run(&pts, &rows, out.wants_geometry()) }?;
    // SAFETY: forwarded from the caller; the input view was dropped in `read_points`.
    unsafe { out.write(&result, arg.scalar, arg.stride) };
    Ok(())
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
        let out = Outputs::smoothing(out_coords, out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        unsafe { on_tree(tree, &Method::Faithful(options, false), &out) }
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
        let out = Outputs::curvatures(out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        unsafe { on_tree(tree, &Method::Faithful(options, true), &out) }
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
    options: *const nbhd_robust_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_robust_tree", || {
        let out = Outputs::smoothing(out_coords, out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        unsafe { on_tree(tree, &Method::Robust(options), &out) }
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
        let out = Outputs::smoothing(out_coords, out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        unsafe { on_table(points, table, &Method::Faithful(options, false), &out) }
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
        let out = Outputs::curvatures(out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        unsafe { on_table(points, table, &Method::Faithful(options, true), &out) }
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
    options: *const nbhd_robust_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_robust_table", || {
        let out = Outputs::smoothing(out_coords, out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        unsafe { on_table(points, table, &Method::Robust(options), &out) }
    })
}
