//! Neighbourhood queries (thesis Chapter 5): the k nearest, all within a radius ε, and the
//! ε-k-neighbourhood (the k nearest among those within ε, Section 2.1.1), answered by the k-d
//! tree and by the two baselines, brute force (Algorithm 7) and the PCA sweep (Algorithm 8).
//!
//! Conventions, shared by every searcher:
//! - indices are the caller's original indices;
//! - a radius is a plain Euclidean radius and inclusive: `‖x − q‖ ≤ ε`, evaluated as
//!   `sq_dist ≤ ε²` in the tree's scalar type;
//! - distances come back squared (`sq_dist`);
//! - [`QueryOptions`] (`options.rs`) change the metric to any Minkowski p-norm (then `sq_dist`
//!   holds that metric's key, `src/metric.rs`), make a search approximate (`eps`) or a radius
//!   strict;
//! - results are ordered by `(sq_dist, index)`, so ties are deterministic (the unsorted radius
//!   variant returns the same set in an unspecified order).

pub mod brute;
mod heap;
pub(crate) mod in_box;
mod options;
pub(crate) mod order;
pub mod pca_sweep;
#[doc(hidden)]
pub mod result_set;

use crate::error::{NbhdError, Result};
use crate::scalar::Scalar;

pub(crate) use heap::NeighborHeap;
pub(crate) use options::Plan;
pub use options::QueryOptions;

/// One neighbour: the caller's index of the point and its squared distance to the query.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Neighbor<T> {
    /// The caller's index of the point.
    pub index: u32,
    /// Squared Euclidean distance to the query point (under a [`QueryOptions::metric`], that
    /// metric's key: [`Metric::key_of`](crate::Metric::key_of)).
    pub sq_dist: T,
}

impl<T: Scalar> Neighbor<T> {
    /// The `(sq_dist, index)` order every sorted result uses (defined in
    /// `src/query/order.rs`).
    #[inline(always)]
    pub fn precedes(&self, other: &Self) -> bool {
        order::precedes(self.key(), other.key())
    }

    /// Total order by `(sq_dist, index)` (distances are never NaN).
    #[inline]
    pub fn cmp_by_distance(&self, other: &Self) -> std::cmp::Ordering {
        order::cmp(self.key(), other.key())
    }

    /// The `(sq_dist, index)` pair the order compares.
    #[inline(always)]
    pub(crate) fn key(&self) -> (T, u32) {
        (self.sq_dist, self.index)
    }
}

/// Which neighbourhood to compute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Neighborhood<T> {
    /// The `k` nearest points.
    Knn {
        /// How many (≥ 1).
        k: usize,
    },
    /// All points with `‖x − q‖ ≤ radius`.
    Radius {
        /// Plain Euclidean radius (≥ 0; a distance in the metric of [`QueryOptions`] if given).
        radius: T,
        /// Sort by `(sq_dist, index)`; `false` returns the same set faster, unordered.
        sorted: bool,
    },
    /// The ε-k-neighbourhood: the `k` nearest among the points with `‖x − q‖ ≤ radius`.
    KnnRadius {
        /// How many at most (≥ 1).
        k: usize,
        /// Plain Euclidean radius (≥ 0; a distance in the metric of [`QueryOptions`] if given).
        radius: T,
    },
}

/// The error for a radius `r` (as the caller passed it) whose square overflows `T`.
pub(crate) fn radius_out_of_range<T: Scalar>(r: f64) -> NbhdError {
    let (scalar, max) = match T::TYPE {
        crate::scalar::ScalarType::F32 => ("f32", (f32::MAX as f64).sqrt()),
        crate::scalar::ScalarType::F64 => ("f64", f64::MAX.sqrt()),
    };
    NbhdError::RadiusOutOfRange {
        radius: r,
        scalar,
        max,
    }
}

impl<T: Scalar> Neighborhood<T> {
    /// Checks `k ≥ 1` and a finite radius ≥ 0 whose square is finite in `T` (squared
    /// distances are compared in `T`): [`NbhdError::RadiusOutOfRange`] above `√T::MAX`.
    pub fn validate(&self) -> Result<()> {
        let check_radius = |r: T| {
            if !(r.is_finite() && r >= T::ZERO) {
                Err(NbhdError::InvalidRadius(r.to_f64()))
            } else if !(r * r).is_finite() {
                Err(radius_out_of_range::<T>(r.to_f64()))
            } else {
                Ok(())
            }
        };
        match *self {
            Neighborhood::Knn { k: 0 } => Err(NbhdError::ZeroK),
            Neighborhood::Knn { .. } => Ok(()),
            Neighborhood::Radius { radius, .. } => check_radius(radius),
            Neighborhood::KnnRadius { k: 0, .. } => Err(NbhdError::ZeroK),
            Neighborhood::KnnRadius { radius, .. } => check_radius(radius),
        }
    }

    /// `(k, squared radius)` of this neighbourhood: `k` is `usize::MAX` for a radius query and
    /// the squared radius is infinite for a k-nearest query.
    pub fn limits(&self) -> (usize, T) {
        match *self {
            Neighborhood::Knn { k } => (k, T::INFINITY),
            Neighborhood::Radius { radius, .. } => (usize::MAX, radius * radius),
            Neighborhood::KnnRadius { k, radius } => (k, radius * radius),
        }
    }

    /// Whether the result must be ordered by `(sq_dist, index)`.
    pub fn is_sorted(&self) -> bool {
        !matches!(self, Neighborhood::Radius { sorted: false, .. })
    }
}

/// A neighbourhood as the front doors take it, its radius a plain `f64` (the C ABI, the command
/// line and Python): the `k` nearest (`k` alone), all within `radius` (`radius` alone, ordered
/// unless `sorted` is `false`) or the ε-k-neighbourhood (both). [`NeighborhoodSpec::to`] makes it
/// the [`Neighborhood`] of an index's scalar type, the one place a radius is converted.
///
/// ```
/// use nbhd::{Neighborhood, NeighborhoodSpec};
///
/// assert_eq!(NeighborhoodSpec::knn(4).to::<f32>()?, Neighborhood::Knn { k: 4 });
/// let eps_k = NeighborhoodSpec::knn_radius(4, 0.5).to::<f64>()?;
/// assert_eq!(eps_k, Neighborhood::KnnRadius { k: 4, radius: 0.5 });
/// // a radius whose square a float cannot hold
/// assert!(NeighborhoodSpec::radius(1e30).to::<f32>().is_err());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeighborhoodSpec {
    /// How many nearest points (≥ 1), if bounded by a count.
    pub k: Option<usize>,
    /// Plain Euclidean radius (finite, ≥ 0, inclusive), if bounded by a distance.
    pub radius: Option<f64>,
    /// Order a radius query's result by `(sq_dist, index)` (k-nearest results always are).
    pub sorted: bool,
}

impl NeighborhoodSpec {
    /// The `k` nearest points.
    pub fn knn(k: usize) -> Self {
        Self {
            k: Some(k),
            radius: None,
            sorted: true,
        }
    }

    /// Every point within `radius`, ordered.
    pub fn radius(radius: f64) -> Self {
        Self {
            k: None,
            radius: Some(radius),
            sorted: true,
        }
    }

    /// The `k` nearest among the points within `radius`.
    pub fn knn_radius(k: usize, radius: f64) -> Self {
        Self {
            k: Some(k),
            radius: Some(radius),
            sorted: true,
        }
    }

    /// The neighbourhood in the scalar type `T`, checked ([`Neighborhood::validate`]): a
    /// negative, NaN or infinite radius is [`NbhdError::InvalidRadius`], a finite one whose
    /// square `T` cannot hold [`NbhdError::RadiusOutOfRange`], both naming the value given;
    /// neither `k` nor a radius is [`NbhdError::InvalidOption`].
    pub fn to<T: Scalar>(&self) -> Result<Neighborhood<T>> {
        let nbhd = self.to_with(&QueryOptions::default())?;
        nbhd.validate()?;
        Ok(nbhd)
    }

    /// The neighbourhood in the scalar type `T` for a query under `options`
    /// (`NeighborIndex::search_with` (`src/index/`), which checks the
    /// radius's key in the metric): a radius whose key `T` cannot hold is
    /// [`NbhdError::RadiusOutOfRange`] naming the value given — under `options.strict` no bound
    /// (beyond `T`'s range, the largest finite `T`). Other errors as [`NeighborhoodSpec::to`].
    pub fn to_with<T: Scalar>(&self, options: &QueryOptions) -> Result<Neighborhood<T>> {
        let metric = options.metric.canonical()?;
        let radius = |r: f64| {
            if !(r.is_finite() && r >= 0.0) {
                return Err(NbhdError::InvalidRadius(r));
            }
            let t = T::from_f64(r);
            if t.is_finite() && (options.strict || metric.key_of(t).is_finite()) {
                Ok(t)
            } else if options.strict {
                Ok(T::INFINITY.next_down())
            } else {
                Err(NbhdError::RadiusOutOfRange {
                    radius: r,
                    scalar: match T::TYPE {
                        crate::scalar::ScalarType::F32 => "f32",
                        crate::scalar::ScalarType::F64 => "f64",
                    },
                    max: metric.max_radius::<T>(),
                })
            }
        };
        Ok(match (self.k, self.radius) {
            (Some(k), None) => Neighborhood::Knn { k },
            (None, Some(r)) => Neighborhood::Radius {
                radius: radius(r)?,
                sorted: self.sorted,
            },
            (Some(k), Some(r)) => Neighborhood::KnnRadius {
                k,
                radius: radius(r)?,
            },
            (None, None) => {
                return Err(NbhdError::InvalidOption {
                    name: "neighborhood",
                    reason: "give k, a radius, or both".into(),
                })
            }
        })
    }
}

/// What to search around.
#[derive(Clone, Copy, Debug)]
pub enum Query<'a, T> {
    /// An arbitrary point (its length must be the tree's dimension), optionally leaving out
    /// one stored point by its caller index.
    Point {
        /// The query coordinates.
        coords: &'a [T],
        /// A caller index to leave out of the result, if any.
        exclude: Option<u32>,
    },
    /// The stored point with this caller index.
    Stored {
        /// The caller's index of the point.
        index: u32,
        /// Leave the point itself out (its duplicates at distance 0 stay).
        exclude_self: bool,
    },
}

impl<'a, T> Query<'a, T> {
    /// An arbitrary query point.
    pub fn point(coords: &'a [T]) -> Self {
        Query::Point {
            coords,
            exclude: None,
        }
    }

    /// The stored point `index`, itself left out of its neighbourhood.
    pub fn stored_excluding_self(index: u32) -> Self {
        Query::Stored {
            index,
            exclude_self: true,
        }
    }

    /// The stored point `index`, itself included (at distance 0).
    pub fn stored(index: u32) -> Self {
        Query::Stored {
            index,
            exclude_self: false,
        }
    }
}

/// Anything that answers neighbourhood queries on a fixed point set: the k-d tree and the
/// baselines. One interface so that the baselines serve as oracles in tests and as
/// comparisons in benchmarks.
pub trait NeighborSearch<T: Scalar>: Sync {
    /// Dimension of the stored points.
    fn dim(&self) -> usize;

    /// Number of points the caller passed in (the range of caller indices).
    fn source_len(&self) -> usize;

    /// Writes the neighbourhood of `query` into `out` (cleared first), ordered by
    /// `(sq_dist, index)` unless an unsorted radius query was asked for.
    fn search(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()>;
}
/// Resolves a query to its coordinates and the caller index to leave out: the shared first
/// step of every searcher. `slot_of` maps caller indices to the searcher's slots.
pub(crate) fn resolve_query<'q, T: Scalar>(
    query: Query<'q, T>,
    dim: usize,
    source_len: usize,
    slot_of: &[u32],
    point_of_slot: impl Fn(usize) -> &'q [T],
) -> Result<(&'q [T], Option<u32>)> {
    match query {
        Query::Point { coords, exclude } => {
            if coords.len() != dim {
                return Err(NbhdError::DimensionMismatch {
                    expected: dim,
                    got: coords.len(),
                });
            }
            if let Some(j) = coords.iter().position(|c| !c.is_finite()) {
                return Err(NbhdError::NonFiniteQuery {
                    query: None,
                    coordinate: j,
                });
            }
            Ok((coords, exclude))
        }
        Query::Stored {
            index,
            exclude_self,
        } => {
            let i = index as usize;
            if i >= source_len {
                return Err(NbhdError::IndexOutOfRange {
                    index: i,
                    count: source_len,
                });
            }
            let slot = slot_of[i];
            if slot == u32::MAX {
                return Err(NbhdError::SkippedPoint { index: i });
            }
            Ok((point_of_slot(slot as usize), exclude_self.then_some(index)))
        }
    }
}
