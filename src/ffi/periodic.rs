//! Periodic trees (a torus, scipy's `boxsize`): the static and the growing tree built over a
//! periodic box, and the box read back; every query of such a tree (nbhd_tree_search and the
//! rest) then wraps the query into the box and measures nearest images.

use super::args::{check_optional, check_ptr, deref, init_out, read_slice};
use super::dynamic::nbhd_dynamic_tree;
use super::enums::{enum_argument, nbhd_scalar_type, ScalarTypeArg};
use super::status::{guard, nbhd_status};
use super::tree::{hand_out_index, nbhd_tree, IndexHandle};
use super::types::{nbhd_build_options, nbhd_points, read_build_options, PointsArg};
use crate::handle::AnyIndex;
use crate::scalar::ScalarType;

/// Builds a periodic k-d tree (a torus, as scipy's `cKDTree(data, boxsize=...)`) over
/// `*points` and stores a new handle in `*out_tree`. `boxsize[0 .. boxsize_count]` holds the
/// box size L of every axis (`boxsize_count` = the dimension) or one size for every axis
/// (`boxsize_count` = 1); 0 or +infinity makes an axis open (not periodic). On a periodic axis
/// every point must lie in [0, L) (points are not wrapped; scipy refuses them too); every query
/// of the tree is wrapped into [0, L) and measures each axis difference t at its nearest image,
/// min(t, L - t), under any metric, so each point counts once, even for a radius beyond L/2.
/// With no periodic axis this is nbhd_tree_build. Box queries (nbhd_tree_in_box) are not
/// periodic: they take the box in the tree's coordinates.
///
/// Errors: those of nbhd_tree_build; NULL_POINTER / MISALIGNED_POINTER (`boxsize` with a
/// count above 0); INVALID_OPTION (a size negative, NaN or rounding to 0 in the tree's scalar
/// type, or `boxsize_count` neither 1 nor the dimension); OUTSIDE_PERIOD (a point outside the
/// box: the message names the smallest such index, the coordinate, its value and L).
///
/// Ownership: as nbhd_tree_build (free with nbhd_tree_free); `boxsize` may be freed once this
/// returns.
///
/// # Safety
/// As nbhd_tree_build; `boxsize` NULL or readable for `boxsize_count` doubles.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_build_periodic(
    points: *const nbhd_points,
    options: *const nbhd_build_options,
    boxsize: *const f64,
    boxsize_count: usize,
    out_tree: *mut *mut nbhd_tree,
) -> nbhd_status {
    guard("nbhd_tree_build_periodic", || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `points`, `options` and `boxsize` are NULL or readable (caller).
        let (arg, options, boxsize) = unsafe {
            (
                PointsArg::read(points, "points")?,
                read_build_options(options)?,
                read_slice(boxsize, boxsize_count, "boxsize")?,
            )
        };
        // SAFETY: the caller's description of the point memory is true (contract above).
        let view = unsafe { arg.view() }?;
        let index = AnyIndex::build_periodic(&view, &options, boxsize)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, index) };
        Ok(())
    })
}

/// Makes an empty periodic dynamic tree (as nbhd_dynamic_create) over the box
/// `boxsize[0 .. boxsize_count]` (as nbhd_tree_build_periodic): every inserted point must lie
/// in the box (nbhd_dynamic_insert refuses a batch holding one outside with OUTSIDE_PERIOD,
/// naming its position in the batch), and every query is wrapped into it.
///
/// Errors: those of nbhd_dynamic_create; NULL_POINTER / MISALIGNED_POINTER (`boxsize`);
/// INVALID_OPTION (the box, as nbhd_tree_build_periodic).
///
/// # Safety
/// As nbhd_dynamic_create; `boxsize` NULL or readable for `boxsize_count` doubles.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_create_periodic(
    dim: usize,
    scalar_type: ScalarTypeArg,
    options: *const nbhd_build_options,
    boxsize: *const f64,
    boxsize_count: usize,
    out_tree: *mut *mut nbhd_dynamic_tree,
) -> nbhd_status {
    guard("nbhd_dynamic_create_periodic", || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `options` and `boxsize` are NULL or readable (caller).
        let (options, boxsize) = unsafe {
            (
                read_build_options(options)?,
                read_slice(boxsize, boxsize_count, "boxsize")?,
            )
        };
        let scalar: nbhd_scalar_type = enum_argument(scalar_type, "scalar_type")?;
        let index = AnyIndex::growing_periodic(dim, ScalarType::from(scalar), &options, boxsize)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, index) };
        Ok(())
    })
}

/// Writes the box sizes of `tree` to `out_boxsize[0 .. dim]` (0 for an open axis; all 0 for a
/// tree that is not periodic) and returns whether it is periodic in `*out_periodic` (may be
/// NULL).
///
/// Errors: NULL_POINTER (`tree`, `out_boxsize`), MISALIGNED_POINTER, BUFFER_TOO_SMALL
/// (`capacity` below the dimension; nothing written).
///
/// # Safety
/// `tree` NULL or a live handle; `out_boxsize` NULL or writable for `capacity` doubles;
/// `out_periodic` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_boxsize(
    tree: *const nbhd_tree,
    out_boxsize: *mut f64,
    capacity: usize,
    out_periodic: *mut bool,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `boxsize` requires.
    unsafe {
        boxsize(
            "nbhd_tree_boxsize",
            tree,
            out_boxsize,
            capacity,
            out_periodic,
        )
    }
}

/// Writes the box sizes of a dynamic tree; as nbhd_tree_boxsize.
///
/// # Safety
/// As nbhd_tree_boxsize, with `tree` a live dynamic tree.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_boxsize(
    tree: *const nbhd_dynamic_tree,
    out_boxsize: *mut f64,
    capacity: usize,
    out_periodic: *mut bool,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `boxsize` requires.
    unsafe {
        boxsize(
            "nbhd_dynamic_boxsize",
            tree,
            out_boxsize,
            capacity,
            out_periodic,
        )
    }
}

/// The body of nbhd_tree_boxsize and nbhd_dynamic_boxsize over either handle.
///
/// # Safety
/// As nbhd_tree_boxsize.
unsafe fn boxsize<H: IndexHandle>(
    name: &str,
    tree: *const H,
    out: *mut f64,
    capacity: usize,
    out_periodic: *mut bool,
) -> nbhd_status {
    guard(name, || {
        check_optional(out_periodic.cast_const(), "out_periodic")?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let index = unsafe { deref(tree, "tree") }?.index();
        check_ptr(out.cast_const(), "out_boxsize")?;
        let dim = index.dim();
        if capacity < dim {
            return Err(crate::NbhdError::BufferTooSmall {
                what: "out_boxsize (doubles)",
                len: capacity,
                needed: dim,
            }
            .into());
        }
        let sizes = index.boxsize();
        let periodic = sizes.is_some();
        let sizes = sizes.unwrap_or_else(|| vec![0.0; dim]);
        // SAFETY: `out` is non-NULL, aligned (checked above) and writable for `capacity` ≥ `dim`
        // doubles (caller, checked above); `sizes` is our own vector.
        unsafe { std::ptr::copy_nonoverlapping(sizes.as_ptr(), out, dim) };
        if !out_periodic.is_null() {
            // SAFETY: non-NULL, aligned (checked above) and writable (caller).
            unsafe { out_periodic.write(periodic) };
        }
        Ok(())
    })
}
