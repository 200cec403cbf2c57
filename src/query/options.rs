//! How a query measures, beyond which neighbourhood it asks for: the metric (a Minkowski
//! p-norm, `src/metric.rs`), approximation by `eps`, and a strict radius. The default is the
//! exact Euclidean query with an inclusive radius that every plain query method answers.
//!
//! Keys: results carry each metric's key in `sq_dist` (squared for Euclidean, the distance for
//! p = 1 and ∞, `Σ |x_j|^p` otherwise; [`Metric::distance_of`] converts), and a radius is
//! compared as its key ([`Metric::key_of`]).
//!
//! Approximation (`eps > 0`, the rule of Arya & Mount that scipy's `cKDTree` keeps): a cell is
//! skipped when its lower bound exceeds the result's bound divided by `(1 + eps)`, in keys
//! `bound · f` with `f = 1 / (1 + eps)^p` ([`Metric::eps_factor`]). So
//! - k nearest: the i-th neighbour returned is within `(1 + eps)` times the true i-th distance;
//! - radius: cells are pruned at `r / (1 + eps)` and points accepted up to `r · (1 + eps)`, so the
//!   result holds every point within `r / (1 + eps)` and none beyond `r · (1 + eps)`;
//! - the ε-k-neighbourhood: the k-nearest rule among the points within `r · (1 + eps)`.
//!
//! Which points an approximate query returns depends on the tree (its pivot policy), never on
//! the thread count.

use super::Neighborhood;
use crate::error::{NbhdError, Result};
use crate::metric::{Measure, Metric};
use crate::scalar::{Scalar, ScalarType};

/// Options of a query (`NeighborIndex::search_with` (`src/index/`), and
/// of tables through `TableOptions::query` (`src/table.rs`)).
///
/// ```
/// use nbhd::{Metric, QueryOptions};
///
/// let manhattan = QueryOptions { metric: Metric::Manhattan, ..QueryOptions::default() };
/// assert_eq!(QueryOptions::with_p(1.0)?, manhattan);
/// assert_eq!(QueryOptions::default().metric, Metric::Euclidean);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct QueryOptions {
    /// The distance measured (default Euclidean).
    pub metric: Metric,
    /// Approximation: `0` exact (the default), `eps > 0` allows each returned distance to
    /// exceed the exact one by a factor `1 + eps` (the rules of this module's doc). Finite, ≥ 0.
    pub eps: f64,
    /// A radius is exclusive (`‖x − q‖ < r`) instead of inclusive (scipy's
    /// `distance_upper_bound`); a finite radius whose key overflows the tree's scalar type is
    /// then no bound at all.
    pub strict: bool,
}

impl QueryOptions {
    /// The defaults (exact Euclidean, inclusive radius) as a constant.
    pub const DEFAULT: Self = Self {
        metric: Metric::Euclidean,
        eps: 0.0,
        strict: false,
    };

    /// Exact queries by the Minkowski `p`-norm ([`Metric::from_p`]).
    pub fn with_p(p: f64) -> Result<Self> {
        Ok(Self {
            metric: Metric::from_p(p)?,
            ..Self::default()
        })
    }

    /// Checks the options: a Minkowski `p ∈ [1, ∞]`, a finite `eps ≥ 0`
    /// ([`NbhdError::InvalidOption`]).
    pub fn validate(&self) -> Result<()> {
        self.metric.canonical()?;
        if !(self.eps.is_finite() && self.eps >= 0.0) {
            return Err(NbhdError::InvalidOption {
                name: "eps",
                reason: format!("must be finite and ≥ 0, got {}", self.eps),
            });
        }
        Ok(())
    }

    /// `nbhd` under these options, checked and resolved for a traversal.
    pub(crate) fn plan<T: Scalar>(&self, nbhd: Neighborhood<T>) -> Result<Plan<T>> {
        self.validate()?;
        let metric = self.metric.canonical()?;
        if metric == Metric::Euclidean && self.eps == 0.0 && !self.strict {
            nbhd.validate()?;
            let (k, bound) = nbhd.limits();
            return Ok(Plan {
                nbhd,
                plain: true,
                k,
                bound,
                measure: Measure::EUCLIDEAN,
            });
        }
        let f = metric.eps_factor(self.eps);
        let (k, bound, scale) = match nbhd {
            Neighborhood::Knn { k: 0 } | Neighborhood::KnnRadius { k: 0, .. } => {
                return Err(NbhdError::ZeroK)
            }
            Neighborhood::Knn { k } => (k, T::INFINITY, 1.0 / f),
            // pruned at r / (1 + eps): the cells' bounds scaled by 1/f against r·(1+eps)'s key
            Neighborhood::Radius { radius, .. } => (
                usize::MAX,
                self.radius_key(metric, f, radius)?,
                1.0 / (f * f),
            ),
            Neighborhood::KnnRadius { k, radius } => {
                (k, self.radius_key(metric, f, radius)?, 1.0 / f)
            }
        };
        Ok(Plan {
            nbhd,
            plain: false,
            k,
            bound,
            measure: Measure { metric, scale },
        })
    }

    /// The key a radius `r` admits up to: that of `r · (1 + eps)`, its predecessor if strict.
    fn radius_key<T: Scalar>(&self, metric: Metric, f: f64, r: T) -> Result<T> {
        if !(r.is_finite() && r >= T::ZERO) {
            return Err(NbhdError::InvalidRadius(r.to_f64()));
        }
        let key = metric.key_of(r);
        if !key.is_finite() {
            if self.strict {
                return Ok(T::INFINITY);
            }
            return Err(NbhdError::RadiusOutOfRange {
                radius: r.to_f64(),
                scalar: match T::TYPE {
                    ScalarType::F32 => "f32",
                    ScalarType::F64 => "f64",
                },
                max: metric.max_radius::<T>(),
            });
        }
        let outer = if f == 1.0 {
            key
        } else {
            key * T::from_f64(1.0 / f)
        };
        Ok(if self.strict {
            outer.next_down()
        } else {
            outer
        })
    }
}

/// A neighbourhood resolved under its [`QueryOptions`] for the traversal.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Plan<T> {
    /// The neighbourhood asked for.
    pub nbhd: Neighborhood<T>,
    /// The default exact Euclidean query with an inclusive radius (the plain queries' paths).
    pub plain: bool,
    /// How many neighbours at most (`usize::MAX` for a radius query).
    pub k: usize,
    /// The largest key admitted (∞ without a radius).
    pub bound: T,
    /// How the traversal measures and prunes.
    pub measure: Measure,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strict_radii_admit_keys_below_the_radius_only() {
        let strict = QueryOptions {
            strict: true,
            ..QueryOptions::default()
        };
        let plan = strict
            .plan(Neighborhood::Radius {
                radius: 2.0f64,
                sorted: true,
            })
            .unwrap();
        assert!(plan.bound < 4.0 && 4.0f64.next_down() <= plan.bound);
        // a radius whose square overflows is no bound under `strict`, refused otherwise
        let huge = Neighborhood::KnnRadius {
            k: 3,
            radius: 1e30f32,
        };
        assert_eq!(strict.plan(huge).unwrap().bound, f32::INFINITY);
        assert!(matches!(
            QueryOptions::default().plan(huge),
            Err(NbhdError::RadiusOutOfRange { .. })
        ));
        // Manhattan keys are distances: the same radius fits
        let l1 = QueryOptions::with_p(1.0).unwrap();
        assert_eq!(l1.plan(huge).unwrap().bound, 1e30f32);
    }

    #[test]
    fn bad_eps_and_p_are_refused() {
        for eps in [-0.1, f64::NAN, f64::INFINITY] {
            let o = QueryOptions {
                eps,
                ..QueryOptions::default()
            };
            assert!(matches!(
                o.plan(Neighborhood::<f32>::Knn { k: 1 }),
                Err(NbhdError::InvalidOption { name: "eps", .. })
            ));
        }
        let o = QueryOptions {
            metric: Metric::Minkowski(0.5),
            ..QueryOptions::default()
        };
        assert!(matches!(
            o.plan(Neighborhood::<f64>::Knn { k: 1 }),
            Err(NbhdError::InvalidOption { name: "p", .. })
        ));
    }
}
