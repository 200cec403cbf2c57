//! The sum of outer products `Σ d dᵀ` behind the covariance matrices of the normals and
//! curvatures (thesis eq. 2.8): the upper triangle accumulated in the order the offsets come.
//! (The robust plane fits sum the same products in lanes: `src/geometry/robust_plane.rs`.)

use glam::{DMat3, DVec3};

/// The upper triangle of a running sum of outer products.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct OuterSum {
    xx: f64,
    xy: f64,
    xz: f64,
    yy: f64,
    yz: f64,
    zz: f64,
}

impl OuterSum {
    /// Adds `d dᵀ`; every entry is the same product in the same order as in the full matrix.
    #[inline(always)]
    pub(crate) fn add(&mut self, d: DVec3) {
        self.xx += d.x * d.x;
        self.xy += d.x * d.y;
        self.xz += d.x * d.z;
        self.yy += d.y * d.y;
        self.yz += d.y * d.z;
        self.zz += d.z * d.z;
    }

    /// The symmetric matrix.
    #[inline]
    pub(crate) fn matrix(&self) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(self.xx, self.xy, self.xz),
            DVec3::new(self.xy, self.yy, self.yz),
            DVec3::new(self.xz, self.yz, self.zz),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_outer_products() {
        let pts = [
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(-0.5, 0.25, 4.0),
            DVec3::new(0.1, -7.0, 0.3),
        ];
        let mut s = OuterSum::default();
        let mut full = DMat3::ZERO;
        for &p in &pts {
            s.add(p);
            full += DMat3::from_cols(p * p.x, p * p.y, p * p.z);
        }
        assert!((s.matrix() - full).abs_diff_eq(DMat3::ZERO, 1e-12));
    }
}
