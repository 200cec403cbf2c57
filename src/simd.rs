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
//! - the normals' batched eigen solves (`geometry/eigen.rs`: AVX), the robust planes'
//!   neighbourhood fills and lane sums (`geometry/robust_plane.rs`: AVX) and the robust
//!   smoothing's scores and steps (`smooth/robust/`: AVX).
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

/// Four 3-vectors in three AVX registers, coordinate by coordinate: `[x0 x1 x2 x3]`,
/// `[y0 y1 y2 y3]` and `[z0 z1 z2 z3]`, with the first two coordinates of each vector in one
/// 128-bit load, transposed by unpacking (gathering through memory instead, four narrow stores
/// and one wide load, stalls the gather). The robust smoothing's neighbourhood fills
/// (`geometry/robust_plane.rs`) and umbrella steps (`smooth/robust/step.rs`) read their
/// neighbours this way.
///
/// # Safety
/// The processor supports AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
pub(crate) unsafe fn transpose4_avx(q: [&glam::DVec3; 4]) -> [std::arch::x86_64::__m256d; 3] {
    use std::arch::x86_64::*;
    // SAFETY: each reference is to a `DVec3`, three consecutive `f64` (`repr(C)`), so `&v.x`
    // starts two of them; AVX as the caller guarantees
    unsafe {
        let xy = |v: &glam::DVec3| _mm_loadu_pd(&v.x);
        let z = |u: &glam::DVec3, v: &glam::DVec3| _mm_loadh_pd(_mm_load_sd(&u.z), &v.z);
        let pair =
            |lo: __m128d, hi: __m128d| _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(lo), hi);
        // [x0 y0 x2 y2] and [x1 y1 x3 y3]: unpacked to [x0 x1 x2 x3], [y0 y1 y2 y3]
        let (a, b) = (pair(xy(q[0]), xy(q[2])), pair(xy(q[1]), xy(q[3])));
        let z = pair(z(q[0], q[1]), z(q[2], q[3]));
        [_mm256_unpacklo_pd(a, b), _mm256_unpackhi_pd(a, b), z]
    }
}
