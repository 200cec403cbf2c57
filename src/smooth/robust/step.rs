//! Step 4 of the robust smoothing (see the parent module): one normal-projected anisotropic
//! umbrella step (eq. 2.18 and 2.30 with normal-based weights).

use super::rows::Rows;
use super::RobustOptions;
use crate::geometry::robust_plane::biweight;
use glam::DVec3;
use rayon::prelude::*;

/// Fraction of the inlier width within which a chord counts as perpendicular to the mean normal
/// of its end points.
const CHORD_WIDTH: f64 = 0.25;

/// The points after one step `p_i + τ Σ_j g_ij m_ij m_ijᵀ (x_j − p_i) / Σ_j g_ij` over the
/// umbrella neighbourhoods (the first `k` of each row). Every point reads `points` only and sums
/// its neighbours in a fixed order (see [`Sums`]): the result does not depend on the number of
/// threads.
pub(super) fn step(
    points: &[DVec3],
    rows: &Rows,
    normals: &[DVec3],
    width: f64,
    o: &RobustOptions,
) -> Vec<DVec3> {
    let kernel = Kernel::new(width, o);
    (0..points.len())
        .into_par_iter()
        .map(|s| kernel.moved(points, normals, s, rows.narrow(s, o.k)))
        .collect()
}

/// Neighbours evaluated together: four `f64` lanes, one AVX register.
const LANES: usize = 4;

/// The constants of one step.
struct Kernel {
    /// `1 / width` for the biweight of a neighbour's tangent-plane distance (a product per
    /// neighbour instead of a quotient).
    inv_width: f64,
    /// `1 / w²` for the width `w` within which a chord counts as perpendicular to the mean
    /// normal.
    inv_chord_width_sq: f64,
    /// The weight of "one smooth patch" between two normals.
    patch: PatchWeight,
    tau: f64,
}

/// [`LANES`] neighbours of `p_i`, coordinate by coordinate: the offsets `e = x_j − p_i` and the
/// normals `n_j`.
struct Block {
    e: [[f64; LANES]; 3],
    n: [[f64; LANES]; 3],
}

/// The sums of a row's step, lane by lane: lane `l` adds the neighbours `l`, `l + 4`, `l + 8`,
/// ... of the row in that order, and [`Sums::total`] adds the lanes in one fixed order. Four
/// independent chains of additions instead of one, and the same order on every machine.
///
/// The step term is kept as `v ⟨v, e⟩ / ‖v‖²` with `v = a n_i + b n_j` (see
/// [`Kernel::add_terms`]): its part along `n_i` is a multiple of the point's own normal, so only
/// the multiple is summed.
#[derive(Default)]
struct Sums {
    /// `Σ g f a`, the step's part along `n_i` in units of `n_i`.
    along_ni: [f64; LANES],
    /// `Σ g f b n_j`, coordinate by coordinate.
    along_nj: [[f64; LANES]; 3],
    /// `Σ g_ij`.
    weight: [f64; LANES],
}

impl Kernel {
    fn new(width: f64, o: &RobustOptions) -> Self {
        Self {
            inv_width: 1.0 / width,
            inv_chord_width_sq: 1.0 / (CHORD_WIDTH * width).powi(2),
            patch: PatchWeight::new(o.feature_angle),
            tau: o.tau,
        }
    }

    /// Stored point `s` after the step over its umbrella `row`.
    fn moved(&self, points: &[DVec3], normals: &[DVec3], s: usize, row: &[u32]) -> DVec3 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx() {
            // SAFETY: the processor supports AVX (checked just above).
            return unsafe { self.moved_avx(points, normals, s, row) };
        }
        self.moved_with(points, normals, s, row, Block::gather)
    }

    /// [`Kernel::moved`] compiled for AVX, with the neighbours gathered in AVX registers: the
    /// same operations on the same lanes, so the same bits (no FMA, which would round
    /// differently).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn moved_avx(&self, points: &[DVec3], normals: &[DVec3], s: usize, row: &[u32]) -> DVec3 {
        self.moved_with(points, normals, s, row, |points, normals, p, ids| {
            // SAFETY: the processor supports AVX (this function is compiled for it and called
            // only where it runs).
            unsafe { Block::gather_avx(points, normals, p, ids) }
        })
    }

    /// The neighbours' terms in full blocks of [`LANES`] gathered by `gather`, the last block
    /// padded with `s` itself and its padding weighted 0, summed lane by lane.
    #[inline(always)]
    fn moved_with(
        &self,
        points: &[DVec3],
        normals: &[DVec3],
        s: usize,
        row: &[u32],
        gather: impl Fn(&[DVec3], &[DVec3], DVec3, &[u32; LANES]) -> Block,
    ) -> DVec3 {
        // as long as `points`: one bounds check per neighbour covers both
        let normals = &normals[..points.len()];
        let (p, ni) = (points[s], normals[s]);
        let mut sums = Sums::default();
        let blocks = row.chunks_exact(LANES);
        let rest = blocks.remainder();
        for block in blocks {
            let ids = block.try_into().expect("a full block");
            self.add_terms(&mut sums, ni, &gather(points, normals, p, ids), LANES);
        }
        if !rest.is_empty() {
            let mut ids = [s as u32; LANES];
            ids[..rest.len()].copy_from_slice(rest);
            self.add_terms(&mut sums, ni, &gather(points, normals, p, &ids), rest.len());
        }
        let (step, weight) = sums.total(ni);
        if weight > 0.0 {
            p + step * (self.tau / weight)
        } else {
            p
        }
    }

    /// Adds the terms of the first `live` lanes of `block` to `sums`: the weight `g_ij` and the
    /// step term `g_ij m_ij m_ijᵀ (x_j − p_i)` where the direction `m_ij` exists (`‖v‖ > 0`).
    /// Each lane's arithmetic is the same scalar formula, so the lanes vectorise and every
    /// instruction set gives the same bits.
    ///
    /// With `c = ⟨n_i, n_j⟩`, `n'_j = ±n_j` turned so that `⟨n_i, n'_j⟩ = |c|`, and the patch
    /// weight `a_ij` (the parent module, item 4): `m_ij ∝ a_ij n_i + n'_j`. Scaled by
    /// `‖n_i + n'_j‖⁴` and by the sign of `c`, `v = a n_i + b n_j` with `a = ±‖n_i + n'_j‖⁴ a_ij`
    /// and `b = ‖n_i + n'_j‖⁴` points along `±m_ij`, and `m_ij m_ijᵀ e = v ⟨v, e⟩ / ‖v‖²` for any
    /// such `v`. The scaling takes the quotient out of the chord's biweight; for unit normals
    /// `‖n_i + n'_j‖² = 2 (1 + |c|)` and `‖v‖² = a (a + 2bc) + b²`, and `⟨v, e⟩ = a ⟨n_i, e⟩ +
    /// b ⟨n_j, e⟩` reuses the tangent-plane distance: one division per neighbour.
    #[inline(always)]
    fn add_terms(&self, sums: &mut Sums, ni: DVec3, block: &Block, live: usize) {
        for l in 0..LANES {
            let (ex, ey, ez) = (block.e[0][l], block.e[1][l], block.e[2][l]);
            let (nx, ny, nz) = (block.n[0][l], block.n[1][l], block.n[2][l]);
            // the biweight of the distance to the neighbour's tangent plane (far from p:
            // another face, weight 0); the padding weighs 0
            let d = nx * ex + ny * ey + nz * ez;
            let g = if l < live {
                biweight(d * self.inv_width)
            } else {
                0.0
            };
            let c = ni.x * nx + ni.y * ny + ni.z * nz;
            let flip = c < 0.0;
            let ne = ni.x * ex + ni.y * ey + ni.z * ez;
            // one smooth patch: normals close, or the chord perpendicular to their mean
            // s = n_i + n'_j (the biweight of ⟨s, e⟩ / (w ‖s‖), w the chord width): b a_ij is
            // the larger of b times the patch weight and (‖s‖² − ⟨s, e⟩² / w²)², b = ‖s‖⁴
            let chord = ne + if flip { -d } else { d };
            let ss = 2.0 * (1.0 + c.abs());
            let off_chord = (ss - chord * chord * self.inv_chord_width_sq).max(0.0);
            let b = ss * ss;
            let (patch, chord_weight) = (self.patch.weight(c.abs()) * b, off_chord * off_chord);
            let a = if patch > chord_weight {
                patch
            } else {
                chord_weight
            };
            let a = if flip { -a } else { a };
            let vv = a * (a + 2.0 * b * c) + b * b;
            let ve = a * ne + b * d;
            let gf = if vv > 0.0 { g * (ve / vv) } else { 0.0 };
            let gfb = gf * b;
            sums.along_ni[l] += gf * a;
            sums.along_nj[0][l] += gfb * nx;
            sums.along_nj[1][l] += gfb * ny;
            sums.along_nj[2][l] += gfb * nz;
            sums.weight[l] += g;
        }
    }
}

impl Block {
    /// The neighbours `ids` of `p` with their normals, lane by lane.
    #[inline(always)]
    fn gather(points: &[DVec3], normals: &[DVec3], p: DVec3, ids: &[u32; LANES]) -> Self {
        let mut b = Self {
            e: [[0.0; LANES]; 3],
            n: [[0.0; LANES]; 3],
        };
        for (l, &j) in ids.iter().enumerate() {
            let (x, n) = (points[j as usize], normals[j as usize]);
            (b.e[0][l], b.e[1][l], b.e[2][l]) = (x.x, x.y, x.z);
            (b.n[0][l], b.n[1][l], b.n[2][l]) = (n.x, n.y, n.z);
        }
        for (e, p) in b.e.iter_mut().zip(p.to_array()) {
            for x in e {
                *x -= p;
            }
        }
        b
    }

    /// [`Block::gather`] in AVX registers (`crate::simd::transpose4_avx`).
    ///
    /// # Safety
    /// The processor supports AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    unsafe fn gather_avx(
        points: &[DVec3],
        normals: &[DVec3],
        p: DVec3,
        ids: &[u32; LANES],
    ) -> Self {
        use std::arch::x86_64::*;
        // SAFETY: AVX as the caller guarantees
        let x = unsafe { crate::simd::transpose4_avx(ids.map(|j| &points[j as usize])) };
        // SAFETY: as above
        let n = unsafe { crate::simd::transpose4_avx(ids.map(|j| &normals[j as usize])) };
        // SAFETY: `__m256d` and `[f64; 4]` are the same 32 bytes
        let array = |v: __m256d| unsafe { std::mem::transmute::<__m256d, [f64; LANES]>(v) };
        let p = p.to_array();
        Self {
            e: [0, 1, 2].map(|c| array(_mm256_sub_pd(x[c], _mm256_set1_pd(p[c])))),
            n: n.map(array),
        }
    }
}

impl Sums {
    /// The step term and the weight of the row: the lanes added in one fixed order, the part
    /// along `n_i` last.
    #[inline(always)]
    fn total(&self, ni: DVec3) -> (DVec3, f64) {
        let sum = |l: &[f64; LANES]| (l[0] + l[1]) + (l[2] + l[3]);
        let along_nj = DVec3::new(
            sum(&self.along_nj[0]),
            sum(&self.along_nj[1]),
            sum(&self.along_nj[2]),
        );
        (along_nj + sum(&self.along_ni) * ni, sum(&self.weight))
    }
}

/// The weight of "one smooth patch" between two unit normals: a Gaussian in the distance between
/// them, `exp(−‖n_i − n_j‖² / c²)` with `‖n_i − n_j‖² = 2(1 − |cos θ|)` (sign ignored) and
/// `c = 2 sin(feature_angle/2)` the distance of normals `feature_angle` apart: 1 for parallel
/// normals, `1/e` at the feature angle, like a Gaussian in the angle (`‖n_i − n_j‖ = 2 sin(θ/2)
/// ≈ θ`) without its arc cosine.
struct PatchWeight {
    /// `−2/c²` (the factor 2 is exact: `(1 − |cos θ|)·(−2/c²)` rounds as `−2(1 − |cos θ|)/c²`).
    scale: f64,
}

impl PatchWeight {
    fn new(feature_angle_deg: f64) -> Self {
        let c = 2.0 * (feature_angle_deg.to_radians() / 2.0).sin();
        Self {
            scale: -2.0 / (c * c),
        }
    }

    #[inline(always)]
    fn weight(&self, abs_cos: f64) -> f64 {
        exp_non_positive((1.0 - abs_cos.min(1.0)) * self.scale)
    }
}

/// `eˣ` for finite `x ≤ 0`, to within 5e-11 relative (the patch weight needs nowhere near the
/// last bit: it blends two directions, and an error ε in it turns `m_ij` by about ε), in plain
/// arithmetic that vectorises and gives the same bits on every machine and instruction set (the
/// C library's `exp` may differ between versions). Cody–Waite reduction `x = k ln 2 + r`,
/// `|r| ≤ ln 2 / 2`, and a degree-7 polynomial of `eʳ` whose constant term is 1 (so `e⁰ = 1`
/// exactly) and whose other coefficients minimise the largest relative error on that interval
/// (4.7e-11; the Taylor polynomial of degree 7 is off by up to 5e-9), evaluated by Estrin's
/// scheme: a tree of depth three instead of a chain of seven multiply-adds. Below −700 it
/// returns e⁻⁷⁰⁰ ≈ 1e-304, which is 0 to every use here.
#[inline(always)]
fn exp_non_positive(x: f64) -> f64 {
    // 1.5·2⁵²: adding it rounds to an integer held in the low bits of the mantissa
    const ROUND: f64 = 6_755_399_441_055_744.0;
    // ln 2 split so that k·LN2_HI is exact for |k| < 2¹¹
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // the coefficients of r⁰ … r⁷, fitted on |r| ≤ 1.0005 ln 2 / 2 (a margin for the rounding
    // of the reduction)
    const C: [f64; 8] = [
        1.0,
        1.000_000_000_209_429,
        0.500_000_007_737_619_7,
        0.166_666_651_593_024_96,
        0.041_666_271_767_110_16,
        0.008_333_569_367_158_92,
        0.001_394_595_457_032_406_5,
        0.000_197_675_994_298_660_92,
    ];
    let x = x.max(-700.0);
    let t = x * std::f64::consts::LOG2_E + ROUND;
    let k = t - ROUND;
    let ki = t.to_bits() as i64 - ROUND.to_bits() as i64;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let r2 = r * r;
    let pair = |i: usize| C[i] + C[i + 1] * r;
    let p = (pair(0) + pair(2) * r2) + (pair(4) + pair(6) * r2) * (r2 * r2);
    p * f64::from_bits(((ki + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_is_within_5e11_of_the_c_library() {
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            let x = -(i as f64) * 3.5e-3 - (i % 7) as f64 * 1e-9;
            let (ours, libm) = (exp_non_positive(x), x.exp());
            worst = worst.max(((ours - libm) / libm).abs());
        }
        assert!(worst < 5e-11, "{worst}");
        assert_eq!(exp_non_positive(0.0), 1.0);
        assert_eq!(exp_non_positive(-0.0), 1.0);
        assert!(exp_non_positive(f64::NEG_INFINITY) < 1e-300);
    }

    /// The step of one point as the formula reads, neighbour by neighbour in plain `DVec3`
    /// arithmetic (neighbour `t` of the row into lane `t mod 4`), against the lanes of the
    /// portable build and of the AVX build where it runs: the same bits.
    #[test]
    fn lanes_give_the_scalar_formula_bits() {
        let o = RobustOptions::default();
        let width = 0.3;
        let kernel = Kernel::new(width, &o);
        let points: Vec<DVec3> = (0..23)
            .map(|i| {
                let f = i as f64;
                DVec3::new((f * 0.37).sin(), (f * 0.61).cos(), 0.05 * (f * 1.3).sin())
            })
            .collect();
        let normals: Vec<DVec3> = (0..23)
            .map(|i| {
                let f = i as f64;
                let n = DVec3::new(0.2 * (f * 0.9).sin(), 0.3 * (f * 0.4).cos(), 1.0).normalize();
                if i % 5 == 0 {
                    -n
                } else {
                    n
                }
            })
            .collect();
        // 22 neighbours: five full blocks and a block of two
        let row: Vec<u32> = (1..23).collect();
        let (p, ni) = (points[0], normals[0]);
        let (mut along_ni, mut along_nj, mut weight) = ([0.0; 4], [DVec3::ZERO; 4], [0.0; 4]);
        let mut used = 0;
        for (t, &j) in row.iter().enumerate() {
            let (e, nj) = (points[j as usize] - p, normals[j as usize]);
            // the kernel's constants: 1/width and 1/(chord width)² rounded once
            let g = biweight(nj.dot(e) * (1.0 / width));
            used += usize::from(g > 0.0);
            let c = ni.dot(nj);
            let sign = if c < 0.0 { -1.0 } else { 1.0 };
            let chord = ni.dot(e) + sign * nj.dot(e);
            let ss = 2.0 * (1.0 + c.abs());
            let off_chord = (ss - chord * chord * (1.0 / (CHORD_WIDTH * width).powi(2))).max(0.0);
            let b = ss * ss;
            let a = sign * (kernel.patch.weight(c.abs()) * b).max(off_chord * off_chord);
            let f = (a * ni.dot(e) + b * nj.dot(e)) / (a * (a + 2.0 * b * c) + b * b);
            along_ni[t % 4] += g * f * a;
            along_nj[t % 4] += g * f * b * nj;
            weight[t % 4] += g;
        }
        assert!(used > 10, "{used} neighbours weighted");
        let weight = (weight[0] + weight[1]) + (weight[2] + weight[3]);
        let step = ((along_nj[0] + along_nj[1]) + (along_nj[2] + along_nj[3]))
            + ((along_ni[0] + along_ni[1]) + (along_ni[2] + along_ni[3])) * ni;
        let expect = p + step * (o.tau / weight);
        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
        let portable = kernel.moved_with(&points, &normals, 0, &row, Block::gather);
        assert_eq!(bits(portable), bits(expect));
        let dispatched = kernel.moved(&points, &normals, 0, &row);
        assert_eq!(bits(dispatched), bits(expect));
    }

    #[test]
    fn patch_weight_is_a_gaussian_in_the_normals_distance() {
        let w = PatchWeight::new(20.0);
        assert_eq!(w.weight(1.0), 1.0);
        assert!((w.weight(20f64.to_radians().cos()) - (-1f64).exp()).abs() < 2e-11);
        assert!(w.weight(0.0) < 1e-6); // perpendicular normals: e^(−16.6)
    }
}
