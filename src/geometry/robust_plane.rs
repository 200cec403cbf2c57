//! Weighted plane fits for the robust smoothing: Tukey's biweight of a plane distance and the
//! normal of a weighted covariance (eq. 2.8–2.10 with a weight per point).

use super::covariance::OuterSum;
use super::eigen::{sym_eigen3_fast, sym_eigen3_smallest};
use glam::DVec3;

/// Tukey's biweight `(1 − (d/width)²)²` for `|d| < width`, 0 from there on (and 0 for
/// `width ≤ 0`). A robust inlier weight: smooth, 1 on the plane, and exactly 0 for outliers.
#[inline]
pub fn biweight(d: f64, width: f64) -> f64 {
    // branch-free (it runs in the innermost loop of the plane selection): for |d| ≥ width,
    // 1 − u² ≤ 0 and the max gives 0; a NaN (d or width not finite, 0/0) gives 0 as well
    let u = d / width;
    let v = (1.0 - u * u).max(0.0);
    v * v
}

/// Unit normal of the weighted covariance of `points` about their weighted barycentre: the
/// eigenvector of the smallest eigenvalue of `Σ w (x − b)(x − b)ᵀ` (eq. 2.8–2.10 with weights).
/// `None` when the weights (non-negative, finite) sum to 0. The orientation is the eigen-solver's.
pub fn weighted_plane_normal(points: &[DVec3], weight: impl Fn(DVec3) -> f64) -> Option<DVec3> {
    let origin = *points.first()?;
    let (mut ws, mut sum) = (0.0, DVec3::ZERO);
    let mut outer = OuterSum::default();
    for &x in points {
        let w = weight(x);
        if w > 0.0 {
            let d = x - origin;
            ws += w;
            sum += w * d;
            outer.add_weighted(w, d);
        }
    }
    if !(ws > 0.0 && ws.is_finite()) {
        return None;
    }
    // Σ w (d − c)(d − c)ᵀ = Σ w d dᵀ − ws c cᵀ with c = sum/ws
    let m = outer.matrix_less(ws, sum / ws);
    // closed form, or the Jacobi iteration where the two smallest eigenvalues are close
    let normal = sym_eigen3_smallest(m).map_or_else(|| sym_eigen3_fast(m).1[0], |(_, n)| n);
    normal.is_finite().then_some(normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn biweight_is_a_bounded_bump() {
        assert_eq!(biweight(0.0, 1.0), 1.0);
        assert_eq!(biweight(0.5, 1.0), 0.5625);
        assert_eq!(biweight(-1.0, 1.0), 0.0);
        assert_eq!(biweight(0.0, 0.0), 0.0);
        assert_eq!(biweight(f64::NAN, 1.0), 0.0);
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
        let floor = weighted_plane_normal(&pts, |x| biweight(x.z, 0.05)).unwrap();
        assert!((floor.z.abs() - 1.0).abs() < 1e-12);
        let wall = weighted_plane_normal(&pts, |x| biweight(x.x, 0.05)).unwrap();
        assert!((wall.x.abs() - 1.0).abs() < 1e-12);
        let blend = weighted_plane_normal(&pts, |_| 1.0).unwrap();
        assert!(blend.x.abs() > 0.3 && blend.z.abs() > 0.3);
        assert_eq!(weighted_plane_normal(&pts, |_| 0.0), None);
        assert_eq!(weighted_plane_normal(&[], |_| 1.0), None);
    }
}
