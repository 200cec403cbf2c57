//! The plain C types of the ABI: enums for the core's choices, the points descriptor, the
//! build and table options, tree statistics, and their conversions to and from the core.
//!
//! C may store any integer in an enum-typed field, and a Rust enum holding a value outside
//! its variants is undefined behaviour; so structs coming from C are never read as Rust
//! values of these types. Their fields are read one by one through raw pointers, enum fields
//! as `int` (see [`read_enum`]), and then checked.

use std::ffi::{c_int, c_void};

use super::args::check_ptr;
use super::status::FfiError;
use crate::error::NbhdError;
use crate::points::PointsView;
use crate::scalar::ScalarType;
use crate::table::TableOptions;
use crate::tree::{BuildOptions, MedianAlgorithm, PivotPolicy, TreeStats};
use crate::{NonFinitePolicy, Scalar};

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
pub(crate) use c_enum;

/// Reads field `$f` of the C struct behind the raw pointer `$o` through a raw place (never the
/// struct as a Rust value). `$o` must have been checked to be non-NULL and aligned, and must be
/// readable (the export's contract).
macro_rules! c_field {
    ($o:expr, $f:ident) => {
        // SAFETY: `$o` is non-NULL, aligned (checked by the caller) and readable (the
        // export's contract); the field is read through a raw place.
        unsafe { std::ptr::addr_of!((*$o).$f).read() }
    };
}
pub(crate) use c_field;

/// Reads the enum field `$f` of the options struct behind `$o` as the `int` C stored there and
/// checks it is a value of `$ty`; otherwise returns an INVALID_ARGUMENT error naming the field.
/// Same contract as [`c_field`].
macro_rules! c_enum_field {
    ($o:expr, $f:ident, $ty:ty) => {
        // SAFETY: as for `c_field!`; the enum is read as `int` and checked.
        unsafe { $crate::ffi::types::read_enum(std::ptr::addr_of!((*$o).$f)) }
            .map_err(|v| $crate::ffi::types::invalid_enum::<$ty>("options", stringify!($f), v))?
    };
}
pub(crate) use c_enum_field;

/// Reads the `bool` field `$f` of the struct behind `$o` as a byte, so any value C stored is
/// sound (non-zero is true). Same contract as [`c_field`].
macro_rules! c_bool_field {
    ($o:expr, $f:ident) => {
        // SAFETY: as for `c_field!`; the bool is read as a byte.
        unsafe { std::ptr::addr_of!((*$o).$f).cast::<u8>().read() != 0 }
    };
}
pub(crate) use c_bool_field;

/// Reads the enum field at `field` as the `int` C stored there: the variant of `E` it
/// names, or the raw value if it names none.
///
/// # Safety
/// `field` must point to a readable, aligned field of type `E` inside a struct given by C.
pub(crate) unsafe fn read_enum<E: CEnum>(field: *const E) -> Result<E, c_int> {
    // SAFETY: the caller guarantees `field` is readable and aligned; `E` has the size of
    // `int` (asserted by `c_enum!`) and at least its alignment, and any bit pattern is a
    // valid `int`.
    let raw = unsafe { field.cast::<c_int>().read() };
    E::from_value(raw).ok_or(raw)
}

/// The error for an enum field of an argument struct that holds no value of `E`.
pub(crate) fn invalid_enum<E: CEnum>(arg: &str, field: &str, value: c_int) -> FfiError {
    FfiError::InvalidArgument(format!(
        "{arg}->{field} is {value}, not a value of {}",
        E::C_NAME
    ))
}

/// The error for an enum field of an options struct that holds no value of `E`.
fn invalid_option<E: CEnum>(name: &'static str, value: c_int) -> FfiError {
    FfiError::Core(NbhdError::InvalidOption {
        name,
        reason: format!("{value} is not a value of {}", E::C_NAME),
    })
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
c_enum!(nbhd_scalar_type, [F32, F64]);

impl From<nbhd_scalar_type> for ScalarType {
    fn from(s: nbhd_scalar_type) -> Self {
        match s {
            nbhd_scalar_type::F32 => ScalarType::F32,
            nbhd_scalar_type::F64 => ScalarType::F64,
        }
    }
}

impl From<ScalarType> for nbhd_scalar_type {
    fn from(s: ScalarType) -> Self {
        match s {
            ScalarType::F32 => nbhd_scalar_type::F32,
            ScalarType::F64 => nbhd_scalar_type::F64,
        }
    }
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
c_enum!(
    nbhd_pivot_policy,
    [CyclicMedian, SpreadMedian, ClosestToMiddle, SlidingMidpoint]
);

impl From<nbhd_pivot_policy> for PivotPolicy {
    fn from(p: nbhd_pivot_policy) -> Self {
        match p {
            nbhd_pivot_policy::CyclicMedian => PivotPolicy::CyclicMedian,
            nbhd_pivot_policy::SpreadMedian => PivotPolicy::SpreadMedian,
            nbhd_pivot_policy::ClosestToMiddle => PivotPolicy::ClosestToMiddle,
            nbhd_pivot_policy::SlidingMidpoint => PivotPolicy::SlidingMidpoint,
        }
    }
}

impl From<PivotPolicy> for nbhd_pivot_policy {
    fn from(p: PivotPolicy) -> Self {
        match p {
            PivotPolicy::CyclicMedian => nbhd_pivot_policy::CyclicMedian,
            PivotPolicy::SpreadMedian => nbhd_pivot_policy::SpreadMedian,
            PivotPolicy::ClosestToMiddle => nbhd_pivot_policy::ClosestToMiddle,
            PivotPolicy::SlidingMidpoint => nbhd_pivot_policy::SlidingMidpoint,
        }
    }
}

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
c_enum!(
    nbhd_median_algorithm,
    [Presorted, Sort, Quickselect, FloydRivest, MedianOfMedians]
);

impl From<nbhd_median_algorithm> for MedianAlgorithm {
    fn from(m: nbhd_median_algorithm) -> Self {
        match m {
            nbhd_median_algorithm::Presorted => MedianAlgorithm::Presorted,
            nbhd_median_algorithm::Sort => MedianAlgorithm::Sort,
            nbhd_median_algorithm::Quickselect => MedianAlgorithm::Quickselect,
            nbhd_median_algorithm::FloydRivest => MedianAlgorithm::FloydRivest,
            nbhd_median_algorithm::MedianOfMedians => MedianAlgorithm::MedianOfMedians,
        }
    }
}

impl From<MedianAlgorithm> for nbhd_median_algorithm {
    fn from(m: MedianAlgorithm) -> Self {
        match m {
            MedianAlgorithm::Presorted => nbhd_median_algorithm::Presorted,
            MedianAlgorithm::Sort => nbhd_median_algorithm::Sort,
            MedianAlgorithm::Quickselect => nbhd_median_algorithm::Quickselect,
            MedianAlgorithm::FloydRivest => nbhd_median_algorithm::FloydRivest,
            MedianAlgorithm::MedianOfMedians => nbhd_median_algorithm::MedianOfMedians,
        }
    }
}

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
c_enum!(nbhd_non_finite_policy, [Reject, Skip]);

impl From<nbhd_non_finite_policy> for NonFinitePolicy {
    fn from(p: nbhd_non_finite_policy) -> Self {
        match p {
            nbhd_non_finite_policy::Reject => NonFinitePolicy::Reject,
            nbhd_non_finite_policy::Skip => NonFinitePolicy::Skip,
        }
    }
}

impl From<NonFinitePolicy> for nbhd_non_finite_policy {
    fn from(p: NonFinitePolicy) -> Self {
        match p {
            NonFinitePolicy::Reject => nbhd_non_finite_policy::Reject,
            NonFinitePolicy::Skip => nbhd_non_finite_policy::Skip,
        }
    }
}

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

/// Describes `count` points of dimension `dim` in a caller's buffer, read in place (the tree
/// copies what it needs; the buffer may be freed once nbhd_tree_build returns).
///
/// Point i starts at byte `i * stride` from `data`; its coordinates are `dim` consecutive
/// values of `scalar_type`. So a packed `float xyz[n][3]` is `{xyz, n, 3, 0, NBHD_SCALAR_TYPE_F32}`
/// and PCL's `PointXYZ` (x, y, z, padding) is `{cloud, n, 3, 16, NBHD_SCALAR_TYPE_F32}`.
/// `data` needs no particular alignment (coordinates are read byte-wise).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_points {
    /// First byte of point 0. Must not be NULL.
    pub data: *const c_void,
    /// Number of points, 1 to 4294967295 (UINT32_MAX): indices are `uint32_t`.
    pub count: usize,
    /// Coordinates per point, at least 1.
    pub dim: usize,
    /// Bytes from one point to the next, at least `dim * sizeof(scalar)`; 0 means tightly
    /// packed (`dim * sizeof(scalar)`).
    pub stride: usize,
    /// Type of every coordinate. A tree built from these points computes in this type.
    pub scalar_type: nbhd_scalar_type,
}

/// A points description read from C and checked: what [`PointsView::new`] needs.
pub(crate) struct PointsArg {
    /// The argument's name, for messages.
    arg: &'static str,
    data: *const u8,
    count: usize,
    dim: usize,
    /// Bytes from one point to the next (a stride of 0 given by C is already made packed).
    pub(crate) stride: usize,
    pub(crate) scalar: ScalarType,
}

impl PointsArg {
    /// Reads `*points` field by field and checks its pointer and scalar type.
    ///
    /// # Safety
    /// `points` must be NULL or point to a readable `nbhd_points`.
    pub(crate) unsafe fn read(
        points: *const nbhd_points,
        arg: &'static str,
    ) -> Result<Self, FfiError> {
        check_ptr(points, arg)?;
        // SAFETY: `points` is non-NULL and aligned (checked above) and readable (caller); the
        // fields are read through raw places, never as a whole `nbhd_points` value.
        let (data, count, dim, stride) = unsafe {
            (
                std::ptr::addr_of!((*points).data).read(),
                std::ptr::addr_of!((*points).count).read(),
                std::ptr::addr_of!((*points).dim).read(),
                std::ptr::addr_of!((*points).stride).read(),
            )
        };
        // SAFETY: as above, for the enum field.
        let scalar: nbhd_scalar_type =
            unsafe { read_enum(std::ptr::addr_of!((*points).scalar_type)) }
                .map_err(|v| invalid_enum::<nbhd_scalar_type>(arg, "scalar_type", v))?;
        if data.is_null() {
            return Err(FfiError::Null(format!("{arg}->data")));
        }
        let scalar = ScalarType::from(scalar);
        let stride = if stride == 0 {
            dim.saturating_mul(scalar.size())
        } else {
            stride
        };
        Ok(Self {
            arg,
            data: data.cast(),
            count,
            dim,
            stride,
            scalar,
        })
    }

    /// The core's view of the points, after the core's geometry checks.
    ///
    /// # Safety
    /// The description must be true: `(count - 1) * stride + dim * size` bytes readable from
    /// `data`, not written while the view lives.
    pub(crate) unsafe fn view<'a>(&self) -> Result<PointsView<'a>, FfiError> {
        let len = PointsView::required_bytes(self.count, self.dim, self.stride, self.scalar)
            .map_err(|e| match e {
                NbhdError::SizeOverflow { what } => NbhdError::SizeOverflow {
                    what: format!("{}: {what}", self.arg),
                },
                e => e,
            })?;
        // SAFETY: `data` is non-NULL (checked in `read`), `len` <= isize::MAX (checked by
        // `required_bytes`) and, by the caller's description, `len` bytes from `data` are
        // readable and not mutated while the view is used. u8 has no alignment requirement.
        let bytes = unsafe { std::slice::from_raw_parts(self.data, len) };
        Ok(PointsView::new(
            bytes,
            self.count,
            self.dim,
            self.stride,
            self.scalar,
        )?)
    }
}

/// Everything that shapes a tree. Start from nbhd_build_options_default() and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_build_options {
    /// Pivot policy. Default: NBHD_PIVOT_POLICY_SLIDING_MIDPOINT.
    pub pivot: nbhd_pivot_policy,
    /// Median algorithm. Default: NBHD_MEDIAN_ALGORITHM_FLOYD_RIVEST.
    pub median: nbhd_median_algorithm,
    /// Most points in a leaf, 1 to UINT32_MAX. Default: 12.
    pub leaf_size: usize,
    /// Reject or skip points with NaN or infinite coordinates. Default: reject.
    pub non_finite: nbhd_non_finite_policy,
    /// Worker threads of the build: 0 uses a shared pool with one thread per core, 1 builds
    /// on the calling thread, n > 1 uses a pool of n threads made for this call; more than
    /// NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION. The tree is identical for every value.
    /// Default: 0.
    pub threads: usize,
}

impl From<BuildOptions> for nbhd_build_options {
    fn from(o: BuildOptions) -> Self {
        Self {
            pivot: o.pivot.into(),
            median: o.median.into(),
            leaf_size: o.leaf_size,
            non_finite: o.non_finite.into(),
            threads: o.threads,
        }
    }
}

/// Reads `*options` field by field into the core's options; NULL gives the defaults. The
/// core checks the leaf size when it builds.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_build_options`.
pub(crate) unsafe fn read_build_options(
    options: *const nbhd_build_options,
) -> Result<BuildOptions, FfiError> {
    if options.is_null() {
        return Ok(BuildOptions::default());
    }
    check_ptr(options, "options")?;
    // SAFETY: `options` is non-NULL and aligned (checked above) and readable (caller); each
    // field is read through a raw place, the enums as `int` and then checked.
    unsafe {
        let pivot = read_enum(std::ptr::addr_of!((*options).pivot))
            .map_err(|v| invalid_option::<nbhd_pivot_policy>("pivot", v))?;
        let median = read_enum(std::ptr::addr_of!((*options).median))
            .map_err(|v| invalid_option::<nbhd_median_algorithm>("median", v))?;
        let non_finite = read_enum(std::ptr::addr_of!((*options).non_finite))
            .map_err(|v| invalid_option::<nbhd_non_finite_policy>("non_finite", v))?;
        Ok(BuildOptions {
            pivot: pivot.into(),
            median: median.into(),
            leaf_size: std::ptr::addr_of!((*options).leaf_size).read(),
            non_finite: non_finite.into(),
            threads: std::ptr::addr_of!((*options).threads).read(),
        })
    }
}

/// Shape and memory of a built tree (filled by nbhd_tree_stats).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct nbhd_stats {
    /// Points held (points skipped as non-finite not counted).
    pub points: usize,
    /// Points the caller passed in, skipped ones included: the range of valid indices and the
    /// number of rows of nbhd_tree_neighborhoods.
    pub source_points: usize,
    /// Dimension.
    pub dim: usize,
    /// Edges on the longest root-to-leaf path (a single leaf has depth 0).
    pub depth: usize,
    /// Internal nodes plus leaves.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Most points in one leaf.
    pub max_leaf_points: usize,
    /// Bytes of coordinates, index map and nodes held by the tree.
    pub bytes: usize,
    /// Coordinate type of the tree: the type of query coordinates and of squared distances.
    pub scalar_type: nbhd_scalar_type,
}

impl nbhd_stats {
    pub(crate) fn new(s: TreeStats, source_points: usize, scalar: ScalarType) -> Self {
        Self {
            points: s.points,
            source_points,
            dim: s.dim,
            depth: s.depth,
            nodes: s.nodes,
            leaves: s.leaves,
            max_leaf_points: s.max_leaf_points,
            bytes: s.bytes,
            scalar_type: scalar.into(),
        }
    }
}

/// Which neighbourhood nbhd_tree_neighborhoods computes for every row.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_neighborhood_spec {
    /// k nearest, all within a radius, or k nearest within a radius.
    pub kind: nbhd_neighborhood_kind,
    /// Number of neighbours (>= 1) for NBHD_NEIGHBORHOOD_KIND_KNN and _KNN_RADIUS; ignored
    /// for _RADIUS. A k larger than the number of points gives all of them.
    pub k: usize,
    /// Plain (not squared) Euclidean radius, finite and >= 0, inclusive, for _RADIUS and
    /// _KNN_RADIUS; ignored for _KNN. Converted to the tree's scalar type.
    pub radius: f64,
}

/// A neighbourhood as the C ABI receives it, before conversion to the tree's scalar type.
#[derive(Clone, Copy, Debug)]
pub(crate) enum NbhdArg {
    Knn(usize),
    Radius(f64),
    KnnRadius(usize, f64),
}

impl NbhdArg {
    /// The core's neighbourhood in scalar type `T` (the radius rounded to `T`; the core
    /// validates `k` and the radius).
    /// The core's neighbourhood in the tree's type `T`. A finite radius that overflows `T` (or
    /// whose square does) is refused here, with the value the caller passed.
    pub(crate) fn to_core<T: Scalar>(self) -> Result<crate::Neighborhood<T>, FfiError> {
        use crate::Neighborhood;
        let radius = |r: f64| {
            let t = T::from_f64(r);
            if r.is_finite() && r >= 0.0 && !(t * t).is_finite() {
                Err(crate::query::radius_out_of_range::<T>(r))
            } else {
                Ok(t)
            }
        };
        Ok(match self {
            NbhdArg::Knn(k) => Neighborhood::Knn { k },
            NbhdArg::Radius(r) => Neighborhood::Radius {
                radius: radius(r)?,
                sorted: true,
            },
            NbhdArg::KnnRadius(k, r) => Neighborhood::KnnRadius {
                k,
                radius: radius(r)?,
            },
        })
    }

    /// Reads `*spec` field by field.
    ///
    /// # Safety
    /// `spec` must be NULL or point to a readable `nbhd_neighborhood_spec`.
    pub(crate) unsafe fn read(spec: *const nbhd_neighborhood_spec) -> Result<Self, FfiError> {
        check_ptr(spec, "spec")?;
        // SAFETY: `spec` is non-NULL and aligned (checked above) and readable (caller); the
        // fields are read through raw places, the enum as `int` and then checked.
        unsafe {
            let kind = read_enum(std::ptr::addr_of!((*spec).kind))
                .map_err(|v| invalid_enum::<nbhd_neighborhood_kind>("spec", "kind", v))?;
            let k = std::ptr::addr_of!((*spec).k).read();
            let radius = std::ptr::addr_of!((*spec).radius).read();
            Ok(match kind {
                nbhd_neighborhood_kind::Knn => NbhdArg::Knn(k),
                nbhd_neighborhood_kind::Radius => NbhdArg::Radius(radius),
                nbhd_neighborhood_kind::KnnRadius => NbhdArg::KnnRadius(k, radius),
            })
        }
    }
}

/// Options of nbhd_tree_neighborhoods. Start from nbhd_table_options_default().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_table_options {
    /// Leave each point out of its own row (its duplicates at distance 0 stay). Applies to
    /// nbhd_tree_neighborhoods only. Default: true.
    pub exclude_self: bool,
    /// Worker threads: 0 uses a shared pool with one thread per core, n >= 1 a pool of n
    /// threads made for this call; more than NBHD_MAX_THREADS is NBHD_STATUS_INVALID_OPTION.
    /// The table is identical for every value. Default: 0.
    pub threads: usize,
}

impl From<TableOptions> for nbhd_table_options {
    fn from(o: TableOptions) -> Self {
        Self {
            exclude_self: o.exclude_self,
            threads: o.threads,
        }
    }
}

/// Reads `*options` field by field into the core's table options; NULL gives the defaults.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_table_options`.
pub(crate) unsafe fn read_table_options(
    options: *const nbhd_table_options,
) -> Result<TableOptions, FfiError> {
    if options.is_null() {
        return Ok(TableOptions::default());
    }
    check_ptr(options, "options")?;
    // SAFETY: `options` is non-NULL and aligned (checked above) and readable (caller); the
    // bool is read as a byte, so any value C stored there is sound (non-zero is true).
    unsafe {
        Ok(TableOptions {
            exclude_self: std::ptr::addr_of!((*options).exclude_self)
                .cast::<u8>()
                .read()
                != 0,
            threads: std::ptr::addr_of!((*options).threads).read(),
        })
    }
}

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
    fn out_of_range_enum_in_options_is_an_invalid_option() {
        let mut raw = std::mem::MaybeUninit::new(nbhd_build_options::from(BuildOptions::default()));
        let p = raw.as_mut_ptr();
        // SAFETY: writes an int into the int-sized enum field, as C may; the memory is only
        // read again through `read_build_options`, never as a Rust `nbhd_build_options`.
        unsafe {
            std::ptr::addr_of_mut!((*p).median)
                .cast::<c_int>()
                .write(99)
        };
        // SAFETY: `p` points to a live, aligned nbhd_build_options-sized buffer.
        let err = unsafe { read_build_options(p) }.unwrap_err();
        assert_eq!(
            err.to_string(),
            "option median: 99 is not a value of nbhd_median_algorithm"
        );
    }
}
