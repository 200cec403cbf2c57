//! Box queries ([`NeighborIndex::in_box`], [`NeighborIndex::in_boxes`]) into the caller's
//! buffers: one box, or a batch of boxes answered in parallel. The convention (closed boxes,
//! refusals) is the core's (`src/query/in_box.rs`).

use std::ffi::c_void;

use super::args::{check_aligned, check_optional, check_ptr, copy_out, deref, init_out};
use super::dynamic::nbhd_dynamic_tree;
use super::fields::{c_field, CStruct};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::tree::{nbhd_tree, IndexHandle};
use crate::error::NbhdError;
use crate::index::NeighborIndex;
use crate::scalar::Scalar;
use crate::with_index;

/// `len` values of `T` at `p`, after the NULL and alignment checks (an empty slice for
/// `len` 0 without reading `p`, which may then be NULL).
///
/// # Safety
/// `p` must be NULL or point to `len` readable values of `T`.
unsafe fn slice_of<'a, T: Scalar>(
    p: *const c_void,
    len: usize,
    arg: &str,
) -> Result<&'a [T], FfiError> {
    if len == 0 {
        check_optional(p.cast::<T>(), arg)?;
        return Ok(&[]);
    }
    check_aligned(p, std::mem::align_of::<T>(), arg)?;
    // SAFETY: non-NULL, aligned for `T` (checked above), `len` readable values (caller).
    Ok(unsafe { std::slice::from_raw_parts(p.cast::<T>(), len) })
}

/// All points of the tree inside the closed axis-aligned box `min[j] <= x[j] <= max[j]`
/// (every coordinate j).
///
/// - `min`, `max`: `dim` values each in the tree's scalar type (`float` for a tree built from
///   NBHD_SCALAR_TYPE_F32 points, `double` for F64), aligned for it. Bounds may be infinite
///   (a slab, a half-space); min = max in a coordinate is a valid, zero-extent box.
/// - Results: `*count` caller indices (uint32_t) ascending, in `indices` (`capacity` values).
///   If more than `capacity` points are inside, nothing is written to `indices`, `*count`
///   receives the number needed and the status is NBHD_STATUS_BUFFER_TOO_SMALL; `indices` may
///   be NULL with capacity 0 to ask for the size. Points skipped at build time are never
///   inside. On any other error `*count` is 0.
///
/// Errors: NULL_POINTER (`tree`, `min`, `max`, `count`, `indices` when needed),
/// MISALIGNED_POINTER, INVALID_BOX (a NaN bound, or min > max in some coordinate: an inverted
/// box is refused, not taken as empty), BUFFER_TOO_SMALL.
///
/// Thread safety: any number of threads may query one tree at once.
///
/// # Safety
/// `tree` must be NULL or a live handle; `min` and `max` NULL or `dim` readable values of the
/// tree's scalar type; `indices` NULL or writable for `capacity` values; `count` NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_in_box(
    tree: *const nbhd_tree,
    min: *const c_void,
    max: *const c_void,
    indices: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `in_box_of` requires.
    unsafe { in_box_of("nbhd_tree_in_box", tree, min, max, indices, capacity, count) }
}

/// All live points of the growing tree inside the closed box `min[j] <= x[j] <= max[j]`; as
/// nbhd_tree_in_box (removed points are never inside).
///
/// # Safety
/// As nbhd_tree_in_box, with `tree` a live dynamic tree not being changed by another thread.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_in_box(
    tree: *const nbhd_dynamic_tree,
    min: *const c_void,
    max: *const c_void,
    indices: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `in_box_of` requires.
    unsafe {
        in_box_of(
            "nbhd_dynamic_in_box",
            tree,
            min,
            max,
            indices,
            capacity,
            count,
        )
    }
}

/// The body of nbhd_tree_in_box and nbhd_dynamic_in_box, for either handle.
///
/// # Safety
/// As nbhd_tree_in_box, `tree` NULL or a live handle of kind `H`.
unsafe fn in_box_of<H: IndexHandle>(
    name: &str,
    tree: *const H,
    min: *const c_void,
    max: *const c_void,
    indices: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    guard(name, || {
        // SAFETY: `count` is NULL or writable (caller).
        let count = unsafe { init_out(count, "count", 0) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let tree = unsafe { deref(tree, "tree") }?;
        check_optional(indices.cast_const(), "indices")?;
        // SAFETY: the pointers are as the caller describes (contract above).
        with_index!(tree.index(), t, _T => unsafe { one_box(t, min, max, indices, capacity, count) })
    })
}

/// [`nbhd_tree_in_box`] on a typed tree.
///
/// # Safety
/// As nbhd_tree_in_box; `count` checked and writable.
unsafe fn one_box<T: Scalar, I: NeighborIndex<T>>(
    tree: &I,
    min: *const c_void,
    max: *const c_void,
    indices: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> Result<(), FfiError> {
    let dim = tree.dim();
    // SAFETY: `min` and `max` are NULL or `dim` readable values of `T` (caller).
    let (lo, hi) = unsafe {
        (
            slice_of::<T>(min, dim, "min")?,
            slice_of::<T>(max, dim, "max")?,
        )
    };
    let mut found = Vec::new();
    tree.in_box(lo, hi, &mut found)?;
    // SAFETY: `count` is non-NULL, aligned and writable (checked by the caller).
    unsafe { count.write(found.len()) };
    // SAFETY: `indices` is NULL or writable for `capacity` values (caller).
    unsafe {
        copy_out(
            &found,
            indices,
            capacity,
            "indices (the size needed is in *count)",
        )
    }
}

/// Options of nbhd_tree_in_boxes. Start from nbhd_box_options_default() and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_box_options {
    /// Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
    /// threads; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The rows are the
    /// same for every value. Default: 0.
    pub threads: usize,
}

/// The default box options: the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_box_options_default() -> nbhd_box_options {
    let defaults = nbhd_box_options { threads: 0 };
    guard_value("nbhd_box_options_default", defaults, || defaults)
}

/// Reads `*options` field by field: the thread count of the core's `in_boxes`; NULL gives the
/// defaults.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_box_options`.
unsafe fn read_box_threads(options: *const nbhd_box_options) -> Result<usize, FfiError> {
    let defaults = nbhd_box_options_default();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    Ok(c_field!(o.threads))
}

/// The points inside each box of a batch, computed in parallel; rows in the boxes' order,
/// identical for any thread count.
///
/// - `boxes`: `n_boxes * 2 * dim` values in the tree's scalar type: box i is its `min`
///   corner (`dim` values) then its `max` corner. Closed boxes, as nbhd_tree_in_box.
/// - `options`: NULL for the defaults (the shared thread pool).
/// - `offsets`: `n_boxes + 1` values (size_t); row i is `indices[offsets[i] .. offsets[i + 1]]`,
///   the caller indices inside box i, ascending.
/// - `indices`: `capacity` values; `*total` receives the number of indices over all rows.
///   If `capacity` is smaller, nothing is written to `offsets` or `indices` and the status is
///   NBHD_STATUS_BUFFER_TOO_SMALL: call again with `*total` values (`indices` may be NULL
///   with capacity 0 to ask for the size). On any other error `*total` is 0.
///
/// Errors: NULL_POINTER (`tree`, `boxes` when n_boxes > 0, `offsets`, `total`, `indices`
/// when needed), MISALIGNED_POINTER, INVALID_BOX (the message names the box), INVALID_OPTION
/// (threads), INVALID_ARGUMENT (n_boxes * 2 * dim overflows), BUFFER_TOO_SMALL, OUT_OF_MEMORY.
///
/// # Safety
/// `tree` must be NULL or a live handle; `boxes` NULL or `n_boxes * 2 * dim` readable values
/// of the tree's scalar type; `options` NULL or readable; `offsets` NULL or writable for
/// `n_boxes + 1` values; `indices` NULL or writable for `capacity` values; `total` NULL or
/// writable.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_tree_in_boxes(
    tree: *const nbhd_tree,
    boxes: *const c_void,
    n_boxes: usize,
    options: *const nbhd_box_options,
    offsets: *mut usize,
    indices: *mut u32,
    capacity: usize,
    total: *mut usize,
) -> nbhd_status {
    let out = BatchOut {
        offsets,
        indices,
        capacity,
        total,
    };
    // SAFETY: the caller's contract is the one `in_boxes_of` requires.
    unsafe { in_boxes_of("nbhd_tree_in_boxes", tree, boxes, n_boxes, options, out) }
}

/// The live points of the growing tree inside each box of a batch; as nbhd_tree_in_boxes.
///
/// # Safety
/// As nbhd_tree_in_boxes, with `tree` a live dynamic tree not being changed by another thread.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_dynamic_in_boxes(
    tree: *const nbhd_dynamic_tree,
    boxes: *const c_void,
    n_boxes: usize,
    options: *const nbhd_box_options,
    offsets: *mut usize,
    indices: *mut u32,
    capacity: usize,
    total: *mut usize,
) -> nbhd_status {
    let out = BatchOut {
        offsets,
        indices,
        capacity,
        total,
    };
    // SAFETY: the caller's contract is the one `in_boxes_of` requires.
    unsafe { in_boxes_of("nbhd_dynamic_in_boxes", tree, boxes, n_boxes, options, out) }
}

/// The body of nbhd_tree_in_boxes and nbhd_dynamic_in_boxes, for either handle.
///
/// # Safety
/// As nbhd_tree_in_boxes, `tree` NULL or a live handle of kind `H`.
unsafe fn in_boxes_of<H: IndexHandle>(
    name: &str,
    tree: *const H,
    boxes: *const c_void,
    n_boxes: usize,
    options: *const nbhd_box_options,
    out: BatchOut,
) -> nbhd_status {
    guard(name, || {
        // SAFETY: `total` is NULL or writable (caller).
        let total = unsafe { init_out(out.total, "total", 0) }?;
        // SAFETY: `tree` is NULL or a live handle; `options` NULL or readable (caller).
        let (tree, threads) = unsafe { (deref(tree, "tree")?, read_box_threads(options)?) };
        check_ptr(out.offsets.cast_const(), "offsets")?;
        check_optional(out.indices.cast_const(), "indices")?;
        let out = BatchOut { total, ..out };
        // SAFETY: the pointers are as the caller describes (contract above).
        with_index!(tree.index(), t, _T => unsafe { many_boxes(t, boxes, n_boxes, threads, out) })
    })
}

/// The caller's output buffers of nbhd_tree_in_boxes.
struct BatchOut {
    offsets: *mut usize,
    indices: *mut u32,
    capacity: usize,
    total: *mut usize,
}

/// [`nbhd_tree_in_boxes`] on a typed tree.
///
/// # Safety
/// As nbhd_tree_in_boxes; `out.total` and `out.offsets` checked.
unsafe fn many_boxes<T: Scalar, I: NeighborIndex<T>>(
    tree: &I,
    boxes: *const c_void,
    n_boxes: usize,
    threads: usize,
    out: BatchOut,
) -> Result<(), FfiError> {
    crate::parallel::check_threads(threads)?;
    let dim = tree.dim();
    let len = n_boxes
        .checked_mul(2 * dim)
        .filter(|&l| l.checked_mul(std::mem::size_of::<T>()).is_some())
        .ok_or_else(|| {
            FfiError::InvalidArgument(format!(
                "n_boxes {n_boxes} * 2 * dim {dim} values overflow the address space"
            ))
        })?;
    // SAFETY: `boxes` is NULL or `len` readable values of `T` (caller).
    let values = unsafe { slice_of::<T>(boxes, len, "boxes") }?;
    let rows = tree.in_boxes(values, threads)?;
    // SAFETY: `total` is non-NULL, aligned and writable (checked by the caller).
    unsafe { out.total.write(rows.total()) };
    if rows.total() > out.capacity {
        return Err(NbhdError::BufferTooSmall {
            what: "indices (the size needed is in *total)",
            len: out.capacity,
            needed: rows.total(),
        }
        .into());
    }
    // SAFETY: `indices` NULL or writable for `capacity` values; `offsets` non-NULL, aligned and
    // writable for `n_boxes + 1` values (caller; checked above).
    unsafe {
        copy_out(rows.indices(), out.indices, out.capacity, "indices")?;
        copy_out(rows.offsets(), out.offsets, n_boxes + 1, "offsets")
    }
}
