//! A seeded synthetic aerial LiDAR survey, generated tile by tile: [`AerialScene::tile`].
//!
//! The scene is endless and fixed by its seed: a rolling terrain, buildings with flat or gable
//! roofs (their eaves and ridges are sharp edges), trees whose crowns give several returns per
//! pulse, and the scan pattern of an airborne scanner — flight strips along y with overlapping
//! swaths, zig-zag scan lines across them (an oscillating mirror), range noise, a small
//! height offset per strip that shows in the overlaps, and rare isolated outliers.
//!
//! **Tiles are independent.** Every random draw is seeded by what it belongs to — a pulse by
//! `(seed, strip, line, pulse)`, a building by `(seed, parcel)`, a tree by `(seed, cell)`,
//! a strip's offset by `(seed, strip)` — never by a stream shared across tiles, and a pulse
//! belongs to the tile holding its nominal footprint. So any tile is generated alone in time
//! proportional to its pulses, and gives exactly the points the same area gives when generated
//! among its neighbours (the tests check it bit for bit).
//!
//! Simplifications: the pulses are vertical (walls are not sampled; a roof's edge is a step
//! from roof to ground), and the scan angle recorded is the nominal one of the pulse's place in
//! its swath.

use super::rng::Rng;
use glam::DVec3;

/// The survey's parameters (all lengths in metres).
#[derive(Clone, Copy, Debug)]
pub struct AerialScene {
    /// Fixes the whole scene.
    pub seed: u64,
    /// Pulses per square metre of one strip (overlaps hold more).
    pub density: f64,
    /// Width of a strip's swath.
    pub swath: f64,
    /// Fraction of a swath its neighbour covers too.
    pub overlap: f64,
    /// Range noise (standard deviation along the vertical beam).
    pub noise: f64,
    /// Standard deviation of each strip's height offset.
    pub strip_offset: f64,
    /// Probability of a pulse giving an isolated outlier instead of its returns.
    pub outliers: f64,
}

impl Default for AerialScene {
    fn default() -> Self {
        Self {
            seed: 39,
            density: 16.0,
            swath: 400.0,
            overlap: 0.3,
            noise: 0.025,
            strip_offset: 0.03,
            outliers: 1e-5,
        }
    }
}

/// The ASPRS classes the scene uses.
pub const GROUND: u8 = 2;
/// High vegetation.
pub const VEGETATION: u8 = 5;
/// Building.
pub const BUILDING: u8 = 6;
/// Low point (noise).
pub const NOISE: u8 = 7;

/// The points of a tile with the LAS fields of their records, in pulse order (strip, scan
/// line, pulse), a pulse's returns first to last.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AerialPoints {
    /// Positions.
    pub positions: Vec<DVec3>,
    /// ASPRS class ([`GROUND`], [`VEGETATION`], [`BUILDING`], [`NOISE`]).
    pub classification: Vec<u8>,
    /// 1-based return number within the pulse.
    pub return_number: Vec<u8>,
    /// Returns of the pulse.
    pub number_of_returns: Vec<u8>,
    /// Time of the pulse, seconds (distinct for every pulse of the scene).
    pub gps_time: Vec<f64>,
    /// Return strength.
    pub intensity: Vec<u16>,
    /// The strip (flight line) the pulse came from.
    pub point_source_id: Vec<u16>,
    /// Nominal scan angle as LAS 1.4 stores it: units of 0.006° (negative left of the flight
    /// line).
    pub scan_angle: Vec<i16>,
}

/// One pulse: its strip, scan line and place in the line, its nominal footprint, time and
/// scan angle.
struct Pulse {
    strip: i64,
    line: i64,
    index: i64,
    x: f64,
    y: f64,
    time: f64,
    angle: i16,
}

/// One return of a pulse: height, class, intensity base.
struct Return {
    z: f64,
    class: u8,
    intensity: f64,
}

/// A seed for the draws of one thing of the scene (SplitMix64's finaliser over its parts).
fn mix(parts: &[u64]) -> u64 {
    parts.iter().fold(0x243F_6A88_85A3_08D3, |h, &p| {
        let mut r = Rng::new(h ^ p.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        r.next_u64()
    })
}

/// Tags keeping the seeds of different kinds of things apart.
const PULSE: u64 = 1;
const PARCEL: u64 = 2;
const TREE: u64 = 3;
const STRIP: u64 = 4;
const TERRAIN: u64 = 5;

/// Side of the building parcels.
const PARCEL_SIDE: f64 = 40.0;
/// Side of the tree cells.
const TREE_CELL: f64 = 12.0;

impl AerialScene {
    /// The distance between neighbouring strips' flight lines.
    fn strip_step(&self) -> f64 {
        self.swath * (1.0 - self.overlap)
    }

    /// Spacing of the pulses along and across a scan line.
    fn pitch(&self) -> f64 {
        1.0 / self.density.sqrt()
    }

    /// Every point whose pulse's nominal footprint lies in `[x0, x1) × [y0, y1)`, in pulse
    /// order. An empty or inverted box, or a scene with no pulses, gives no points.
    pub fn tile(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> AerialPoints {
        let mut out = AerialPoints::default();
        let usable = self.density.is_finite() && self.density > 0.0 && self.swath > 0.0;
        if !(usable && x1 > x0 && y1 > y0 && (0.0..1.0).contains(&self.overlap)) {
            return out;
        }
        let (step, pitch, half) = (self.strip_step(), self.pitch(), self.swath / 2.0);
        let per_line = (self.swath / pitch).floor() as i64;
        let first = ((x0 - half) / step).ceil() as i64;
        let last = ((x1 + half) / step).floor() as i64;
        for s in first..=last {
            let centre = s as f64 * step;
            // a line's pulses zig-zag over one line spacing in y
            let (j0, j1) = ((y0 / pitch).floor() as i64 - 1, (y1 / pitch).ceil() as i64);
            let i0 = (((x0 - centre + half) / pitch).floor() as i64).max(0);
            let i1 = (((x1 - centre + half) / pitch).ceil() as i64).min(per_line - 1);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let t = (i as f64 + 0.5) / per_line as f64;
                    let sweep = if j % 2 == 0 { t } else { 1.0 - t };
                    let x = centre - half + (i as f64 + 0.5) * pitch;
                    let y = (j as f64 + sweep) * pitch;
                    if x >= x0 && x < x1 && y >= y0 && y < y1 {
                        let pulse = Pulse {
                            strip: s,
                            line: j,
                            index: i,
                            x,
                            y,
                            time: s as f64 * 1.0e6 + (j * per_line + i) as f64 * 1.0e-5,
                            angle: (((x - centre) / 1000.0).atan().to_degrees() / 0.006).round()
                                as i16,
                        };
                        self.returns(&pulse, &mut out);
                    }
                }
            }
        }
        out
    }

    /// The height offset of strip `s` (its boresight error).
    pub fn strip_offset(&self, s: i64) -> f64 {
        Rng::new(mix(&[self.seed, STRIP, s as u64])).gaussian() * self.strip_offset
    }

    /// The returns of `pulse`, appended to `out`.
    fn returns(&self, pulse: &Pulse, out: &mut AerialPoints) {
        let (s, j, i) = (pulse.strip, pulse.line, pulse.index);
        let mut rng = Rng::new(mix(&[self.seed, PULSE, s as u64, j as u64, i as u64]));
        let offset = self.strip_offset(s);
        let (x, y) = (pulse.x, pulse.y);
        let ground = self.terrain(x, y);
        let mut returns: Vec<Return> = Vec::with_capacity(3);
        if rng.unit() < self.outliers {
            let z = ground + rng.uniform(15.0, 80.0);
            returns.push(Return {
                z,
                class: NOISE,
                intensity: 20.0,
            });
        } else if let Some(roof) = self.roof(x, y) {
            returns.push(Return {
                z: roof,
                class: BUILDING,
                intensity: 180.0,
            });
        } else {
            if let Some((top, bottom)) = self.crown(x, y) {
                returns.push(Return {
                    z: top,
                    class: VEGETATION,
                    intensity: 90.0,
                });
                if rng.unit() < 0.5 {
                    returns.push(Return {
                        z: rng.uniform(bottom, top),
                        class: VEGETATION,
                        intensity: 60.0,
                    });
                }
            }
            returns.push(Return {
                z: ground,
                class: GROUND,
                intensity: 120.0,
            });
        }
        let n = returns.len() as u8;
        for (k, r) in returns.iter().enumerate() {
            let z = r.z + offset + self.noise * rng.gaussian();
            out.positions.push(DVec3::new(x, y, z));
            out.classification.push(r.class);
            out.return_number.push(k as u8 + 1);
            out.number_of_returns.push(n);
            out.gps_time.push(pulse.time);
            let strength = r.intensity * (1.0 + 0.1 * rng.gaussian()) / f64::from(k as u8 + 1);
            out.intensity.push(strength.clamp(0.0, 65535.0) as u16);
            out.point_source_id.push(s.rem_euclid(65536) as u16);
            out.scan_angle.push(pulse.angle);
        }
    }

    /// The terrain's height: a sum of seeded waves, slopes below about 20 %.
    pub fn terrain(&self, x: f64, y: f64) -> f64 {
        let mut rng = Rng::new(mix(&[self.seed, TERRAIN]));
        let mut z = 0.0;
        for octave in 0..5 {
            let wavelength = 600.0 / f64::from(1 << octave);
            let amplitude = 0.015 * wavelength / (octave as f64 + 1.0);
            let angle = rng.uniform(0.0, std::f64::consts::TAU);
            let (phase_a, phase_b) = (rng.uniform(0.0, 6.3), rng.uniform(0.0, 6.3));
            let k = std::f64::consts::TAU / wavelength;
            let (u, v) = (angle.cos(), angle.sin());
            z += amplitude
                * (k * (u * x + v * y) + phase_a).sin()
                * (k * (-v * x + u * y) + phase_b).cos();
        }
        z
    }

    /// The roof height at `(x, y)` when a building stands there: the parcel's building, a
    /// rectangle with a flat roof or a gable whose ridge runs along its longer side.
    pub fn roof(&self, x: f64, y: f64) -> Option<f64> {
        let (a, b) = ((x / PARCEL_SIDE).floor(), (y / PARCEL_SIDE).floor());
        let mut rng = Rng::new(mix(&[self.seed, PARCEL, a as i64 as u64, b as i64 as u64]));
        if rng.unit() >= 0.35 {
            return None;
        }
        let (w, d) = (rng.uniform(10.0, 26.0), rng.uniform(8.0, 20.0));
        let cx = (a + 0.5) * PARCEL_SIDE + rng.uniform(-1.0, 1.0) * (PARCEL_SIDE - w) / 2.0 * 0.8;
        let cy = (b + 0.5) * PARCEL_SIDE + rng.uniform(-1.0, 1.0) * (PARCEL_SIDE - d) / 2.0 * 0.8;
        let (eave, gable) = (rng.uniform(4.0, 20.0), rng.unit() < 0.6);
        let pitch = rng.uniform(20f64, 40.0).to_radians().tan();
        let (dx, dy) = ((x - cx).abs(), (y - cy).abs());
        if dx > w / 2.0 || dy > d / 2.0 {
            return None;
        }
        let base = self.terrain(cx, cy) + eave;
        if !gable {
            return Some(base);
        }
        // the ridge along the longer side: the height falls toward the two long eaves
        let rise = if w >= d { d / 2.0 - dy } else { w / 2.0 - dx };
        Some(base + pitch * rise)
    }

    /// The crown a vertical pulse at `(x, y)` passes through: its top and lowest height there.
    pub fn crown(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (a, b) = ((x / TREE_CELL).floor(), (y / TREE_CELL).floor());
        // a crown reaches at most one cell beyond its own
        let mut best: Option<(f64, f64)> = None;
        for (ca, cb) in [-1.0, 0.0, 1.0]
            .iter()
            .flat_map(|&p| [(a + p, b - 1.0), (a + p, b), (a + p, b + 1.0)])
        {
            let mut rng = Rng::new(mix(&[self.seed, TREE, ca as i64 as u64, cb as i64 as u64]));
            if rng.unit() >= 0.3 {
                continue;
            }
            let cx = (ca + rng.unit()) * TREE_CELL;
            let cy = (cb + rng.unit()) * TREE_CELL;
            let (r, trunk) = (rng.uniform(2.0, 5.5), rng.uniform(2.0, 8.0));
            if self.roof(cx, cy).is_some() {
                continue; // no tree grows in a house
            }
            let d2 = (x - cx).powi(2) + (y - cy).powi(2);
            if d2 >= r * r {
                continue;
            }
            let centre = self.terrain(cx, cy) + trunk + r;
            let half = (r * r - d2).sqrt();
            let (top, bottom) = (centre + half, centre - half);
            if best.is_none_or(|(t, _)| top > t) {
                best = Some((top, bottom));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One point's record as bits: time, return, position, class, returns, intensity,
    /// strip, scan angle.
    type Bits = (u64, u8, [u64; 3], u8, u8, u16, u16, i16);

    /// The points sorted by (time, return), as bits: the same set in any order compares equal.
    fn sorted_bits(p: &AerialPoints) -> Vec<Bits> {
        let mut v: Vec<_> = (0..p.positions.len())
            .map(|k| {
                (
                    p.gps_time[k].to_bits(),
                    p.return_number[k],
                    p.positions[k].to_array().map(f64::to_bits),
                    p.classification[k],
                    p.number_of_returns[k],
                    p.intensity[k],
                    p.point_source_id[k],
                    p.scan_angle[k],
                )
            })
            .collect();
        v.sort_unstable();
        v
    }

    #[test]
    fn a_tile_alone_equals_the_same_tile_among_its_neighbours() {
        let scene = AerialScene {
            density: 2.0,
            outliers: 1e-3,
            ..AerialScene::default()
        };
        // a 2 x 2 block of 150 m tiles across a strip boundary and the origin (negative
        // strips, lines and parcels)
        let (x, y, side) = (-170.0, -60.0, 150.0);
        let block = scene.tile(x, y, x + 2.0 * side, y + 2.0 * side);
        let mut tiles = AerialPoints::default();
        for (a, b) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let (tx, ty) = (x + a * side, y + b * side);
            let t = scene.tile(tx, ty, tx + side, ty + side);
            assert!(!t.positions.is_empty());
            assert!(t.positions.iter().all(|p| p.x >= tx && p.x < tx + side));
            // the same tile twice: the same bits in the same order
            assert_eq!(t, scene.tile(tx, ty, tx + side, ty + side));
            tiles.positions.extend(&t.positions);
            tiles.classification.extend(&t.classification);
            tiles.return_number.extend(&t.return_number);
            tiles.number_of_returns.extend(&t.number_of_returns);
            tiles.gps_time.extend(&t.gps_time);
            tiles.intensity.extend(&t.intensity);
            tiles.point_source_id.extend(&t.point_source_id);
            tiles.scan_angle.extend(&t.scan_angle);
        }
        assert_eq!(sorted_bits(&tiles), sorted_bits(&block));
        // another seed is another scene
        let other = AerialScene { seed: 40, ..scene }.tile(x, y, x + side, y + side);
        assert_ne!(
            other.positions,
            scene.tile(x, y, x + side, y + side).positions
        );
    }

    #[test]
    fn the_scene_holds_ground_buildings_trees_returns_and_overlaps() {
        let scene = AerialScene::default();
        let (side, area) = (120.0, 120.0 * 120.0);
        let t = scene.tile(100.0, 100.0, 100.0 + side, 100.0 + side);
        let count = |c: u8| t.classification.iter().filter(|&&k| k == c).count();
        let pulses = t.return_number.iter().filter(|&&r| r == 1).count();
        // one strip's density everywhere, two where the swaths overlap (x from 80 to 200 m)
        let per_m2 = pulses as f64 / area;
        assert!(
            per_m2 > scene.density && per_m2 < 2.0 * scene.density,
            "{per_m2}"
        );
        for class in [GROUND, VEGETATION, BUILDING] {
            assert!(
                count(class) > pulses / 200,
                "class {class}: {}",
                count(class)
            );
        }
        // every pulse through a crown ends on the ground: multiple returns, the last ground
        for k in 0..t.positions.len() {
            let (r, n) = (t.return_number[k], t.number_of_returns[k]);
            assert!(r >= 1 && r <= n && n <= 3);
            if n > 1 && r == n {
                assert_eq!(t.classification[k], GROUND);
            }
        }
        // ground returns lie on the terrain, each strip shifted by its offset, with the range
        // noise about it
        for strip in [0, 1] {
            let r: Vec<f64> = (0..t.positions.len())
                .filter(|&k| t.classification[k] == GROUND && t.point_source_id[k] == strip)
                .map(|k| t.positions[k].z - scene.terrain(t.positions[k].x, t.positions[k].y))
                .collect();
            let mean = r.iter().sum::<f64>() / r.len() as f64;
            let sd = (r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / r.len() as f64).sqrt();
            let offset = scene.strip_offset(i64::from(strip));
            assert!(
                (mean - offset).abs() < 0.002,
                "strip {strip}: {mean} {offset}"
            );
            assert!((sd / scene.noise - 1.0).abs() < 0.05, "strip {strip}: {sd}");
        }
        // a roof's edge is a step: building returns stand well above the terrain
        assert!((0..t.positions.len())
            .filter(|&k| t.classification[k] == BUILDING)
            .all(|k| t.positions[k].z - scene.terrain(t.positions[k].x, t.positions[k].y) > 0.5));
        // no tile from an empty box or a scene without pulses
        assert!(scene.tile(0.0, 0.0, 0.0, 10.0).positions.is_empty());
        let none = AerialScene {
            density: 0.0,
            ..scene
        };
        assert!(none.tile(0.0, 0.0, 10.0, 10.0).positions.is_empty());
    }
}
