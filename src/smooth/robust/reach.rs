//! How far one round of the robust smoothing reaches, and so which of a tile's points get the
//! one-machine value: the halo check of `robust/tile.rs`, decided per point from the rows
//! themselves instead of argued from a radius.
//!
//! A point's row is the `k_plane` (or `WIDE`·`k_plane`) nearest of the **input**, however far
//! (the rows are not cut at ε when searched, and a candidate beyond ε can move inside it
//! later); the iterations re-sort and re-cut it on each proxy but never change its set of
//! candidates. A round reads, for a point x:
//! - the ratio, the plane distance and the outputs: x's row (one hop);
//! - the step: the normals of x's first `k`; the normal of j is chosen among the planes of j's
//!   own row and of its farthest quarter; the plane of l is fitted to l's row (three hops).
//!
//! So with `cand(x)` the candidate set and `cert(x)` "x's row is the cloud's" (below):
//! `plane(x) ⇐ cert(x)`, `normal(x) ⇐ cert(x) ∧ ∀c ∈ cand(x): cert(c)` (which quarter is
//! the farthest depends on the proxy, so every candidate counts), and
//! `step(x) ⇐ normal(x) ∧ ∀c ∈ cand(x): normal(c)`. These sets are fixed for a run's rows, so
//! the flags are computed once per search. The positions a round reads are the proxy of its
//! generation, which the tile's driver gives it for every gathered point.
//!
//! `cert(x)`: the tile's search found the same row as a search of the whole cloud. The tile
//! holds every point of the cloud inside its region (a closed box, unbounded on the sides where
//! nothing lies beyond), and the search orders by `(sq_dist, index)` with local indices that
//! ascend with the cloud's; so the rows agree when the row is full (`k` candidates) and every
//! point at most as far as its last candidate — ties included — lies inside the region: the
//! last candidate's distance, widened by the rounding of the computed distances, is below the
//! distance of x to the region's boundary. Next to an outlier or a hole no radius bounds a hop;
//! there the check fails and the driver gathers a wider halo.

use super::rows::Rows;
use glam::DVec3;
use rayon::prelude::*;

/// The closed box a tile's points were gathered from: every point of the cloud inside it is in
/// the tile. Infinite bounds stand for the sides beyond which the cloud has no point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// The lower corner.
    pub lo: DVec3,
    /// The upper corner.
    pub hi: DVec3,
}

impl Region {
    /// Whether `p` is finite and inside the box (its boundary included).
    pub fn contains(&self, p: DVec3) -> bool {
        p.is_finite() && p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }

    /// Whether the region is all of space: the tile is the whole cloud.
    fn is_everything(&self) -> bool {
        self.lo.cmpeq(DVec3::NEG_INFINITY).all() && self.hi.cmpeq(DVec3::INFINITY).all()
    }

    /// Whether every point within `sqrt(sq_radius)` of `p` (inside the region) lies in the
    /// region: the radius, widened by 64 ulps relative and of the coordinates' magnitude for the
    /// roundings of the distances, is below the distance of `p` to the nearest face.
    fn holds_ball(&self, p: DVec3, sq_radius: f64) -> bool {
        let inside = (p - self.lo).min(self.hi - p).min_element();
        let finite = |v: DVec3| DVec3::select(v.is_finite_mask(), v.abs(), DVec3::ZERO);
        let scale = p
            .abs()
            .max(finite(self.lo))
            .max(finite(self.hi))
            .max_element();
        let slack = 64.0 * f64::EPSILON;
        sq_radius.sqrt() * (1.0 + slack) + slack * scale < inside
    }
}

/// Which stored points of a tile get the one-machine value of each kind of round.
pub(super) struct Reach {
    /// `cert(x)`: the row is the whole cloud's.
    cert: Vec<bool>,
    /// `step(x)`: the step's reach (three hops) is certified.
    step: Vec<bool>,
}

impl Reach {
    /// The flags of the rows `rows` searched with `k` candidates on `input` (stored order)
    /// in a tile gathered from `region`.
    pub(super) fn new(input: &[DVec3], rows: &Rows, k: usize, region: &Region) -> Self {
        let everything = region.is_everything();
        let cert: Vec<bool> = (0..input.len())
            .into_par_iter()
            .map(|s| {
                let row = rows.candidates(s);
                let p = input[s];
                let far = row
                    .iter()
                    .map(|&c| input[c as usize].distance_squared(p))
                    .fold(0.0, f64::max);
                everything || (row.len() == k && region.holds_ball(p, far))
            })
            .collect();
        let normal = closure(&cert, rows);
        let step = closure(&normal, rows);
        Self { cert, step }
    }

    /// The flags as `robust/row_file.rs` kept them (1 or 0 per stored point); `None` for
    /// flags of other lengths or values.
    pub(super) fn from_flags(cert: &[u8], step: &[u8]) -> Option<Self> {
        let of = |f: &[u8]| f.iter().map(|&b| (b <= 1).then_some(b == 1)).collect();
        let (cert, step): (Option<Vec<bool>>, Option<Vec<bool>>) = (of(cert), of(step));
        let (cert, step) = (cert?, step?);
        (cert.len() == step.len()).then_some(Self { cert, step })
    }

    /// The rounds that read a point's own row (ratio, plane distance, outputs).
    pub(super) fn cert(&self) -> &[bool] {
        &self.cert
    }

    /// The step.
    pub(super) fn step(&self) -> &[bool] {
        &self.step
    }
}

/// One more hop: `flags(x) ∧ ∀c ∈ cand(x): flags(c)`.
fn closure(flags: &[bool], rows: &Rows) -> Vec<bool> {
    (0..flags.len())
        .into_par_iter()
        .map(|s| flags[s] && rows.candidates(s).iter().all(|&c| flags[c as usize]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ball_is_held_only_inside_the_faces_with_margin() {
        let r = Region {
            lo: DVec3::ZERO,
            hi: DVec3::new(10.0, f64::INFINITY, 10.0),
        };
        let p = DVec3::new(3.0, 1e9, 5.0);
        assert!(r.contains(p));
        assert!(r.holds_ball(p, 2.9 * 2.9));
        // exactly at the distance of the face: a point on the face's far side could tie
        assert!(!r.holds_ball(p, 9.0));
        assert!(!r.contains(DVec3::new(3.0, -1.0, 5.0)));
        assert!(!r.contains(DVec3::new(f64::NAN, 1.0, 5.0)));
        let all = Region {
            lo: DVec3::NEG_INFINITY,
            hi: DVec3::INFINITY,
        };
        assert!(all.is_everything() && !r.is_everything());
        assert!(all.holds_ball(p, 1e300));
    }
}
