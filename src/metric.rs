//! The distances a query may measure by: the Minkowski p-norms `‖x‖_p = (Σ |x_j|^p)^(1/p)`,
//! `p ∈ [1, ∞]` (thesis Section 2.1 defines neighbourhoods over a metric; the Euclidean norm,
//! p = 2, is the default of every query).
//!
//! A query compares *keys*, not distances: a monotone function of the distance that is cheap to
//! compute and needs no root, the metric's own form — `Σ x_j²` for p = 2 (the squared distance
//! every result has always carried), `Σ |x_j|` for p = 1, `max |x_j|` for p = ∞ and `Σ |x_j|^p`
//! for any other p (the forms scipy's `cKDTree` compares too). A radius becomes a key once per
//! query ([`Metric::key_of`]); a key becomes a distance with [`Metric::distance_of`].
//!
//! Inside the traversals a metric is a `Norm`: how one axis difference contributes (`term`)
//! and how contributions combine (`fold`), chosen once per call (`Measure::apply`) so that
//! each norm gets its own monomorphised search. Keys are folded over the axes in order,
//! `fold(… fold(fold(0, term(t0)), term(t1)) …)`, by every searcher alike (tree, brute force),
//! so every searcher gives the same bits.

use crate::error::{NbhdError, Result};
use crate::scalar::Scalar;

/// The distance a query measures by: a Minkowski p-norm, `p ∈ [1, ∞]`.
///
/// ```
/// use nbhd::Metric;
///
/// assert_eq!(Metric::from_p(1.0)?, Metric::Manhattan);
/// assert_eq!(Metric::from_p(f64::INFINITY)?, Metric::Chebyshev);
/// assert_eq!(Metric::from_p(3.0)?, Metric::Minkowski(3.0));
/// // keys: squared for p = 2, plain for p = 1 and ∞, the p-th power otherwise
/// assert_eq!(Metric::Euclidean.key_of(3.0f64), 9.0);
/// assert_eq!(Metric::Minkowski(3.0).key_of(2.0f64), 8.0);
/// assert_eq!(Metric::Euclidean.distance_of(9.0f64), 3.0);
/// assert!(Metric::from_p(0.5).is_err());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Metric {
    /// p = 2: `√(Σ x_j²)`; keys are squared distances.
    #[default]
    Euclidean,
    /// p = 1: `Σ |x_j|`; keys are the distances.
    Manhattan,
    /// p = ∞: `max |x_j|`; keys are the distances.
    Chebyshev,
    /// Any `p ≥ 1` (1, 2 and ∞ are served by the variants above): `(Σ |x_j|^p)^(1/p)`; keys
    /// are `Σ |x_j|^p`.
    Minkowski(f64),
}

impl Metric {
    /// The p-norm: 1, 2 and ∞ as [`Metric::Manhattan`], [`Metric::Euclidean`] and
    /// [`Metric::Chebyshev`], any other `p ≥ 1` as [`Metric::Minkowski`].
    ///
    /// Errors: `p < 1` or NaN ([`NbhdError::InvalidOption`]: not a norm).
    pub fn from_p(p: f64) -> Result<Self> {
        if p.is_nan() || p < 1.0 {
            return Err(NbhdError::InvalidOption {
                name: "p",
                reason: format!("the Minkowski p must lie in [1, ∞], got {p}"),
            });
        }
        Ok(if p == 1.0 {
            Metric::Manhattan
        } else if p == 2.0 {
            Metric::Euclidean
        } else if p == f64::INFINITY {
            Metric::Chebyshev
        } else {
            Metric::Minkowski(p)
        })
    }

    /// The `p` of the norm (∞ for [`Metric::Chebyshev`]).
    pub fn p(self) -> f64 {
        match self {
            Metric::Euclidean => 2.0,
            Metric::Manhattan => 1.0,
            Metric::Chebyshev => f64::INFINITY,
            Metric::Minkowski(p) => p,
        }
    }

    /// The metric checked and in its fastest form ([`Metric::from_p`] of [`Metric::p`]):
    /// `Minkowski(2.0)` is `Euclidean`, and so on.
    pub fn canonical(self) -> Result<Self> {
        Self::from_p(self.p())
    }

    /// The key of a distance `r ≥ 0` (the form results carry and radii are compared in):
    /// `r²`, `r`, `r`, `r^p`, computed in `T`; ∞ stays ∞. May overflow to ∞ for a finite `r`.
    pub fn key_of<T: Scalar>(self, r: T) -> T {
        match self {
            Metric::Euclidean => r * r,
            Metric::Manhattan | Metric::Chebyshev => r,
            Metric::Minkowski(p) => r.powf(T::from_f64(p)),
        }
    }

    /// The distance of a key: `√key`, `key`, `key`, `key^(1/p)` (scipy's conversion too).
    pub fn distance_of<T: Scalar>(self, key: T) -> T {
        match self {
            Metric::Euclidean => key.sqrt(),
            Metric::Manhattan | Metric::Chebyshev => key,
            Metric::Minkowski(p) => key.powf(T::from_f64(1.0 / p)),
        }
    }

    /// The factor `1 / (1 + eps)^p` that turns the key of a distance `d` into the key of
    /// `d / (1 + eps)` (`1 / (1 + eps)` for p = ∞): how approximate searches prune.
    pub fn eps_factor(self, eps: f64) -> f64 {
        match self {
            Metric::Chebyshev => 1.0 / (1.0 + eps),
            _ => 1.0 / (1.0 + eps).powf(self.p()),
        }
    }

    /// The largest distance whose key `T` holds: `√MAX`, `MAX`, `MAX`, `MAX^(1/p)`.
    pub(crate) fn max_radius<T: Scalar>(self) -> f64 {
        let max = match T::TYPE {
            crate::scalar::ScalarType::F32 => f32::MAX as f64,
            crate::scalar::ScalarType::F64 => f64::MAX,
        };
        self.distance_of(max)
    }
}

/// The spelling of the command line and reports: `l2`, `l1`, `linf`, `p=<x>`.
impl std::fmt::Display for Metric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Metric::Euclidean => f.write_str("l2"),
            Metric::Manhattan => f.write_str("l1"),
            Metric::Chebyshev => f.write_str("linf"),
            Metric::Minkowski(p) => write!(f, "p={p}"),
        }
    }
}

/// Reads `l2`/`euclidean`, `l1`/`manhattan`, `linf`/`chebyshev`, or `p=<x>` (any `x ≥ 1`,
/// `inf` included, as [`Metric::from_p`]).
///
/// ```
/// use nbhd::Metric;
///
/// assert_eq!("l1".parse::<Metric>()?, Metric::Manhattan);
/// assert_eq!("p=3".parse::<Metric>()?, Metric::Minkowski(3.0));
/// assert_eq!("p=inf".parse::<Metric>()?, Metric::Chebyshev);
/// assert_eq!(Metric::Minkowski(1.5).to_string().parse::<Metric>()?, Metric::Minkowski(1.5));
/// assert!("p=0.5".parse::<Metric>().is_err());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
impl std::str::FromStr for Metric {
    type Err = NbhdError;

    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim().to_ascii_lowercase();
        match t.as_str() {
            "l2" | "euclidean" => return Ok(Metric::Euclidean),
            "l1" | "manhattan" => return Ok(Metric::Manhattan),
            "linf" | "chebyshev" => return Ok(Metric::Chebyshev),
            _ => {}
        }
        match t.strip_prefix("p=").map(str::parse::<f64>) {
            Some(Ok(p)) => Metric::from_p(p),
            _ => Err(NbhdError::InvalidOption {
                name: "metric",
                reason: format!("{s:?} is none of l2, l1, linf, p=<x> (x ≥ 1)"),
            }),
        }
    }
}

/// How one traversal measures (plumbing of `NeighborIndex::visit_with`): the metric in its
/// canonical form and the factor `scale ≥ 1` a cell's lower bound is multiplied by before it is
/// compared with the result's bound (1 for an exact search; `(1 + eps)^p` or its square for an
/// approximate one, `src/query/mod.rs`).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measure {
    /// The metric, canonical ([`Metric::canonical`]).
    pub metric: Metric,
    /// The factor on cells' lower bounds.
    pub scale: f64,
}

/// What runs with a [`Norm`] chosen at run time: [`Measure::apply`] calls `with` once, with
/// the norm's own type, so the work inside is monomorphised per norm.
pub(crate) trait NormUser<T: Scalar> {
    /// What the work returns.
    type Out;
    /// The work, for the norm `norm`.
    fn with<N: Norm<T>>(self, norm: N) -> Self::Out;
}

impl Measure {
    /// The exact Euclidean measure (what the default queries use).
    pub const EUCLIDEAN: Measure = Measure {
        metric: Metric::Euclidean,
        scale: 1.0,
    };

    /// Runs `user` with the norm of this measure: [`L2`] for the exact Euclidean one (the
    /// default queries' arithmetic), otherwise the metric's norm with its cell bounds
    /// scaled ([`Scaled`]). The general p's bounds get a few ulps of slack, as the platform's
    /// `pow` is not guaranteed monotone (a bound must never exceed a point's computed key).
    pub(crate) fn apply<T: Scalar, U: NormUser<T>>(&self, user: U) -> U::Out {
        // a huge eps: the largest finite factor (an infinite one would make a bound of 0 NaN)
        let scale = T::from_f64(self.scale).min_of(T::MAX);
        match self.metric {
            Metric::Euclidean if self.scale == 1.0 => user.with(L2),
            Metric::Euclidean => user.with(Scaled(L2, scale)),
            Metric::Manhattan => user.with(Scaled(L1, scale)),
            Metric::Chebyshev => user.with(Scaled(LInf, scale)),
            Metric::Minkowski(p) => {
                let slack = T::from_f64(1.0) - T::EPSILON * T::from_f64(16.0);
                user.with(Scaled(Lp(T::from_f64(p)), scale * slack))
            }
        }
    }
}

/// A norm as a traversal computes it (crate-private): the key of a difference vector is
/// `fold(… fold(fold(0, term(t0)), term(t1)) …)` over the axes in order. `term` and `fold`
/// must be monotone in their arguments (for non-negative values) so that a cell's bound, the
/// same fold over gaps no larger than a point's differences, never exceeds the point's key.
pub(crate) trait Norm<T: Scalar>: Copy + Send + Sync {
    /// The contribution of one axis difference `t` (any sign).
    fn term(self, t: T) -> T;

    /// Combines the key so far with one more contribution.
    fn fold(self, acc: T, x: T) -> T;

    /// A cell's lower bound `lb` as it is compared with a result's bound (`lb` itself for an
    /// exact norm).
    #[inline(always)]
    fn lower(self, lb: T) -> T {
        lb
    }

    /// The key of `q − p` over their first `d` axes.
    #[inline(always)]
    fn key(self, q: &[T], p: &[T], d: usize) -> T {
        let mut s = T::ZERO;
        for j in 0..d {
            s = self.fold(s, self.term(q[j] - p[j]));
        }
        s
    }
}

/// p = 2: `Σ t²` (keys are squared distances).
#[derive(Clone, Copy)]
pub(crate) struct L2;

impl<T: Scalar> Norm<T> for L2 {
    #[inline(always)]
    fn term(self, t: T) -> T {
        t * t
    }
    #[inline(always)]
    fn fold(self, acc: T, x: T) -> T {
        acc + x
    }
}

/// p = 1: `Σ |t|`.
#[derive(Clone, Copy)]
pub(crate) struct L1;

impl<T: Scalar> Norm<T> for L1 {
    #[inline(always)]
    fn term(self, t: T) -> T {
        t.abs()
    }
    #[inline(always)]
    fn fold(self, acc: T, x: T) -> T {
        acc + x
    }
}

/// p = ∞: `max |t|`.
#[derive(Clone, Copy)]
pub(crate) struct LInf;

impl<T: Scalar> Norm<T> for LInf {
    #[inline(always)]
    fn term(self, t: T) -> T {
        t.abs()
    }
    #[inline(always)]
    fn fold(self, acc: T, x: T) -> T {
        acc.max_of(x)
    }
}

/// Any finite `p ≥ 1`: `Σ |t|^p` (the exponent in `T`).
#[derive(Clone, Copy)]
pub(crate) struct Lp<T>(pub T);

impl<T: Scalar> Norm<T> for Lp<T> {
    #[inline(always)]
    fn term(self, t: T) -> T {
        t.abs().powf(self.0)
    }
    #[inline(always)]
    fn fold(self, acc: T, x: T) -> T {
        acc + x
    }
}

/// A norm whose cells' lower bounds are multiplied by a factor (approximate search, slack),
/// at most the largest finite value: a scaled bound that overflowed would tie with an
/// infinite result bound (keys of a large p overflow) and prune by index a cell whose points
/// may enter.
#[derive(Clone, Copy)]
pub(crate) struct Scaled<N, T>(pub N, pub T);

impl<T: Scalar, N: Norm<T>> Norm<T> for Scaled<N, T> {
    #[inline(always)]
    fn term(self, t: T) -> T {
        self.0.term(t)
    }
    #[inline(always)]
    fn fold(self, acc: T, x: T) -> T {
        self.0.fold(acc, x)
    }
    #[inline(always)]
    fn lower(self, lb: T) -> T {
        (lb * self.1).min_of(T::MAX)
    }
}

/// A periodic box (a torus, scipy's `boxsize`): on a periodic axis of size `L` the points lie in
/// `[0, L)`, a query is wrapped into it, and the difference `t = |x_j − q_j|` counts as its
/// nearest image, `min(t, L − t)` — every point once, at its image nearest to the query, even
/// for radii beyond `L / 2`. An axis of size 0 or +∞ is open (not periodic); open axes are held
/// as +∞, so that one formula serves every axis (`min(t, ∞ − t) = t`).
///
/// ```
/// use nbhd::metric::Period;
///
/// let period = Period::<f64>::new(&[1.0, 0.0], 2)?.expect("one periodic axis");
/// assert_eq!(period.sizes(), [1.0, 0.0]);
/// let mut q = [0.0; 2];
/// period.wrap(&[-0.25, -0.25], &mut q); // the open axis is left as it is
/// assert_eq!(q, [0.75, -0.25]);
/// assert!(Period::<f64>::new(&[0.0, f64::INFINITY], 2)?.is_none()); // no periodic axis
/// assert!(Period::<f64>::new(&[-1.0], 1).is_err());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Period<T> {
    /// Per axis the box size, +∞ on an open axis.
    sizes: Vec<T>,
}

impl<T: Scalar> Period<T> {
    /// The box of the sizes `boxsize` (one per axis, or one for every axis), converted to `T`;
    /// `None` if no axis is periodic (every size 0 or +∞).
    ///
    /// Errors ([`NbhdError::InvalidOption`]): a size negative or NaN, or a positive size that
    /// `T` rounds to 0; a slice whose length is neither 1 nor `dim`.
    pub fn new(boxsize: &[f64], dim: usize) -> Result<Option<Self>> {
        let invalid = |reason: String| NbhdError::InvalidOption {
            name: "boxsize",
            reason,
        };
        if boxsize.len() != dim && boxsize.len() != 1 {
            return Err(invalid(format!(
                "{} sizes given for points of dimension {dim} (give 1 or {dim})",
                boxsize.len()
            )));
        }
        let mut sizes = Vec::with_capacity(dim);
        for j in 0..dim {
            let l = boxsize[j.min(boxsize.len() - 1)];
            let t = T::from_f64(l);
            if l.is_nan() || l < 0.0 || (l > 0.0 && t == T::ZERO) {
                return Err(invalid(format!(
                    "the size of axis {j} must be 0 (open), positive or +inf (open), got {l}"
                )));
            }
            sizes.push(if l == 0.0 { T::INFINITY } else { t });
        }
        Ok(sizes
            .iter()
            .any(|l| l.is_finite())
            .then_some(Self { sizes }))
    }

    /// The box sizes per axis, 0 for an open axis (the form [`Period::new`] takes).
    pub fn sizes(&self) -> Vec<f64> {
        let open = |l: T| if l.is_finite() { l.to_f64() } else { 0.0 };
        self.sizes.iter().map(|&l| open(l)).collect()
    }

    /// The first axis of `p` outside the box: a coordinate below 0 or not below `L` on a
    /// periodic axis (scipy refuses such data too; queries, unlike data, are wrapped).
    pub fn outside(&self, p: &[T]) -> Option<usize> {
        (0..p.len()).find(|&j| {
            let l = self.sizes[j];
            l.is_finite() && !(p[j] >= T::ZERO && p[j] < l)
        })
    }

    /// Writes `q` wrapped into the box to `out`: `q mod L` in `[0, L)` on every periodic axis
    /// (a remainder that rounds up to `L` is 0, its nearest value in the box), `q` itself on
    /// an open one. `q` finite.
    pub fn wrap(&self, q: &[T], out: &mut [T]) {
        for ((o, &x), &l) in out.iter_mut().zip(q).zip(&self.sizes) {
            *o = if !l.is_finite() || (x >= T::ZERO && x < l) {
                x
            } else {
                // `%` is exact (IEEE remainder of truncation); a negative one moves up by L
                let r = x % l;
                let r = if r < T::ZERO { r + l } else { r };
                if r < l {
                    r
                } else {
                    T::ZERO
                }
            };
        }
    }

    /// The key (under `norm`) from the wrapped `q` to `p` (in the box): each axis difference
    /// `t = |q_j − p_j|` taken at its nearest image, `min(t, L − t)`, folded in axis order.
    #[inline(always)]
    pub(crate) fn key<N: Norm<T>>(&self, norm: N, q: &[T], p: &[T]) -> T {
        let mut s = T::ZERO;
        for j in 0..q.len() {
            let t = (q[j] - p[j]).abs();
            s = norm.fold(s, norm.term(t.min_of(self.sizes[j] - t)));
        }
        s
    }

    /// A lower bound (under `norm`, through its `lower`) of the key from the wrapped `q` to
    /// any point of the box `[lo, hi]` (inside the periodic box): per axis the gap to the
    /// nearer of the interval and its image, `min(lo − q, L − (hi − q))` below it and
    /// `min(q − hi, L − (q − lo))` above it. Each is a rounding of a value no larger than the
    /// same expression for a point of the interval (rounding is monotone), and the terms are
    /// folded in the order of [`Period::key`], so the bound never exceeds a point's key.
    #[inline]
    pub(crate) fn box_key<N: Norm<T>>(&self, norm: N, q: &[T], lo: &[T], hi: &[T]) -> T {
        let mut s = T::ZERO;
        for j in 0..q.len() {
            let l = self.sizes[j];
            let gap = if q[j] < lo[j] {
                (lo[j] - q[j]).min_of(l - (hi[j] - q[j]))
            } else if q[j] > hi[j] {
                (q[j] - hi[j]).min_of(l - (q[j] - lo[j]))
            } else {
                T::ZERO
            };
            s = norm.fold(s, norm.term(gap));
        }
        norm.lower(s)
    }

    /// A lower bound (under `norm`, through its `lower`) of the key between any point of the
    /// box `[la, ha]` and any point of the box `[lb, hb]` (both inside the periodic box): per
    /// axis the smaller of the gap between the two intervals and `L − t`, `t` the widest
    /// difference of their points (`max(hb − la, ha − lb)`). A pair's difference `t'` rounds to
    /// at least the rounded gap and at most the rounded `t` (rounding is monotone), so each term
    /// is at most the pair's `min(t', L − t')`, and the terms are folded in the order of
    /// [`Period::key`]: the bound never exceeds a pair's key.
    #[inline]
    pub(crate) fn boxes_key<N: Norm<T>>(
        &self,
        norm: N,
        la: &[T],
        ha: &[T],
        lb: &[T],
        hb: &[T],
    ) -> T {
        let mut s = T::ZERO;
        for j in 0..la.len() {
            let gap = interval_gap(la[j], ha[j], lb[j], hb[j]);
            let widest = (hb[j] - la[j]).max_of(ha[j] - lb[j]);
            s = norm.fold(s, norm.term(gap.min_of(self.sizes[j] - widest)));
        }
        norm.lower(s)
    }
}

/// The gap between the intervals `[la, ha]` and `[lb, hb]` (0 where they meet): the smallest
/// difference of a point of one and a point of the other, rounded down as each of those
/// differences rounds (rounding is monotone), so a lower bound of every pair's difference.
#[inline(always)]
pub(crate) fn interval_gap<T: Scalar>(la: T, ha: T, lb: T, hb: T) -> T {
    if lb > ha {
        lb - ha
    } else if la > hb {
        la - hb
    } else {
        T::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct KeyOf<'a>(&'a [f64], &'a [f64]);

    impl NormUser<f64> for KeyOf<'_> {
        type Out = f64;
        fn with<N: Norm<f64>>(self, norm: N) -> f64 {
            norm.key(self.0, self.1, self.0.len())
        }
    }

    #[test]
    fn keys_are_each_norms_form() {
        let (q, p) = ([1.0, -2.0, 0.5], [4.0, 2.0, 0.5]);
        let key = |metric| Measure { metric, scale: 1.0 }.apply(KeyOf(&q, &p));
        assert_eq!(key(Metric::Euclidean), 25.0);
        assert_eq!(key(Metric::Manhattan), 7.0);
        assert_eq!(key(Metric::Chebyshev), 4.0);
        assert_eq!(key(Metric::Minkowski(3.0)), 27.0 + 64.0);
        for (m, d) in [
            (Metric::Euclidean, 5.0),
            (Metric::Manhattan, 7.0),
            (Metric::Chebyshev, 4.0),
        ] {
            assert_eq!(m.distance_of(key(m)), d);
            assert_eq!(m.key_of(d), key(m));
        }
    }

    #[test]
    fn p_below_one_and_nan_are_refused() {
        for p in [0.999, 0.0, -1.0, f64::NAN, f64::NEG_INFINITY] {
            assert!(matches!(
                Metric::from_p(p),
                Err(NbhdError::InvalidOption { name: "p", .. })
            ));
            assert!(Metric::Minkowski(p).canonical().is_err());
        }
        assert_eq!(Metric::Minkowski(2.0).canonical(), Ok(Metric::Euclidean));
        assert_eq!(
            Metric::Minkowski(1.5).canonical(),
            Ok(Metric::Minkowski(1.5))
        );
    }

    #[test]
    fn eps_factors_shrink_keys_by_one_plus_eps() {
        assert_eq!(Metric::Euclidean.eps_factor(1.0), 0.25);
        assert_eq!(Metric::Manhattan.eps_factor(1.0), 0.5);
        assert_eq!(Metric::Chebyshev.eps_factor(1.0), 0.5);
        assert_eq!(Metric::Minkowski(3.0).eps_factor(1.0), 0.125);
        assert_eq!(Metric::Minkowski(3.0).eps_factor(0.0), 1.0);
    }
}
