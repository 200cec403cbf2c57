//! Saving a tree (static or dynamic) and loading it back: to and from a file, and to a
//! caller's buffer and from bytes (the formats: docs/tree-file-format.md; the Rust side:
//! src/tree/persist.rs and src/dynamic/persist.rs).

use std::ffi::{c_char, c_void, CStr};
use std::path::PathBuf;

use super::args::{deref, init_out};
use super::dynamic::nbhd_dynamic_tree;
use super::status::{guard, nbhd_status, FfiError};
use super::tree::{hand_out_index, nbhd_tree, IndexHandle};
use crate::error::NbhdError;
use crate::handle::AnyIndex;

/// The path C passed: a NUL-terminated string (bytes on Unix, UTF-8 elsewhere).
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string.
unsafe fn read_path(path: *const c_char) -> Result<PathBuf, FfiError> {
    if path.is_null() {
        return Err(FfiError::Null("path".into()));
    }
    // SAFETY: non-NULL and NUL-terminated (caller); only read here.
    let bytes = unsafe { CStr::from_ptr(path) }.to_bytes();
    if bytes.is_empty() {
        return Err(FfiError::InvalidArgument("path is empty".into()));
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
    }
    #[cfg(not(unix))]
    {
        std::str::from_utf8(bytes)
            .map(PathBuf::from)
            .map_err(|_| FfiError::InvalidArgument("path is not UTF-8".into()))
    }
}

/// Writes `*size = needed`, then (if `capacity` suffices and `buffer` is not NULL) lets `save`
/// write exactly `needed` bytes into `buffer`: the body of the save-to-buffer exports.
///
/// # Safety
/// `size` was checked by `init_out`; `buffer` is NULL or writable for `capacity` bytes.
unsafe fn into_buffer(
    size: *mut usize,
    needed: usize,
    buffer: *mut c_void,
    capacity: usize,
    save: impl FnOnce(&mut &mut [u8]) -> Result<(), NbhdError>,
) -> Result<(), FfiError> {
    // SAFETY: `size` was checked by `init_out` (caller).
    unsafe { size.write(needed) };
    if capacity < needed {
        return Err(NbhdError::BufferTooSmall {
            what: "buffer (bytes)",
            len: capacity,
            needed,
        }
        .into());
    }
    if buffer.is_null() {
        return Err(FfiError::Null("buffer".into()));
    }
    // SAFETY: `buffer` is non-NULL and writable for `capacity` >= `needed` bytes (caller);
    // u8 needs no alignment, and the slice is the only access to it during the call.
    let out = unsafe { std::slice::from_raw_parts_mut(buffer.cast::<u8>(), needed) };
    let mut dst: &mut [u8] = out;
    save(&mut dst)?;
    Ok(())
}

/// The `size` bytes at `data`, checked: the input of the load-from-buffer exports.
///
/// # Safety
/// `data` is NULL or readable for `size` bytes, not written during the call.
unsafe fn input_bytes<'a>(data: *const c_void, size: usize) -> Result<&'a [u8], FfiError> {
    if data.is_null() {
        return Err(FfiError::Null("data".into()));
    }
    if size > isize::MAX as usize {
        return Err(FfiError::InvalidArgument(format!(
            "size {size} exceeds the address space"
        )));
    }
    // SAFETY: `data` is non-NULL, readable for `size` <= isize::MAX bytes and not written
    // during the call (caller); u8 needs no alignment.
    Ok(unsafe { std::slice::from_raw_parts(data.cast::<u8>(), size) })
}

/// The bytes of the file `path`, an I/O error naming it and `what` was read.
fn read_file(path: &std::path::Path, what: &str) -> Result<Vec<u8>, NbhdError> {
    std::fs::read(path).map_err(|e| {
        NbhdError::io(
            format!("reading the saved {what} from {}", path.display()),
            &e,
        )
    })
}

/// The body of nbhd_tree_save and nbhd_dynamic_save.
///
/// # Safety
/// As nbhd_tree_save.
unsafe fn save<H: IndexHandle>(func: &str, tree: *const H, path: *const c_char) -> nbhd_status {
    guard(func, || {
        // SAFETY: `tree` is NULL or a live handle (caller).
        let tree = unsafe { deref(tree, "tree") }?;
        // SAFETY: `path` is NULL or NUL-terminated (caller).
        let path = unsafe { read_path(path) }?;
        tree.index().save_file(&path)?;
        Ok(())
    })
}

/// The body of nbhd_tree_save_to_buffer and nbhd_dynamic_save_to_buffer.
///
/// # Safety
/// As nbhd_tree_save_to_buffer.
unsafe fn save_to_buffer<H: IndexHandle>(
    func: &str,
    tree: *const H,
    buffer: *mut c_void,
    capacity: usize,
    size: *mut usize,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `size` is NULL or writable (caller).
        let size = unsafe { init_out(size, "size", 0) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let index = unsafe { deref(tree, "tree") }?.index();
        let needed = index.saved_len();
        // SAFETY: `size` was checked by `init_out`; `buffer` is as the caller describes.
        unsafe { into_buffer(size, needed, buffer, capacity, |dst| index.save(dst)) }
    })
}

/// The body of nbhd_tree_load and nbhd_dynamic_load.
///
/// # Safety
/// As nbhd_tree_load.
unsafe fn load<H: IndexHandle>(
    func: &str,
    path: *const c_char,
    out_tree: *mut *mut H,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `path` is NULL or NUL-terminated (caller).
        let path = unsafe { read_path(path) }?;
        let what = if H::GROWING { "dynamic tree" } else { "tree" };
        let bytes = read_file(&path, what)?;
        let index = AnyIndex::from_bytes(&bytes, H::GROWING)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, index) };
        Ok(())
    })
}

/// The body of nbhd_tree_load_from_buffer and nbhd_dynamic_load_from_buffer.
///
/// # Safety
/// As nbhd_tree_load_from_buffer.
unsafe fn load_from_buffer<H: IndexHandle>(
    func: &str,
    data: *const c_void,
    size: usize,
    out_tree: *mut *mut H,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `data` is NULL or readable for `size` bytes, not written (caller).
        let bytes = unsafe { input_bytes(data, size) }?;
        let index = AnyIndex::from_bytes(bytes, H::GROWING)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, index) };
        Ok(())
    })
}

/// Writes `tree` to the file `path` (created, or truncated if it exists) in the saved-tree
/// format (docs/tree-file-format.md): a versioned header with checksums, then the tree as
/// built. nbhd_tree_load reads it back into a tree that answers every query exactly as
/// `tree` does.
///
/// Errors: NULL_POINTER (`tree`, `path`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
/// `path`; off Unix, a `path` that is not UTF-8), IO_ERROR (the file cannot be created or
/// written; the message names it and gives the system's reason).
///
/// # Safety
/// `tree` must be NULL or a live handle; `path` NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_save(
    tree: *const nbhd_tree,
    path: *const c_char,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `save` requires.
    unsafe { save("nbhd_tree_save", tree, path) }
}

/// Writes `tree` in the saved-tree format into the caller's `buffer` of `capacity` bytes, and
/// the number of bytes the saved tree takes to `*size` — also when the buffer is too small, so
/// a first call with `capacity` 0 (and `buffer` NULL) asks for the size. The bytes are those
/// nbhd_tree_save writes to a file; nbhd_tree_load_from_buffer reads them.
///
/// Errors: NULL_POINTER (`tree`, `size`, or `buffer` when `capacity` is large enough),
/// MISALIGNED_POINTER, BUFFER_TOO_SMALL (`capacity` < `*size`; nothing is written to
/// `buffer`).
///
/// # Safety
/// `tree` must be NULL or a live handle; `buffer` NULL or writable for `capacity` bytes;
/// `size` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_save_to_buffer(
    tree: *const nbhd_tree,
    buffer: *mut c_void,
    capacity: usize,
    size: *mut usize,
) -> nbhd_status {
    let name = "nbhd_tree_save_to_buffer";
    // SAFETY: the caller's contract is the one `save_to_buffer` requires.
    unsafe { save_to_buffer(name, tree, buffer, capacity, size) }
}

/// Loads the tree saved in the file `path` (by nbhd_tree_save or nbhd_tree_save_to_buffer,
/// by any nbhd that writes format version 1) and stores a new handle in `*out_tree`. The tree
/// has the scalar type it was saved with (nbhd_tree_stats tells it) and answers every query
/// exactly as the saved tree did.
///
/// Nothing in the file is trusted: the header and data are checked (magic, byte order, format
/// version, checksums, every field, the node structure) before a tree is handed out, so a
/// damaged or crafted file is refused, never answered wrong. On any error `*out_tree` is set
/// to NULL (if `out_tree` is not NULL).
///
/// Errors: NULL_POINTER (`path`, `out_tree`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
/// `path`; off Unix, not UTF-8), IO_ERROR (the file cannot be read; the message names it),
/// FORMAT_MISMATCH (not a saved nbhd tree, or one of another format version or byte order: the
/// message names the file's value and this library's), CORRUPT_DATA (truncated, followed by
/// other bytes, a checksum that does not match, an inconsistent field or node structure: the
/// message says which).
///
/// Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free.
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string; `out_tree` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_load(
    path: *const c_char,
    out_tree: *mut *mut nbhd_tree,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `load` requires.
    unsafe { load("nbhd_tree_load", path, out_tree) }
}

/// Loads the tree saved in the `size` bytes at `data` (as nbhd_tree_save_to_buffer wrote
/// them, or read from a file nbhd_tree_save wrote) and stores a new handle in `*out_tree`. The
/// bytes are copied: `data` may be freed as soon as this returns. Checks and errors as
/// nbhd_tree_load, without IO_ERROR: NULL_POINTER (`data`, `out_tree`), MISALIGNED_POINTER,
/// INVALID_ARGUMENT (`size` above PTRDIFF_MAX), FORMAT_MISMATCH, CORRUPT_DATA. On any error
/// `*out_tree` is set to NULL (if `out_tree` is not NULL).
///
/// Ownership: the caller owns `*out_tree` and frees it with nbhd_tree_free.
///
/// # Safety
/// `data` must be NULL or readable for `size` bytes, not written during the call; `out_tree`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_load_from_buffer(
    data: *const c_void,
    size: usize,
    out_tree: *mut *mut nbhd_tree,
) -> nbhd_status {
    let name = "nbhd_tree_load_from_buffer";
    // SAFETY: the caller's contract is the one `load_from_buffer` requires.
    unsafe { load_from_buffer(name, data, size, out_tree) }
}

/// Writes the dynamic tree `tree` to the file `path` (created, or truncated if it exists) in
/// the saved dynamic-tree format (docs/tree-file-format.md, "Dynamic trees"): a versioned
/// header with checksums, the index bitmaps, the kept coordinates and every static tree of the
/// forest as built. nbhd_dynamic_load reads it back into a dynamic tree that answers every
/// query exactly as `tree` does and grows and shrinks the same way.
///
/// Errors: NULL_POINTER (`tree`, `path`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
/// `path`; off Unix, a `path` that is not UTF-8), IO_ERROR (the file cannot be created or
/// written; the message names it and gives the system's reason).
///
/// # Safety
/// `tree` must be NULL or a live handle not being changed by another thread; `path` NULL or a
/// NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_save(
    tree: *const nbhd_dynamic_tree,
    path: *const c_char,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `save` requires.
    unsafe { save("nbhd_dynamic_save", tree, path) }
}

/// Writes `tree` in the saved dynamic-tree format into the caller's `buffer` of `capacity`
/// bytes, and the number of bytes it takes to `*size` — also when the buffer is too small, so
/// a first call with `capacity` 0 (and `buffer` NULL) asks for the size. The bytes are those
/// nbhd_dynamic_save writes; nbhd_dynamic_load_from_buffer reads them.
///
/// Errors: NULL_POINTER (`tree`, `size`, or `buffer` when `capacity` is large enough),
/// MISALIGNED_POINTER, BUFFER_TOO_SMALL (`capacity` < `*size`; nothing is written to
/// `buffer`).
///
/// # Safety
/// `tree` must be NULL or a live handle not being changed by another thread; `buffer` NULL or
/// writable for `capacity` bytes; `size` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_save_to_buffer(
    tree: *const nbhd_dynamic_tree,
    buffer: *mut c_void,
    capacity: usize,
    size: *mut usize,
) -> nbhd_status {
    let name = "nbhd_dynamic_save_to_buffer";
    // SAFETY: the caller's contract is the one `save_to_buffer` requires.
    unsafe { save_to_buffer(name, tree, buffer, capacity, size) }
}

/// Loads the dynamic tree saved in the file `path` (by nbhd_dynamic_save or
/// nbhd_dynamic_save_to_buffer) and stores a new handle in `*out_tree`. The tree has the
/// scalar type it was saved with (nbhd_dynamic_tree_stats tells it), answers every query
/// exactly as the saved one did, and continues its indices where the saved one stopped.
///
/// Nothing in the file is trusted: the header, every static tree and what spans them (index
/// ranges, bitmaps, kept coordinates, live count; a dimension whose point would not fit in
/// memory) are checked before a tree is handed out, and the thread count the file states is
/// not obeyed: the loaded tree builds on the shared pool (0) until nbhd_dynamic_set_threads.
/// On any error `*out_tree` is set to NULL (if `out_tree` is not NULL).
///
/// Errors: NULL_POINTER (`path`, `out_tree`), MISALIGNED_POINTER, INVALID_ARGUMENT (an empty
/// `path`; off Unix, not UTF-8), IO_ERROR (the file cannot be read; the message names it),
/// FORMAT_MISMATCH (not a saved nbhd tree, a saved *static* tree, or one of another format
/// version or byte order: the message names the file's value and this library's),
/// CORRUPT_DATA (truncated, followed by other bytes, a checksum that does not match, an
/// inconsistent field, static tree or cross-tree fact: the message says which).
///
/// Ownership: the caller owns `*out_tree` and frees it with nbhd_dynamic_free.
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string; `out_tree` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_load(
    path: *const c_char,
    out_tree: *mut *mut nbhd_dynamic_tree,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `load` requires.
    unsafe { load("nbhd_dynamic_load", path, out_tree) }
}

/// Loads the dynamic tree saved in the `size` bytes at `data` (as
/// nbhd_dynamic_save_to_buffer wrote them) and stores a new handle in `*out_tree`. The bytes
/// are copied: `data` may be freed as soon as this returns. Checks and errors as
/// nbhd_dynamic_load, without IO_ERROR: NULL_POINTER (`data`, `out_tree`),
/// MISALIGNED_POINTER, INVALID_ARGUMENT (`size` above PTRDIFF_MAX), FORMAT_MISMATCH,
/// CORRUPT_DATA. On any error `*out_tree` is set to NULL (if `out_tree` is not NULL).
///
/// Ownership: the caller owns `*out_tree` and frees it with nbhd_dynamic_free.
///
/// # Safety
/// `data` must be NULL or readable for `size` bytes, not written during the call; `out_tree`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_load_from_buffer(
    data: *const c_void,
    size: usize,
    out_tree: *mut *mut nbhd_dynamic_tree,
) -> nbhd_status {
    let name = "nbhd_dynamic_load_from_buffer";
    // SAFETY: the caller's contract is the one `load_from_buffer` requires.
    unsafe { load_from_buffer(name, data, size, out_tree) }
}
