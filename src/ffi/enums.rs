//! Every C enum of the ABI, each with its conversions to and from the core's type, written
//! once: the tree's choices (scalar type, pivot policy, median algorithm, non-finite policy,
//! neighbourhood kind) and the smoothing's (units, weighting, feature criterion, orientation,
//! progress stage).
//!
//! C may store any integer in an enum-typed field, and a Rust enum holding a value outside
//! its variants is undefined behaviour; so these enums are never read from C memory as Rust
//! values. `fields.rs` reads an enum field as `int` and checks it against `CEnum`.

use std::ffi::c_int;

use glam::DVec3;

use super::status::FfiError;
use crate::error::NbhdError;
use crate::geometry::Orientation;
use crate::metric::Metric;
use crate::packed::NonFinitePolicy;
use crate::scalar::ScalarType;
use crate::smooth::{Curvature, FeatureCriterion, Length, Stage, Weighting};
use crate::tree::{MedianAlgorithm, PivotPolicy};

/// A C enum of this ABI: its values and name, to check an integer read from C.
pub(crate) trait CEnum: Copy + 'static {
    /// The C name of the enum, for messages.
    const C_NAME: &'static str;
    /// Every variant.
    const ALL: &'static [Self];
    /// The integer value of a variant.
    fn value(self) -> c_int;
    /// The variant with integer value `raw`, if any.
    fn from_value(raw: c_int) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.value() == raw)
    }
}

/// Implements [`CEnum`] for a C enum and asserts it has the size of `int`.
macro_rules! c_enum {
    ($ty:ident, [$($var:ident),+ $(,)?]) => {
        impl CEnum for $ty {
            const C_NAME: &'static str = stringify!($ty);
            const ALL: &'static [Self] = &[$($ty::$var),+];
            fn value(self) -> c_int {
                self as c_int
            }
        }
        const _: () = assert!(std::mem::size_of::<$ty>() == std::mem::size_of::<c_int>());
    };
}

/// Converts between a C enum and the core's enum of the same variants, both ways.
macro_rules! same_variants {
    ($c:ident, $core:ident, [$($var:ident),+ $(,)?]) => {
        c_enum!($c, [$($var),+]);
        impl From<$c> for $core {
            fn from(v: $c) -> Self {
                match v {
                    $($c::$var => $core::$var),+
                }
            }
        }
        impl From<$core> for $c {
            fn from(v: $core) -> Self {
                match v {
                    $($core::$var => $c::$var),+
                }
            }
        }
    };
}

/// Coordinate type of a point buffer, of a tree and of its distances.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum nbhd_scalar_type {
    /// 32-bit IEEE 754 `float`.
    #[default]
    F32 = 0,
    /// 64-bit IEEE 754 `double`.
    F64 = 1,
}
same_variants!(nbhd_scalar_type, ScalarType, [F32, F64]);

/// An nbhd_scalar_type passed by value from C: the `int` C passes, checked against
/// [`CEnum`] before use, since a Rust enum holding a value C may pass, such as
/// `(nbhd_scalar_type)7`, would be undefined behaviour. cbindgen.toml names it
/// `nbhd_scalar_type` in the header, so C sees the enum's type.
pub(crate) type ScalarTypeArg = c_int;

/// Reads an enum value `raw` that C passed by value as argument `arg`:
/// NBHD_STATUS_INVALID_ARGUMENT naming it when it is no value of `E`.
pub(crate) fn enum_argument<E: CEnum>(raw: c_int, arg: &str) -> Result<E, FfiError> {
    E::from_value(raw).ok_or_else(|| {
        FfiError::InvalidArgument(format!("{arg} {raw} is not a value of {}", E::C_NAME))
    })
}

/// How a tree node chooses its splitting dimension and pivot (thesis Sections 3.2 and 5.4).
/// Every policy splits by the composite (lexicographic) order, so duplicates never make the
/// tree degenerate.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_pivot_policy {
    /// Dimensions in turn (depth mod d), split at the median (thesis Algorithm 4). Balanced.
    CyclicMedian = 0,
    /// Median of the dimension of largest spread (Omohundro). Balanced.
    SpreadMedian = 1,
    /// The point closest to the middle of the most spread dimension (Moore). Not balanced.
    ClosestToMiddle = 2,
    /// Sliding midpoint (ANN, nanoflann, FLANN). The default.
    SlidingMidpoint = 3,
}
same_variants!(
    nbhd_pivot_policy,
    PivotPolicy,
    [CyclicMedian, SpreadMedian, ClosestToMiddle, SlidingMidpoint]
);

/// How the pivot of a node is found (thesis Section 3.3 and Chapter 6). For one pivot policy
/// every algorithm builds the identical tree; they differ in speed only.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_median_algorithm {
    /// Lists presorted once per dimension, kept sorted by stable partitions (Algorithm 6).
    Presorted = 0,
    /// Sort the node's points, then pick.
    Sort = 1,
    /// Randomised quickselect with a median-of-three pivot (Algorithm 10).
    Quickselect = 2,
    /// Floyd-Rivest selection. The default.
    FloydRivest = 3,
    /// Deterministic median of medians (Algorithm 11).
    MedianOfMedians = 4,
}
same_variants!(
    nbhd_median_algorithm,
    MedianAlgorithm,
    [Presorted, Sort, Quickselect, FloydRivest, MedianOfMedians]
);

/// What a build does with points that have a NaN or infinite coordinate.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_non_finite_policy {
    /// Refuse the input with NBHD_STATUS_NON_FINITE; the message names the first such point.
    /// The default.
    Reject = 0,
    /// Leave such points out; the others keep their indices. Queries by the index of a
    /// skipped point fail with NBHD_STATUS_SKIPPED_POINT; tables give them empty rows.
    Skip = 1,
}
same_variants!(nbhd_non_finite_policy, NonFinitePolicy, [Reject, Skip]);

/// Which neighbourhood a table holds for every row.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_neighborhood_kind {
    /// The k nearest points (`k` >= 1).
    Knn = 0,
    /// All points within `radius` (inclusive), sorted by (squared distance, index).
    Radius = 1,
    /// The k nearest among the points within `radius` (the epsilon-k-neighbourhood).
    KnnRadius = 2,
}
c_enum!(nbhd_neighborhood_kind, [Knn, Radius, KnnRadius]);

/// The distance a query measures by (nbhd_query_options.metric): a Minkowski p-norm.
/// Distances come back as the metric's key ("sq_dists"): squared for EUCLIDEAN, the distance
/// itself for MANHATTAN and CHEBYSHEV, sum |x_j - q_j|^p for MINKOWSKI.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_metric {
    /// p = 2, the default.
    Euclidean = 0,
    /// p = 1: the sum of absolute coordinate differences.
    Manhattan = 1,
    /// p = infinity: the largest absolute coordinate difference.
    Chebyshev = 2,
    /// Any p >= 1, given in nbhd_query_options.p (1, 2 and infinity take the variants above).
    Minkowski = 3,
}
c_enum!(nbhd_metric, [Euclidean, Manhattan, Chebyshev, Minkowski]);

impl nbhd_metric {
    /// The core's metric of this variant, `p` read for MINKOWSKI only.
    pub(crate) fn metric(self, p: f64) -> Result<Metric, NbhdError> {
        match self {
            nbhd_metric::Euclidean => Ok(Metric::Euclidean),
            nbhd_metric::Manhattan => Ok(Metric::Manhattan),
            nbhd_metric::Chebyshev => Ok(Metric::Chebyshev),
            nbhd_metric::Minkowski => Metric::from_p(p),
        }
    }
}

impl From<Metric> for nbhd_metric {
    fn from(m: Metric) -> Self {
        match m {
            Metric::Euclidean => nbhd_metric::Euclidean,
            Metric::Manhattan => nbhd_metric::Manhattan,
            Metric::Chebyshev => nbhd_metric::Chebyshev,
            Metric::Minkowski(_) => nbhd_metric::Minkowski,
        }
    }
}

/// Whether a length or curvature option is absolute or relative to the mean spacing `h` of
/// the input (the mean distance of a point to its nearest other point, estimated by nbhd).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_units {
    /// A length in multiples of `h`, a curvature in multiples of `1/h`: the same settings suit
    /// a metre and a millimetre scan. The default.
    Relative = 0,
    /// In the points' own units (a curvature in inverse units).
    Absolute = 1,
}
c_enum!(nbhd_units, [Relative, Absolute]);

impl nbhd_units {
    /// The core's length of `value` in these units.
    pub(crate) fn length(self, value: f64) -> Length {
        match self {
            nbhd_units::Relative => Length::Relative(value),
            nbhd_units::Absolute => Length::Absolute(value),
        }
    }

    /// The core's curvature of `value` in these units.
    pub(crate) fn curvature(self, value: f64) -> Curvature {
        match self {
            nbhd_units::Relative => Curvature::Relative(value),
            nbhd_units::Absolute => Curvature::Absolute(value),
        }
    }

    /// The C units and value of the core's length.
    pub(crate) fn of_length(l: Length) -> (Self, f64) {
        match l {
            Length::Relative(v) => (nbhd_units::Relative, v),
            Length::Absolute(v) => (nbhd_units::Absolute, v),
        }
    }

    /// The C units and value of the core's curvature.
    pub(crate) fn of_curvature(c: Curvature) -> (Self, f64) {
        match c {
            Curvature::Relative(v) => (nbhd_units::Relative, v),
            Curvature::Absolute(v) => (nbhd_units::Absolute, v),
        }
    }
}

/// The weights `g_ij` of the smoothing step (thesis eq. 2.30–2.32).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_weighting {
    /// `g = 1`: isotropic Laplacian fairing (eq. 2.16).
    Isotropic = 0,
    /// `g_sharp` (eq. 2.31): 1 where the directional curvature `|κ_ij|` is below `lambda`, 0
    /// from it on. The default.
    Sharp = 1,
    /// `g_cont` (eq. 2.32): 1 below `lambda`, `λ²/(λ² + 10(|κ| − λ)²)` from it on.
    Continuous = 2,
}
same_variants!(nbhd_weighting, Weighting, [Isotropic, Sharp, Continuous]);

/// Which points are smoothed anisotropically (thesis eq. 2.33–2.35); the others are smoothed
/// isotropically.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_feature_criterion {
    /// Every point. The default.
    AllPoints = 0,
    /// Edge quotient Q (eq. 2.33): `min(|k1|,|k2|) / max(|k1|,|k2|) < feature_threshold`.
    EdgeQuotient = 1,
    /// Principal curvature K (eq. 2.34): `max(|k1|,|k2|) > feature_threshold`.
    PrincipalCurvature = 2,
    /// Directional curvature D (eq. 2.35): some neighbour has `|κ_ij| > feature_threshold`.
    DirectionalCurvature = 3,
}
c_enum!(
    nbhd_feature_criterion,
    [
        AllPoints,
        EdgeQuotient,
        PrincipalCurvature,
        DirectionalCurvature
    ]
);

/// The `feature_threshold` C shows for a criterion without one ([`FeatureCriterion::AllPoints`]),
/// so that switching to NBHD_FEATURE_CRITERION_EDGE_QUOTIENT alone gives a usable quotient.
const ALL_POINTS_THRESHOLD: f64 = 0.5;

impl nbhd_feature_criterion {
    /// The core's criterion of this kind with `threshold` (a quotient for EDGE_QUOTIENT, a
    /// curvature in `units` for the curvature criteria).
    pub(crate) fn to_core(self, threshold: f64, units: nbhd_units) -> FeatureCriterion {
        match self {
            Self::AllPoints => FeatureCriterion::AllPoints,
            Self::EdgeQuotient => FeatureCriterion::EdgeQuotient(threshold),
            Self::PrincipalCurvature => {
                FeatureCriterion::PrincipalCurvature(units.curvature(threshold))
            }
            Self::DirectionalCurvature => {
                FeatureCriterion::DirectionalCurvature(units.curvature(threshold))
            }
        }
    }

    /// The C kind, threshold and units of the core's criterion.
    pub(crate) fn of_core(f: FeatureCriterion) -> (Self, f64, nbhd_units) {
        match f {
            FeatureCriterion::AllPoints => {
                (Self::AllPoints, ALL_POINTS_THRESHOLD, nbhd_units::Relative)
            }
            FeatureCriterion::EdgeQuotient(q) => (Self::EdgeQuotient, q, nbhd_units::Relative),
            FeatureCriterion::PrincipalCurvature(c) => {
                let (u, v) = nbhd_units::of_curvature(c);
                (Self::PrincipalCurvature, v, u)
            }
            FeatureCriterion::DirectionalCurvature(c) => {
                let (u, v) = nbhd_units::of_curvature(c);
                (Self::DirectionalCurvature, v, u)
            }
        }
    }
}

/// How the sign-free covariance normals are oriented in the outputs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_orientation {
    /// The eigen-solver's sign: arbitrary but deterministic. The default.
    Unoriented = 0,
    /// Every normal points toward `orientation_point` (a scanner's viewpoint).
    TowardPoint = 1,
    /// Every normal points away from `orientation_point` (outward for star-shaped surfaces).
    AwayFromPoint = 2,
    /// One consistent orientation spread over the neighbour graph along smooth paths
    /// (Hoppe et al. 1992); in each connected part the highest point's normal has `z >= 0`.
    Propagate = 3,
}
c_enum!(
    nbhd_orientation,
    [Unoriented, TowardPoint, AwayFromPoint, Propagate]
);

impl nbhd_orientation {
    /// The core's orientation of this kind with `point` (which must be finite when used).
    pub(crate) fn to_core(self, point: [f64; 3]) -> Result<Orientation, FfiError> {
        let p = DVec3::from_array(point);
        if matches!(self, Self::TowardPoint | Self::AwayFromPoint) && !p.is_finite() {
            return Err(NbhdError::InvalidOption {
                name: "orientation_point",
                reason: format!("{point:?} must be finite"),
            }
            .into());
        }
        Ok(match self {
            Self::Unoriented => Orientation::Unoriented,
            Self::Propagate => Orientation::Propagate,
            Self::TowardPoint => Orientation::TowardViewpoint(p),
            Self::AwayFromPoint => Orientation::AwayFrom(p),
        })
    }

    /// The C kind and point of the core's orientation (the origin when it has none).
    pub(crate) fn of_core(o: Orientation) -> (Self, [f64; 3]) {
        match o {
            Orientation::Unoriented => (Self::Unoriented, [0.0; 3]),
            Orientation::TowardViewpoint(p) => (Self::TowardPoint, p.to_array()),
            Orientation::AwayFrom(p) => (Self::AwayFromPoint, p.to_array()),
            Orientation::Propagate => (Self::Propagate, [0.0; 3]),
        }
    }
}

/// What a smoothing run is doing when it calls the progress callback.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_stage {
    /// Neighbourhood search and the spacing estimate.
    Neighbors = 0,
    /// Normals and curvatures of a step.
    Geometry = 1,
    /// Moving the points.
    Step = 2,
    /// Per-point geometry of the result.
    Outputs = 3,
    /// Finished (fraction 1).
    Done = 4,
}
same_variants!(
    nbhd_stage,
    Stage,
    [Neighbors, Geometry, Step, Outputs, Done]
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enums_round_trip_to_the_core_and_reject_other_values() {
        for p in PivotPolicy::ALL {
            assert_eq!(PivotPolicy::from(nbhd_pivot_policy::from(p)), p);
        }
        for m in MedianAlgorithm::ALL {
            assert_eq!(MedianAlgorithm::from(nbhd_median_algorithm::from(m)), m);
        }
        assert_eq!(nbhd_pivot_policy::ALL.len(), PivotPolicy::ALL.len());
        assert_eq!(nbhd_median_algorithm::ALL.len(), MedianAlgorithm::ALL.len());
        assert_eq!(nbhd_scalar_type::from_value(1), Some(nbhd_scalar_type::F64));
        assert_eq!(nbhd_scalar_type::from_value(2), None);
        assert_eq!(nbhd_pivot_policy::from_value(-1), None);
    }

    #[test]
    fn smoothing_choices_round_trip_to_the_core() {
        for &w in nbhd_weighting::ALL {
            assert_eq!(nbhd_weighting::from(Weighting::from(w)), w);
        }
        for &u in nbhd_units::ALL {
            assert_eq!(nbhd_units::of_length(u.length(2.5)), (u, 2.5));
            assert_eq!(nbhd_units::of_curvature(u.curvature(0.3)), (u, 0.3));
            for &f in nbhd_feature_criterion::ALL {
                let back = nbhd_feature_criterion::of_core(f.to_core(0.25, u));
                match f {
                    nbhd_feature_criterion::AllPoints => assert_eq!(back.0, f),
                    nbhd_feature_criterion::EdgeQuotient => assert_eq!(back.0, f),
                    _ => assert_eq!(back, (f, 0.25, u)),
                }
            }
        }
        for &o in nbhd_orientation::ALL {
            let core = o.to_core([1.0, 2.0, 3.0]).unwrap();
            let (back, _) = nbhd_orientation::of_core(core);
            assert_eq!(back, o);
        }
        assert!(nbhd_orientation::TowardPoint
            .to_core([f64::NAN, 0.0, 0.0])
            .is_err());
        assert!(nbhd_orientation::Unoriented
            .to_core([f64::NAN, 0.0, 0.0])
            .is_ok());
    }
}
