//! Point sets for the tests: seeded, in any dimension, of the kinds that break trees.
#![allow(dead_code)]

pub use nbhd::shapes::Rng;

pub mod keys;
pub mod trees;

/// The kinds of point sets the property tests run on.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Random,
    Clustered,
    /// Half the points are copies of 10 points.
    DuplicateHeavy,
    AllIdentical,
    Collinear,
    Coplanar,
    /// Coordinates on a coarse integer grid: many shared coordinates and exact distance ties.
    Grid,
}

pub const KINDS: [Kind; 7] = [
    Kind::Random,
    Kind::Clustered,
    Kind::DuplicateHeavy,
    Kind::AllIdentical,
    Kind::Collinear,
    Kind::Coplanar,
    Kind::Grid,
];

/// `n` points of dimension `d`, packed, as f64.
pub fn points(kind: Kind, n: usize, d: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let mut v = Vec::with_capacity(n * d);
    match kind {
        Kind::Random => (0..n * d).for_each(|_| v.push(rng.unit() * 10.0 - 5.0)),
        Kind::Clustered => {
            let centres: Vec<f64> = (0..4 * d).map(|_| rng.unit() * 100.0).collect();
            for _ in 0..n {
                let c = rng.below(4);
                for j in 0..d {
                    v.push(centres[c * d + j] + (rng.unit() - 0.5) * 0.5);
                }
            }
        }
        Kind::DuplicateHeavy => {
            let base: Vec<f64> = (0..10 * d).map(|_| rng.unit()).collect();
            for i in 0..n {
                if i % 2 == 0 {
                    let c = rng.below(10);
                    v.extend_from_slice(&base[c * d..(c + 1) * d]);
                } else {
                    (0..d).for_each(|_| v.push(rng.unit()));
                }
            }
        }
        Kind::AllIdentical => (0..n).for_each(|_| (0..d).for_each(|j| v.push(j as f64 + 0.5))),
        Kind::Collinear => {
            let dir: Vec<f64> = (0..d).map(|_| rng.unit() - 0.5).collect();
            for _ in 0..n {
                let t = rng.unit() * 4.0;
                dir.iter().for_each(|c| v.push(1.0 + c * t));
            }
        }
        Kind::Coplanar => {
            // Points in a plane spanned by two directions (axis-aligned when d > 2, so many
            // points share the last coordinates exactly).
            for _ in 0..n {
                let (s, t) = (rng.unit(), rng.unit());
                for j in 0..d {
                    v.push(match j {
                        0 => s,
                        1 => t + 0.25 * s,
                        _ => 0.75,
                    });
                }
            }
        }
        Kind::Grid => (0..n * d).for_each(|_| v.push(rng.below(4) as f64)),
    }
    v
}

pub fn to_f32(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// The rows of `t` as `(sq_dist, index)` lists, each sorted (to compare unsorted radius rows).
pub fn sorted_rows<T: nbhd::Scalar>(t: &nbhd::NeighborTable<T>) -> Vec<Vec<(T, u32)>> {
    (0..t.len())
        .map(|i| {
            let mut r: Vec<(T, u32)> = t
                .sq_dists_of(i)
                .iter()
                .copied()
                .zip(t.indices_of(i).iter().copied())
                .collect();
            r.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap().then(a.1.cmp(&b.1)));
            r
        })
        .collect()
}
