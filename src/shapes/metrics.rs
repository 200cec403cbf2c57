//! Quality metrics of the smoothing results (`docs/smoothing-results.md`), all lengths in units of the
//! mean spacing `h` of the clean sample. Points keep their order through smoothing, so point
//! `i` of a result is compared with clean sample point `i`.

use super::{Sample, Shape};
use crate::error::{NbhdError, Result};
use crate::geometry::neighbors::neighbor_table;
use crate::query::Neighborhood;
use glam::DVec3;

/// Width of the band around sharp features whose points the edge RMS measures, in `h`.
pub const EDGE_BAND: f64 = 2.0;

/// Quality of a point set against the analytic surface it was sampled from.
#[derive(Clone, Debug, PartialEq)]
pub struct Quality {
    /// RMS distance to the true surface, in `h`.
    pub rms: f64,
    /// Largest distance to the true surface, in `h`.
    pub max: f64,
    /// RMS distance over the points whose clean position lies within [`EDGE_BAND`]·h of a sharp
    /// feature, in `h` (NaN-free: 0 when there are none, see `edge_count`).
    pub edge_rms: f64,
    /// Number of points the edge RMS is taken over.
    pub edge_count: usize,
    /// Mean signed distance to the surface (negative = shrank inward), in `h`.
    pub shrinkage: f64,
    /// Mean unsigned angle in degrees between the given normals and the true normal at each
    /// point's nearest surface point; `None` without normals.
    pub normal_error_deg: Option<f64>,
}

/// Measures `points` (and optionally estimated `normals`) against `shape`; `clean` is the
/// clean sample they derive from (same order) and `h` its mean spacing.
pub fn evaluate(
    shape: &dyn Shape,
    clean: &Sample,
    h: f64,
    points: &[DVec3],
    normals: Option<&[DVec3]>,
) -> Result<Quality> {
    let n = points.len();
    if n == 0 || n != clean.points.len() || normals.is_some_and(|v| v.len() != n) {
        return Err(NbhdError::InvalidOption {
            name: "points",
            reason: "points, clean sample and normals must be non-empty and of one length".into(),
        });
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(NbhdError::InvalidOption {
            name: "h",
            reason: format!("spacing {h} must be finite and > 0"),
        });
    }
    let (mut sq, mut max, mut signed, mut edge_sq, mut edge_count, mut angle) =
        (0.0, 0.0f64, 0.0, 0.0, 0usize, 0.0);
    for (i, &p) in points.iter().enumerate() {
        let c = shape.closest(p);
        let d = c.signed_distance / h;
        sq += d * d;
        max = max.max(d.abs());
        signed += d;
        if clean.feature_distance[i] <= EDGE_BAND * h {
            edge_sq += d * d;
            edge_count += 1;
        }
        if let Some(nv) = normals {
            angle += unsigned_angle_deg(nv[i], c.normal);
        }
    }
    let nf = n as f64;
    Ok(Quality {
        rms: (sq / nf).sqrt(),
        max,
        edge_rms: if edge_count > 0 {
            (edge_sq / edge_count as f64).sqrt()
        } else {
            0.0
        },
        edge_count,
        shrinkage: signed / nf,
        normal_error_deg: normals.map(|_| angle / nf),
    })
}

/// Angle in degrees between the lines spanned by `a` and `b` (orientation ignored), in
/// `[0, 90]`; 90 if either is zero.
pub fn unsigned_angle_deg(a: DVec3, b: DVec3) -> f64 {
    let l = a.length() * b.length();
    if l == 0.0 {
        return 90.0;
    }
    (a.dot(b).abs() / l).min(1.0).acos().to_degrees()
}

/// Tangential clustering: the 99th percentile of the local density `1/r8²` (`r8` = distance to
/// the 8th nearest other point) over its mean. Clean samples give about 1.5–1.9. Needs at least
/// 9 points.
pub fn tangential_clustering(points: &[DVec3]) -> Result<f64> {
    if points.len() < 9 {
        return Err(NbhdError::InvalidOption {
            name: "points",
            reason: "tangential clustering needs at least 9 points".into(),
        });
    }
    let table = neighbor_table(points, Neighborhood::Knn { k: 8 }, true)?;
    let mut dens: Vec<f64> = (0..table.len())
        .map(|i| {
            let r2 = table.sq_dists_of(i)[7];
            if r2 > 0.0 {
                1.0 / r2
            } else {
                f64::MAX
            }
        })
        .collect();
    let mean = dens.iter().sum::<f64>() / dens.len() as f64;
    dens.sort_by(f64::total_cmp);
    let idx = ((0.99 * dens.len() as f64).ceil() as usize).clamp(1, dens.len()) - 1;
    Ok(dens[idx] / mean)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::neighbors::mean_spacing;
    use crate::shapes::{add_noise, sample, Cube, NoiseKind, Torus};

    #[test]
    fn clean_and_noisy_cube() {
        let cube = Cube::new(1.0);
        let s = sample(&cube, 4000, 2);
        let h = mean_spacing(&s.points).unwrap();
        let q = evaluate(&cube, &s, h, &s.points, Some(&s.normals)).unwrap();
        assert!(q.rms < 1e-12 && q.max < 1e-12 && q.shrinkage.abs() < 1e-12);
        assert_eq!(q.normal_error_deg, Some(0.0));
        assert!(q.edge_count > 0);
        let noisy = add_noise(&s, 0.3, h, NoiseKind::Gaussian, 9).unwrap();
        let q = evaluate(&cube, &s, h, &noisy, None).unwrap();
        // the normal coefficient has unit variance; near edges the tangential part also moves
        // points off the surface, so the RMS is a little above 0.3
        assert!(q.rms > 0.28 && q.rms < 0.34, "{}", q.rms);
        let c = tangential_clustering(&s.points).unwrap();
        assert!(c > 1.2 && c < 2.5, "{c}");
    }

    #[test]
    fn torus_shrinkage_is_radial() {
        let t = Torus::new(1.0, 0.3);
        let s = sample(&t, 1000, 4);
        let shrunk: Vec<DVec3> = s
            .points
            .iter()
            .zip(&s.normals)
            .map(|(&p, &n)| p - 0.01 * n)
            .collect();
        let q = evaluate(&t, &s, 0.1, &shrunk, None).unwrap();
        assert!((q.shrinkage + 0.1).abs() < 1e-9 && (q.rms - 0.1).abs() < 1e-9);
        assert!(evaluate(&t, &s, 0.0, &shrunk, None).is_err());
        assert!(evaluate(&t, &s, 0.1, &shrunk[1..], None).is_err());
    }
}
