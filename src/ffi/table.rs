//! Neighbourhood tables: the neighbourhoods of every point of a tree, or of a batch of query
//! points, as compressed rows (offsets, indices, squared distances) behind an opaque handle.

use std::ffi::c_void;

use super::args::{deref, init_out};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::tree::{nbhd_tree, IndexHandle};
use super::types::{
    nbhd_neighborhood_spec, nbhd_points, nbhd_table_options, read_spec, read_table_options,
    PointsArg,
};
use crate::handle::AnyTable;
use crate::table::{NeighborTable, TableOptions};
use crate::with_table;

/// A table of neighbourhoods (opaque): row i holds the neighbours of point i (or of query i),
/// ordered by (squared distance, index). Made by nbhd_tree_neighborhoods or
/// nbhd_tree_neighborhoods_of (or their nbhd_dynamic_* twins), freed by
/// nbhd_neighborhoods_free. It does not refer to the
/// tree: either may be freed first. Immutable: any number of threads may read it at once.
pub struct nbhd_neighborhoods {
    table: AnyTable,
}

impl nbhd_neighborhoods {
    /// The rows as the smoothing reads them (see `smooth::source::table_in_f64`).
    pub(super) fn rows_in_f64(
        &self,
        points: &[glam::DVec3],
    ) -> crate::error::Result<std::borrow::Cow<'_, NeighborTable<f64>>> {
        use crate::smooth::source::table_in_f64;
        Ok(match &self.table {
            AnyTable::F64(t) if t.len() == points.len() => std::borrow::Cow::Borrowed(t),
            AnyTable::F64(t) => std::borrow::Cow::Owned(table_in_f64(points, t)?),
            AnyTable::F32(t) => std::borrow::Cow::Owned(table_in_f64(points, t)?),
        })
    }
}

/// The default table options: each point left out of its own row, the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_table_options_default() -> nbhd_table_options {
    let defaults = TableOptions::default().into();
    guard_value("nbhd_table_options_default", defaults, || defaults)
}

/// Stores a new table handle made from `table` in `out`.
///
/// # Safety
/// `out` was checked by `init_out`.
pub(super) unsafe fn hand_out(out: *mut *mut nbhd_neighborhoods, table: AnyTable) {
    let handle = Box::into_raw(Box::new(nbhd_neighborhoods { table }));
    // SAFETY: `out` is non-NULL, aligned and writable (checked by the caller); the handle is
    // a fresh Box that the C caller now owns.
    unsafe { out.write(handle) };
}

/// The neighbourhood `*spec` of every point of `tree`, computed in parallel, as a new table in
/// `*out_table`. Row i belongs to the point with index i in the points given to
/// nbhd_tree_build (so there are nbhd_stats.source_points rows; points skipped at build time
/// get empty rows). `options` may be NULL for the defaults (each point left out of its own
/// row). The table is identical for any number of threads.
///
/// On any error `*out_table` is set to NULL (if `out_table` is not NULL).
///
/// Errors: NULL_POINTER (`tree`, `spec`, `out_table`), MISALIGNED_POINTER, INVALID_ARGUMENT
/// (`spec->kind` out of range), INVALID_K, INVALID_RADIUS (also a radius whose square
/// overflows the tree's type, e.g. 1e20 on a float tree; the message gives the value passed),
/// OUT_OF_MEMORY (the table does not fit: a radius covering every point of a large set, k =
/// SIZE_MAX with KNN; the message gives the bytes needed — a KNN table's size is checked
/// before any search), THREAD_POOL.
///
/// Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
///
/// # Safety
/// `tree` must be NULL or a live handle; `spec` and `options` NULL or readable; `out_table`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_neighborhoods(
    tree: *const nbhd_tree,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `neighborhoods` requires.
    unsafe { neighborhoods("nbhd_tree_neighborhoods", tree, spec, options, out_table) }
}

/// The body of nbhd_tree_neighborhoods and nbhd_dynamic_neighborhoods.
///
/// # Safety
/// As nbhd_tree_neighborhoods.
pub(super) unsafe fn neighborhoods<H: IndexHandle>(
    func: &str,
    tree: *const H,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `out_table` is NULL or writable (caller).
        let out = unsafe { init_out(out_table, "out_table", std::ptr::null_mut()) }?;
        // SAFETY: `tree` is NULL or a live handle; `spec`, `options` NULL or readable (caller).
        let (tree, nbhd, options) = unsafe {
            (
                deref(tree, "tree")?,
                read_spec(spec)?,
                read_table_options(options)?,
            )
        };
        let table = tree.index().neighborhoods(nbhd, &options)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out(out, table) };
        Ok(())
    })
}

/// The neighbourhood `*spec` of each point of `*queries` in `tree`, computed in parallel, as
/// a new table in `*out_table`: row i belongs to query point i. The query points may be of
/// either scalar type (they are converted to the tree's) but must have the tree's dimension;
/// none may be NaN or infinite. `options` may be NULL; its `exclude_self` does not apply
/// (queries are not stored points). No query (`queries->count` 0) gives a table of no row.
///
/// On any error `*out_table` is set to NULL (if `out_table` is not NULL).
///
/// Errors: as nbhd_tree_neighborhoods, plus those of a points description (see
/// nbhd_tree_build), DIMENSION_MISMATCH and NON_FINITE_QUERY (the message names the query's
/// index and coordinate).
///
/// Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
///
/// # Safety
/// As nbhd_tree_neighborhoods; `queries` must be NULL or describe readable memory (see
/// nbhd_points).
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_neighborhoods_of(
    tree: *const nbhd_tree,
    queries: *const nbhd_points,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    let name = "nbhd_tree_neighborhoods_of";
    // SAFETY: the caller's contract is the one `neighborhoods_of` requires.
    unsafe { neighborhoods_of(name, tree, queries, spec, options, out_table) }
}

/// The body of nbhd_tree_neighborhoods_of and nbhd_dynamic_neighborhoods_of.
///
/// # Safety
/// As nbhd_tree_neighborhoods_of.
pub(super) unsafe fn neighborhoods_of<H: IndexHandle>(
    func: &str,
    tree: *const H,
    queries: *const nbhd_points,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `out_table` is NULL or writable (caller).
        let out = unsafe { init_out(out_table, "out_table", std::ptr::null_mut()) }?;
        // SAFETY: `tree` is NULL or a live handle; the structs NULL or readable (caller).
        let (tree, queries, nbhd, options) = unsafe {
            (
                deref(tree, "tree")?,
                PointsArg::read(queries, "queries")?,
                read_spec(spec)?,
                read_table_options(options)?,
            )
        };
        // SAFETY: the caller's description of the query memory is true (contract above).
        let view = unsafe { queries.view() }?;
        let table = tree.index().neighborhoods_of(&view, nbhd, &options)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out(out, table) };
        Ok(())
    })
}

/// Frees a table. NULL is ignored. Pointers obtained from its accessors become invalid.
///
/// # Safety
/// `table` must be NULL or a handle from nbhd_tree_neighborhoods(_of) not freed before.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_free(table: *mut nbhd_neighborhoods) {
    guard_value("nbhd_neighborhoods_free", (), || {
        if table.is_null() {
            return;
        }
        if (table as usize) % std::mem::align_of::<nbhd_neighborhoods>() != 0 {
            // Not a handle of ours: freeing it would corrupt the heap. Leak it, and say so.
            let _ = guard("nbhd_neighborhoods_free", || {
                super::args::check_ptr(table.cast_const(), "table")
            });
            return;
        }
        // SAFETY: `table` came from Box::into_raw in `hand_out` and is freed only once
        // (caller).
        drop(unsafe { Box::from_raw(table) });
    })
}

/// The table behind a handle for an accessor, or `None` for NULL or a misaligned pointer.
///
/// # Safety
/// `table` must be NULL or a live handle.
unsafe fn table_ref<'a>(table: *const nbhd_neighborhoods) -> Option<&'a AnyTable> {
    // SAFETY: `table` is NULL or a live handle (caller); `deref` checks NULL and alignment.
    unsafe { deref(table, "table") }.ok().map(|t| &t.table)
}

/// Number of rows (0 for NULL).
///
/// # Safety
/// `table` must be NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_rows(table: *const nbhd_neighborhoods) -> usize {
    guard_value("nbhd_neighborhoods_rows", 0, || {
        // SAFETY: as this function's contract.
        unsafe { table_ref(table) }.map_or(0, |t| with_table!(t, t => t.len()))
    })
}

/// Total number of neighbours over all rows: the length of the indices and squared-distance
/// arrays (0 for NULL).
///
/// # Safety
/// `table` must be NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_total(table: *const nbhd_neighborhoods) -> usize {
    guard_value("nbhd_neighborhoods_total", 0, || {
        // SAFETY: as this function's contract.
        unsafe { table_ref(table) }.map_or(0, |t| with_table!(t, t => t.total()))
    })
}

/// The row boundaries: `rows + 1` values, starting at 0, non-decreasing, ending at `total`;
/// row i is `offsets[i] .. offsets[i + 1]` of the indices and squared distances. NULL for a
/// NULL table. The array belongs to the table and lives until nbhd_neighborhoods_free.
///
/// # Safety
/// `table` must be NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_offsets(
    table: *const nbhd_neighborhoods,
) -> *const usize {
    guard_value("nbhd_neighborhoods_offsets", std::ptr::null(), || {
        // SAFETY: as this function's contract.
        unsafe { table_ref(table) }.map_or(
            std::ptr::null(),
            |t| with_table!(t, t => t.offsets().as_ptr()),
        )
    })
}

/// The caller's indices of all neighbours, row after row (`total` values). NULL for a NULL
/// table; when `total` is 0 the pointer is not NULL but must not be read. The array belongs
/// to the table and lives until nbhd_neighborhoods_free.
///
/// # Safety
/// `table` must be NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_indices(
    table: *const nbhd_neighborhoods,
) -> *const u32 {
    guard_value("nbhd_neighborhoods_indices", std::ptr::null(), || {
        // SAFETY: as this function's contract.
        unsafe { table_ref(table) }.map_or(
            std::ptr::null(),
            |t| with_table!(t, t => t.indices().as_ptr()),
        )
    })
}

/// The squared distances of all neighbours, row after row (`total` values), parallel to the
/// indices, in the scalar type of the tree the table was computed with (`const float*` or
/// `const double*`). NULL for a NULL table; when `total` is 0 the pointer is not NULL but must
/// not be read. The array belongs to the table and lives until nbhd_neighborhoods_free.
///
/// # Safety
/// `table` must be NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_sq_dists(
    table: *const nbhd_neighborhoods,
) -> *const c_void {
    guard_value("nbhd_neighborhoods_sq_dists", std::ptr::null(), || {
        // SAFETY: as this function's contract.
        unsafe { table_ref(table) }.map_or(
            std::ptr::null(),
            |t| with_table!(t, t => t.sq_dists().as_ptr().cast::<c_void>()),
        )
    })
}

/// One row: `*indices` and `*sq_dists` receive pointers to its first neighbour inside the
/// table's arrays and `*len` its length (0 for an empty row, with pointers not to be read).
/// `sq_dists` may be NULL if the distances are not wanted. The pointers live until
/// nbhd_neighborhoods_free.
///
/// Errors: NULL_POINTER (`table`, `indices`, `len`), MISALIGNED_POINTER, INVALID_ARGUMENT
/// (`row` >= the number of rows); on error `*len` is 0 and the pointers NULL.
///
/// # Safety
/// `table` must be NULL or a live handle; `indices`, `sq_dists` and `len` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_neighborhoods_row(
    table: *const nbhd_neighborhoods,
    row: usize,
    indices: *mut *const u32,
    sq_dists: *mut *const c_void,
    len: *mut usize,
) -> nbhd_status {
    guard("nbhd_neighborhoods_row", || {
        // Every usable out-pointer gets its "nothing" value before any error is returned.
        // SAFETY: the out-pointers are NULL or writable (caller).
        let outs = unsafe { RowOut::init(indices, sq_dists, len) }?;
        // SAFETY: `table` is NULL or a live handle (caller).
        let table = unsafe { deref(table, "table") }?;
        let (ids, dists, n) = with_table!(&table.table, t => {
            if row >= t.len() {
                return Err(FfiError::InvalidArgument(format!(
                    "row {row} is out of range (the table has {} rows)",
                    t.len()
                )));
            }
            let ids = t.indices_of(row);
            (ids.as_ptr(), t.sq_dists_of(row).as_ptr().cast::<c_void>(), ids.len())
        });
        // SAFETY: the out-pointers were checked by `RowOut::init`.
        unsafe { outs.write(ids, dists, n) };
        Ok(())
    })
}

/// The out-pointers of nbhd_neighborhoods_row, checked and set to "nothing".
struct RowOut {
    indices: *mut *const u32,
    sq_dists: Option<*mut *const c_void>,
    len: *mut usize,
}

impl RowOut {
    /// Checks every out-pointer and stores its "nothing" value (NULL, 0) in each usable one,
    /// before the first error is returned.
    ///
    /// # Safety
    /// Each pointer must be NULL or writable.
    unsafe fn init(
        indices: *mut *const u32,
        sq_dists: *mut *const c_void,
        len: *mut usize,
    ) -> Result<Self, FfiError> {
        // SAFETY: forwarded from the caller.
        let (len, indices, sq_dists) = unsafe {
            (
                init_out(len, "len", 0),
                init_out(indices, "indices", std::ptr::null()),
                if sq_dists.is_null() {
                    Ok(None)
                } else {
                    init_out(sq_dists, "sq_dists", std::ptr::null()).map(Some)
                },
            )
        };
        Ok(Self {
            len: len?,
            indices: indices?,
            sq_dists: sq_dists?,
        })
    }

    /// Writes a row.
    ///
    /// # Safety
    /// The pointers must still be writable (checked by `init`).
    unsafe fn write(&self, ids: *const u32, dists: *const c_void, n: usize) {
        // SAFETY: checked by `init_out`, writable (caller).
        unsafe {
            self.indices.write(ids);
            if let Some(p) = self.sq_dists {
                p.write(dists);
            }
            self.len.write(n);
        }
    }
}
