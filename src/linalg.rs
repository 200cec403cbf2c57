//! Symmetric eigen-decomposition by cyclic Jacobi rotations: robust for repeated eigenvalues
//! and rank-deficient matrices (collinear or coplanar neighbourhoods), which is what the
//! covariance matrices of eq. (2.8) and of the PCA sweep (Section 5.1) are.

#[cfg(test)]
use glam::{DMat3, DVec3};

/// Eigenvalues (ascending) and orthonormal eigenvectors of a symmetric `d × d` matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct SymEigen {
    /// Eigenvalues, ascending.
    pub values: Vec<f64>,
    /// Eigenvectors, `vectors[i * d..(i + 1) * d]` belongs to `values[i]`; unit length,
    /// mutually orthogonal.
    pub vectors: Vec<f64>,
}

/// Decomposes the symmetric matrix `a` (row-major, `d × d`; only its symmetric part is used).
///
/// Always returns finite results for finite input. Sweeps stop when the off-diagonal mass is
/// below `1e-30` of the total or after 64 sweeps.
pub fn sym_eigen(a: &[f64], d: usize) -> SymEigen {
    assert_eq!(a.len(), d * d, "matrix must be d × d");
    let mut m: Vec<f64> = (0..d * d)
        .map(|ij| 0.5 * (a[ij] + a[(ij % d) * d + ij / d]))
        .collect();
    // v holds eigenvectors as columns.
    let mut v = vec![0.0; d * d];
    for i in 0..d {
        v[i * d + i] = 1.0;
    }
    let total: f64 = m.iter().map(|x| x * x).sum();
    for _sweep in 0..64 {
        let off: f64 = (0..d)
            .flat_map(|p| (0..d).filter(move |&q| q != p).map(move |q| (p, q)))
            .map(|(p, q)| m[p * d + q] * m[p * d + q])
            .sum();
        if off <= 1e-30 * total || off == 0.0 {
            break;
        }
        for p in 0..d {
            for q in p + 1..d {
                let apq = m[p * d + q];
                if apq == 0.0 {
                    continue;
                }
                let (app, aqq) = (m[p * d + p], m[q * d + q]);
                let theta = (aqq - app) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for r in 0..d {
                    let (mrp, mrq) = (m[r * d + p], m[r * d + q]);
                    m[r * d + p] = c * mrp - s * mrq;
                    m[r * d + q] = s * mrp + c * mrq;
                }
                for r in 0..d {
                    let (mpr, mqr) = (m[p * d + r], m[q * d + r]);
                    m[p * d + r] = c * mpr - s * mqr;
                    m[q * d + r] = s * mpr + c * mqr;
                }
                for r in 0..d {
                    let (vrp, vrq) = (v[r * d + p], v[r * d + q]);
                    v[r * d + p] = c * vrp - s * vrq;
                    v[r * d + q] = s * vrp + c * vrq;
                }
            }
        }
    }
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|&i, &j| m[i * d + i].total_cmp(&m[j * d + j]).then(i.cmp(&j)));
    let values = order.iter().map(|&i| m[i * d + i]).collect();
    let mut vectors = Vec::with_capacity(d * d);
    for &i in &order {
        vectors.extend((0..d).map(|r| v[r * d + i]));
    }
    SymEigen { values, vectors }
}

/// [`sym_eigen`] for a 3 × 3 matrix: eigenvalues ascending and the matching unit eigenvectors;
/// the reference the 3 × 3 solvers of `geometry/eigen.rs` are tested against.
#[cfg(test)]
pub fn sym_eigen3(a: DMat3) -> (DVec3, [DVec3; 3]) {
    let rows = a.transpose().to_cols_array();
    let e = sym_eigen(&rows, 3);
    let vec = |i: usize| DVec3::from_slice(&e.vectors[i * 3..i * 3 + 3]);
    (DVec3::from_slice(&e.values), [vec(0), vec(1), vec(2)])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(a: &[f64], d: usize) {
        let e = sym_eigen(a, d);
        for i in 0..d {
            let v = &e.vectors[i * d..(i + 1) * d];
            // A v = λ v
            for r in 0..d {
                let av: f64 = (0..d).map(|c| a[r * d + c] * v[c]).sum();
                assert!((av - e.values[i] * v[r]).abs() < 1e-9, "A v != λ v");
            }
            for j in 0..d {
                let w = &e.vectors[j * d..(j + 1) * d];
                let dot: f64 = v.iter().zip(w).map(|(x, y)| x * y).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot - want).abs() < 1e-9, "not orthonormal");
            }
        }
        assert!(e.values.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn diagonal_repeated_and_singular() {
        check(&[2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0], 3);
        check(&[0.0; 9], 3);
        // rank one: collinear neighbourhood along (1, 1, 0)
        check(&[1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0], 3);
        check(&[4.0, 1.0, 2.0, 1.0, 3.0, 0.5, 2.0, 0.5, 1.0], 3);
        check(&[5.0], 1);
    }

    #[test]
    fn larger_matrix() {
        let d = 7;
        let a: Vec<f64> = (0..d * d)
            .map(|ij| {
                let (i, j) = (ij / d, ij % d);
                1.0 / (1.0 + i as f64 + j as f64)
            })
            .collect();
        check(&a, d);
    }

    #[test]
    fn glam_wrapper_gives_plane_normal() {
        // covariance of points in the z = 0 plane: normal is the smallest eigenvector
        let m = DMat3::from_cols_array(&[2.0, 0.3, 0.0, 0.3, 1.0, 0.0, 0.0, 0.0, 0.0]);
        let (vals, vecs) = sym_eigen3(m);
        assert!(vals.x.abs() < 1e-12);
        assert!((vecs[0].z.abs() - 1.0).abs() < 1e-12);
    }
}
