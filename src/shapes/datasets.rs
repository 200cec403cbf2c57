//! The benchmark point sets of the speed comparisons (seeded, so every run and every peer
//! sees the same points): surface samples as scanners produce them, a volumetric cube, and a
//! duplicate-heavy set.

use super::{sample, CylinderPlane, Rng, Torus};

/// A named benchmark point set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dataset {
    /// Torus surface (major radius 1, minor 0.35), 77,616 points (thesis Fig. 8.2 size).
    Torus77k,
    /// Open cylinder united with a plane through its axis, 123,393 points (Fig. 8.2 size).
    CylinderPlane123k,
    /// Torus surface, 1,000,000 points.
    Torus1M,
    /// Uniform in the cube [−1, 1]³ (volumetric), 1,000,000 points.
    Cube1M,
    /// 100,000 torus points of which half are copies of 10 of them.
    HalfDuplicates100k,
    /// Torus surface, 100,000 points: the duplicate-free reference for `HalfDuplicates100k`.
    Torus100k,
}

impl Dataset {
    /// All sets, smallest first.
    pub const ALL: [Dataset; 6] = [
        Dataset::Torus77k,
        Dataset::Torus100k,
        Dataset::HalfDuplicates100k,
        Dataset::CylinderPlane123k,
        Dataset::Torus1M,
        Dataset::Cube1M,
    ];

    /// A short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Dataset::Torus77k => "torus-77k",
            Dataset::CylinderPlane123k => "cylinder-plane-123k",
            Dataset::Torus1M => "torus-1M",
            Dataset::Cube1M => "cube-1M",
            Dataset::HalfDuplicates100k => "half-duplicates-100k",
            Dataset::Torus100k => "torus-100k",
        }
    }

    /// The set named `name` (as [`Dataset::name`] spells it), if there is one; `"x".parse()`
    /// does the same with an error that lists the names.
    pub fn from_name(name: &str) -> Option<Dataset> {
        Dataset::ALL.into_iter().find(|d| d.name() == name)
    }

    /// The points, in a random (scan-like) order.
    pub fn points(self) -> Vec<[f64; 3]> {
        let torus = Torus::new(1.0, 0.35);
        let on = |shape: &dyn super::Shape, n: usize| -> Vec<[f64; 3]> {
            sample(shape, n, 2024)
                .points
                .iter()
                .map(|p| p.to_array())
                .collect()
        };
        match self {
            Dataset::Torus77k => on(&torus, 77_616),
            Dataset::Torus100k => on(&torus, 100_000),
            Dataset::CylinderPlane123k => on(&CylinderPlane::new(0.5, 2.0), 123_393),
            Dataset::Torus1M => on(&torus, 1_000_000),
            Dataset::Cube1M => {
                let mut rng = Rng::new(2024);
                (0..1_000_000)
                    .map(|_| std::array::from_fn(|_| rng.uniform(-1.0, 1.0)))
                    .collect()
            }
            Dataset::HalfDuplicates100k => {
                let mut pts = on(&torus, 100_000);
                let mut rng = Rng::new(7);
                for i in (0..pts.len()).step_by(2) {
                    pts[i] = pts[1 + 2 * rng.below(10)];
                }
                pts
            }
        }
    }
}

/// A name that is no [`Dataset`]'s; its message lists the names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownDataset(pub String);

impl std::fmt::Display for UnknownDataset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let known: Vec<&str> = Dataset::ALL.iter().map(|d| d.name()).collect();
        write!(
            f,
            "'{}' is not a benchmark set ({})",
            self.0,
            known.join(", ")
        )
    }
}

impl std::error::Error for UnknownDataset {}

impl std::str::FromStr for Dataset {
    type Err = UnknownDataset;
    fn from_str(name: &str) -> Result<Self, Self::Err> {
        Dataset::from_name(name).ok_or_else(|| UnknownDataset(name.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_back_and_an_unknown_one_lists_them() {
        for d in Dataset::ALL {
            assert_eq!(d.name().parse::<Dataset>(), Ok(d));
            assert_eq!(Dataset::from_name(d.name()), Some(d));
        }
        let e = "torus-78k".parse::<Dataset>().unwrap_err();
        assert_eq!(e, UnknownDataset("torus-78k".into()));
        let msg = e.to_string();
        assert!(
            msg.starts_with("'torus-78k' is not a benchmark set ("),
            "{msg}"
        );
        assert!(Dataset::ALL.iter().all(|d| msg.contains(d.name())), "{msg}");
    }
}
