//! Cache hints: requests for memory the code will touch soon, issued early enough to overlap
//! the wait with other work. A hint never faults and changes no result; on processors without
//! the instruction it does nothing.

/// Requests the cache lines of `s`.
#[inline(always)]
pub(crate) fn prefetch_range<U>(s: &[U]) {
    prefetch_bytes(s.as_ptr().cast(), std::mem::size_of_val(s));
}

/// Requests the elements of `items` at `indices` (a row's neighbours, say, scattered over the
/// caller's array).
#[inline(always)]
pub(crate) fn prefetch_at<U>(items: &[U], indices: &[u32]) {
    for &i in indices {
        prefetch_range(std::slice::from_ref(&items[i as usize]));
    }
}

/// Requests the cache lines of the `bytes` bytes from `p`. `p` need not point into an
/// allocation the caller may read (the slots another part of a table holds, say): the address
/// is only computed, never dereferenced.
#[inline(always)]
pub(crate) fn prefetch_bytes(p: *const u8, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let mut off = 0;
        while off < bytes {
            // SAFETY: a prefetch reads nothing architecturally and cannot fault, whatever the
            // address; `wrapping_add` computes it without asserting that it is in bounds.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(off).cast()) };
            off += 64;
        }
        if bytes > 0 {
            // The last line, which the steps of 64 bytes miss when `p` is not line-aligned.
            // SAFETY: as above.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(bytes - 1).cast()) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, bytes);
}
