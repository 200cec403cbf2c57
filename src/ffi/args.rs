//! Checks of the pointers C passes in, before anything is read or written through them.

use std::ffi::c_void;

use super::status::FfiError;
use crate::error::NbhdError;

/// Checks that `p` is not NULL and is aligned for `T`; `arg` names it for the message.
pub(crate) fn check_ptr<T>(p: *const T, arg: &str) -> Result<(), FfiError> {
    check_aligned(p.cast(), std::mem::align_of::<T>(), arg)
}

/// Checks that `p` is not NULL and is a multiple of `align`; `arg` names it for the message.
pub(crate) fn check_aligned(p: *const c_void, align: usize, arg: &str) -> Result<(), FfiError> {
    if p.is_null() {
        return Err(FfiError::Null(arg.to_owned()));
    }
    let addr = p as usize;
    if addr % align != 0 {
        return Err(FfiError::Misaligned {
            what: arg.to_owned(),
            addr,
            align,
        });
    }
    Ok(())
}

/// Checks an optional pointer: NULL is fine, anything else must be aligned for `T`.
pub(crate) fn check_optional<T>(p: *const T, arg: &str) -> Result<(), FfiError> {
    if p.is_null() {
        Ok(())
    } else {
        check_ptr(p, arg)
    }
}

/// The object behind a handle or struct pointer, after the NULL and alignment checks.
///
/// # Safety
/// `p` must be NULL or point to a live `T` that is not written during `'a`.
pub(crate) unsafe fn deref<'a, T>(p: *const T, arg: &str) -> Result<&'a T, FfiError> {
    check_ptr(p, arg)?;
    // SAFETY: non-NULL and aligned (checked above); live and not written (caller).
    Ok(unsafe { &*p })
}

/// Checks an out-pointer and stores `value` in it at once, so that the caller's variable
/// holds a defined value (NULL, 0) whatever happens next; returns the pointer for later writes.
///
/// # Safety
/// `p` must be NULL or point to writable memory for a `T`.
pub(crate) unsafe fn init_out<T>(p: *mut T, arg: &str, value: T) -> Result<*mut T, FfiError> {
    check_ptr(p.cast_const(), arg)?;
    // SAFETY: non-NULL and aligned (checked above) and writable (caller); `T` is a plain
    // pointer or integer, so nothing is dropped by overwriting it.
    unsafe { p.write(value) };
    Ok(p)
}

/// The `count` values at `p` (`arg` names it), checked: `count` 0 needs no pointer (NULL or
/// aligned); otherwise `p` non-NULL and aligned, and the byte size within the address space.
///
/// # Safety
/// `p` NULL or readable for `count` values of `T`, not written during `'a`.
pub(crate) unsafe fn read_slice<'a, T>(
    p: *const T,
    count: usize,
    arg: &str,
) -> Result<&'a [T], FfiError> {
    if count == 0 {
        check_optional(p, arg)?;
        return Ok(&[]);
    }
    check_ptr(p, arg)?;
    if count > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return Err(FfiError::InvalidArgument(format!(
            "{arg}: {count} values overflow the address space"
        )));
    }
    // SAFETY: non-NULL and aligned (checked above), `count` readable values (caller) whose
    // byte size fits in isize (checked above); only read.
    Ok(unsafe { std::slice::from_raw_parts(p, count) })
}

/// Writes `values` to `out` if they fit in `capacity`, else BUFFER_TOO_SMALL naming `what`.
///
/// # Safety
/// `out` must be NULL or writable for `capacity` values.
pub(crate) unsafe fn copy_out<V: Copy>(
    values: &[V],
    out: *mut V,
    capacity: usize,
    what: &'static str,
) -> Result<(), FfiError> {
    if values.len() > capacity {
        return Err(NbhdError::BufferTooSmall {
            what,
            len: capacity,
            needed: values.len(),
        }
        .into());
    }
    if !values.is_empty() {
        check_ptr(out.cast_const(), what)?;
        // SAFETY: non-NULL and aligned (checked above), writable for `capacity` >=
        // values.len() values (caller); a fresh Rust slice never overlaps the caller's buffer.
        unsafe { std::ptr::copy_nonoverlapping(values.as_ptr(), out, values.len()) };
    }
    Ok(())
}

/// Writes `values.len()` to `*count` and `values` to `out` as [`copy_out`] does; a NULL or
/// misaligned `out` that would be written is refused first, with `*count` left as it was.
///
/// # Safety
/// `out` must be NULL or writable for `capacity` values; `count` checked and writable.
pub(crate) unsafe fn copy_counted<V: Copy>(
    values: &[V],
    out: *mut V,
    capacity: usize,
    count: *mut usize,
    what: &'static str,
) -> Result<(), FfiError> {
    if !values.is_empty() && values.len() <= capacity {
        check_ptr(out.cast_const(), what)?;
    }
    // SAFETY: `count` is non-NULL, aligned and writable (caller).
    unsafe { count.write(values.len()) };
    // SAFETY: forwarded from the caller.
    unsafe { copy_out(values, out, capacity, what) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn null_and_misaligned_pointers_are_named() {
        let x = [0u64; 2];
        assert!(check_ptr(x.as_ptr(), "x").is_ok());
        let e = check_ptr(std::ptr::null::<u32>(), "indices").unwrap_err();
        assert_eq!(e.to_string(), "argument indices is NULL");
        let odd = (x.as_ptr() as usize + 1) as *const u32;
        let e = check_ptr(odd, "indices").unwrap_err();
        assert!(e.to_string().ends_with("is not aligned to 4 bytes"), "{e}");
        assert!(check_optional(std::ptr::null::<f64>(), "sq_dists").is_ok());
    }
}
