//! Allocation-free cyclic Jacobi for symmetric 3 × 3 matrices: the same method and ordering as
//! [`crate::linalg::sym_eigen3`] on fixed-size arrays, since the covariance of every point is
//! decomposed in every smoothing step.

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
}
