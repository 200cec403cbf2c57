//! The sum of outer products `Σ w d dᵀ` behind every covariance matrix of the crate (thesis
//! eq. 2.8, and its weighted form for the robust plane fits in `src/geometry/robust_plane.rs`):
//! the upper triangle accumulated in the order the offsets come, one definition for the
//! plain and the weighted sums.

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
    /// Adds `d dᵀ`.
    #[inline(always)]
    pub(crate) fn add(&mut self, d: DVec3) {
        self.add_scaled(d, d);
    }

    /// Adds `w d dᵀ`, as `(w d) dᵀ`.
    #[inline(always)]
    pub(crate) fn add_weighted(&mut self, w: f64, d: DVec3) {
        self.add_scaled(w * d, d);
    }

    /// Adds `a dᵀ` (`a` is `d` or `w d`); every entry is the same product in the same order as
    /// in the full matrix.
    #[inline(always)]
    fn add_scaled(&mut self, a: DVec3, d: DVec3) {
        self.xx += a.x * d.x;
        self.xy += a.x * d.y;
        self.xz += a.x * d.z;
        self.yy += a.y * d.y;
        self.yz += a.y * d.z;
        self.zz += a.z * d.z;
    }

    /// The symmetric matrix, less `w c cᵀ` (`w = 0` subtracts nothing): the sum about a centre
    /// `c` from the raw sum, `Σ w (d − c)(d − c)ᵀ = Σ w d dᵀ − (Σ w) c cᵀ` when `c` is the
    /// weighted mean of the `d`.
    #[inline]
    pub(crate) fn matrix_less(&self, w: f64, c: DVec3) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(self.xx, self.xy, self.xz) - w * c * c.x,
            DVec3::new(self.xy, self.yy, self.yz) - w * c * c.y,
            DVec3::new(self.xz, self.yz, self.zz) - w * c * c.z,
        )
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
        // a weight of 1 is the plain sum, bit for bit
        let mut w = OuterSum::default();
        pts.iter().for_each(|&p| w.add_weighted(1.0, p));
        assert_eq!(w, s);
        // about the mean: the same as summing the centred offsets
        let c = pts.iter().sum::<DVec3>() / 3.0;
        let mut centred = OuterSum::default();
        pts.iter().for_each(|&p| centred.add(p - c));
        assert!(s.matrix_less(3.0, c).abs_diff_eq(centred.matrix(), 1e-12));
    }
}
