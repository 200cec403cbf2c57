//! The spacing estimate and the point filters (outlier removal, voxel-grid downsampling)
//! of `src/filter/`, over a built tree.

use super::args::{check_optional, check_ptr, deref, init_out};
use super::dynamic::nbhd_dynamic_tree;
use super::fields::{c_field, CStruct};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::tree::{nbhd_tree, IndexHandle};
use super::types::{nbhd_points, PointsArg};
use crate::error::NbhdError;
use crate::filter::{
    voxel_grid, RadiusOutlierOptions, StatisticalOutlierOptions, VoxelGridOptions,
};
use crate::scalar::ScalarType;

/// The nearest-neighbour spacing of a point set: the distance of each point to its nearest
/// other point, summarised. `mean` is the h of every relative length (epsilon = 6 h).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_spacing {
    /// Mean nearest-neighbour distance h, summed in index order.
    pub mean: f64,
    /// Median nearest-neighbour distance (the mean of the middle two for an even count).
    pub median: f64,
    /// Number of points the distances were taken over (the tree's points).
    pub points: usize,
}

/// Options of nbhd_tree_spacing. Start from nbhd_spacing_options_default() and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_spacing_options {
    /// Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
    /// threads; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The spacing is the
    /// same for every value. Default: 0.
    pub threads: usize,
}

/// The default spacing options: the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_spacing_options_default() -> nbhd_spacing_options {
    let defaults = nbhd_spacing_options { threads: 0 };
    guard_value("nbhd_spacing_options_default", defaults, || defaults)
}

/// Reads `*options` field by field: the thread count of the core's `spacing`; NULL gives the
/// defaults.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_spacing_options`.
unsafe fn read_spacing_threads(options: *const nbhd_spacing_options) -> Result<usize, FfiError> {
    let defaults = nbhd_spacing_options_default();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    Ok(c_field!(o.threads))
}

/// The nearest-neighbour spacing of the tree's points, computed on `options->threads` workers
/// (`options` NULL for the defaults); the same value for any thread count. Points skipped at
/// build time are left out.
///
/// Errors: NULL_POINTER (`tree`, `out`), MISALIGNED_POINTER, INVALID_OPTION (fewer than two
/// points in the tree, or threads above NBHD_MAX_THREADS). On error `*out` is all zero.
///
/// # Safety
/// `tree` must be NULL or a live handle; `options` NULL or readable; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_spacing(
    tree: *const nbhd_tree,
    options: *const nbhd_spacing_options,
    out: *mut nbhd_spacing,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `spacing_of` requires.
    unsafe { spacing_of("nbhd_tree_spacing", tree, options, out) }
}

/// The spacing of the growing tree's live points; as nbhd_tree_spacing.
///
/// # Safety
/// As nbhd_tree_spacing, with `tree` a live dynamic tree not being changed by another thread.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_spacing(
    tree: *const nbhd_dynamic_tree,
    options: *const nbhd_spacing_options,
    out: *mut nbhd_spacing,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `spacing_of` requires.
    unsafe { spacing_of("nbhd_dynamic_spacing", tree, options, out) }
}

/// The body of nbhd_tree_spacing and nbhd_dynamic_spacing, for either handle.
///
/// # Safety
/// As nbhd_tree_spacing, `tree` NULL or a live handle of kind `H`.
unsafe fn spacing_of<H: IndexHandle>(
    name: &str,
    tree: *const H,
    options: *const nbhd_spacing_options,
    out: *mut nbhd_spacing,
) -> nbhd_status {
    guard(name, || {
        // SAFETY: `out` is NULL or writable (caller).
        let out = unsafe { init_out(out, "out", nbhd_spacing::default()) }?;
        // SAFETY: `tree` is NULL or a live handle; `options` NULL or readable (caller).
        let (tree, threads) = unsafe { (deref(tree, "tree")?, read_spacing_threads(options)?) };
        let s = tree.index().spacing(threads)?;
        // SAFETY: `out` is non-NULL, aligned and writable (checked by init_out).
        unsafe {
            out.write(nbhd_spacing {
                mean: s.mean,
                median: s.median,
                points: s.points,
            })
        };
        Ok(())
    })
}

/// The caller's output buffers of a filter: the kept indices and the optional mask.
struct KeptOut {
    kept: *mut u32,
    capacity: usize,
    count: *mut usize,
    mask: *mut u8,
}

/// Writes a filter's result: the kept indices (if they fit) and the mask (if asked for).
///
/// # Safety
/// `out.kept` NULL or writable for `out.capacity` values; `out.count` checked and writable;
/// `out.mask` NULL or writable for `kept.source_len` bytes.
unsafe fn write_kept(kept: &crate::filter::Kept, out: KeptOut) -> Result<(), FfiError> {
    let n = kept.indices.len();
    if n > 0 && n <= out.capacity {
        // Before `*count` is written: on this error it stays 0.
        check_ptr(out.kept.cast_const(), "kept")?;
    }
    // SAFETY: `count` is non-NULL, aligned and writable (checked by the caller).
    unsafe { out.count.write(n) };
    if n > out.capacity {
        return Err(NbhdError::BufferTooSmall {
            what: "kept (the size needed is in *count; the number of points always suffices)",
            len: out.capacity,
            needed: n,
        }
        .into());
    }
    if n > 0 {
        // SAFETY: non-NULL and aligned (checked above), writable for `capacity` >= n values
        // (caller).
        unsafe { std::ptr::copy_nonoverlapping(kept.indices.as_ptr(), out.kept, n) };
    }
    if !out.mask.is_null() {
        for (i, m) in kept.mask().into_iter().enumerate() {
            // SAFETY: `mask` is writable for `source_len` bytes (caller), i < source_len.
            unsafe { out.mask.add(i).write(u8::from(m)) };
        }
    }
    Ok(())
}

/// Options of nbhd_remove_statistical_outliers. Start from
/// nbhd_statistical_outlier_options_default() and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_statistical_outlier_options {
    /// Number of nearest *other* points whose distances are averaged, >= 1 and below the
    /// number of points (PCL's setMeanK, Open3D's nb_neighbors). Default: 50.
    pub k: usize,
    /// A point is kept when its mean distance is at most mean + std_ratio * s (PCL's
    /// setStddevMulThresh, Open3D's std_ratio); finite, may be negative. Default: 1.
    pub std_ratio: f64,
    /// Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
    /// threads; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The result is the
    /// same for every value. Default: 0.
    pub threads: usize,
}

impl From<StatisticalOutlierOptions> for nbhd_statistical_outlier_options {
    fn from(o: StatisticalOutlierOptions) -> Self {
        Self {
            k: o.k,
            std_ratio: o.std_ratio,
            threads: o.threads,
        }
    }
}

/// The default statistical outlier options: PCL's tutorial values k = 50, std_ratio = 1,
/// the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_statistical_outlier_options_default() -> nbhd_statistical_outlier_options {
    let defaults = StatisticalOutlierOptions::default().into();
    guard_value("nbhd_statistical_outlier_options_default", defaults, || {
        defaults
    })
}

/// Reads `*options` field by field into the core's options; NULL gives the defaults. The core
/// checks the values.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_statistical_outlier_options`.
unsafe fn read_statistical_options(
    options: *const nbhd_statistical_outlier_options,
) -> Result<StatisticalOutlierOptions, FfiError> {
    let defaults = nbhd_statistical_outlier_options_default();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    Ok(StatisticalOutlierOptions {
        k: c_field!(o.k),
        std_ratio: c_field!(o.std_ratio),
        threads: c_field!(o.threads),
    })
}

/// Statistical outlier removal (PCL's StatisticalOutlierRemoval, Open3D's
/// remove_statistical_outlier): for each point its mean distance d_i to its `options->k`
/// nearest other points (PCL's setMeanK(k): PCL searches k + 1 and skips the point itself);
/// over all points the mean m and the sample standard deviation s (n - 1 in the denominator,
/// as PCL); a point is kept when d_i <= m + std_ratio * s. `options` may be NULL for the
/// defaults. Points skipped at build time are never kept and take no part in m and s (PCL 1.13
/// keeps NaN points in its output).
///
/// - `kept`: `capacity` values (uint32_t); receives the caller indices of the kept points,
///   ascending, `*count` of them. The number of points given to nbhd_tree_build always
///   suffices; with less, `*count` receives the number needed and the status is
///   NBHD_STATUS_BUFFER_TOO_SMALL (nothing written; `kept` may be NULL with capacity 0).
/// - `mask`: NULL, or one byte per point given to nbhd_tree_build: 1 kept, 0 removed.
///
/// Errors: NULL_POINTER (`tree`, `count`, `kept` when needed), MISALIGNED_POINTER, INVALID_K
/// (k = 0), INVALID_OPTION (k >= the number of points, std_ratio NaN or infinite, threads),
/// BUFFER_TOO_SMALL, OUT_OF_MEMORY. On error `*count` is 0 except for BUFFER_TOO_SMALL.
///
/// # Safety
/// `tree` must be NULL or a live handle; `options` NULL or readable; `kept` NULL or writable
/// for `capacity` values; `count` NULL or writable; `mask` NULL or writable for the number of
/// points given.
#[no_mangle]
pub unsafe extern "C" fn nbhd_remove_statistical_outliers(
    tree: *const nbhd_tree,
    options: *const nbhd_statistical_outlier_options,
    kept: *mut u32,
    capacity: usize,
    count: *mut usize,
    mask: *mut u8,
) -> nbhd_status {
    let out = KeptOut {
        kept,
        capacity,
        count,
        mask,
    };
    // SAFETY: the caller's contract is the one `statistical_of` requires.
    unsafe { statistical_of("nbhd_remove_statistical_outliers", tree, options, out) }
}

/// Statistical outlier removal over the live points of a growing tree: the points kept are
/// those the static tree built on the live points keeps (nbhd_remove_statistical_outliers),
/// `k` must be below the number of live points, and m and s are taken over the live points.
///
/// - `kept`: the caller indices of the kept live points, ascending (`*count` of them); the
///   number of live points always suffices as `capacity`.
/// - `mask`: NULL, or one byte per index given so far (nbhd_dynamic_tree_stats' `next_index`
///   bytes): 1 for a kept point, 0 for a removed outlier and for every index not live
///   (removed with nbhd_dynamic_remove or skipped as non-finite when inserted).
///
/// Errors as nbhd_remove_statistical_outliers (INVALID_OPTION for k >= the live points).
///
/// # Safety
/// As nbhd_remove_statistical_outliers, with `tree` a live dynamic tree not being changed by
/// another thread and `mask` NULL or writable for `next_index` bytes.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_remove_statistical_outliers(
    tree: *const nbhd_dynamic_tree,
    options: *const nbhd_statistical_outlier_options,
    kept: *mut u32,
    capacity: usize,
    count: *mut usize,
    mask: *mut u8,
) -> nbhd_status {
    let out = KeptOut {
        kept,
        capacity,
        count,
        mask,
    };
    // SAFETY: the caller's contract is the one `statistical_of` requires.
    unsafe {
        statistical_of(
            "nbhd_dynamic_remove_statistical_outliers",
            tree,
            options,
            out,
        )
    }
}

/// The body of nbhd_remove_statistical_outliers and nbhd_dynamic_remove_statistical_outliers,
/// for either handle.
///
/// # Safety
/// As nbhd_remove_statistical_outliers, `tree` NULL or a live handle of kind `H`.
unsafe fn statistical_of<H: IndexHandle>(
    name: &str,
    tree: *const H,
    options: *const nbhd_statistical_outlier_options,
    out: KeptOut,
) -> nbhd_status {
    guard(name, || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(out.count, "count", 0) }?;
        // SAFETY: `tree` is NULL or a live handle; `options` NULL or readable (caller).
        let (tree, options) = unsafe { (deref(tree, "tree")?, read_statistical_options(options)?) };
        check_optional(out.kept.cast_const(), "kept")?;
        let result = tree.index().statistical_outlier_removal(&options)?;
        // SAFETY: the buffers are as the caller describes (contract above).
        unsafe { write_kept(&result, KeptOut { count, ..out }) }
    })
}

/// Options of nbhd_remove_radius_outliers (the radius is an argument of its own, as in
/// nbhd_tree_radius). Start from nbhd_radius_outlier_options_default() and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_radius_outlier_options {
    /// A point is kept when at least this many *other* points lie within the radius. PCL's
    /// setMinNeighborsInRadius(m) is the same m (its count includes the point itself and keeps
    /// counts > m). 0 keeps every point the tree holds. Default: 2.
    pub min_neighbors: usize,
    /// Worker threads, as in nbhd_statistical_outlier_options. Default: 0.
    pub threads: usize,
}

impl From<RadiusOutlierOptions> for nbhd_radius_outlier_options {
    fn from(o: RadiusOutlierOptions) -> Self {
        Self {
            min_neighbors: o.min_neighbors,
            threads: o.threads,
        }
    }
}

/// The default radius outlier options: at least 2 other points within the radius, the shared
/// thread pool.
#[no_mangle]
pub extern "C" fn nbhd_radius_outlier_options_default() -> nbhd_radius_outlier_options {
    // The radius is the call's argument: every other field is the core's default.
    let defaults = RadiusOutlierOptions::within(0.0).into();
    guard_value("nbhd_radius_outlier_options_default", defaults, || defaults)
}

/// Reads `*options` field by field into the core's options for `radius`; NULL gives the
/// defaults. The core checks the values.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_radius_outlier_options`.
unsafe fn read_radius_options(
    radius: f64,
    options: *const nbhd_radius_outlier_options,
) -> Result<RadiusOutlierOptions, FfiError> {
    let defaults = nbhd_radius_outlier_options_default();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    Ok(RadiusOutlierOptions {
        radius,
        min_neighbors: c_field!(o.min_neighbors),
        threads: c_field!(o.threads),
    })
}

/// Radius outlier removal (PCL's RadiusOutlierRemoval, Open3D's remove_radius_outlier): a
/// point is kept when at least `options->min_neighbors` other points lie within `radius`
/// (plain Euclidean, inclusive: |x - p| <= radius). `options` may be NULL for the defaults.
/// Points skipped at build time are never kept. Results as nbhd_remove_statistical_outliers.
///
/// Errors: NULL_POINTER, MISALIGNED_POINTER, INVALID_RADIUS (negative, NaN, infinite, or too
/// large for the tree's type), INVALID_OPTION (threads), BUFFER_TOO_SMALL, OUT_OF_MEMORY.
///
/// # Safety
/// As nbhd_remove_statistical_outliers.
#[no_mangle]
pub unsafe extern "C" fn nbhd_remove_radius_outliers(
    tree: *const nbhd_tree,
    radius: f64,
    options: *const nbhd_radius_outlier_options,
    kept: *mut u32,
    capacity: usize,
    count: *mut usize,
    mask: *mut u8,
) -> nbhd_status {
    let out = KeptOut {
        kept,
        capacity,
        count,
        mask,
    };
    // SAFETY: the caller's contract is the one `radius_of` requires.
    unsafe { radius_of("nbhd_remove_radius_outliers", tree, radius, options, out) }
}

/// Radius outlier removal over the live points of a growing tree: the points kept are those
/// the static tree built on the live points keeps (nbhd_remove_radius_outliers); removed
/// points are not counted as neighbours. `kept` and `mask` as in
/// nbhd_dynamic_remove_statistical_outliers (the mask has `next_index` bytes, 0 for every
/// index not live).
///
/// Errors as nbhd_remove_radius_outliers.
///
/// # Safety
/// As nbhd_dynamic_remove_statistical_outliers.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_remove_radius_outliers(
    tree: *const nbhd_dynamic_tree,
    radius: f64,
    options: *const nbhd_radius_outlier_options,
    kept: *mut u32,
    capacity: usize,
    count: *mut usize,
    mask: *mut u8,
) -> nbhd_status {
    let out = KeptOut {
        kept,
        capacity,
        count,
        mask,
    };
    // SAFETY: the caller's contract is the one `radius_of` requires.
    unsafe {
        radius_of(
            "nbhd_dynamic_remove_radius_outliers",
            tree,
            radius,
            options,
            out,
        )
    }
}

/// The body of nbhd_remove_radius_outliers and nbhd_dynamic_remove_radius_outliers, for
/// either handle.
///
/// # Safety
/// As nbhd_remove_radius_outliers, `tree` NULL or a live handle of kind `H`.
unsafe fn radius_of<H: IndexHandle>(
    name: &str,
    tree: *const H,
    radius: f64,
    options: *const nbhd_radius_outlier_options,
    out: KeptOut,
) -> nbhd_status {
    guard(name, || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(out.count, "count", 0) }?;
        // SAFETY: `tree` is NULL or a live handle; `options` NULL or readable (caller).
        let (tree, options) =
            unsafe { (deref(tree, "tree")?, read_radius_options(radius, options)?) };
        check_optional(out.kept.cast_const(), "kept")?;
        let result = tree.index().radius_outlier_removal(&options)?;
        // SAFETY: the buffers are as the caller describes (contract above).
        unsafe { write_kept(&result, KeptOut { count, ..out }) }
    })
}

/// Options of nbhd_voxel_grid (the leaf sizes are arguments of their own). Start from
/// nbhd_voxel_grid_options_default() and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_voxel_grid_options {
    /// Voxels with fewer points are left out (PCL's setMinimumPointsNumberPerVoxel; 0 and 1
    /// keep every occupied voxel). Default: 0.
    pub min_points_per_voxel: usize,
    /// Worker threads, as in nbhd_statistical_outlier_options. Default: 0.
    pub threads: usize,
}

impl From<VoxelGridOptions> for nbhd_voxel_grid_options {
    fn from(o: VoxelGridOptions) -> Self {
        Self {
            min_points_per_voxel: o.min_points_per_voxel,
            threads: o.threads,
        }
    }
}

/// The default voxel-grid options: every occupied voxel kept, the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_voxel_grid_options_default() -> nbhd_voxel_grid_options {
    // The edge lengths are the call's arguments: every other field is the core's default.
    let defaults = VoxelGridOptions::cube(1.0).into();
    guard_value("nbhd_voxel_grid_options_default", defaults, || defaults)
}

/// Reads `*options` field by field into the core's options for the edge lengths `leaf`; NULL
/// gives the defaults. The core checks the values.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_voxel_grid_options`.
unsafe fn read_voxel_options(
    leaf: Vec<f64>,
    options: *const nbhd_voxel_grid_options,
) -> Result<VoxelGridOptions, FfiError> {
    let defaults = nbhd_voxel_grid_options_default();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    Ok(VoxelGridOptions {
        leaf,
        min_points_per_voxel: c_field!(o.min_points_per_voxel),
        threads: c_field!(o.threads),
    })
}

/// Voxel-grid downsampling (PCL's VoxelGrid, Open3D's voxel_down_sample) of the points
/// `*points` (no tree needed): the occupied voxels of the finite points, in ascending linear
/// voxel index (x fastest), each with its centroid and the index of its point nearest the
/// centroid (ties by the smaller index: an original point, whose attributes the caller keeps).
/// The arithmetic is PCL 1.13's in the points' scalar type: float points give PCL's voxels
/// exactly (centroids summed in ascending index; PCL's order within a voxel is not defined).
///
/// - `leaf`: `leaf_count` edge lengths, 1 (a cube) or `points->dim`; each finite and > 0.
/// - `options`: NULL for the defaults (every occupied voxel, the shared pool).
/// - `centroids`: NULL, or `capacity * points->dim` doubles: voxel v's centroid at
///   `centroids[v * dim ..]` (float values converted exactly).
/// - `nearest`: NULL, or `capacity` uint32_t: voxel v's point nearest its centroid.
/// - `*count` receives the number of voxels. The number of points always suffices as
///   capacity; with less, the status is NBHD_STATUS_BUFFER_TOO_SMALL, `*count` the number
///   needed, nothing written.
///
/// Errors: NULL_POINTER (`points`, `leaf`, `count`), MISALIGNED_POINTER, the point-buffer
/// statuses of nbhd_tree_build, INVALID_OPTION (a leaf NaN, <= 0 or infinite, a leaf count
/// other than 1 or dim, a leaf so small for the points' extent that a voxel number passes the
/// exact integers of the type — 2^24 for float — or the box holds more than 2^64 voxels;
/// threads above NBHD_MAX_THREADS), BUFFER_TOO_SMALL, OUT_OF_MEMORY. On error `*count` is 0
/// except for BUFFER_TOO_SMALL.
///
/// # Safety
/// `points` NULL or a readable description of readable memory; `leaf` NULL or readable for
/// `leaf_count` values; `options` NULL or readable; `centroids`, `nearest` NULL or writable as
/// described; `count` NULL or writable.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_voxel_grid(
    points: *const nbhd_points,
    leaf: *const f64,
    leaf_count: usize,
    options: *const nbhd_voxel_grid_options,
    centroids: *mut f64,
    nearest: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    guard("nbhd_voxel_grid", || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(count, "count", 0) }?;
        // SAFETY: `points` is NULL or a readable struct (caller).
        let arg = unsafe { PointsArg::read(points, "points") }?;
        check_ptr(leaf, "leaf")?;
        check_optional(centroids.cast_const(), "centroids")?;
        check_optional(nearest.cast_const(), "nearest")?;
        // SAFETY: the caller's description of the point memory is true (contract above).
        let view = unsafe { arg.view() }?;
        // A count other than 1 or the dimension is refused before `leaf` is read (it bounds
        // the read too: at most `dim` values, which fit in memory as a point does).
        crate::filter::check_leaf_count(leaf_count, view.dim())?;
        // SAFETY: `leaf` is non-NULL, aligned and readable for `leaf_count` values (caller),
        // and `leaf_count` is 1 or the points' dimension (checked just above).
        let leaf = unsafe { std::slice::from_raw_parts(leaf, leaf_count) }.to_vec();
        // SAFETY: `options` is NULL or readable (caller).
        let options = unsafe { read_voxel_options(leaf, options) }?;
        let (cents, near): (Vec<f64>, Vec<u32>) = match arg.scalar {
            ScalarType::F32 => {
                let g = voxel_grid::<f32>(&view, &options)?;
                (g.centroids.iter().map(|&c| c as f64).collect(), g.nearest)
            }
            ScalarType::F64 => {
                let g = voxel_grid::<f64>(&view, &options)?;
                (g.centroids, g.nearest)
            }
        };
        // SAFETY: `count` was checked by init_out.
        unsafe { count.write(near.len()) };
        if near.len() > capacity {
            return Err(NbhdError::BufferTooSmall {
                what: "voxels (the size needed is in *count; the number of points always suffices)",
                len: capacity,
                needed: near.len(),
            }
            .into());
        }
        if !centroids.is_null() {
            // SAFETY: non-NULL, aligned, writable for capacity * dim >= len doubles (caller).
            unsafe { std::ptr::copy_nonoverlapping(cents.as_ptr(), centroids, cents.len()) };
        }
        if !nearest.is_null() {
            // SAFETY: non-NULL, aligned, writable for capacity >= len values (caller).
            unsafe { std::ptr::copy_nonoverlapping(near.as_ptr(), nearest, near.len()) };
        }
        Ok(())
    })
}
