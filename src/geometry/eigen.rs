//! Allocation-free eigen-solvers for symmetric 3 × 3 matrices, since the covariance of every
//! point (eq. 2.8) is decomposed in every smoothing step: a cyclic Jacobi with the same method
//! and ordering as `linalg::sym_eigen3` (the test reference) on fixed-size arrays, and a closed form for the
//! smallest eigenvector (the normal of eq. 2.10) that declines whenever it would be less exact.

use glam::{DMat3, DVec3};

/// Eigenvalues (ascending) and unit eigenvectors of the symmetric matrix `a` (its symmetric
/// part). Finite for finite input; repeated and zero eigenvalues give an orthonormal basis.
pub(crate) fn sym_eigen3_fast(a: DMat3) -> (DVec3, [DVec3; 3]) {
    let c = a.to_cols_array_2d();
    let mut m = [[0.0f64; 3]; 3];
    for (r, row) in m.iter_mut().enumerate() {
        for (col, v) in row.iter_mut().enumerate() {
            *v = 0.5 * (c[col][r] + c[r][col]);
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]; // v[r][i]: column i
    let total: f64 = m.iter().flatten().map(|x| x * x).sum();
    for _sweep in 0..64 {
        let off = 2.0 * (m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2]);
        if off <= 1e-30 * total || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = m[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (m[q][q] - m[p][p]) / (2.0 * apq);
            let t = if theta == 0.0 {
                1.0
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let cs = 1.0 / (t * t + 1.0).sqrt();
            let sn = t * cs;
            for row in m.iter_mut() {
                let (mrp, mrq) = (row[p], row[q]);
                row[p] = cs * mrp - sn * mrq;
                row[q] = sn * mrp + cs * mrq;
            }
            let (rp, rq) = (m[p], m[q]);
            m[p] = std::array::from_fn(|r| cs * rp[r] - sn * rq[r]);
            m[q] = std::array::from_fn(|r| sn * rp[r] + cs * rq[r]);
            for row in v.iter_mut() {
                let (vrp, vrq) = (row[p], row[q]);
                row[p] = cs * vrp - sn * vrq;
                row[q] = sn * vrp + cs * vrq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| m[i][i].total_cmp(&m[j][j]).then(i.cmp(&j)));
    let col = |i: usize| DVec3::new(v[0][i], v[1][i], v[2][i]);
    (
        DVec3::new(
            m[order[0]][order[0]],
            m[order[1]][order[1]],
            m[order[2]][order[2]],
        ),
        [col(order[0]), col(order[1]), col(order[2])],
    )
}

/// Relative eigenvalue gap below which [`sym_eigen3_smallest`] declines: the root of the cubic
/// loses accuracy near a double root, and the eigenvector's error grows like
/// (round-off of `λ0`)/(`λ1 − λ0`).
const CLOSED_FORM_MIN_GAP: f64 = 1e-2;

/// Upper bound on the Newton steps of [`sym_eigen3_smallest`] (about five are taken).
const NEWTON_STEPS: usize = 100;

/// Eigenvalues (ascending) and the unit eigenvector of the smallest one of the symmetric matrix
/// `a` (read from its upper triangle), in closed form: the smallest root of the characteristic
/// cubic of `a − (tr a/3) I` by a monotone Newton iteration, the two others from the deflated
/// quadratic, then the eigenvector as the longest cross product of two rows of `a − λ0 I`. `None` when the two smallest eigenvalues are closer than
/// `CLOSED_FORM_MIN_GAP` of the spread `λ2 − λ0`, or the input is not finite, or all
/// eigenvalues coincide; the caller then uses [`sym_eigen3_fast`]. About five times faster
/// than the Jacobi iteration; the normal agrees with it to round-off.
pub(crate) fn sym_eigen3_smallest(a: DMat3) -> Option<(DVec3, DVec3)> {
    let c = Cubic::of(a);
    if !c.solvable() {
        return None;
    }
    let mut m0 = c.start();
    for _ in 0..NEWTON_STEPS {
        let step = c.newton(m0);
        if !step.rises {
            break;
        }
        m0 = step.next;
        if step.converged {
            break;
        }
    }
    c.eigen(m0)
}

/// [`sym_eigen3_smallest`] of `N` matrices at once, each lane bit for bit the scalar result:
/// the same operations in the same order per lane (no fused multiply-add), a lane that has
/// stopped keeps its root while the others go on, until all have stopped. The Newton iteration
/// is a chain of dependent divisions: one solve alone waits on each division in turn, and where
/// the callers fill a neighbourhood between two solves, nothing overlaps the wait; `N`
/// independent chains interleaved (with AVX, four lanes' divisions in one instruction) hide it.
pub(crate) fn sym_eigen3_smallest_lanes<const N: usize>(
    a: &[DMat3; N],
) -> [Option<(DVec3, DVec3)>; N] {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx() {
        // SAFETY: the processor supports AVX (checked just above).
        return unsafe { lanes_avx(a) };
    }
    lanes(a)
}

/// [`sym_eigen3_smallest_lanes`] compiled for AVX: the same operations on the same lanes, so
/// the same bits (no FMA, which would round differently).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn lanes_avx<const N: usize>(a: &[DMat3; N]) -> [Option<(DVec3, DVec3)>; N] {
    lanes(a)
}

/// The loops of [`sym_eigen3_smallest_lanes`], inlined into each instruction set's version.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lane `l` of several arrays at once
fn lanes<const N: usize>(a: &[DMat3; N]) -> [Option<(DVec3, DVec3)>; N] {
    // plain loops over the lanes (`array::from_fn` and `map` are not always inlined, and would
    // leave their part outside this instruction set's version)
    let mut c = [Cubic::default(); N];
    let (mut solvable, mut m0) = ([false; N], [0.0; N]);
    for l in 0..N {
        c[l] = Cubic::of(a[l]);
        solvable[l] = c[l].solvable();
        m0[l] = c[l].start();
    }
    let mut active = solvable;
    for _ in 0..NEWTON_STEPS {
        if !active.contains(&true) {
            break;
        }
        for l in 0..N {
            let step = c[l].newton(m0[l]);
            // the scalar loop's two exits, as masks: no rise keeps the root, a converged
            // step keeps the new one
            let take = active[l] && step.rises;
            m0[l] = if take { step.next } else { m0[l] };
            active[l] = take && !step.converged;
        }
    }
    let mut solved = [None; N];
    for l in 0..N {
        if solvable[l] {
            solved[l] = c[l].eigen(m0[l]);
        }
    }
    solved
}

/// The characteristic cubic of a symmetric 3 × 3 matrix shifted by its mean eigenvalue: the
/// eigenvalues μ of `b = a − qI` (`q = tr a/3`) are the roots of `f(μ) = μ³ − 3p²μ − det b`,
/// all in `[−2p, 2p]`. One value per matrix, so that [`sym_eigen3_smallest`] and its lanes
/// share every operation.
#[derive(Clone, Copy, Default)]
struct Cubic {
    q: f64,
    b00: f64,
    b11: f64,
    b22: f64,
    a01: f64,
    a02: f64,
    a12: f64,
    p: f64,
    p2: f64,
    /// `3p²`.
    j2: f64,
    det: f64,
}

/// One Newton step of [`Cubic::newton`].
struct NewtonStep {
    next: f64,
    /// Whether the step rose (false for NaN): the iteration stops, keeping the root, when not.
    rises: bool,
    /// Whether the step was below `1e-9 p`: the iteration stops after taking it.
    converged: bool,
}

impl Cubic {
    /// The cubic of `a`, read from its upper triangle.
    #[inline(always)]
    fn of(a: DMat3) -> Self {
        let (a00, a01, a02) = (a.x_axis.x, a.y_axis.x, a.z_axis.x);
        let (a11, a12, a22) = (a.y_axis.y, a.z_axis.y, a.z_axis.z);
        let q = (a00 + a11 + a22) / 3.0;
        let (b00, b11, b22) = (a00 - q, a11 - q, a22 - q);
        let off = a01 * a01 + a02 * a02 + a12 * a12;
        let p2 = (b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0;
        let det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02)
            + a02 * (a01 * a12 - b11 * a02);
        Self {
            q,
            b00,
            b11,
            b22,
            a01,
            a02,
            a12,
            p: p2.sqrt(),
            p2,
            j2: 3.0 * p2,
            det,
        }
    }

    /// Whether the eigenvalues are finite and not all equal: `0 < p² < ∞` (false for NaN).
    #[inline(always)]
    fn solvable(&self) -> bool {
        self.p2 > 0.0 && self.p2 < f64::INFINITY
    }

    /// Where the Newton iteration starts: `−2p`. `f` is concave and `f(−2p) ≤ 0` left of 0, so
    /// Newton's method from there rises monotonically to the smallest root μ0 (no arc cosine,
    /// no cosine): it stops when it no longer rises, or after a step below 1e-9 p (the error
    /// left is about step²·3|μ0|/(gap·spread), below 3e-16 p for the gaps accepted here).
    #[inline(always)]
    fn start(&self) -> f64 {
        -2.0 * self.p
    }

    /// The Newton step from `m0`.
    #[inline(always)]
    fn newton(&self, m0: f64) -> NewtonStep {
        let j2 = self.j2;
        let f = (m0 * m0 - j2) * m0 - self.det;
        let next = m0 - f / (3.0 * m0 * m0 - j2);
        NewtonStep {
            next,
            rises: next > m0,
            converged: next - m0 <= 1e-9 * self.p,
        }
    }

    /// The eigenvalues and the smallest eigenvector from the smallest root `m0`, or `None`
    /// where [`sym_eigen3_smallest`] declines.
    #[inline(always)]
    fn eigen(&self, m0: f64) -> Option<(DVec3, DVec3)> {
        let (q, b00, b11, b22) = (self.q, self.b00, self.b11, self.b22);
        let (a01, a02, a12) = (self.a01, self.a02, self.a12);
        // the other two roots: f(μ) = (μ − μ0)(μ² + μ0 μ + μ0² − 3p²)
        let root = (4.0 * self.j2 - 3.0 * m0 * m0).max(0.0).sqrt();
        let (m1, m2) = (0.5 * (-m0 - root), 0.5 * (root - m0));
        let separated = m1 - m0 >= CLOSED_FORM_MIN_GAP * (m2 - m0); // false for NaN
        if !separated {
            return None;
        }
        let r0 = DVec3::new(b00 - m0, a01, a02);
        let r1 = DVec3::new(a01, b11 - m0, a12);
        let r2 = DVec3::new(a02, a12, b22 - m0);
        let (c01, c02, c12) = (r0.cross(r1), r0.cross(r2), r1.cross(r2));
        let (l01, l02, l12) = (
            c01.length_squared(),
            c02.length_squared(),
            c12.length_squared(),
        );
        let (v, l) = if l01 >= l02 && l01 >= l12 {
            (c01, l01)
        } else if l02 >= l12 {
            (c02, l02)
        } else {
            (c12, l12)
        };
        // the longest cross product is at least (λ1 − λ0)(λ2 − λ0)/√3 in exact arithmetic
        let spread = m2 - m0;
        let floor =
            1e-6 * spread * spread * spread * spread * CLOSED_FORM_MIN_GAP * CLOSED_FORM_MIN_GAP;
        let long = l > floor;
        if !long {
            return None;
        }
        Some((DVec3::new(q + m0, q + m1, q + m2), v / l.sqrt()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Rng;

    #[test]
    fn agrees_with_the_general_solver() {
        let mut rng = Rng::new(1);
        let mut mats = vec![
            DMat3::ZERO,
            DMat3::IDENTITY,
            DMat3::from_cols_array(&[1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
        ];
        for _ in 0..200 {
            let b = DMat3::from_cols_array(&std::array::from_fn(|_| rng.gaussian()));
            mats.push(b * b.transpose());
        }
        for a in mats {
            let (vals, vecs) = sym_eigen3_fast(a);
            let (ref_vals, _) = crate::linalg::sym_eigen3(a);
            let scale = 1.0 + ref_vals.abs().max_element();
            assert!((vals - ref_vals).abs().max_element() < 1e-12 * scale);
            assert!(vals.x <= vals.y && vals.y <= vals.z);
            for i in 0..3 {
                assert!((a * vecs[i] - vals[i] * vecs[i]).length() < 1e-10 * scale);
                for j in 0..3 {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((vecs[i].dot(vecs[j]) - want).abs() < 1e-12);
                }
            }
        }
    }
    #[test]
    fn closed_form_agrees_with_jacobi_or_declines() {
        let mut rng = Rng::new(2);
        let mut mats = vec![
            DMat3::ZERO,
            DMat3::IDENTITY,
            DMat3::from_diagonal(DVec3::new(1.0, 1.0, 2.0)),
            DMat3::from_diagonal(DVec3::new(1.0, 2.0, 2.0)),
            DMat3::from_diagonal(DVec3::new(0.0, 1.0, 5.0)),
            DMat3::from_cols_array(&[1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
        ];
        for _ in 0..2000 {
            let b = DMat3::from_cols_array(&std::array::from_fn(|_| rng.gaussian()));
            // flattened like a covariance of surface points: small third axis
            let s = DMat3::from_diagonal(DVec3::new(1.0, 0.5, 1e-3 * rng.gaussian().abs()));
            mats.push(b * b.transpose());
            mats.push(b * s * s * b.transpose());
        }
        let mut accepted = 0;
        for a in mats {
            let (ref_vals, ref_vecs) = sym_eigen3_fast(a);
            let scale = 1.0 + ref_vals.abs().max_element();
            match sym_eigen3_smallest(a) {
                None => assert!(
                    ref_vals.y - ref_vals.x <= 0.02 * (ref_vals.z - ref_vals.x),
                    "{a:?}"
                ),
                Some((vals, n)) => {
                    accepted += 1;
                    assert!((vals - ref_vals).abs().max_element() < 1e-12 * scale);
                    assert!((n.length() - 1.0).abs() < 1e-14);
                    assert!(n.dot(ref_vecs[0]).abs() > 1.0 - 1e-14, "{a:?}");
                    assert!((a * n - vals.x * n).length() < 1e-10 * scale);
                }
            }
        }
        // random matrices have close eigenvalues now and then (3,859 of 4,006 accepted)
        assert!(accepted > 3700, "{accepted}");
    }

    /// The bits of an answer of the closed form.
    fn bits(r: Option<(DVec3, DVec3)>) -> Option<[u64; 6]> {
        r.map(|(vals, n)| {
            let [a, b, c] = vals.to_array();
            let [x, y, z] = n.to_array();
            [a, b, c, x, y, z].map(f64::to_bits)
        })
    }

    /// Every `N` consecutive matrices of `mats` (cycled) as lanes, against the scalar solver:
    /// the instruction set's version (AVX where the processor has it) and the portable one.
    fn check_lanes<const N: usize>(mats: &[DMat3]) -> (usize, usize) {
        let (mut mixed, mut declined) = (0, 0);
        for start in 0..mats.len() {
            let a: [DMat3; N] = std::array::from_fn(|l| mats[(start + l) % mats.len()]);
            let (lanes, portable) = (sym_eigen3_smallest_lanes(&a), super::lanes(&a));
            for l in 0..N {
                let scalar = bits(sym_eigen3_smallest(a[l]));
                assert_eq!(bits(lanes[l]), scalar, "{:?}", a[l]);
                assert_eq!(bits(portable[l]), scalar, "{:?}", a[l]);
            }
            let n = lanes.iter().filter(|r| r.is_none()).count();
            declined += n;
            mixed += usize::from(n > 0 && n < N);
        }
        (mixed, declined)
    }

    #[test]
    fn lanes_give_the_scalar_bits() {
        let mut rng = Rng::new(3);
        let diagonal = |x, y, z| DMat3::from_diagonal(DVec3::new(x, y, z));
        let mut mats = vec![
            DMat3::ZERO,
            DMat3::IDENTITY,
            diagonal(1.0, 1.0, 2.0),
            diagonal(1.0, 2.0, 2.0),
            diagonal(0.0, 1.0, 5.0),
            diagonal(1e300, 2e300, 3e300), // p² overflows
            diagonal(1e-300, 2e-300, 0.0), // p² underflows
            DMat3::from_cols_array(&[1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
        ];
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for i in [0, 3, 4, 8] {
                let mut c = diagonal(0.1, 1.0, 2.0).to_cols_array();
                c[i] = bad;
                mats.push(DMat3::from_cols_array(&c));
            }
        }
        for _ in 0..500 {
            let b = DMat3::from_cols_array(&std::array::from_fn(|_| rng.gaussian()));
            // flattened like a covariance of surface points: small third axis
            let s = DMat3::from_diagonal(DVec3::new(1.0, 0.5, 1e-3 * rng.gaussian().abs()));
            // close smallest eigenvalues: declined, or many Newton steps
            let t = DMat3::from_diagonal(DVec3::new(1.0, 1e-2 * rng.unit(), 1e-2 * rng.unit()));
            mats.extend([
                b * b.transpose(),
                b * s * s * b.transpose(),
                b * t * b.transpose(),
            ]);
            // not symmetric, not positive: only the upper triangle is read
            mats.push(b * 1e3);
        }
        let (mixed, declined) = check_lanes::<4>(&mats);
        assert!(mixed > 100 && declined > 100, "{mixed} {declined}");
        check_lanes::<1>(&mats);
        check_lanes::<3>(&mats);
        check_lanes::<8>(&mats);
    }
}
