//! The plain C structs of the ABI that are not about smoothing: the points descriptor, the
//! build and table options, tree statistics and the neighbourhood spec, with their
//! conversions to and from the core. Their enums live in [`super::enums`]; structs coming
//! from C are read field by field with `fields.rs`.

use std::ffi::c_void;

use super::enums::{nbhd_median_algorithm, nbhd_non_finite_policy, nbhd_pivot_policy};
use super::enums::{nbhd_metric, nbhd_neighborhood_kind, nbhd_scalar_type};
use super::fields::{c_field, CStruct};
use super::status::FfiError;
use crate::error::NbhdError;
use crate::points::PointsView;
use crate::query::{NeighborhoodSpec, QueryOptions};
use crate::scalar::ScalarType;
use crate::table::TableOptions;
use crate::tree::{BuildOptions, TreeStats};

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
    /// First byte of point 0. Must not be NULL, except for no point (`count` 0).
    pub data: *const c_void,
    /// Number of points, 0 to 4294967295 (UINT32_MAX): indices are `uint32_t`. No point is a
    /// valid set: a tree over it finds nothing, a batch of no query gives a table of no row
    /// (functions that need points, such as smoothing, refuse it with EMPTY_INPUT).
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
        // SAFETY: forwarded from the caller.
        let p = unsafe { CStruct::argument(points, arg) }?;
        let (data, count, dim, stride) = (
            c_field!(p.data),
            c_field!(p.count),
            c_field!(p.dim),
            c_field!(p.stride),
        );
        let scalar = c_field!(p.scalar_type as enum)?;
        // No point needs no memory: an empty std::vector's data() may be NULL.
        if data.is_null() && count > 0 {
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
        let bytes: &[u8] = if len == 0 {
            &[] // no point (`data` may be NULL)
        } else {
            // SAFETY: `data` is non-NULL when there are points (checked in `read`), `len` <=
            // isize::MAX (checked by `required_bytes`) and, by the caller's description, `len`
            // bytes from `data` are readable and not mutated while the view is used. u8 has
            // no alignment requirement.
            unsafe { std::slice::from_raw_parts(self.data, len) }
        };
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
    let defaults = nbhd_build_options::from(BuildOptions::default());
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    Ok(BuildOptions {
        pivot: c_field!(o.pivot as enum)?.into(),
        median: c_field!(o.median as enum)?.into(),
        leaf_size: c_field!(o.leaf_size),
        non_finite: c_field!(o.non_finite as enum)?.into(),
        threads: c_field!(o.threads),
    })
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
    /// Plain (not squared) radius, finite and >= 0, inclusive (Euclidean unless query options
    /// name another metric, and exclusive under their `strict`), for _RADIUS and
    /// _KNN_RADIUS; ignored for _KNN. Converted to the tree's scalar type.
    pub radius: f64,
}

/// Reads `*spec` field by field into the core's neighbourhood (its radius still a plain `f64`,
/// converted to an index's type by [`NeighborhoodSpec::to`]).
///
/// # Safety
/// `spec` must be NULL or point to a readable `nbhd_neighborhood_spec`.
pub(crate) unsafe fn read_spec(
    spec: *const nbhd_neighborhood_spec,
) -> Result<NeighborhoodSpec, FfiError> {
    // SAFETY: forwarded from the caller.
    let s = unsafe { CStruct::argument(spec, "spec") }?;
    let (k, radius) = (c_field!(s.k), c_field!(s.radius));
    Ok(match c_field!(s.kind as enum)? {
        nbhd_neighborhood_kind::Knn => NeighborhoodSpec::knn(k),
        nbhd_neighborhood_kind::Radius => NeighborhoodSpec::radius(radius),
        nbhd_neighborhood_kind::KnnRadius => NeighborhoodSpec::knn_radius(k, radius),
    })
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
    /// How every row's query measures (metric, eps, strict radius). Default:
    /// nbhd_query_options_default(); all zero (as `{true, 2}` leaves it) is the same.
    pub query: nbhd_query_options,
}

impl From<TableOptions> for nbhd_table_options {
    fn from(o: TableOptions) -> Self {
        Self {
            exclude_self: o.exclude_self,
            threads: o.threads,
            query: o.query.into(),
        }
    }
}

/// How a query measures (nbhd_tree_search, nbhd_dynamic_search, nbhd_table_options.query).
/// Start from nbhd_query_options_default(); all fields zero are the defaults too.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_query_options {
    /// The distance: a Minkowski p-norm. Results carry its key (see nbhd_metric) and a radius
    /// is a distance in it. Default: NBHD_METRIC_EUCLIDEAN.
    pub metric: nbhd_metric,
    /// The p of NBHD_METRIC_MINKOWSKI, in [1, infinity] (read for that metric only; NaN or
    /// below 1 is NBHD_STATUS_INVALID_OPTION). Default: 2.
    pub p: f64,
    /// Approximation, finite and >= 0 (else NBHD_STATUS_INVALID_OPTION): 0 is exact; eps > 0
    /// returns k nearest whose i-th distance is at most (1 + eps) times the true i-th, and
    /// for a radius r every point within r / (1 + eps) and none beyond r * (1 + eps), pruning
    /// harder (scipy's cKDTree rule). Default: 0.
    pub eps: f64,
    /// A radius is exclusive (|x - q| < r, scipy's distance_upper_bound) instead of inclusive;
    /// a radius too large for the tree's scalar type is then no bound. Default: false.
    pub strict: bool,
}

impl From<QueryOptions> for nbhd_query_options {
    fn from(o: QueryOptions) -> Self {
        Self {
            metric: o.metric.into(),
            p: o.metric.p(),
            eps: o.eps,
            strict: o.strict,
        }
    }
}

/// Reads a query options struct field by field into the core's options, checked.
fn query_options_of(s: &CStruct<'_, nbhd_query_options>) -> Result<QueryOptions, FfiError> {
    let options = QueryOptions {
        metric: c_field!(s.metric as enum)?.metric(c_field!(s.p))?,
        eps: c_field!(s.eps),
        strict: c_field!(s.strict as bool),
    };
    options.validate()?;
    Ok(options)
}

/// Reads `*options` into the core's query options; NULL gives the defaults.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_query_options`.
pub(crate) unsafe fn read_query_options(
    options: *const nbhd_query_options,
) -> Result<QueryOptions, FfiError> {
    let defaults = nbhd_query_options::from(QueryOptions::default());
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    query_options_of(&o)
}

/// Reads `*options` field by field into the core's table options; NULL gives the defaults.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_table_options`.
pub(crate) unsafe fn read_table_options(
    options: *const nbhd_table_options,
) -> Result<TableOptions, FfiError> {
    let defaults = nbhd_table_options::from(TableOptions::default());
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    // SAFETY: `query` is a member of the struct `o` points to.
    let query = unsafe { o.member(std::ptr::addr_of!((*o.ptr()).query)) };
    Ok(TableOptions {
        exclude_self: c_field!(o.exclude_self as bool),
        threads: c_field!(o.threads),
        query: query_options_of(&query)?,
    })
}
