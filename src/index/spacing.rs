//! The spacing `h` of a point set: the distance of each point to its nearest other point,
//! summarised by its mean and median. Every length given "relative" (ε = 6h, the robust
//! smoothing's lengths, the CLI's `6h`) is a multiple of the mean; this file is its one
//! definition, for every index ([`NeighborIndex::spacing`]), with the lengths given in it
//! ([`Length`]).

use super::NeighborIndex;
use crate::error::{NbhdError, Result};
use crate::named_option;
use crate::names::OptionName;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::table::TableOptions;

/// Nearest-neighbour distances of a point set: the distance `d_i = min_{j≠i} ‖x_i − x_j‖` of
/// every point to its nearest other point (duplicates count, at distance 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spacing {
    /// Mean of the `d_i`, summed in index order (so it does not depend on the thread count):
    /// the `h` of every relative length.
    pub mean: f64,
    /// Median of the `d_i` (the mean of the two middle values for an even count), robust to
    /// outliers and to clusters of duplicates far from the rest.
    pub median: f64,
    /// Number of points the distances were taken over (the finite points; 0 if none has a
    /// neighbour).
    pub points: usize,
}

impl Spacing {
    /// From each point's squared distance to its nearest other point, in index order (`None`
    /// for a point without one: skipped, or alone). `mean` and `median` are 0 without any.
    pub(crate) fn from_nearest(nearest_sq_dist: impl Iterator<Item = Option<f64>>) -> Self {
        let mut d: Vec<f64> = nearest_sq_dist.flatten().map(f64::sqrt).collect();
        let n = d.len();
        if n == 0 {
            return Spacing {
                mean: 0.0,
                median: 0.0,
                points: 0,
            };
        }
        let mean = mean_distance(d.iter().copied());
        d.sort_unstable_by(f64::total_cmp);
        let median = if n % 2 == 1 {
            d[n / 2]
        } else {
            0.5 * (d[n / 2 - 1] + d[n / 2])
        };
        Spacing {
            mean,
            median,
            points: n,
        }
    }
}

/// [`Spacing::mean`] alone, from the nearest-neighbour distances in index order (0 without
/// any): the same sum, without the median's sort of every distance (70 ms at a million points,
/// on one thread, in every call that needs only `h`).
pub(crate) fn mean_distance(distances: impl Iterator<Item = f64>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for x in distances {
        sum += x;
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// A length, absolute or in units of the input's mean spacing `h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Length {
    /// In the points' own units.
    Absolute(f64),
    /// Multiples of `h`.
    Relative(f64),
}

/// The units of a length or curvature given in numbers: the points' own, or relative to the
/// mean spacing `h` ([`Spacing::mean`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Units {
    /// The points' own units.
    Absolute,
    /// Multiples of `h` (lengths) or of `1/h` (curvatures).
    #[default]
    Relative,
}

impl OptionName for Units {
    const OPTION: &'static str = "units";
    const WHAT: &'static str = "units";
    const NAMES: &'static [(Self, &'static str)] =
        &[(Units::Relative, "relative"), (Units::Absolute, "absolute")];
}
named_option!(Units);

impl Length {
    /// The length `value` in `units`.
    pub fn new(value: f64, units: Units) -> Self {
        match units {
            Units::Absolute => Length::Absolute(value),
            Units::Relative => Length::Relative(value),
        }
    }

    /// The length's units.
    pub fn units(self) -> Units {
        match self {
            Length::Absolute(_) => Units::Absolute,
            Length::Relative(_) => Units::Relative,
        }
    }

    /// The absolute value for spacing `h`.
    pub fn resolve(self, h: f64) -> f64 {
        match self {
            Length::Absolute(v) => v,
            Length::Relative(v) => v * h,
        }
    }
}

/// Refuses relative parameters (`relative`) when the mean spacing `h` cannot scale them
/// (not > 0 or not finite: fewer than two distinct points).
pub(crate) fn check_spacing(h: f64, relative: bool) -> Result<()> {
    if relative && !(h > 0.0 && h.is_finite()) {
        return Err(NbhdError::InvalidOption {
            name: "epsilon",
            reason: "relative parameters need a mean spacing > 0 (at least two distinct points)"
                .into(),
        });
    }
    Ok(())
}

/// [`NeighborIndex::spacing`].
pub(super) fn spacing<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    threads: usize,
) -> Result<Spacing> {
    if index.len() < 2 {
        return Err(NbhdError::InvalidOption {
            name: "points",
            reason: format!(
                "the spacing needs at least two (finite) points, the tree holds {}",
                index.len()
            ),
        });
    }
    let table = index.neighborhoods(
        Neighborhood::Knn { k: 1 },
        &TableOptions {
            exclude_self: true,
            threads,
            ..Default::default()
        },
    )?;
    Ok(Spacing::from_nearest(
        (0..table.len()).map(|i| table.sq_dists_of(i).first().map(|d| d.to_f64())),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::{BuildOptions, KdTree};
    use crate::PointsView;

    #[test]
    fn mean_and_median_of_known_gaps() {
        // points on a line at 0, 1, 3, 7, 8: nearest distances 1, 1, 2, 1, 1
        let pts = [0.0, 1.0, 3.0, 7.0, 8.0];
        let tree = KdTree::<f64>::build(
            &PointsView::from_flat(&pts, 1).unwrap(),
            &BuildOptions::default(),
        )
        .unwrap();
        let s = tree.spacing(1).unwrap();
        assert_eq!(s.points, 5);
        assert_eq!(s.mean, 6.0 / 5.0);
        assert_eq!(s.median, 1.0);
        assert_eq!(tree.spacing(2).unwrap(), s);
        // an even count: the mean of the middle two
        let pts = [0.0, 1.0, 3.0, 6.0];
        let tree = KdTree::<f64>::build(
            &PointsView::from_flat(&pts, 1).unwrap(),
            &BuildOptions::default(),
        )
        .unwrap();
        // nearest: 1, 1, 2, 3
        assert_eq!(tree.spacing(0).unwrap().median, 1.5);
        let one = KdTree::<f64>::build(
            &PointsView::from_flat(&[1.0], 1).unwrap(),
            &BuildOptions::default(),
        )
        .unwrap();
        assert!(matches!(
            one.spacing(0),
            Err(NbhdError::InvalidOption { name: "points", .. })
        ));
        assert_eq!(Spacing::from_nearest(std::iter::once(None)).points, 0);
    }

    /// The mean alone is the spacing's mean bit for bit (the same sum in the same order).
    #[test]
    fn the_mean_alone_is_the_spacings_mean() {
        let sq: Vec<Option<f64>> = (0..10_000u32)
            .map(|i| (i % 97 != 0).then(|| f64::from(i.wrapping_mul(2_654_435_761) >> 8) * 1e-9))
            .collect();
        let alone = mean_distance(sq.iter().flatten().map(|d| d.sqrt()));
        assert_eq!(alone, Spacing::from_nearest(sq.iter().copied()).mean);
        assert_eq!(mean_distance(std::iter::empty()), 0.0);
    }
}
