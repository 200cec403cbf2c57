//! Plane fits for the robust smoothing, over a neighbourhood stored coordinate by coordinate:
//! the covariance plane (eq. 2.8–2.10), Tukey's biweight of a plane distance, and the normal of
//! a weighted covariance (eq. 2.8–2.10 with a weight per point).
//!
//! The sums run in [`LANES`] independent lanes over the coordinates of a [`Neighborhood`] and
//! are added lane by lane at the end: the same operations in the same order on every machine
//! and thread, so the same bits whether the compiler turns each lane step into one SIMD
//! instruction (AVX, chosen at run time) or into scalar ones. No fused multiply-add is used,
//! which would round differently.

use super::eigen::{sym_eigen3_fast, sym_eigen3_smallest, sym_eigen3_smallest_lanes};
use super::normals::unit_scale;
use glam::{DMat3, DVec3};

/// Lanes of the sums; the coordinates are padded to a multiple of it.
pub(crate) const LANES: usize = 4;

/// Tukey's biweight `(1 − u²)²` of a distance `u = d/width` in units of the width, for
/// `|u| < 1`; 0 from there on. A robust inlier weight: smooth, 1 on the plane, and exactly 0
/// for outliers. It takes the ratio, so that a loop with one width multiplies by its inverse.
#[inline]
pub(crate) fn biweight(u: f64) -> f64 {
    // branch-free (it runs in the innermost loops of the plane selection): for |u| ≥ 1,
    // 1 − u² ≤ 0 and the max gives 0; a NaN (d or width not finite, 0/0) gives 0 as well
    let v = (1.0 - u * u).max(0.0);
    v * v
}

/// The points of a neighbourhood relative to an origin, one vector per coordinate, padded with
/// zeros to a multiple of [`LANES`]; `len` of them are points.
#[derive(Clone, Debug, Default)]
pub(crate) struct Neighborhood {
    pub(crate) x: Vec<f64>,
    pub(crate) y: Vec<f64>,
    pub(crate) z: Vec<f64>,
    len: usize,
    /// Scratch: the weight of each point in [`Neighborhood::weighted_normal`].
    w: Vec<f64>,
}

/// What the covariance plane of a neighbourhood is made of: the covariance matrix whose smallest
/// eigenvector is the plane's normal (eq. 2.8–2.10, see [`Neighborhood::covariance`]) and the
/// sum of its points (the barycentre times the count, eq. 2.3), relative to the origin.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Covariance {
    pub(crate) matrix: DMat3,
    pub(crate) sum: DVec3,
}

impl Neighborhood {
    /// Holds the point `points[s]` and its neighbours `points[j]`, `j` in `row`, relative to the
    /// point (the point first, at the origin) from now on.
    #[inline]
    pub(crate) fn fill(&mut self, points: &[DVec3], s: usize, row: &[u32]) {
        let p = points[s];
        self.len = row.len() + 1;
        let padded = self.len.div_ceil(LANES) * LANES;
        for v in [&mut self.x, &mut self.y, &mut self.z] {
            // every element is written below: no clearing pass
            v.truncate(padded);
            v.resize(padded, 0.0);
            v[0] = 0.0;
            // the padding, fewer than `LANES` elements: stores, not a call to `memset`
            for c in 0..LANES - 1 {
                if let Some(x) = v.get_mut(self.len + c) {
                    *x = 0.0;
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx() {
            // SAFETY: the processor supports AVX (checked just above).
            unsafe { self.fill_avx(points, p, row) };
            return;
        }
        self.fill_from(0, points, p, row);
    }

    /// The neighbours `row[t..]` relative to `p`, at `t + 1..` (the portable loop of
    /// [`Neighborhood::fill`], and the rest of its AVX blocks).
    #[inline(always)]
    fn fill_from(&mut self, t: usize, points: &[DVec3], p: DVec3, row: &[u32]) {
        // zipped, so that only the read of a neighbour is bounds-checked
        let coordinates = self.x[t + 1..]
            .iter_mut()
            .zip(&mut self.y[t + 1..])
            .zip(&mut self.z[t + 1..]);
        for (((x, y), z), &j) in coordinates.zip(&row[t..]) {
            let d = points[j as usize] - p;
            (*x, *y, *z) = (d.x, d.y, d.z);
        }
    }

    /// [`Neighborhood::fill`]'s neighbours four at a time in AVX registers
    /// (`crate::simd::transpose4_avx`): the same subtraction per coordinate, so the same bits
    /// as the portable loop, in about two thirds of its instructions (each neighbour's first two
    /// coordinates one load, each block's differences three subtractions and three stores).
    ///
    /// # Safety
    /// The processor supports AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn fill_avx(&mut self, points: &[DVec3], p: DVec3, row: &[u32]) {
        use std::arch::x86_64::*;
        let blocks = row.len() / LANES * LANES;
        let origin = [p.x, p.y, p.z].map(|c| _mm256_set1_pd(c));
        let coordinates = self.x[1..=blocks]
            .chunks_exact_mut(LANES)
            .zip(self.y[1..=blocks].chunks_exact_mut(LANES))
            .zip(self.z[1..=blocks].chunks_exact_mut(LANES));
        for (((x, y), z), ids) in coordinates.zip(row.chunks_exact(LANES)) {
            let q = [0, 1, 2, 3].map(|l| &points[ids[l] as usize]);
            // SAFETY: AVX as the caller guarantees
            let c = unsafe { crate::simd::transpose4_avx(q) };
            for (out, (c, o)) in [x, y, z].into_iter().zip(c.into_iter().zip(origin)) {
                // SAFETY: `out` is a chunk of `LANES` = 4 `f64`, the 32 bytes stored
                unsafe { _mm256_storeu_pd(out.as_mut_ptr(), _mm256_sub_pd(c, o)) };
            }
        }
        self.fill_from(blocks, points, p, row);
    }

    /// How many points it holds.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds no point.
    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The covariance of the points (eq. 2.8) whose smallest eigenvector is their covariance
    /// plane's normal (eq. 2.10): `Σ (d − b)(d − b)ᵀ` about the barycentre `b`, summed in a
    /// frame scaled by a power of two (exact) so that no square under- or overflows, over the
    /// whole finite range of f64; the eigenvector comes from [`smallest_eigenvectors`], several
    /// neighbourhoods at a time. `None` for an empty neighbourhood.
    pub(crate) fn covariance(&mut self) -> Option<Covariance> {
        if self.is_empty() {
            return None;
        }
        let (sum, max_abs) = lanes::sum_and_max_abs(self);
        let f = unit_scale(std::iter::once(DVec3::splat(max_abs)));
        let b = sum / self.len as f64;
        // the padding at the barycentre: its offset is exactly 0 and adds nothing
        for (v, c) in [(&mut self.x, b.x), (&mut self.y, b.y), (&mut self.z, b.z)] {
            v[self.len..].fill(c);
        }
        let matrix = lanes::centred_outer(self, b, f);
        for v in [&mut self.x, &mut self.y, &mut self.z] {
            v[self.len..].fill(0.0);
        }
        Some(Covariance { matrix, sum })
    }

    /// Unit normal of the covariance of the points weighted by the biweight of their distance
    /// to the plane `⟨n, d⟩ = offset` with `width` (eq. 2.8–2.10 with a weight per point): the
    /// smallest eigenvector of `Σ w (d − c)(d − c)ᵀ` about the weighted barycentre `c`. `None`
    /// when no point has weight. The orientation is the eigen-solver's.
    pub(crate) fn weighted_normal(&mut self, n: DVec3, offset: f64, width: f64) -> Option<DVec3> {
        self.weighted_sums(n, offset, width).normal()
    }

    /// The sums behind [`Neighborhood::weighted_normal`]; their weight `Σ w` is the plane's
    /// support, the robust count of the points it explains.
    pub(crate) fn weighted_sums(&mut self, n: DVec3, offset: f64, width: f64) -> WeightedSums {
        let mut w = std::mem::take(&mut self.w);
        // every element is written below: no clearing pass
        w.truncate(self.x.len());
        w.resize(self.x.len(), 0.0);
        lanes::plane_weights(self, n, offset, width, &mut w);
        w[self.len..].fill(0.0);
        let (weight, sum, outer) = lanes::weighted_sums(self, &w);
        self.w = w;
        WeightedSums { weight, sum, outer }
    }
}

/// `Σ w`, `Σ w d` and `Σ w d dᵀ` of a neighbourhood with a weight per point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WeightedSums {
    pub(crate) weight: f64,
    sum: DVec3,
    outer: DMat3,
}

impl WeightedSums {
    /// The smallest eigenvector of `Σ w (d − c)(d − c)ᵀ` about the weighted barycentre `c`;
    /// `None` when no point has weight.
    pub(crate) fn normal(&self) -> Option<DVec3> {
        let normal = smallest_eigenvector(self.centred()?);
        normal.is_finite().then_some(normal)
    }

    /// `Σ w (d − c)(d − c)ᵀ` about the weighted barycentre `c`, the matrix of
    /// [`WeightedSums::normal`] (for [`smallest_eigenvectors`]); `None` when no point has
    /// weight.
    pub(crate) fn centred(&self) -> Option<DMat3> {
        let ws = self.weight;
        if !(ws > 0.0 && ws.is_finite()) {
            return None;
        }
        // Σ w (d − c)(d − c)ᵀ = Σ w d dᵀ − ws c cᵀ with c = sum/ws
        let c = self.sum / ws;
        Some(self.outer - DMat3::from_cols(c * c.x, c * c.y, c * c.z) * ws)
    }
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric matrix: closed form, or the
/// Jacobi iteration where the two smallest eigenvalues are close.
fn smallest_eigenvector(m: DMat3) -> DVec3 {
    sym_eigen3_smallest(m).map_or_else(|| sym_eigen3_fast(m).1[0], |(_, n)| n)
}

/// [`smallest_eigenvector`] of `N` matrices at once, the same bits: the closed forms run in
/// lanes, whose Newton iterations overlap where one alone waits on its divisions
/// ([`sym_eigen3_smallest_lanes`]); the Jacobi iteration where a lane declines. A lane without
/// a matrix is best given the zero matrix: the closed form declines it at once, and the Jacobi
/// iteration has nothing to rotate.
pub(crate) fn smallest_eigenvectors<const N: usize>(m: &[DMat3; N]) -> [DVec3; N] {
    let closed = sym_eigen3_smallest_lanes(m);
    std::array::from_fn(|l| match closed[l] {
        Some((_, n)) => n,
        None => sym_eigen3_fast(m[l]).1[0],
    })
}

/// The lane loops. Each public function runs the AVX version of its loop where the processor
/// has AVX, else the portable one, which does the same operations on the same lanes in the same
/// order (no fused multiply-add): the same bits on every machine (tested below).
mod lanes {
    use super::{Neighborhood, LANES};
    use glam::{DMat3, DVec3};

    /// Whether the AVX loops can run (`crate::simd`: the processor has AVX, the portable
    /// forms are not forced).
    #[inline]
    fn has_avx() -> bool {
        crate::simd::avx()
    }

    /// The sum of the points and the largest absolute coordinate.
    pub(super) fn sum_and_max_abs(h: &Neighborhood) -> (DVec3, f64) {
        #[cfg(target_arch = "x86_64")]
        if has_avx() {
            // SAFETY: the processor supports AVX (checked just above).
            return unsafe { avx::sum_and_max_abs(h) };
        }
        portable::sum_and_max_abs(h)
    }

    /// `Σ (f(d − b))(f(d − b))ᵀ` over all lanes (the padding must make `d − b` zero).
    pub(super) fn centred_outer(h: &Neighborhood, b: DVec3, f: f64) -> DMat3 {
        #[cfg(target_arch = "x86_64")]
        if has_avx() {
            // SAFETY: the processor supports AVX (checked just above).
            return unsafe { avx::centred_outer(h, b, f) };
        }
        portable::centred_outer(h, b, f)
    }

    /// The biweight of every point's distance to the plane `⟨n, d⟩ = offset`, into `w` (as
    /// long as the coordinates).
    pub(super) fn plane_weights(
        h: &Neighborhood,
        n: DVec3,
        offset: f64,
        width: f64,
        w: &mut [f64],
    ) {
        assert_eq!(w.len(), h.x.len());
        #[cfg(target_arch = "x86_64")]
        if has_avx() {
            // SAFETY: the processor supports AVX (checked just above).
            return unsafe { avx::plane_weights(h, n, offset, width, w) };
        }
        portable::plane_weights(h, n, offset, width, w)
    }

    /// `Σ w`, `Σ w d` and `Σ w d dᵀ` over all lanes (`w` as long as the coordinates).
    pub(super) fn weighted_sums(h: &Neighborhood, w: &[f64]) -> (f64, DVec3, DMat3) {
        assert_eq!(w.len(), h.x.len());
        #[cfg(target_arch = "x86_64")]
        if has_avx() {
            // SAFETY: the processor supports AVX (checked just above).
            return unsafe { avx::weighted_sums(h, w) };
        }
        portable::weighted_sums(h, w)
    }

    /// The lanes added in a fixed order.
    #[inline(always)]
    fn total(a: &[f64; LANES]) -> f64 {
        a.iter().fold(0.0, |s, &v| s + v)
    }

    /// The larger of two values as the processor's `max` instruction picks it: `a` if `a > b`,
    /// else `b`.
    #[inline(always)]
    fn larger(a: f64, b: f64) -> f64 {
        if a > b {
            a
        } else {
            b
        }
    }

    /// The symmetric matrix of an upper triangle `xx, xy, xz, yy, yz, zz`.
    #[inline(always)]
    fn symmetric(u: [f64; 6]) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(u[0], u[1], u[2]),
            DVec3::new(u[1], u[3], u[4]),
            DVec3::new(u[2], u[4], u[5]),
        )
    }

    /// The loops lane by lane in plain Rust (indexed like the AVX loops: lane `l` of chunk `k`).
    #[allow(clippy::needless_range_loop)]
    pub(super) mod portable {
        use super::{larger, symmetric, total, Neighborhood, LANES};
        use glam::{DMat3, DVec3};

        pub(in super::super) fn sum_and_max_abs(h: &Neighborhood) -> (DVec3, f64) {
            let mut s = [[0.0; LANES]; 4];
            for k in (0..h.x.len()).step_by(LANES) {
                for l in 0..LANES {
                    let (x, y, z) = (h.x[k + l], h.y[k + l], h.z[k + l]);
                    s[0][l] += x;
                    s[1][l] += y;
                    s[2][l] += z;
                    s[3][l] = larger(larger(larger(x.abs(), y.abs()), z.abs()), s[3][l]);
                }
            }
            let max = s[3].iter().fold(0.0, |m, &v| larger(v, m));
            (DVec3::new(total(&s[0]), total(&s[1]), total(&s[2])), max)
        }

        pub(in super::super) fn centred_outer(h: &Neighborhood, b: DVec3, f: f64) -> DMat3 {
            let mut s = [[0.0; LANES]; 6];
            for k in (0..h.x.len()).step_by(LANES) {
                for l in 0..LANES {
                    let dx = (h.x[k + l] - b.x) * f;
                    let dy = (h.y[k + l] - b.y) * f;
                    let dz = (h.z[k + l] - b.z) * f;
                    s[0][l] += dx * dx;
                    s[1][l] += dx * dy;
                    s[2][l] += dx * dz;
                    s[3][l] += dy * dy;
                    s[4][l] += dy * dz;
                    s[5][l] += dz * dz;
                }
            }
            symmetric(s.map(|a| total(&a)))
        }

        pub(in super::super) fn plane_weights(
            h: &Neighborhood,
            n: DVec3,
            offset: f64,
            width: f64,
            w: &mut [f64],
        ) {
            for k in 0..h.x.len() {
                // super::super::biweight, written out as the AVX loop computes it
                let d = n.x * h.x[k] + n.y * h.y[k] + n.z * h.z[k];
                let u = (d - offset) / width;
                let v = 1.0 - u * u;
                w[k] = if v > 0.0 { v * v } else { 0.0 };
            }
        }

        pub(in super::super) fn weighted_sums(h: &Neighborhood, w: &[f64]) -> (f64, DVec3, DMat3) {
            let mut s = [[0.0; LANES]; 10];
            for k in (0..h.x.len()).step_by(LANES) {
                for l in 0..LANES {
                    let (x, y, z, w) = (h.x[k + l], h.y[k + l], h.z[k + l], w[k + l]);
                    let (ax, ay, az) = (w * x, w * y, w * z);
                    s[0][l] += w;
                    s[1][l] += ax;
                    s[2][l] += ay;
                    s[3][l] += az;
                    s[4][l] += ax * x;
                    s[5][l] += ax * y;
                    s[6][l] += ax * z;
                    s[7][l] += ay * y;
                    s[8][l] += ay * z;
                    s[9][l] += az * z;
                }
            }
            let t = s.map(|a| total(&a));
            let outer = symmetric([t[4], t[5], t[6], t[7], t[8], t[9]]);
            (t[0], DVec3::new(t[1], t[2], t[3]), outer)
        }
    }

    /// The same loops, one AVX instruction per lane step (four `f64` lanes).
    #[cfg(target_arch = "x86_64")]
    mod avx {
        use super::{larger, symmetric, total, Neighborhood, LANES};
        use glam::{DMat3, DVec3};
        use std::arch::x86_64::*;

        const _: () = assert!(LANES == 4, "one AVX register holds the four lanes");

        /// The four lanes of a register.
        #[inline(always)]
        unsafe fn lanes(v: __m256d) -> [f64; LANES] {
            let mut a = [0.0; LANES];
            // SAFETY: `a` holds four f64 (unaligned store).
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), v) };
            a
        }

        /// Four consecutive values from `k` (the caller keeps `k + 4 ≤ v.len()`).
        #[inline(always)]
        unsafe fn load(v: &[f64], k: usize) -> __m256d {
            debug_assert!(k + LANES <= v.len());
            // SAFETY: the caller keeps k + 4 within the slice (lengths are multiples of 4).
            unsafe { _mm256_loadu_pd(v.as_ptr().add(k)) }
        }

        #[target_feature(enable = "avx")]
        pub(super) unsafe fn sum_and_max_abs(h: &Neighborhood) -> (DVec3, f64) {
            let sign = _mm256_set1_pd(-0.0);
            let (mut sx, mut sy, mut sz) = (
                _mm256_setzero_pd(),
                _mm256_setzero_pd(),
                _mm256_setzero_pd(),
            );
            let mut m = _mm256_setzero_pd();
            for k in (0..h.x.len()).step_by(LANES) {
                // SAFETY: k + 4 ≤ len, the coordinates are padded to whole lanes.
                let (x, y, z) = unsafe { (load(&h.x, k), load(&h.y, k), load(&h.z, k)) };
                sx = _mm256_add_pd(sx, x);
                sy = _mm256_add_pd(sy, y);
                sz = _mm256_add_pd(sz, z);
                let (ax, ay, az) = (
                    _mm256_andnot_pd(sign, x),
                    _mm256_andnot_pd(sign, y),
                    _mm256_andnot_pd(sign, z),
                );
                // max(a, b) is `a > b ? a : b`, as `larger`
                m = _mm256_max_pd(_mm256_max_pd(_mm256_max_pd(ax, ay), az), m);
            }
            // SAFETY: plain register stores.
            let (sx, sy, sz, m) = unsafe { (lanes(sx), lanes(sy), lanes(sz), lanes(m)) };
            let max = m.iter().fold(0.0, |a, &v| larger(v, a));
            (DVec3::new(total(&sx), total(&sy), total(&sz)), max)
        }

        #[target_feature(enable = "avx")]
        pub(super) unsafe fn centred_outer(h: &Neighborhood, b: DVec3, f: f64) -> DMat3 {
            let (bx, by, bz, f) = (
                _mm256_set1_pd(b.x),
                _mm256_set1_pd(b.y),
                _mm256_set1_pd(b.z),
                _mm256_set1_pd(f),
            );
            let mut s = [_mm256_setzero_pd(); 6];
            for k in (0..h.x.len()).step_by(LANES) {
                // SAFETY: k + 4 ≤ len, the coordinates are padded to whole lanes.
                let (x, y, z) = unsafe { (load(&h.x, k), load(&h.y, k), load(&h.z, k)) };
                let dx = _mm256_mul_pd(_mm256_sub_pd(x, bx), f);
                let dy = _mm256_mul_pd(_mm256_sub_pd(y, by), f);
                let dz = _mm256_mul_pd(_mm256_sub_pd(z, bz), f);
                s[0] = _mm256_add_pd(s[0], _mm256_mul_pd(dx, dx));
                s[1] = _mm256_add_pd(s[1], _mm256_mul_pd(dx, dy));
                s[2] = _mm256_add_pd(s[2], _mm256_mul_pd(dx, dz));
                s[3] = _mm256_add_pd(s[3], _mm256_mul_pd(dy, dy));
                s[4] = _mm256_add_pd(s[4], _mm256_mul_pd(dy, dz));
                s[5] = _mm256_add_pd(s[5], _mm256_mul_pd(dz, dz));
            }
            // SAFETY: plain register stores.
            symmetric(s.map(|v| total(&unsafe { lanes(v) })))
        }

        #[target_feature(enable = "avx")]
        pub(super) unsafe fn plane_weights(
            h: &Neighborhood,
            n: DVec3,
            offset: f64,
            width: f64,
            w: &mut [f64],
        ) {
            let (nx, ny, nz) = (
                _mm256_set1_pd(n.x),
                _mm256_set1_pd(n.y),
                _mm256_set1_pd(n.z),
            );
            let (offset, width) = (_mm256_set1_pd(offset), _mm256_set1_pd(width));
            let (one, zero) = (_mm256_set1_pd(1.0), _mm256_setzero_pd());
            for k in (0..h.x.len()).step_by(LANES) {
                // SAFETY: k + 4 ≤ len, the coordinates are padded to whole lanes.
                let (x, y, z) = unsafe { (load(&h.x, k), load(&h.y, k), load(&h.z, k)) };
                let d = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(nx, x), _mm256_mul_pd(ny, y)),
                    _mm256_mul_pd(nz, z),
                );
                let u = _mm256_div_pd(_mm256_sub_pd(d, offset), width);
                let v = _mm256_sub_pd(one, _mm256_mul_pd(u, u));
                // v > 0 (false for NaN) keeps v², else 0
                let keep = _mm256_cmp_pd::<_CMP_GT_OQ>(v, zero);
                let r = _mm256_and_pd(keep, _mm256_mul_pd(v, v));
                // SAFETY: `w` is as long as the coordinates (asserted by the caller).
                unsafe { _mm256_storeu_pd(w.as_mut_ptr().add(k), r) };
            }
        }

        #[target_feature(enable = "avx")]
        pub(super) unsafe fn weighted_sums(h: &Neighborhood, w: &[f64]) -> (f64, DVec3, DMat3) {
            let mut s = [_mm256_setzero_pd(); 10];
            for k in (0..h.x.len()).step_by(LANES) {
                // SAFETY: k + 4 ≤ len for the coordinates and `w` (asserted by the caller).
                let (x, y, z, w) =
                    unsafe { (load(&h.x, k), load(&h.y, k), load(&h.z, k), load(w, k)) };
                let (ax, ay, az) = (
                    _mm256_mul_pd(w, x),
                    _mm256_mul_pd(w, y),
                    _mm256_mul_pd(w, z),
                );
                s[0] = _mm256_add_pd(s[0], w);
                s[1] = _mm256_add_pd(s[1], ax);
                s[2] = _mm256_add_pd(s[2], ay);
                s[3] = _mm256_add_pd(s[3], az);
                s[4] = _mm256_add_pd(s[4], _mm256_mul_pd(ax, x));
                s[5] = _mm256_add_pd(s[5], _mm256_mul_pd(ax, y));
                s[6] = _mm256_add_pd(s[6], _mm256_mul_pd(ax, z));
                s[7] = _mm256_add_pd(s[7], _mm256_mul_pd(ay, y));
                s[8] = _mm256_add_pd(s[8], _mm256_mul_pd(ay, z));
                s[9] = _mm256_add_pd(s[9], _mm256_mul_pd(az, z));
            }
            // SAFETY: plain register stores.
            let t = s.map(|v| total(&unsafe { lanes(v) }));
            let outer = symmetric([t[4], t[5], t[6], t[7], t[8], t[9]]);
            (t[0], DVec3::new(t[1], t[2], t[3]), outer)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn neighborhood(points: &[DVec3]) -> Neighborhood {
        let padded = points.len().div_ceil(LANES) * LANES;
        let coordinate = |c: fn(&DVec3) -> f64| {
            let mut v: Vec<f64> = points.iter().map(c).collect();
            v.resize(padded, 0.0);
            v
        };
        Neighborhood {
            x: coordinate(|p| p.x),
            y: coordinate(|p| p.y),
            z: coordinate(|p| p.z),
            len: points.len(),
            w: Vec::new(),
        }
    }

    /// The fill's values are the exact differences `points[j] − points[s]` (the AVX blocks and
    /// the portable rest alike), the point itself first at the origin, zeros as padding, also
    /// after a longer neighbourhood held more; a row of any length around the blocks of four.
    #[test]
    fn fill_holds_the_exact_differences_and_zero_padding() {
        let pts: Vec<DVec3> = (0..40)
            .map(|i| {
                let t = i as f64;
                DVec3::new((t * 0.37).sin() * 3.1, t * t * 0.013 - 1.0, 1e3 + t * 0.1)
            })
            .collect();
        let mut local = Neighborhood::default();
        for len in (0..14).chain([35, 2, 9, 0]) {
            let row: Vec<u32> = (0..len).map(|t| ((t * 7 + 3) % 40) as u32).collect();
            local.fill(&pts, 5, &row);
            assert_eq!(local.len(), len + 1);
            let padded = (len + 1).div_ceil(LANES) * LANES;
            for (c, v) in [&local.x, &local.y, &local.z].into_iter().enumerate() {
                assert_eq!(v.len(), padded);
                assert_eq!(v[0].to_bits(), 0);
                for (t, &j) in row.iter().enumerate() {
                    let d = (pts[j as usize] - pts[5]).to_array()[c];
                    assert_eq!(v[t + 1].to_bits(), d.to_bits(), "len {len} t {t} c {c}");
                }
                assert!(v[len + 1..].iter().all(|x| x.to_bits() == 0), "len {len}");
            }
        }
    }

    #[test]
    fn biweight_is_a_bounded_bump() {
        assert_eq!(biweight(0.0), 1.0);
        assert_eq!(biweight(0.5), 0.5625);
        assert_eq!(biweight(-1.0), 0.0);
        assert_eq!(biweight(3.0), 0.0);
        assert_eq!(biweight(f64::NAN), 0.0);
    }

    #[test]
    fn weights_pick_one_of_two_planes() {
        // an L: points on z = 0 (x < 0) and on x = 0 (z > 0)
        let mut pts = Vec::new();
        for i in 0..10 {
            for j in 0..20 {
                pts.push(DVec3::new(-(i as f64) * 0.1, j as f64 * 0.1, 0.0));
                pts.push(DVec3::new(0.0, j as f64 * 0.1, 0.1 + i as f64 * 0.1));
            }
        }
        let mut h = neighborhood(&pts);
        let floor = h.weighted_normal(DVec3::Z, 0.0, 0.05).unwrap();
        assert!((floor.z.abs() - 1.0).abs() < 1e-12);
        let wall = h.weighted_normal(DVec3::X, 0.0, 0.05).unwrap();
        assert!((wall.x.abs() - 1.0).abs() < 1e-12);
        // every point within the width: the plain covariance normal, a blend of both faces
        let blend = h.weighted_normal(DVec3::Z, 0.0, 100.0).unwrap();
        assert!(blend.x.abs() > 0.3 && blend.z.abs() > 0.3);
        assert_eq!(h.weighted_normal(DVec3::Z, 100.0, 0.5), None);
        assert_eq!(
            Neighborhood::default().weighted_normal(DVec3::Z, 0.0, 1.0),
            None
        );
    }

    #[test]
    fn lane_weights_are_the_biweight() {
        let pts: Vec<DVec3> = (0..13)
            .map(|i| DVec3::new(i as f64 * 0.3, (i * i) as f64 * 0.05, (i % 3) as f64 * 0.1))
            .collect();
        let h = neighborhood(&pts);
        assert_eq!(h.x.len(), 16);
        let n = DVec3::new(0.1, 0.2, 1.0).normalize();
        let mut w = vec![0.0; 16];
        lanes::plane_weights(&h, n, 0.05, 0.2, &mut w);
        for (k, &p) in pts.iter().enumerate() {
            assert_eq!(w[k], biweight((n.dot(p) - 0.05) / 0.2), "{k}");
        }
    }

    #[test]
    fn every_instruction_set_gives_the_same_bits() {
        let pts: Vec<DVec3> = (0..23)
            .map(|i| {
                let t = i as f64 * 0.7;
                DVec3::new(t.sin() * 3.1, (t * 1.3).cos() * -2.2, t * 0.01 - 0.5)
            })
            .collect();
        let h = neighborhood(&pts);
        let n = DVec3::new(0.3, -0.2, 0.9).normalize();
        let (mut w, mut wp) = (vec![0.0; h.x.len()], vec![0.0; h.x.len()]);
        lanes::plane_weights(&h, n, 0.1, 0.8, &mut w);
        lanes::portable::plane_weights(&h, n, 0.1, 0.8, &mut wp);
        assert!(w.iter().zip(&wp).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(w[..pts.len()].iter().filter(|&&v| v == 0.0).count() > 1); // some outliers
        assert!(w.iter().filter(|&&v| v > 0.0).count() > 3); // and inliers
        let b = DVec3::new(0.25, -0.125, 0.3);
        let bits = |m: DMat3| m.to_cols_array().map(f64::to_bits);
        assert_eq!(
            bits(lanes::centred_outer(&h, b, 0.5)),
            bits(lanes::portable::centred_outer(&h, b, 0.5))
        );
        let (ws, sum, outer) = lanes::weighted_sums(&h, &w);
        let (pws, psum, pouter) = lanes::portable::weighted_sums(&h, &w);
        assert_eq!((ws.to_bits(), bits(outer)), (pws.to_bits(), bits(pouter)));
        assert_eq!(
            sum.to_array().map(f64::to_bits),
            psum.to_array().map(f64::to_bits)
        );
        let (s1, m1) = lanes::sum_and_max_abs(&h);
        let (s2, m2) = lanes::portable::sum_and_max_abs(&h);
        assert_eq!(
            (s1.to_array().map(f64::to_bits), m1.to_bits()),
            (s2.to_array().map(f64::to_bits), m2.to_bits())
        );
        let expect = pts
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f64::max);
        assert_eq!(m1, expect);
    }

    #[test]
    fn covariance_plane_of_a_tilted_grid() {
        // a 5 × 7 grid on the plane z = 0.5 x − 0.25 y + 3, far from the origin and tiny
        for scale in [1.0, 1e-150, 1e150] {
            let pts: Vec<DVec3> = (0..35)
                .map(|i| {
                    let (u, v) = ((i % 5) as f64, (i / 5) as f64);
                    DVec3::new(u, v, 0.5 * u - 0.25 * v + 3.0) * scale
                })
                .collect();
            let mut h = neighborhood(&pts);
            let c = h.covariance().unwrap();
            let [normal] = smallest_eigenvectors(&[c.matrix]);
            let expect = DVec3::new(0.5, -0.25, -1.0).normalize();
            assert!((normal.dot(expect).abs() - 1.0).abs() < 1e-12, "{scale}");
            let sum: DVec3 = pts.iter().sum();
            assert!((c.sum - sum).length() <= 1e-12 * sum.length(), "{scale}");
            // the padding is zero again (the sums after it are unchanged)
            assert!(h.x[35..].iter().all(|&v| v == 0.0));
        }
        assert!(Neighborhood::default().covariance().is_none());
    }

    /// The solves in lanes against one at a time: the same bits, whether the closed form
    /// solves a lane or declines it (the Jacobi iteration's).
    #[test]
    fn lanes_give_the_bits_of_single_solves() {
        let mut rng = crate::shapes::Rng::new(4);
        let mut matrices = vec![DMat3::ZERO];
        for i in 0..40 {
            let mut pts: Vec<DVec3> = (0..13)
                .map(|_| DVec3::new(rng.gaussian(), rng.gaussian(), 0.1 * rng.gaussian()))
                .collect();
            if i % 4 == 0 {
                // a needle: its two smallest eigenvalues close, which the closed form declines
                let e = 1.0 + 1e-4 * rng.gaussian();
                pts = vec![DVec3::X * (0.1 * e), DVec3::Y * 0.1, DVec3::Z];
                pts.extend(pts.clone().iter().map(|&p| -p));
            }
            let mut h = neighborhood(&pts);
            let sums = h.weighted_sums(DVec3::Z, 0.0, 100.0);
            matrices.push(sums.centred().unwrap());
            matrices.push(h.covariance().unwrap().matrix);
        }
        let declined = |m: &&DMat3| sym_eigen3_smallest(**m).is_none();
        assert!(matrices.iter().filter(declined).count() > 10);
        let bits = |n: DVec3| n.to_array().map(f64::to_bits);
        for start in 0..matrices.len() {
            let lanes: [DMat3; 4] = std::array::from_fn(|l| matrices[(start + l) % matrices.len()]);
            let normals = smallest_eigenvectors(&lanes);
            for l in 0..4 {
                assert_eq!(bits(normals[l]), bits(smallest_eigenvector(lanes[l])));
            }
        }
    }
}
