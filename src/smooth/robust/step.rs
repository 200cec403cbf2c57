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
/// its neighbours in row order: the result does not depend on the number of threads.
pub(super) fn step(
    points: &[DVec3],
    rows: &Rows,
    normals: &[DVec3],
    width: f64,
    o: &RobustOptions,
) -> Vec<DVec3> {
    let patch = PatchWeight::new(o.feature_angle);
    let chord_width = CHORD_WIDTH * width;
    (0..points.len())
        .into_par_iter()
        .map(|s| {
            let (p, ni) = (points[s], normals[s]);
            let (mut acc, mut ws) = (DVec3::ZERO, 0.0);
            for &j in rows.narrow(s, o.k) {
                let (x, nj) = (points[j as usize], normals[j as usize]);
                let e = x - p;
                // the neighbour's tangent plane far from p: another face, drops out
                let g = biweight(nj.dot(e), width);
                if g == 0.0 {
                    continue;
                }
                let c = ni.dot(nj);
                let nj = if c < 0.0 { -nj } else { nj };
                // one smooth patch: normals close, or the chord perpendicular to their mean
                // (⟨n_i + n_j, e⟩ / ‖n_i + n_j‖ within the chord width; squared, no root)
                let sum = ni + nj;
                let a = patch.weight(c.abs()).max(biweight_sq(
                    sum.dot(e).powi(2),
                    sum.length_squared() * chord_width.powi(2),
                ));
                // m = v/‖v‖ with v = a n_i + n_j: m mᵀ e = v ⟨v, e⟩ / ‖v‖²
                let v = a * ni + nj;
                let vv = v.length_squared();
                if vv > 0.0 {
                    acc += g * v * (v.dot(e) / vv);
                }
                ws += g;
            }
            if ws > 0.0 {
                p + o.tau * acc / ws
            } else {
                p
            }
        })
        .collect()
}

/// Tukey's biweight from squares: `(1 − d²/w²)²` for `d² < w²`, else 0 (see
/// `geometry::robust_plane::biweight`); saves the roots of a distance and a width that come
/// squared.
#[inline]
fn biweight_sq(d2: f64, w2: f64) -> f64 {
    let v = 1.0 - d2 / w2;
    if v > 0.0 {
        v * v
    } else {
        0.0
    }
}

/// The weight of "one smooth patch" between two unit normals: a Gaussian in the distance between
/// them, `exp(−‖n_i − n_j‖² / c²)` with `‖n_i − n_j‖² = 2(1 − |cos θ|)` (sign ignored) and
/// `c = 2 sin(feature_angle/2)` the distance of normals `feature_angle` apart: 1 for parallel
/// normals, `1/e` at the feature angle, like a Gaussian in the angle (`‖n_i − n_j‖ = 2 sin(θ/2)
/// ≈ θ`) without its arc cosine.
struct PatchWeight {
    inv_c2: f64,
}

impl PatchWeight {
    fn new(feature_angle_deg: f64) -> Self {
        let c = 2.0 * (feature_angle_deg.to_radians() / 2.0).sin();
        Self {
            inv_c2: 1.0 / (c * c),
        }
    }

    #[inline]
    fn weight(&self, abs_cos: f64) -> f64 {
        (-2.0 * (1.0 - abs_cos.min(1.0)) * self.inv_c2).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patch_weight_is_a_gaussian_in_the_normals_distance() {
        let w = PatchWeight::new(20.0);
        assert_eq!(w.weight(1.0), 1.0);
        assert!((w.weight(20f64.to_radians().cos()) - (-1f64).exp()).abs() < 1e-12);
        assert!(w.weight(0.0) < 1e-6); // perpendicular normals: e^(−16.6)
        assert_eq!(biweight_sq(0.25, 1.0), biweight(0.5, 1.0));
        assert_eq!(biweight_sq(1.0, 1.0), 0.0);
    }
}
