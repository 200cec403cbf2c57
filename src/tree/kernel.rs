//! The arithmetic of a leaf scan that every search shares: the squared distances from a query
//! to a block of points, summed over the dimensions in order, `((0 + t0²) + t1²) + …` (so every
//! search gives the same bits; `0 + x` is exact, as a square is never `-0`), and the bits of
//! those within a bound.

use crate::scalar::{Scalar, ScalarType};

/// Squared distances from `q` to a block of `N` points whose coordinates in dimension `j` are
/// `coord(j)` (struct-of-arrays, the table searches' copies): straight-line code the compiler
/// vectorises.
#[inline(always)]
pub(crate) fn sq_dists_by_dim<'c, T: Scalar, const D: usize, const N: usize>(
    q: &[T; D],
    coord: impl Fn(usize) -> &'c [T],
) -> [T; N] {
    let mut d = [T::ZERO; N];
    for (j, &qj) in q.iter().enumerate() {
        let c: &[T; N] = coord(j).try_into().unwrap();
        for p in 0..N {
            let t = qj - c[p];
            d[p] = d[p] + t * t;
        }
    }
    d
}

/// [`sq_dists_by_dim`] then [`below_mask`]: the squared distances from `q` to a block of `N`
/// points by dimension (the gathered blocks of the tables), and the bits of those within
/// `bound`. With `avx` a block of `f64` in 3-D takes [`sq_dists_below_by_dim_f64x3_avx`] (four
/// points per instruction instead of SSE2's two), the same bits; `avx` must be set only where
/// [`crate::simd::avx`] said so.
#[inline(always)]
pub(crate) fn sq_dists_below_by_dim<'c, T: Scalar, const D: usize, const N: usize>(
    q: &[T; D],
    coord: impl Fn(usize) -> &'c [T],
    bound: T,
    sse: bool,
    avx: bool,
) -> ([T; N], u32) {
    #[cfg(target_arch = "x86_64")]
    if avx && D == 3 && N % 4 == 0 && T::TYPE == ScalarType::F64 {
        debug_assert!(crate::simd::avx());
        let c: [&[T; N]; 3] = std::array::from_fn(|j| coord(j).try_into().unwrap());
        let mut d = [T::ZERO; N];
        // SAFETY: `Scalar` is sealed to f32 and f64 and `T::TYPE` is F64, so `T` is f64 (the
        // casts keep lengths and alignment); the caller set `avx` only where the processor
        // has AVX.
        let mask = unsafe {
            let q = [q[0].to_f64(), q[1].to_f64(), q[2].to_f64()];
            let c = c.map(|c| &*(c as *const [T; N]).cast::<[f64; N]>());
            let out = &mut *(&mut d as *mut [T; N]).cast::<[f64; N]>();
            sq_dists_below_by_dim_f64x3_avx(&q, c, out, bound.to_f64())
        };
        return (d, mask);
    }
    let d = sq_dists_by_dim(q, coord);
    let mask = below_mask(&d, bound, sse);
    (d, mask)
}

/// [`sq_dists_below_by_dim`] for `f64` points in 3-D, compiled for AVX: four points at a time
/// from the three coordinate arrays, `((0 + (qx − x)²) + (qy − y)²) + (qz − z)²` per lane — the
/// order of [`sq_dists_by_dim`] (adding the first square to zero changes no bit), separate
/// multiplies and adds, no fused multiply-add — then one compare and movemask per four bits.
///
/// # Safety
/// The processor must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
unsafe fn sq_dists_below_by_dim_f64x3_avx<const N: usize>(
    q: &[f64; 3],
    c: [&[f64; N]; 3],
    d: &mut [f64; N],
    bound: f64,
) -> u32 {
    use std::arch::x86_64::*;
    let mut mask = 0u32;
    // SAFETY: AVX is this function's contract; group `g` reads `c[j][4g..4g + 4]` and writes
    // `d[4g..4g + 4]`, with 4g + 4 ≤ N.
    unsafe {
        let b = _mm256_set1_pd(bound);
        let (qx, qy, qz) = (
            _mm256_set1_pd(q[0]),
            _mm256_set1_pd(q[1]),
            _mm256_set1_pd(q[2]),
        );
        for g in 0..N / 4 {
            let tx = _mm256_sub_pd(qx, _mm256_loadu_pd(c[0].as_ptr().add(4 * g)));
            let ty = _mm256_sub_pd(qy, _mm256_loadu_pd(c[1].as_ptr().add(4 * g)));
            let tz = _mm256_sub_pd(qz, _mm256_loadu_pd(c[2].as_ptr().add(4 * g)));
            mask |= sum_squares_below([tx, ty, tz], b, d.as_mut_ptr().add(4 * g)) << (4 * g);
        }
    }
    mask
}

/// Squared distances from `q` (its first `D` coordinates) to the points of `points`, packed
/// `[x0, y0, z0, x1, …]` as the tree keeps them (at most `N` points), into the first entries of
/// `d`. Four points at a time: the compiler turns a group into vector arithmetic over its
/// coordinates (in 3-D, three loads and a few shuffles instead of twelve scalar loads).
#[inline(always)]
pub(crate) fn sq_dists_packed<T: Scalar, const D: usize, const N: usize>(
    q: &[T; 4],
    points: &[T],
    d: &mut [T; N],
) {
    let groups = points.chunks_exact(4 * D);
    let rest = groups.remainder();
    let mut filled = 0;
    for (g, out) in groups.zip(d.chunks_exact_mut(4)) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = sq_dist_packed::<T, D>(q, &g[i * D..i * D + D]);
        }
        filled += 4;
    }
    for (p, o) in rest.chunks_exact(D).zip(&mut d[filled..]) {
        *o = sq_dist_packed::<T, D>(q, p);
    }
}

/// The squared distance from `q` to the point `p` (`D` coordinates).
#[inline(always)]
fn sq_dist_packed<T: Scalar, const D: usize>(q: &[T; 4], p: &[T]) -> T {
    let t = q[0] - p[0];
    let mut s = t * t;
    for j in 1..D {
        let t = q[j] - p[j];
        s = s + t * t;
    }
    s
}

/// [`sq_dists_packed`] then [`below_mask`]: the squared distances from `q` to the points of a
/// leaf block (packed, at most `N`) into `d`, and the bits of those within `bound`. With `AVX`
/// an `f64` block in 3-D takes [`sq_dists_below_f64x3_avx`] (four points per instruction
/// instead of SSE2's two), the same bits; `AVX` must be set only where [`crate::simd::avx`]
/// said so (the searches choose it once, at compile time inside the search).
#[inline(always)]
pub(crate) fn sq_dists_below<
    T: Scalar,
    const D: usize,
    const N: usize,
    const SSE: bool,
    const AVX: bool,
>(
    q: &[T; 4],
    points: &[T],
    d: &mut [T; N],
    bound: T,
) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if AVX && D == 3 && T::TYPE == ScalarType::F64 {
        debug_assert!(crate::simd::avx());
        // SAFETY: `Scalar` is sealed to f32 and f64 and `T::TYPE` is F64, so `T` is f64 (the
        // casts keep lengths and alignment); the caller set `AVX` only where the processor
        // has AVX.
        unsafe {
            let q = &*(q as *const [T; 4]).cast::<[f64; 4]>();
            let points = std::slice::from_raw_parts(points.as_ptr().cast::<f64>(), points.len());
            let d = &mut *(d as *mut [T; N]).cast::<[f64; N]>();
            return sq_dists_below_f64x3_avx(q, points, d, bound.to_f64());
        }
    }
    sq_dists_packed::<T, D, N>(q, points, d);
    below_mask(d, bound, SSE)
}

/// [`sq_dists_below`] for `f64` points in 3-D, compiled for AVX: four points at a time, their
/// twelve packed coordinates read as six 128-bit halves, `[x0 y0 | x2 y2]`, `[z0 x1 | z2 x3]`
/// and `[y1 z1 | y3 z3]`, from which two blends and a shuffle make the lanes of x, y and z;
/// then `((qx − x)² + (qy − y)²) + (qz − z)²` per lane — the portable order, separate
/// multiplies and adds (no fused multiply-add), so every lane is the bits of
/// [`sq_dists_packed`] — and one compare and movemask give four bits of the mask. The last
/// points of a block that fill no group of four are computed one by one, as the portable loop
/// does.
///
/// # Safety
/// The processor must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn sq_dists_below_f64x3_avx<const N: usize>(
    q: &[f64; 4],
    points: &[f64],
    d: &mut [f64; N],
    bound: f64,
) -> u32 {
    use std::arch::x86_64::*;
    let n = (points.len() / 3).min(N);
    let groups = n / 4;
    let mut mask = 0u32;
    // SAFETY: AVX is this function's contract; group `g` reads the twelve coordinates
    // `points[12g..12g + 12]` (4g + 4 ≤ n points are in `points`) and writes `d[4g..4g + 4]`
    // (4g + 4 ≤ n ≤ N).
    unsafe {
        let (qx, qy, qz) = (
            _mm256_set1_pd(q[0]),
            _mm256_set1_pd(q[1]),
            _mm256_set1_pd(q[2]),
        );
        let b = _mm256_set1_pd(bound);
        for g in 0..groups {
            let p = points.as_ptr().add(12 * g);
            let r0 = _mm256_loadu2_m128d(p.add(6), p); // x0 y0 | x2 y2
            let r1 = _mm256_loadu2_m128d(p.add(8), p.add(2)); // z0 x1 | z2 x3
            let r2 = _mm256_loadu2_m128d(p.add(10), p.add(4)); // y1 z1 | y3 z3
            let tx = _mm256_sub_pd(qx, _mm256_blend_pd::<0b1010>(r0, r1));
            let ty = _mm256_sub_pd(qy, _mm256_shuffle_pd::<0b0101>(r0, r2));
            let tz = _mm256_sub_pd(qz, _mm256_blend_pd::<0b1010>(r1, r2));
            mask |= sum_squares_below([tx, ty, tz], b, d.as_mut_ptr().add(4 * g)) << (4 * g);
        }
    }
    for i in 4 * groups..n {
        let s = sq_dist_packed::<f64, 3>(q, &points[3 * i..3 * i + 3]);
        d[i] = s;
        mask |= u32::from(s <= bound) << i;
    }
    mask
}

/// The squared distances `(tx² + ty²) + tz²` of a group of four points from their coordinate
/// differences — separate multiplies and adds, the portable order and bits — stored at `out`,
/// and the four bits of those within `b`.
///
/// # Safety
/// The processor must support AVX; `out` must be valid for writing four `f64`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
unsafe fn sum_squares_below(
    [tx, ty, tz]: [std::arch::x86_64::__m256d; 3],
    b: std::arch::x86_64::__m256d,
    out: *mut f64,
) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: AVX and the four writable slots at `out` are this function's contract.
    unsafe {
        let s = _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(tx, tx), _mm256_mul_pd(ty, ty)),
            _mm256_mul_pd(tz, tz),
        );
        _mm256_storeu_pd(out, s);
        _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(s, b)) as u32
    }
}

/// Bit `p` set where `d[p] ≤ bound` (`N` ≤ 32, a multiple of 4): with `sse`
/// ([`crate::simd::sse`], read by the caller once per search or group, not per leaf) SSE
/// compares and movemask on x86-64 (4 or 2 lanes per instruction), else a plain loop.
#[inline(always)]
pub(crate) fn below_mask<T: Scalar, const N: usize>(d: &[T; N], bound: T, sse: bool) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if sse {
        use std::arch::x86_64::*;
        match T::TYPE {
            ScalarType::F32 => {
                // SAFETY: `Scalar` is sealed to f32 and f64 and `T::TYPE` is F32, so `T` is
                // f32 and `[T; N]` is `[f32; N]`.
                let d = unsafe { &*(d as *const [T; N]).cast::<[f32; N]>() };
                let mut mask = 0u32;
                // SAFETY: SSE is part of the x86-64 baseline; each load reads the 4 f32 of
                // `lanes`.
                unsafe {
                    let b = _mm_set1_ps(bound.to_f64() as f32);
                    for (c, lanes) in d.chunks_exact(4).enumerate() {
                        let v = _mm_loadu_ps(lanes.as_ptr());
                        mask |= (_mm_movemask_ps(_mm_cmple_ps(v, b)) as u32) << (4 * c);
                    }
                }
                return mask;
            }
            ScalarType::F64 => {
                // SAFETY: as above, `T` is f64.
                let d = unsafe { &*(d as *const [T; N]).cast::<[f64; N]>() };
                let mut mask = 0u32;
                // SAFETY: SSE2 is part of the x86-64 baseline; each load reads the 2 f64 of
                // `lanes`.
                unsafe {
                    let b = _mm_set1_pd(bound.to_f64());
                    for (c, lanes) in d.chunks_exact(2).enumerate() {
                        let v = _mm_loadu_pd(lanes.as_ptr());
                        mask |= (_mm_movemask_pd(_mm_cmple_pd(v, b)) as u32) << (2 * c);
                    }
                }
                return mask;
            }
        }
    }
    #[allow(unreachable_code)]
    {
        let mut mask = 0u32;
        for (p, &x) in d.iter().enumerate() {
            mask |= u32::from(x <= bound) << p;
        }
        mask
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packed and the by-dimension distances are the point distance's bits, and the mask
    /// holds exactly the entries within the bound (ties included), for both scalar types.
    fn check<T: Scalar + std::fmt::Debug>() {
        let coord = |i: usize| T::from_f64(((i * 2_654_435_761) % 1000) as f64 * 0.37 - 150.0);
        let pts: Vec<T> = (0..3 * 31).map(coord).collect();
        let q = [coord(5000), coord(5001), coord(5002), T::ZERO];
        let direct: Vec<T> = pts
            .chunks_exact(3)
            .map(|p| {
                let mut s = T::ZERO;
                for j in 0..3 {
                    let t = q[j] - p[j];
                    s = s + t * t;
                }
                s
            })
            .collect();
        for n in [0, 1, 3, 4, 5, 17, 31] {
            let mut d = [T::from_f64(-1.0); 32];
            sq_dists_packed::<T, 3, 32>(&q, &pts[..3 * n], &mut d);
            assert_eq!(&d[..n], &direct[..n]);
            assert!(d[n..].iter().all(|&x| x == T::from_f64(-1.0)), "{n}");
        }
        let mut soa = [Vec::new(), Vec::new(), Vec::new()];
        for p in pts.chunks_exact(3).take(16) {
            for j in 0..3 {
                soa[j].push(p[j]);
            }
        }
        let q3 = [q[0], q[1], q[2]];
        let by_dim: [T; 16] = sq_dists_by_dim(&q3, |j| &soa[j][..]);
        assert_eq!(&by_dim[..], &direct[..16]);
        let mut d = [T::ZERO; 32];
        d[..31].copy_from_slice(&direct);
        d[31] = T::from_f64(f64::INFINITY);
        let bound = direct[7];
        for sse in [true, false] {
            let mask = below_mask(&d, bound, sse);
            for (p, &x) in d.iter().enumerate() {
                assert_eq!(mask >> p & 1 == 1, x <= bound, "entry {p}");
            }
            assert_eq!(below_mask(&d, T::from_f64(f64::INFINITY), sse), u32::MAX);
            let nan = [T::from_f64(f64::NAN); 4];
            assert_eq!(below_mask(&nan, T::from_f64(f64::INFINITY), sse), 0);
        }
    }

    #[test]
    fn distances_and_masks_match_the_plain_loops() {
        check::<f32>();
        check::<f64>();
    }

    /// The AVX leaf kernel of `f64` in 3-D gives the portable kernel's distances and mask, bit
    /// for bit, on blocks of every length up to 32 (whole groups of four and a rest), with
    /// bounds exactly on points, between them, zero and infinite, and squared distances that
    /// overflow to infinity or underflow to zero.
    #[test]
    fn the_avx_kernel_matches_the_portable_one() {
        if !crate::simd::avx() {
            return;
        }
        let coord = |i: usize| ((i * 2_654_435_761) % 1000) as f64 * 0.37 - 150.0;
        let spreads = [1.0, 1e-160, 1e155, 1e-310];
        for spread in spreads {
            let pts: Vec<f64> = (0..3 * 32).map(|i| coord(i) * spread).collect();
            let q = [coord(5000) * spread, coord(5001) * spread, coord(5002), 0.0];
            for n in 0..=32 {
                let mut plain = [0.0f64; 32];
                sq_dists_packed::<f64, 3, 32>(&q, &pts[..3 * n], &mut plain);
                let mut bounds = vec![0.0, f64::INFINITY, f64::MAX, 1.0];
                bounds.extend(plain[..n].iter().copied());
                bounds.extend(plain[..n].iter().map(|&x| x * 0.999));
                for bound in bounds {
                    let (mut a, mut b) = ([-1.0f64; 32], [-1.0f64; 32]);
                    let ma =
                        sq_dists_below::<f64, 3, 32, true, true>(&q, &pts[..3 * n], &mut a, bound);
                    let mb = sq_dists_below::<f64, 3, 32, false, false>(
                        &q,
                        &pts[..3 * n],
                        &mut b,
                        bound,
                    );
                    let bits = |d: &[f64]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&a[..n]), bits(&plain[..n]), "n {n} spread {spread}");
                    assert_eq!(ma & low(n), mb & low(n), "n {n} bound {bound}");
                    assert_eq!(u64::from(ma) >> n, 0, "bits past the block, n {n}");
                }
            }
        }
    }

    /// The AVX by-dimension kernel of `f64` in 3-D (the tables' gathered blocks) gives the
    /// portable distances and mask, bit for bit: bounds exactly on points, between them, zero
    /// and infinite; squares that overflow or underflow; infinite padding.
    #[test]
    fn the_by_dim_avx_kernel_matches_the_portable_one() {
        if !crate::simd::avx() {
            return;
        }
        let coord = |i: usize| ((i * 2_654_435_761) % 1000) as f64 * 0.37 - 150.0;
        for spread in [1.0, 1e-160, 1e155, 1e-310] {
            let mut soa: [Vec<f64>; 3] =
                std::array::from_fn(|j| (0..16).map(|i| coord(3 * i + j) * spread).collect());
            soa[0][15] = f64::INFINITY;
            let q = [coord(5000) * spread, coord(5001) * spread, coord(5002)];
            let plain: [f64; 16] = sq_dists_by_dim(&q, |j| &soa[j][..]);
            let mut bounds = vec![0.0, f64::INFINITY, f64::MAX, 1.0];
            bounds.extend(plain.iter().copied());
            bounds.extend(plain.iter().map(|&x| x * 0.999));
            for bound in bounds {
                for sse in [true, false] {
                    let (a, ma) =
                        sq_dists_below_by_dim::<f64, 3, 16>(&q, |j| &soa[j][..], bound, sse, true);
                    let (b, mb) =
                        sq_dists_below_by_dim::<f64, 3, 16>(&q, |j| &soa[j][..], bound, sse, false);
                    let bits = |d: &[f64]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&a), bits(&plain), "spread {spread}");
                    assert_eq!(bits(&b), bits(&plain), "spread {spread}");
                    assert_eq!(ma, mb, "spread {spread} bound {bound}");
                }
            }
        }
    }

    fn low(n: usize) -> u32 {
        ((1u64 << n) - 1) as u32
    }
}
