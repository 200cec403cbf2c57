//! The tree handle: build options, build, free, statistics.

use super::args::{check_aligned, check_ptr, deref, init_out};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::types::{nbhd_build_options, nbhd_points, nbhd_stats, read_build_options, PointsArg};
use crate::error::NbhdError;
use crate::handle::AnyIndex;
use crate::index::NeighborIndex;
use crate::query::Query;
use crate::scalar::Scalar;
use crate::tree::BuildOptions;
use crate::with_index;

/// A built k-d tree (opaque). It holds its own copy of the points, in the scalar type of the
/// points it was built from, and is immutable: any number of threads may query one tree at
/// once. Made by nbhd_tree_build or nbhd_tree_load(_from_buffer), freed by nbhd_tree_free.
pub struct nbhd_tree {
    /// Always a static tree.
    pub(crate) inner: AnyIndex,
}

/// The C handles of an index, nbhd_tree and nbhd_dynamic_tree: each holds the core's
/// [`AnyIndex`], so that an export serving both is one body over it.
pub(crate) trait IndexHandle: Sized {
    /// Whether the handle holds a growing tree.
    const GROWING: bool;
    /// The index behind the handle.
    fn index(&self) -> &AnyIndex;
    /// A handle of this kind holding `index` (of the kind [`Self::GROWING`] says).
    fn new(index: AnyIndex) -> Self;
}

impl IndexHandle for nbhd_tree {
    const GROWING: bool = false;
    fn index(&self) -> &AnyIndex {
        &self.inner
    }
    fn new(inner: AnyIndex) -> Self {
        Self { inner }
    }
}

/// Moves `index` into a fresh handle in `*out`.
///
/// # Safety
/// `out` was checked by `init_out`.
pub(crate) unsafe fn hand_out_index<H: IndexHandle>(out: *mut *mut H, index: AnyIndex) {
    let handle = Box::into_raw(Box::new(H::new(index)));
    // SAFETY: `out` is non-NULL, aligned and writable (checked by the caller); the handle is a
    // fresh Box the caller now owns.
    unsafe { out.write(handle) };
}

/// The default build options: sliding-midpoint pivots, Floyd-Rivest selection, leaf size 12,
/// non-finite points rejected, the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_build_options_default() -> nbhd_build_options {
    let defaults = BuildOptions::default().into();
    guard_value("nbhd_build_options_default", defaults, || defaults)
}

/// Builds a k-d tree over `*points` and stores a new handle in `*out_tree`.
///
/// The tree computes in `points->scalar_type` and keeps its own copy of the points, so the
/// point buffer may be changed or freed as soon as this returns. `options` may be NULL
/// for the defaults. On any error `*out_tree` is set to NULL (if `out_tree` is not NULL) and
/// nothing needs freeing. No point (count 0, or every point skipped) gives a tree of no
/// point: its queries find nothing and its tables have empty rows.
///
/// Errors: NULL_POINTER (`points`, `points->data` with a count above 0, `out_tree`),
/// MISALIGNED_POINTER, INVALID_ARGUMENT (`points->scalar_type` not a value of the enum;
/// `points->dim * sizeof (scalar)` or `(count - 1) * stride` overflowing the address space —
/// the message gives the values passed), ZERO_DIMENSION,
/// STRIDE_TOO_SMALL (a stride below one point, with both sizes), TOO_MANY_POINTS, NON_FINITE
/// (the message names the first point and coordinate), INVALID_OPTION (leaf size 0, an enum
/// field out of range), THREAD_POOL. No other status is returned.
///
/// Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free.
///
/// # Safety
/// `points` must describe readable memory (see nbhd_points); `options` must be NULL or point
/// to an nbhd_build_options; `out_tree` must be writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_build(
    points: *const nbhd_points,
    options: *const nbhd_build_options,
    out_tree: *mut *mut nbhd_tree,
) -> nbhd_status {
    guard("nbhd_tree_build", || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `points` and `options` are NULL or readable structs (caller).
        let (arg, options) = unsafe {
            (
                PointsArg::read(points, "points")?,
                read_build_options(options)?,
            )
        };
        // SAFETY: the caller's description of the point memory is true (contract above).
        let view = unsafe { arg.view() }?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, AnyIndex::build(&view, &options)?) };
        Ok(())
    })
}

/// Builds a k-d tree over the points `indices[0 .. index_count]` of `*points` only, as PCL's
/// `setInputCloud(cloud, indices)`, and stores a new handle in `*out_tree`. The point buffer
/// is read in place (only the listed points are copied into the tree), and every result names
/// the point's index in `*points`, as for nbhd_tree_build: the tree answers exactly as
/// nbhd_tree_build over the listed points would, in the caller's indices. The order of
/// `indices` does not matter.
///
/// Queries by index (nbhd_tree_knn_index, ...) take an index of `*points`; one that is not
/// listed fails with SKIPPED_POINT, as a skipped non-finite point does.
/// nbhd_tree_neighborhoods gives a row for every point of `*points` (row i for index i,
/// `nbhd_stats.source_points` = `points->count` rows): the listed points' neighbourhoods among
/// the listed points, and empty rows for the others.
///
/// Errors: those of nbhd_tree_build (NON_FINITE names the first listed non-finite point unless
/// `options->non_finite` skips them; an `index_count` of 0 gives a tree of no point), plus
/// NULL_POINTER / MISALIGNED_POINTER (`indices`), INDEX_OUT_OF_RANGE (the
/// message names the first index >= `points->count`) and INVALID_ARGUMENT (an index listed
/// twice, named in the message).
///
/// Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free; `indices` and
/// the point buffer may be freed once this returns.
///
/// # Safety
/// As nbhd_tree_build; `indices` must be NULL or point to `index_count` readable uint32_t
/// (NULL is accepted for an `index_count` of 0).
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_build_indices(
    points: *const nbhd_points,
    indices: *const u32,
    index_count: usize,
    options: *const nbhd_build_options,
    out_tree: *mut *mut nbhd_tree,
) -> nbhd_status {
    guard("nbhd_tree_build_indices", || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `points` and `options` are NULL or readable structs (caller).
        let (arg, options) = unsafe {
            (
                PointsArg::read(points, "points")?,
                read_build_options(options)?,
            )
        };
        if index_count > isize::MAX as usize / std::mem::size_of::<u32>() {
            return Err(FfiError::InvalidArgument(format!(
                "index_count {index_count} overflows the address space"
            )));
        }
        let indices: &[u32] = if index_count == 0 {
            super::args::check_optional(indices, "indices")?;
            &[]
        } else {
            check_ptr(indices, "indices")?;
            // SAFETY: `indices` is non-NULL and aligned (checked above) and points to
            // `index_count` readable values (caller), whose byte size fits in isize (checked
            // above); only read.
            unsafe { std::slice::from_raw_parts(indices, index_count) }
        };
        // SAFETY: the caller's description of the point memory is true (contract above).
        let view = unsafe { arg.view() }?;
        let tree = AnyIndex::build_subset(&view, indices, &options)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, tree) };
        Ok(())
    })
}

/// Frees a tree made by nbhd_tree_build(_indices) or nbhd_tree_load(_from_buffer). NULL is
/// ignored. The tree must not be in use by another thread, and must not be used after this call.
///
/// # Safety
/// `tree` must be NULL or a handle from nbhd_tree_build or nbhd_tree_load(_from_buffer) not
/// freed before.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_free(tree: *mut nbhd_tree) {
    guard_value("nbhd_tree_free", (), || {
        if tree.is_null() {
            return;
        }
        if (tree as usize) % std::mem::align_of::<nbhd_tree>() != 0 {
            // Not a handle of ours: freeing it would corrupt the heap. Leak it, and say so.
            let _ = guard("nbhd_tree_free", || {
                super::args::check_ptr(tree.cast_const(), "tree")
            });
            return;
        }
        // SAFETY: `tree` came from Box::into_raw in nbhd_tree_build or a load and is freed only once
        // (caller).
        drop(unsafe { Box::from_raw(tree) });
    })
}

/// Writes the shape and memory of `tree` to `*out_stats`, including its scalar type (the
/// type of query coordinates and of squared distances) and `source_points` (the range of
/// valid indices).
///
/// Errors: NULL_POINTER, MISALIGNED_POINTER.
///
/// # Safety
/// `tree` must be NULL or a live handle from nbhd_tree_build; `out_stats` must be NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_stats(
    tree: *const nbhd_tree,
    out_stats: *mut nbhd_stats,
) -> nbhd_status {
    guard("nbhd_tree_stats", || {
        // SAFETY: `out_stats` is NULL or writable (caller).
        let out = unsafe { init_out(out_stats, "out_stats", nbhd_stats::default()) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let tree = unsafe { deref(tree, "tree") }?;
        let index = &tree.inner;
        let shape = index
            .tree_stats()
            .expect("an nbhd_tree holds a static tree");
        let stats = nbhd_stats::new(shape, index.source_len(), index.scalar_type());
        // SAFETY: `out` was checked by `init_out`.
        unsafe { out.write(stats) };
        Ok(())
    })
}

/// Copies the coordinates the tree holds for the point with index `index` (an index of the
/// points given to nbhd_tree_build) to `out_coords`: `dim` values of the tree's scalar type
/// (nbhd_stats.scalar_type). A wrapper that answers "around point i" through the index path
/// (nbhd_tree_knn_index, ...) compares them with the caller's current coordinates first, so
/// that a point moved since the build is searched where it is now (as nbhd_pcl.hpp does).
///
/// Errors: NULL_POINTER (`tree`, `out_coords`), MISALIGNED_POINTER, INDEX_OUT_OF_RANGE
/// (`index` >= nbhd_stats.source_points), SKIPPED_POINT (a point skipped at build time, or
/// not listed to nbhd_tree_build_indices). Nothing is written on an error.
///
/// # Safety
/// `tree` must be NULL or a live handle; `out_coords` NULL or writable for `dim` values of the
/// tree's scalar type.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_point(
    tree: *const nbhd_tree,
    index: usize,
    out_coords: *mut std::ffi::c_void,
) -> nbhd_status {
    guard("nbhd_tree_point", || {
        // SAFETY: `tree` is NULL or a live handle (caller).
        let tree = unsafe { deref(tree, "tree") }?;
        // SAFETY: `out_coords` is NULL or writable for `dim` values of the tree's type (caller).
        with_index!(&tree.inner, t, _T => unsafe { copy_point(t, index, out_coords) })
    })
}

/// Copies the coordinates of caller index `index` to `out`, or fails as a query around it would.
///
/// # Safety
/// `out` NULL or writable for `dim` values of `T`.
unsafe fn copy_point<T: Scalar, I: NeighborIndex<T>>(
    t: &I,
    index: usize,
    out: *mut std::ffi::c_void,
) -> Result<(), FfiError> {
    check_aligned(out.cast_const(), std::mem::align_of::<T>(), "out_coords")?;
    let count = t.source_len();
    let index = u32::try_from(index).map_err(|_| NbhdError::IndexOutOfRange { index, count })?;
    let (coords, _) = t.resolve(Query::Stored {
        index,
        exclude_self: false,
    })?;
    // SAFETY: `out` is non-NULL and aligned for `T` (checked above) and writable for `dim`
    // values of `T` (caller); `coords` holds `dim` values and cannot overlap a caller's buffer.
    unsafe { std::ptr::copy_nonoverlapping(coords.as_ptr(), out.cast::<T>(), coords.len()) };
    Ok(())
}
