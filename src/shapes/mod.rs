//! Test shapes with analytic ground truth, seeded sampling and seeded noise, and the quality
//! metrics of `docs/smoothing-results.md`.
//!
//! Every shape knows, for any point of space, its distance to the true surface and the true
//! normal there ([`Shape::closest`]), and the distance to its sharp features
//! ([`Shape::feature_distance`]: edges, corners, creases; infinite for smooth shapes). Samples
//! are drawn uniformly by area from a [`Rng`] seeded by the caller, so a (shape, count, seed)
//! triple always gives the same points on every platform.
//!
//! The thesis' benchmark sizes (Fig. 8.2) are provided as [`COSTA_SIZES`],
//! [`CYLINDER_SIZES`] and [`TORUS_SIZES`].

pub mod aerial;
mod analytic;
pub mod datasets;
pub mod mesh;
pub mod metrics;
mod rng;

pub use analytic::{Catenoid, Cube, CylinderPlane, Sphere, Torus};
pub use rng::Rng;

use crate::error::{NbhdError, Result};
use glam::DVec3;

/// Point counts of the Costa surface in Fig. 8.2 (original, one and two subdivisions). The
/// Costa surface itself is replaced by a [`Catenoid`] here (see there why).
pub const COSTA_SIZES: [usize; 3] = [4_918, 28_311, 112_041];
/// Point counts of the cylinder united with a plane segment in Fig. 8.2.
pub const CYLINDER_SIZES: [usize; 3] = [5_249, 30_977, 123_393];
/// Point counts of the torus in Fig. 8.2.
pub const TORUS_SIZES: [usize; 3] = [4_851, 19_404, 77_616];

/// The nearest point of the true surface, as seen from a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Distance to the surface, signed: positive on the side the shape's normal points to
    /// (outside for closed shapes).
    pub signed_distance: f64,
    /// Unit normal of the surface at the nearest point (oriented as the shape documents).
    pub normal: DVec3,
}

/// A surface with analytic ground truth.
pub trait Shape: Sync {
    /// Short name for reports.
    fn name(&self) -> &'static str;
    /// Total surface area.
    fn area(&self) -> f64;
    /// One point drawn uniformly by area, with the true unit normal there.
    fn sample_one(&self, rng: &mut Rng) -> (DVec3, DVec3);
    /// Signed distance of `p` to the surface and the surface normal at the nearest point.
    fn closest(&self, p: DVec3) -> SurfacePoint;
    /// Distance of `p` to the nearest sharp feature (edge, corner, crease); infinite for smooth
    /// shapes. Exact for points on the surface.
    fn feature_distance(&self, _p: DVec3) -> f64 {
        f64::INFINITY
    }
}

/// A clean sample: points on the surface, the true normals there and their distances to the
/// nearest sharp feature.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Points on the surface.
    pub points: Vec<DVec3>,
    /// True unit normals, parallel to `points`.
    pub normals: Vec<DVec3>,
    /// Distance of each point to the nearest sharp feature (infinite for smooth shapes).
    pub feature_distance: Vec<f64>,
}

/// Draws `n` points uniformly by area from `shape` with the generator seeded by `seed`.
pub fn sample(shape: &dyn Shape, n: usize, seed: u64) -> Sample {
    let mut rng = Rng::new(seed);
    let (mut points, mut normals) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for _ in 0..n {
        let (p, nrm) = shape.sample_one(&mut rng);
        points.push(p);
        normals.push(nrm);
    }
    let feature_distance = points.iter().map(|&p| shape.feature_distance(p)).collect();
    Sample {
        points,
        normals,
        feature_distance,
    }
}

/// Distribution of the noise coefficients.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum NoiseKind {
    /// Standard normal coefficients, N(0, 1).
    #[default]
    Gaussian,
    /// Uniform coefficients on (−1, 1).
    Uniform,
}

/// Two unit tangents completing `n` (unit) to a right-handed orthonormal frame.
pub fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.6 { DVec3::X } else { DVec3::Y };
    let t1 = (a - n * n.dot(a)).normalize();
    (t1, n.cross(t1))
}

/// Noise as `docs/smoothing-results.md` defines it: each point moves by
/// `amplitude·h·(g0·n + g1·t1 + g2·t2)` — along the true normal `n` and both tangent
/// directions alike — with `g` drawn from `kind`. `h` is the length unit (normally the mean
/// spacing of the clean sample, [`crate::geometry::neighbors::mean_spacing`]).
pub fn add_noise(
    sample: &Sample,
    amplitude: f64,
    h: f64,
    kind: NoiseKind,
    seed: u64,
) -> Result<Vec<DVec3>> {
    if !(amplitude.is_finite() && amplitude >= 0.0 && h.is_finite() && h >= 0.0) {
        return Err(NbhdError::InvalidOption {
            name: "noise",
            reason: format!("amplitude {amplitude} and spacing {h} must be finite and >= 0"),
        });
    }
    let mut rng = Rng::new(seed);
    let s = amplitude * h;
    Ok(sample
        .points
        .iter()
        .zip(&sample.normals)
        .map(|(&p, &n)| {
            let (t1, t2) = tangent_frame(n);
            let mut g = [0.0; 3];
            for gi in &mut g {
                *gi = match kind {
                    NoiseKind::Gaussian => rng.gaussian(),
                    NoiseKind::Uniform => rng.uniform(-1.0, 1.0),
                };
            }
            p + s * (g[0] * n + g[1] * t1 + g[2] * t2)
        })
        .collect())
}

/// A clean sample, its mean spacing `h` and a noisy copy.
#[derive(Clone, Debug, PartialEq)]
pub struct NoisySample {
    /// The clean sample (ground truth for the metrics).
    pub clean: Sample,
    /// Mean nearest-neighbour spacing of the clean sample.
    pub h: f64,
    /// The clean points moved by [`add_noise`] (same order).
    pub points: Vec<DVec3>,
}

/// Samples `n` points of `shape` (seed `seed`), measures their spacing `h` and adds noise of
/// `amplitude`·h (seed `seed + 1`).
pub fn noisy_sample(
    shape: &dyn Shape,
    n: usize,
    amplitude: f64,
    kind: NoiseKind,
    seed: u64,
) -> Result<NoisySample> {
    let clean = sample(shape, n, seed);
    let h = crate::geometry::neighbors::mean_spacing(&clean.points)?;
    let points = add_noise(&clean, amplitude, h, kind, seed.wrapping_add(1))?;
    Ok(NoisySample { clean, h, points })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::neighbors::mean_spacing;

    fn shapes() -> Vec<Box<dyn Shape>> {
        vec![
            Box::new(Cube::new(1.0)),
            Box::new(Sphere::new(1.0)),
            Box::new(Torus::new(1.0, 0.4)),
            Box::new(CylinderPlane::new(1.0, 2.0)),
            Box::new(Catenoid::new(1.0, 1.2)),
        ]
    }

    #[test]
    fn samples_lie_on_the_surface_with_unit_normals() {
        for shape in shapes() {
            let s = sample(shape.as_ref(), 2000, 7);
            assert_eq!(
                s,
                sample(shape.as_ref(), 2000, 7),
                "{}: seeded",
                shape.name()
            );
            for (&p, &n) in s.points.iter().zip(&s.normals) {
                let c = shape.closest(p);
                assert!(
                    c.signed_distance.abs() < 1e-9,
                    "{} off surface",
                    shape.name()
                );
                assert!((n.length() - 1.0).abs() < 1e-12);
                assert!(
                    c.normal.dot(n).abs() > 1.0 - 1e-9,
                    "{}: normal mismatch at {p}",
                    shape.name()
                );
                // moving along the normal changes the distance by exactly that much
                let q = p + 1e-3 * n;
                assert!((shape.closest(q).signed_distance.abs() - 1e-3).abs() < 1e-7);
            }
        }
    }

    #[test]
    fn area_sampling_is_uniform_on_the_torus() {
        // outer half (cos v > 0) has area share (π R + 2 r)/(2π R) of the whole
        let (big, small) = (1.0, 0.4);
        let t = Torus::new(big, small);
        let s = sample(&t, 20_000, 3);
        let outer = s
            .points
            .iter()
            .filter(|p| (p.x * p.x + p.y * p.y).sqrt() > big)
            .count() as f64
            / 20_000.0;
        let want = (std::f64::consts::PI * big + 2.0 * small) / (2.0 * std::f64::consts::PI * big);
        assert!((outer - want).abs() < 0.015, "{outer} vs {want}");
    }

    #[test]
    fn torus_density_and_noisy_sample() {
        let t = Torus::new(1.0, 0.25);
        // area π², so 500 points per unit area give ≈ 4,935 points
        assert_eq!(t.count_for_density(500.0), 4935);
        let ns = noisy_sample(&t, t.count_for_density(500.0), 0.5, NoiseKind::Uniform, 3).unwrap();
        assert_eq!(ns.points.len(), 4935);
        assert!(ns.h > 0.0 && ns.points != ns.clean.points);
        assert!(noisy_sample(&t, 1, 0.5, NoiseKind::Uniform, 3).is_err());
    }

    #[test]
    fn feature_distances() {
        let cube = Cube::new(1.0);
        assert_eq!(cube.feature_distance(DVec3::new(1.0, 0.0, 0.0)), 1.0);
        assert!((cube.feature_distance(DVec3::new(1.0, 0.9, 0.2)) - 0.1).abs() < 1e-12);
        let cp = CylinderPlane::new(1.0, 2.0);
        assert!((cp.feature_distance(DVec3::new(0.5, 0.0, 0.3)) - 0.5).abs() < 1e-12);
        assert!(Sphere::new(1.0).feature_distance(DVec3::X).is_infinite());
        let s = sample(&cube, 3000, 1);
        let near = s.feature_distance.iter().filter(|&&d| d < 0.1).count() as f64 / 3000.0;
        // strip of width 0.1 along the 4 edges of each unit-half-side face: 1 − 0.9²
        assert!((near - 0.19).abs() < 0.025, "{near}");
    }

    #[test]
    fn noise_has_the_requested_rms() {
        let sphere = Sphere::new(1.0);
        let s = sample(&sphere, 3000, 11);
        let h = mean_spacing(&s.points).unwrap();
        for (kind, per_axis) in [(NoiseKind::Gaussian, 1.0), (NoiseKind::Uniform, 1.0 / 3.0)] {
            let noisy = add_noise(&s, 0.5, h, kind, 5).unwrap();
            let ms_normal: f64 = noisy
                .iter()
                .map(|&p| sphere.closest(p).signed_distance.powi(2))
                .sum::<f64>()
                / 3000.0;
            let ms_move: f64 = noisy
                .iter()
                .zip(&s.points)
                .map(|(a, b)| a.distance_squared(*b))
                .sum::<f64>()
                / 3000.0;
            let want = (0.5 * h).powi(2) * per_axis;
            assert!(
                (ms_normal / want - 1.0).abs() < 0.1,
                "{kind:?} {ms_normal} {want}"
            );
            assert!((ms_move / (3.0 * want) - 1.0).abs() < 0.1);
        }
        assert!(add_noise(&s, -1.0, h, NoiseKind::Gaussian, 1).is_err());
        assert_eq!(
            add_noise(&s, 0.0, h, NoiseKind::Uniform, 1).unwrap(),
            s.points
        );
    }
}
