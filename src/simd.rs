//! Which instruction sets the loops with a SIMD form may use, decided at run time.
//!
//! The loops that have a form for wider registers take it where the processor has the
//! instructions, and give exactly the bits of their portable form either way (the same
//! operations on the same lanes in the same order, no fused multiply-add):
//! - the leaf masks of every search (`tree/kernel.rs`: SSE compares, x86-64's baseline);
//! - the single queries' leaf distances and masks of `f64` points in 3-D (`tree/kernel.rs`: AVX,
//!   four points per instruction);
//! - the grouped table search's keys within a bound and its ranks (`tree/group_search/`:
//!   AVX-512 F + VL, and AVX2 for the ranks);
//! - the normals' batched eigen solves (`geometry/eigen.rs`: AVX), the robust planes' lane
//!   sums (`geometry/robust_plane.rs`: AVX) and the robust smoothing's scores and steps
//!   (`smooth/robust/`: AVX).
//!
//! [`force_portable`] makes every one of them take its portable form instead, in the whole
//! process, until it is called again with `false`. It exists for the tests and fuzz targets
//! that compare both forms bit for bit (`tests/simd_fuzz.rs`, the `simd_*` targets of `fuzz/`)
//! and to measure what the SIMD forms gain; it is a process-wide switch read at each dispatch,
//! not a setting for production code.

use std::sync::atomic::{AtomicBool, Ordering};

static PORTABLE: AtomicBool = AtomicBool::new(false);

/// From now on every dispatched loop takes its portable form (`true`), or the widest form the
/// processor has again (`false`, the default). Results are the same bits either way.
pub fn force_portable(on: bool) {
    PORTABLE.store(on, Ordering::Relaxed);
}

/// Whether [`force_portable`] is in effect.
pub fn portable_forced() -> bool {
    PORTABLE.load(Ordering::Relaxed)
}

/// SSE compares (x86-64's baseline) may be used.
#[inline(always)]
pub(crate) fn sse() -> bool {
    cfg!(target_arch = "x86_64") && !portable_forced()
}

/// AVX may be used: the processor has it and the portable forms are not forced.
#[inline]
pub(crate) fn avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    return !portable_forced() && std::arch::is_x86_feature_detected!("avx");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// AVX2 may be used.
#[inline]
pub(crate) fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    return !portable_forced() && std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// AVX-512 F and VL may be used.
#[inline]
pub(crate) fn avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    return !portable_forced()
        && std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512vl");
    #[cfg(not(target_arch = "x86_64"))]
    false
}
