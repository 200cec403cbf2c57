//! The analytic shapes: cube surface, sphere, torus, open cylinder united with a plane segment
//! through its axis, and a catenoid standing in for the Costa surface.

use super::{Rng, Shape, SurfacePoint};
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// Unit vector of `(x, y)` in the xy-plane, `X` at the axis.
fn radial(p: DVec3) -> (f64, DVec3) {
    let rho = (p.x * p.x + p.y * p.y).sqrt();
    if rho > 0.0 {
        (rho, DVec3::new(p.x / rho, p.y / rho, 0.0))
    } else {
        (0.0, DVec3::X)
    }
}

/// Surface of the axis-aligned cube `[−a, a]³`. Normals point outward; features are its 12
/// edges (and 8 corners).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cube {
    /// Half the side length `a`.
    pub half: f64,
}

impl Cube {
    /// The cube `[−half, half]³`.
    pub fn new(half: f64) -> Self {
        Self { half }
    }
}

impl Shape for Cube {
    fn name(&self) -> &'static str {
        "cube"
    }

    fn area(&self) -> f64 {
        24.0 * self.half * self.half
    }

    fn sample_one(&self, rng: &mut Rng) -> (DVec3, DVec3) {
        let a = self.half;
        let face = rng.below(6);
        let (axis, sign) = (face / 2, if face % 2 == 0 { 1.0 } else { -1.0 });
        let mut p = [0.0; 3];
        p[(axis + 1) % 3] = rng.uniform(-a, a);
        p[(axis + 2) % 3] = rng.uniform(-a, a);
        p[axis] = sign * a;
        let mut n = [0.0; 3];
        n[axis] = sign;
        (DVec3::from_array(p), DVec3::from_array(n))
    }

    fn closest(&self, p: DVec3) -> SurfacePoint {
        let q = p.abs() - DVec3::splat(self.half);
        let outside = q.max(DVec3::ZERO).length();
        let qmax = q.max_element();
        let signed_distance = if outside > 0.0 { outside } else { qmax };
        // normal of the face whose plane is nearest (the face of the largest q)
        let axis = if q.x >= q.y && q.x >= q.z {
            0
        } else if q.y >= q.z {
            1
        } else {
            2
        };
        let mut n = DVec3::ZERO;
        n[axis] = if p[axis] >= 0.0 { 1.0 } else { -1.0 };
        SurfacePoint {
            signed_distance,
            normal: n,
        }
    }

    fn feature_distance(&self, p: DVec3) -> f64 {
        // edge parallel to axis k: the two other coordinates at ±a
        let q = p.abs() - DVec3::splat(self.half);
        (0..3)
            .map(|k| {
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                (q[i] * q[i] + q[j] * q[j] + q[k].max(0.0).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Sphere of radius `r` about the origin; normals point outward. No features.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Radius.
    pub radius: f64,
}

impl Sphere {
    /// Sphere of the given radius about the origin.
    pub fn new(radius: f64) -> Self {
        Self { radius }
    }
}

impl Shape for Sphere {
    fn name(&self) -> &'static str {
        "sphere"
    }

    fn area(&self) -> f64 {
        4.0 * PI * self.radius * self.radius
    }

    fn sample_one(&self, rng: &mut Rng) -> (DVec3, DVec3) {
        loop {
            let g = DVec3::new(rng.gaussian(), rng.gaussian(), rng.gaussian());
            let len = g.length();
            if len > 1e-9 {
                let n = g / len;
                return (n * self.radius, n);
            }
        }
    }

    fn closest(&self, p: DVec3) -> SurfacePoint {
        let len = p.length();
        SurfacePoint {
            signed_distance: len - self.radius,
            normal: if len > 0.0 { p / len } else { DVec3::Z },
        }
    }
}

/// Torus about the z-axis: tube radius `r` around the circle of radius `R` in the xy-plane.
/// Normals point out of the tube; the signed distance is the radial offset from the tube
/// (negative inside), so its mean is the radial change of the tube. No features.
///
/// The thesis' program (Section 7.3) creates its torus by a *density*; [`Torus::count_for_density`]
/// turns a density (points per unit area) into a point count for [`super::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Torus {
    /// Radius `R` of the centre circle.
    pub major: f64,
    /// Tube radius `r` (< R).
    pub minor: f64,
}

impl Torus {
    /// Torus with centre-circle radius `major` and tube radius `minor`.
    pub fn new(major: f64, minor: f64) -> Self {
        Self { major, minor }
    }

    /// Number of points that give `density` points per unit area.
    pub fn count_for_density(&self, density: f64) -> usize {
        (density * self.area()).round().max(0.0) as usize
    }

    /// Principal curvatures at the surface point of tube angle `v` (`v = 0` outermost), for
    /// the inward normal (the convex side positive): `(1/r, cos v / (R + r cos v))`.
    pub fn principal_curvatures(&self, v: f64) -> (f64, f64) {
        (
            1.0 / self.minor,
            v.cos() / (self.major + self.minor * v.cos()),
        )
    }
}

impl Shape for Torus {
    fn name(&self) -> &'static str {
        "torus"
    }

    fn area(&self) -> f64 {
        4.0 * PI * PI * self.major * self.minor
    }

    fn sample_one(&self, rng: &mut Rng) -> (DVec3, DVec3) {
        let (big, small) = (self.major, self.minor);
        loop {
            let (u, v) = (rng.uniform(0.0, TAU), rng.uniform(0.0, TAU));
            let w = big + small * v.cos();
            if rng.unit() * (big + small) < w {
                let n = DVec3::new(v.cos() * u.cos(), v.cos() * u.sin(), v.sin());
                return (DVec3::new(w * u.cos(), w * u.sin(), small * v.sin()), n);
            }
        }
    }

    fn closest(&self, p: DVec3) -> SurfacePoint {
        let (rho, dir) = radial(p);
        let (qx, qz) = (rho - self.major, p.z);
        let len = (qx * qx + qz * qz).sqrt();
        let normal = if len > 0.0 {
            (dir * qx + DVec3::Z * qz) / len
        } else {
            dir
        };
        SurfacePoint {
            signed_distance: len - self.minor,
            normal,
        }
    }
}

/// Open cylinder of radius `R` about the z-axis, `|z| ≤ H/2`, united with the plane segment
/// `y = 0, |x| ≤ R` through its axis: two sharp creases (where the segment meets the wall, at
/// `(±R, 0, z)`). The wall's normals point outward, the segment's along `+y` (its signed
/// distance is `y`). The open rims are boundaries, not features.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CylinderPlane {
    /// Cylinder radius `R`.
    pub radius: f64,
    /// Height `H`.
    pub height: f64,
}

impl CylinderPlane {
    /// Cylinder of `radius` and `height` with its diametral plane segment.
    pub fn new(radius: f64, height: f64) -> Self {
        Self { radius, height }
    }

    fn wall_area(&self) -> f64 {
        TAU * self.radius * self.height
    }
}

impl Shape for CylinderPlane {
    fn name(&self) -> &'static str {
        "cylinder+plane"
    }

    fn area(&self) -> f64 {
        self.wall_area() + 2.0 * self.radius * self.height
    }

    fn sample_one(&self, rng: &mut Rng) -> (DVec3, DVec3) {
        let (r, hh) = (self.radius, 0.5 * self.height);
        let z = rng.uniform(-hh, hh);
        if rng.unit() * self.area() < self.wall_area() {
            let phi = rng.uniform(0.0, TAU);
            let n = DVec3::new(phi.cos(), phi.sin(), 0.0);
            (DVec3::new(r * n.x, r * n.y, z), n)
        } else {
            (DVec3::new(rng.uniform(-r, r), 0.0, z), DVec3::Y)
        }
    }

    fn closest(&self, p: DVec3) -> SurfacePoint {
        let (r, hh) = (self.radius, 0.5 * self.height);
        let dz = (p.z.abs() - hh).max(0.0);
        let (rho, dir) = radial(p);
        let d_wall = ((rho - r).powi(2) + dz * dz).sqrt();
        let dx = (p.x.abs() - r).max(0.0);
        let d_strip = (p.y * p.y + dx * dx + dz * dz).sqrt();
        if d_strip < d_wall {
            SurfacePoint {
                signed_distance: if p.y < 0.0 { -d_strip } else { d_strip },
                normal: DVec3::Y,
            }
        } else {
            SurfacePoint {
                signed_distance: if rho < r { -d_wall } else { d_wall },
                normal: dir,
            }
        }
    }

    fn feature_distance(&self, p: DVec3) -> f64 {
        let dz = (p.z.abs() - 0.5 * self.height).max(0.0);
        let dx = p.x.abs() - self.radius;
        (dx * dx + p.y * p.y + dz * dz).sqrt()
    }
}

/// The catenoid `√(x² + y²) = c·cosh(z/c)`, `|z| ≤ h`, standing in for the Costa surface.
///
/// Why a substitute: the Costa surface has no closed form — its Weierstrass data involve the
/// elliptic ℘ and ζ functions — so neither its distance function nor its normals can be
/// evaluated exactly at arbitrary points, which the metrics need. The catenoid is the minimal
/// surface the Costa surface's two outer ends are asymptotic to; like Costa it has zero mean
/// curvature everywhere (principal curvatures `±1/(c·cosh²(z/c))`, a saddle at every point),
/// and its distance reduces to the distance to a catenary in the meridian half-plane, solved
/// here by safeguarded Newton iteration to machine precision. Normals point away from the axis;
/// the open rims are boundaries, not features.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Catenoid {
    /// Waist radius `c`.
    pub waist: f64,
    /// Half height `h`: the piece `|z| ≤ h`.
    pub half_height: f64,
}

impl Catenoid {
    /// Catenoid of waist radius `waist`, cut at `|z| ≤ half_height`.
    pub fn new(waist: f64, half_height: f64) -> Self {
        Self { waist, half_height }
    }

    /// Principal curvatures `(+κ, −κ)`, `κ = 1/(c·cosh²(z/c))`, at height `z`.
    pub fn principal_curvatures(&self, z: f64) -> (f64, f64) {
        let k = 1.0 / (self.waist * (z / self.waist).cosh().powi(2));
        (k, -k)
    }

    /// Meridian parameter of the nearest point of the catenary to `(rho, z)`.
    fn nearest_t(&self, rho: f64, z: f64) -> f64 {
        let (c, h) = (self.waist, self.half_height);
        let dist2 = |t: f64| (c * (t / c).cosh() - rho).powi(2) + (t - z).powi(2);
        let newton = |mut t: f64| {
            for _ in 0..60 {
                let (ch, sh) = ((t / c).cosh(), (t / c).sinh());
                let g = (c * ch - rho) * sh + (t - z);
                let dg = (sh * sh + (c * ch - rho) * ch / c + 1.0).max(0.5 + sh * sh);
                let next = (t - g / dg).clamp(-h, h);
                if (next - t).abs() <= 1e-15 * (1.0 + t.abs()) {
                    return next;
                }
                t = next;
            }
            t
        };
        let steep = z.signum() * c * (rho / c).max(1.0).acosh();
        [newton(z.clamp(-h, h)), newton(steep.clamp(-h, h)), -h, h]
            .into_iter()
            .min_by(|a, b| dist2(*a).total_cmp(&dist2(*b)))
            .unwrap_or(0.0)
    }
}

impl Shape for Catenoid {
    fn name(&self) -> &'static str {
        "catenoid"
    }

    fn area(&self) -> f64 {
        let (c, h) = (self.waist, self.half_height);
        TAU * c * (h + 0.5 * c * (2.0 * h / c).sinh())
    }

    fn sample_one(&self, rng: &mut Rng) -> (DVec3, DVec3) {
        let (c, h) = (self.waist, self.half_height);
        let top = (h / c).cosh().powi(2);
        loop {
            let t = rng.uniform(-h, h);
            if rng.unit() * top < (t / c).cosh().powi(2) {
                let phi = rng.uniform(0.0, TAU);
                let (ch, sh) = ((t / c).cosh(), (t / c).sinh());
                let dir = DVec3::new(phi.cos(), phi.sin(), 0.0);
                let n = (dir - DVec3::Z * sh) / ch;
                return (dir * (c * ch) + DVec3::Z * t, n);
            }
        }
    }

    fn closest(&self, p: DVec3) -> SurfacePoint {
        let c = self.waist;
        let (rho, dir) = radial(p);
        let t = self.nearest_t(rho, p.z);
        let (ch, sh) = ((t / c).cosh(), (t / c).sinh());
        let (dr, dz) = (rho - c * ch, p.z - t);
        let d = (dr * dr + dz * dz).sqrt();
        let side = dr - dz * sh; // along the meridian normal (1, −sinh)
        SurfacePoint {
            signed_distance: if side < 0.0 { -d } else { d },
            normal: (dir - DVec3::Z * sh) / ch,
        }
    }
}
