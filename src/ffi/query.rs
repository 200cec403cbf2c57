//! Single queries into the caller's buffers: k nearest, within a radius, k nearest within a
//! radius; around given coordinates or around a stored point.

use std::cell::RefCell;
use std::ffi::c_void;

use super::args::{check_aligned, check_optional, check_ptr, deref, init_out};
use super::status::{guard, nbhd_status, FfiError};
use super::tree::{nbhd_tree, IndexHandle};
use super::types::{nbhd_neighborhood_spec, nbhd_query_options, read_query_options, read_spec};
use crate::error::NbhdError;
use crate::index::NeighborIndex;
use crate::query::{Neighbor, NeighborhoodSpec, Query, QueryOptions};
use crate::scalar::Scalar;
use crate::with_index;

/// Scalar types with a per-thread result vector, so that a loop of single queries does not
/// allocate once the vector has grown.
pub(crate) trait FfiScalar: Scalar {
    /// Runs `f` with this thread's scratch vector (or a fresh one if it is unavailable).
    fn with_scratch<R>(f: impl FnOnce(&mut Vec<Neighbor<Self>>) -> R) -> R;
}

/// Entries a scratch vector keeps between calls; a larger result's memory is given back.
const SCRATCH_KEEP: usize = 1 << 14;

macro_rules! scratch {
    ($t:ty, $key:ident) => {
        thread_local! {
            static $key: RefCell<Vec<Neighbor<$t>>> = const { RefCell::new(Vec::new()) };
        }
        impl FfiScalar for $t {
            fn with_scratch<R>(f: impl FnOnce(&mut Vec<Neighbor<Self>>) -> R) -> R {
                let mut f = Some(f);
                let mut run = |v: &mut Vec<Neighbor<Self>>| (f.take().expect("called once"))(v);
                let shared = $key.try_with(|cell| {
                    let mut v = cell.try_borrow_mut().ok()?;
                    let r = run(&mut v);
                    v.clear();
                    v.shrink_to(SCRATCH_KEEP);
                    Some(r)
                });
                match shared {
                    Ok(Some(r)) => r,
                    _ => run(&mut Vec::new()),
                }
            }
        }
    };
}
scratch!(f32, SCRATCH_F32);
scratch!(f64, SCRATCH_F64);

/// Where to search around.
#[derive(Clone, Copy)]
pub(crate) enum At {
    /// `dim` coordinates of the tree's scalar type.
    Point(*const c_void),
    /// A stored point by the caller's index.
    Stored { index: usize, exclude_self: bool },
}

/// The caller's result buffers.
#[derive(Clone, Copy)]
pub(crate) struct Results {
    pub(crate) indices: *mut u32,
    pub(crate) sq_dists: *mut c_void,
    pub(crate) capacity: usize,
    pub(crate) count: *mut usize,
}

/// The common body of every single query.
///
/// # Safety
/// As documented on nbhd_tree_knn: `tree` a live handle or NULL; `query` NULL or `dim`
/// readable values of the tree's scalar type; `indices` and `sq_dists` NULL or writable for
/// `capacity` values; `count` NULL or writable.
pub(crate) unsafe fn query<H: IndexHandle>(
    func: &str,
    tree: *const H,
    at: At,
    nbhd: NeighborhoodSpec,
    out: Results,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: forwarded from the caller.
        unsafe { query_with(tree, at, nbhd, &QueryOptions::DEFAULT, out) }
    })
}

/// [`query`] under query options, inside the caller's guard.
///
/// # Safety
/// As for [`query`].
unsafe fn query_with<H: IndexHandle>(
    tree: *const H,
    at: At,
    nbhd: NeighborhoodSpec,
    options: &QueryOptions,
    out: Results,
) -> Result<(), FfiError> {
    // SAFETY: `count` is NULL or writable (caller).
    let count = unsafe { init_out(out.count, "count", 0) }?;
    // SAFETY: `tree` is NULL or a live handle (caller).
    let tree = unsafe { deref(tree, "tree") }?;
    // SAFETY: the buffers are as the caller describes (contract above).
    with_index!(tree.index(), t, _T => unsafe { run(t, at, nbhd, options, out, count) })
}

/// The body of nbhd_tree_search and nbhd_dynamic_search: the spec and options read, then
/// [`query_with`] around the point `query`.
///
/// # Safety
/// As nbhd_tree_search.
pub(crate) unsafe fn search<H: IndexHandle>(
    func: &str,
    tree: *const H,
    query: *const c_void,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_query_options,
    out: Results,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `count` is NULL or writable (caller); set to 0 before any other check.
        unsafe { init_out(out.count, "count", 0) }?;
        // SAFETY: `spec` and `options` are NULL or readable (caller).
        let (nbhd, options) = unsafe { (read_spec(spec)?, read_query_options(options)?) };
        // SAFETY: forwarded from the caller.
        unsafe { query_with(tree, At::Point(query), nbhd, &options, out) }
    })
}

/// Runs one query on a typed index (static or growing) and copies the result out.
///
/// # Safety
/// As for [`query`]; `count` is checked and writable.
unsafe fn run<T: FfiScalar, S: NeighborIndex<T>>(
    tree: &S,
    at: At,
    nbhd: NeighborhoodSpec,
    options: &QueryOptions,
    out: Results,
    count: *mut usize,
) -> Result<(), FfiError> {
    if out.capacity > 0 {
        check_ptr(out.indices.cast_const(), "indices")?;
    } else {
        check_optional(out.indices.cast_const(), "indices")?;
    }
    let sq_dists = out.sq_dists.cast::<T>();
    check_optional(sq_dists.cast_const(), "sq_dists")?;
    let query = match at {
        At::Point(p) => {
            check_aligned(p, std::mem::align_of::<T>(), "query")?;
            // SAFETY: `p` is non-NULL and aligned for `T` (checked above) and points to `dim`
            // readable values of the tree's scalar type `T` (caller), which the call only reads.
            let coords = unsafe { std::slice::from_raw_parts(p.cast::<T>(), tree.dim()) };
            Query::point(coords)
        }
        At::Stored {
            index,
            exclude_self,
        } => Query::Stored {
            index: u32::try_from(index).map_err(|_| NbhdError::IndexOutOfRange {
                index,
                count: tree.source_len(),
            })?,
            exclude_self,
        },
    };
    T::with_scratch(|found| {
        let nbhd = nbhd.to_with::<T>(options)?;
        if *options == QueryOptions::DEFAULT {
            // The plain search, as `KdTree::knn` runs it: same checks, same result, without
            // resolving the options into a plan on every call (callgrind, docs/speed-log.md).
            tree.search(query, nbhd, found)?;
        } else {
            tree.search_with(query, nbhd, options, found)?;
        }
        // SAFETY: `count` is non-NULL, aligned and writable (checked by the caller of `run`).
        unsafe { count.write(found.len()) };
        if found.len() > out.capacity {
            return Err(NbhdError::BufferTooSmall {
                what: "result buffers (neighbours; the size needed is in *count)",
                len: out.capacity,
                needed: found.len(),
            }
            .into());
        }
        for (i, nb) in found.iter().enumerate() {
            // SAFETY: i < found.len() <= capacity, and `indices` is non-NULL (capacity > 0
            // here), aligned and writable for `capacity` values (checked above; caller).
            unsafe { out.indices.add(i).write(nb.index) };
            if !sq_dists.is_null() {
                // SAFETY: as above for `sq_dists`, whose values are of the tree's type `T`.
                unsafe { sq_dists.add(i).write(nb.sq_dist) };
            }
        }
        Ok(())
    })
}

/// The `k` points of the tree nearest to the point `query`.
///
/// - `query`: `dim` coordinates in the tree's scalar type (`float` for a tree built from
///   NBHD_SCALAR_TYPE_F32 points, `double` for F64; see nbhd_stats.scalar_type), aligned for
///   that type.
/// - `k` >= 1; a k larger than the number of points gives all of them.
/// - Results: `*count` neighbours, nearest first, ordered by (squared distance, index), so ties
///   are deterministic. `indices` receives the caller's point indices (uint32_t); `sq_dists`,
///   if not NULL, the squared Euclidean distances, in the tree's scalar type. Both buffers
///   hold `capacity` values; a capacity of `k` always suffices.
/// - If the result has more than `capacity` neighbours, nothing is written to the buffers,
///   `*count` receives the number needed and the status is NBHD_STATUS_BUFFER_TOO_SMALL: call
///   again with buffers that large. `indices` may be NULL when `capacity` is 0, to ask for the
///   size.
/// - On any other error `*count` is 0.
///
/// Errors: NULL_POINTER (`tree`, `query`, `count`, `indices` with a capacity > 0),
/// MISALIGNED_POINTER, NON_FINITE_QUERY, INVALID_K (k = 0), BUFFER_TOO_SMALL.
///
/// Thread safety: any number of threads may query one tree at once.
///
/// # Safety
/// `tree` must be NULL or a live handle; `query` NULL or `dim` readable values of the tree's
/// scalar type; `indices` and `sq_dists` NULL or writable for `capacity` values each (of
/// uint32_t and of the tree's scalar type); `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_knn(
    tree: *const nbhd_tree,
    query: *const c_void,
    k: usize,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    // SAFETY: the caller's contract is the one `query` requires.
    unsafe {
        self::query(
            "nbhd_tree_knn",
            tree,
            At::Point(query),
            NeighborhoodSpec::knn(k),
            out,
        )
    }
}

/// All points of the tree within `radius` of the point `query`: `|x - q| <= radius`, with a
/// plain (not squared) radius, finite and >= 0, converted to the tree's scalar type. Results
/// are ordered by (squared distance, index). Their number is not known in advance: if
/// `capacity` is too small, `*count` receives the size needed and the status is
/// NBHD_STATUS_BUFFER_TOO_SMALL. Arguments, results and errors otherwise as nbhd_tree_knn,
/// with INVALID_RADIUS for a negative, NaN or infinite radius.
///
/// # Safety
/// As nbhd_tree_knn.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_radius(
    tree: *const nbhd_tree,
    query: *const c_void,
    radius: f64,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    let nbhd = NeighborhoodSpec::radius(radius);
    // SAFETY: the caller's contract is the one `query` requires.
    unsafe { self::query("nbhd_tree_radius", tree, At::Point(query), nbhd, out) }
}

/// The epsilon-k-neighbourhood of the point `query`: the `k` nearest among the points within
/// `radius` (plain radius, inclusive). At most `k` results, so a capacity of `k` suffices.
/// Arguments, results and errors as nbhd_tree_knn and nbhd_tree_radius.
///
/// # Safety
/// As nbhd_tree_knn.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_knn_radius(
    tree: *const nbhd_tree,
    query: *const c_void,
    k: usize,
    radius: f64,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    let nbhd = NeighborhoodSpec::knn_radius(k, radius);
    // SAFETY: the caller's contract is the one `query` requires.
    unsafe { self::query("nbhd_tree_knn_radius", tree, At::Point(query), nbhd, out) }
}

/// The `k` nearest neighbours of the stored point with the caller's index `index` (its index
/// in the points given to nbhd_tree_build). With `exclude_self` the point itself is left out
/// (its duplicates at distance 0 stay), so k = 3 gives its 3 nearest other points. Results
/// and buffers as nbhd_tree_knn.
///
/// Errors: as nbhd_tree_knn, plus INDEX_OUT_OF_RANGE (`index` >= the number of points given)
/// and SKIPPED_POINT (the point was skipped at build time as non-finite).
///
/// # Safety
/// As nbhd_tree_knn (there is no `query` pointer).
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_knn_index(
    tree: *const nbhd_tree,
    index: usize,
    exclude_self: bool,
    k: usize,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    let at = At::Stored {
        index,
        exclude_self,
    };
    // SAFETY: the caller's contract is the one `query` requires.
    unsafe {
        self::query(
            "nbhd_tree_knn_index",
            tree,
            at,
            NeighborhoodSpec::knn(k),
            out,
        )
    }
}

/// All points within `radius` of the stored point `index`, optionally without the point
/// itself. Results and buffers as nbhd_tree_radius; errors as nbhd_tree_knn_index.
///
/// # Safety
/// As nbhd_tree_knn (there is no `query` pointer).
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_radius_index(
    tree: *const nbhd_tree,
    index: usize,
    exclude_self: bool,
    radius: f64,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    let at = At::Stored {
        index,
        exclude_self,
    };
    let nbhd = NeighborhoodSpec::radius(radius);
    // SAFETY: the caller's contract is the one `query` requires.
    unsafe { self::query("nbhd_tree_radius_index", tree, at, nbhd, out) }
}

/// The k nearest within `radius` of the stored point `index`, optionally without the point
/// itself. Results and buffers as nbhd_tree_knn_radius; errors as nbhd_tree_knn_index.
///
/// # Safety
/// As nbhd_tree_knn (there is no `query` pointer).
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_tree_knn_radius_index(
    tree: *const nbhd_tree,
    index: usize,
    exclude_self: bool,
    k: usize,
    radius: f64,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    let at = At::Stored {
        index,
        exclude_self,
    };
    let nbhd = NeighborhoodSpec::knn_radius(k, radius);
    // SAFETY: the caller's contract is the one `query` requires.
    unsafe { self::query("nbhd_tree_knn_radius_index", tree, at, nbhd, out) }
}

/// The default query options: the exact Euclidean metric, an inclusive radius.
#[no_mangle]
pub extern "C" fn nbhd_query_options_default() -> nbhd_query_options {
    let defaults = QueryOptions::default().into();
    super::status::guard_value("nbhd_query_options_default", defaults, || defaults)
}

/// The neighbourhood `*spec` (k nearest, within a radius, or the k nearest within a radius)
/// of the point `query` under `*options` (NULL: the defaults, which answer as nbhd_tree_knn,
/// nbhd_tree_radius and nbhd_tree_knn_radius): any Minkowski metric, an approximate search, a
/// strict radius. The radius is a distance in the metric; `sq_dists` receives each
/// neighbour's key in the metric (squared for Euclidean, the distance for Manhattan and
/// Chebyshev, sum |x_j - q_j|^p for Minkowski p; see nbhd_metric), in the tree's scalar type;
/// results are ordered by (key, index). Arguments, buffers and results otherwise as
/// nbhd_tree_knn.
///
/// Errors: those of nbhd_tree_knn and nbhd_tree_radius; NULL_POINTER for `spec`;
/// INVALID_OPTION for a metric out of range, a Minkowski p below 1 or NaN, a negative or
/// non-finite eps; INVALID_RADIUS also for a radius whose key overflows the tree's scalar type
/// (not under `strict`).
///
/// # Safety
/// As nbhd_tree_knn; `spec` NULL or a readable nbhd_neighborhood_spec; `options` NULL or a
/// readable nbhd_query_options.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_search(
    tree: *const nbhd_tree,
    query: *const c_void,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_query_options,
    indices: *mut u32,
    sq_dists: *mut c_void,
    capacity: usize,
    count: *mut usize,
) -> nbhd_status {
    let out = Results {
        indices,
        sq_dists,
        capacity,
        count,
    };
    // SAFETY: the caller's contract is the one `search` requires.
    unsafe { search("nbhd_tree_search", tree, query, spec, options, out) }
}
