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
}
