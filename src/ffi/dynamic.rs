//! The dynamic tree handle (`src/dynamic/`): create, insert a batch, remove indices, the
//! single queries and tables of the static tree, statistics, free.

use std::ffi::c_void;

use super::args::{check_optional, deref, init_out};
use super::enums::{enum_argument, nbhd_scalar_type, ScalarTypeArg};
use super::query::{query as single_query, search, At, Results};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::table::{nbhd_neighborhoods, neighborhoods, neighborhoods_of};
use super::tree::{hand_out_index, IndexHandle};
use super::types::{
    nbhd_build_options, nbhd_neighborhood_spec, nbhd_points, nbhd_query_options,
    nbhd_table_options, read_build_options, PointsArg,
};
use crate::handle::AnyIndex;
use crate::query::NeighborhoodSpec;
use crate::scalar::ScalarType;

/// A k-d tree that accepts insertions and removals (opaque); see nbhd_dynamic_create.
///
/// Index rule: the points of each inserted batch get consecutive indices continuing from the
/// previous batch (the first batch gets 0, 1, ...); a point keeps its index until it is
/// removed, and a removed index is never given again (queries and removals naming it fail
/// with NBHD_STATUS_REMOVED_POINT). Every query answers exactly what a static tree
/// (nbhd_tree_build) over the live points, under these indices, answers.
///
/// Thread safety: any number of threads may query one dynamic tree at once, but
/// nbhd_dynamic_insert and nbhd_dynamic_remove must not run at the same time as any other
/// call on the same tree.
pub struct nbhd_dynamic_tree {
    /// Always a growing tree.
    pub(crate) inner: AnyIndex,
}

impl IndexHandle for nbhd_dynamic_tree {
    const GROWING: bool = true;
    fn index(&self) -> &AnyIndex {
        &self.inner
    }
    fn new(inner: AnyIndex) -> Self {
        Self { inner }
    }
}

/// Size and shape of a dynamic tree.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct nbhd_dynamic_stats {
    /// Live points.
    pub live: usize,
    /// Indices given so far (live, removed and skipped points): the index the next inserted
    /// point gets, and the number of rows of nbhd_dynamic_neighborhoods.
    pub next_index: usize,
    /// Static trees in the forest.
    pub trees: usize,
    /// Removed points still held by the trees (skipped by every query).
    pub removed_held: usize,
    /// Dimension.
    pub dim: usize,
    /// The tree's scalar type: of query coordinates and of squared distances.
    pub scalar_type: nbhd_scalar_type,
}

/// Makes an empty dynamic tree of dimension `dim` computing in `scalar_type` (an
/// nbhd_scalar_type value) and stores the handle in `*out_tree`. `options` (NULL for the
/// defaults) shape every static tree of the forest; its `non_finite` decides what inserting a
/// NaN or infinite point does: REJECT refuses the batch, SKIP gives the point its index but
/// leaves it out (queries naming it fail with NBHD_STATUS_SKIPPED_POINT).
///
/// Errors: NULL_POINTER (`out_tree`), MISALIGNED_POINTER, ZERO_DIMENSION, INVALID_ARGUMENT
/// (`scalar_type` not a value of nbhd_scalar_type; `dim * sizeof(scalar)` overflowing the
/// address space, as nbhd_tree_build refuses such points), INVALID_OPTION. On error
/// `*out_tree` is NULL.
///
/// Ownership: the caller frees `*out_tree` with nbhd_dynamic_free.
///
/// # Safety
/// `options` must be NULL or point to an nbhd_build_options; `out_tree` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_create(
    dim: usize,
    scalar_type: ScalarTypeArg,
    options: *const nbhd_build_options,
    out_tree: *mut *mut nbhd_dynamic_tree,
) -> nbhd_status {
    guard("nbhd_dynamic_create", || {
        // SAFETY: `out_tree` is NULL or writable (caller).
        let out = unsafe { init_out(out_tree, "out_tree", std::ptr::null_mut()) }?;
        // SAFETY: `options` is NULL or readable (caller).
        let options = unsafe { read_build_options(options) }?;
        let scalar: nbhd_scalar_type = enum_argument(scalar_type, "scalar_type")?;
        let inner = AnyIndex::growing(dim, ScalarType::from(scalar), &options)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out_index(out, inner) };
        Ok(())
    })
}

/// Inserts the points `*points` (of either scalar type, converted to the tree's; of the
/// tree's dimension) as one batch. `*out_first` (may be NULL) receives the index of the
/// first: the batch gets `first .. first + points->count - 1`, in order. The point buffer
/// may be freed as soon as this returns (the tree copies the points). A batch of no point
/// inserts nothing (`*out_first` receives the next index).
///
/// Errors, with nothing inserted: NULL_POINTER (`tree`, `points`, `points->data` with a
/// count above 0), MISALIGNED_POINTER, the errors of a points description (see
/// nbhd_tree_build: INVALID_ARGUMENT, STRIDE_TOO_SMALL, TOO_MANY_POINTS), DIMENSION_MISMATCH,
/// NON_FINITE (with options.non_finite REJECT; the message names the point's position in the
/// batch), TOO_MANY_POINTS (indices would pass UINT32_MAX - 1 over the tree's life),
/// OUT_OF_MEMORY, THREAD_POOL.
///
/// # Safety
/// `tree` must be NULL or a live handle not in use by another thread; `points` NULL or a
/// true description of readable memory; `out_first` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_insert(
    tree: *mut nbhd_dynamic_tree,
    points: *const nbhd_points,
    out_first: *mut u32,
) -> nbhd_status {
    guard("nbhd_dynamic_insert", || {
        check_optional(out_first.cast_const(), "out_first")?;
        super::args::check_ptr(tree.cast_const(), "tree")?;
        // SAFETY: non-NULL and aligned (checked); a live handle used by no other thread
        // (caller).
        let tree = unsafe { &mut *tree };
        // SAFETY: `points` is NULL or readable (caller).
        let arg = unsafe { PointsArg::read(points, "points") }?;
        // SAFETY: the caller's description of the point memory is true (contract above).
        let view = unsafe { arg.view() }?;
        let first = tree.inner.insert(&view)?;
        if !out_first.is_null() {
            // SAFETY: non-NULL, aligned (checked above) and writable (caller).
            unsafe { out_first.write(first) };
        }
        Ok(())
    })
}

/// Removes the live points `indices[0 .. count - 1]` (any order). Their indices are never
/// given again. `indices` may be NULL when `count` is 0 (nothing to do).
///
/// Errors, with nothing removed: NULL_POINTER, MISALIGNED_POINTER, INVALID_ARGUMENT (`count`
/// larger than an array can be), INDEX_OUT_OF_RANGE (an index not given yet),
/// REMOVED_POINT (an index already removed, or named twice), SKIPPED_POINT (a non-finite
/// point skipped at insertion), THREAD_POOL.
///
/// # Safety
/// `tree` must be NULL or a live handle not in use by another thread; `indices` NULL or
/// `count` readable `uint32_t`.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_remove(
    tree: *mut nbhd_dynamic_tree,
    indices: *const u32,
    count: usize,
) -> nbhd_status {
    guard("nbhd_dynamic_remove", || {
        super::args::check_ptr(tree.cast_const(), "tree")?;
        if count > isize::MAX as usize / std::mem::size_of::<u32>() {
            return Err(FfiError::InvalidArgument(format!(
                "count {count} is larger than an array of uint32_t can be"
            )));
        }
        let ids: &[u32] = if count == 0 {
            check_optional(indices, "indices")?;
            &[]
        } else {
            super::args::check_ptr(indices, "indices")?;
            // SAFETY: non-NULL and aligned (checked), `count` readable values (caller), and
            // `count * 4` fits in isize (checked above).
            unsafe { std::slice::from_raw_parts(indices, count) }
        };
        // SAFETY: non-NULL and aligned (checked); a live handle used by no other thread
        // (caller).
        let tree = unsafe { &mut *tree };
        tree.inner.remove(ids)?;
        Ok(())
    })
}

/// Sets the worker threads of the builds that later insertions and removals run: 0 the shared
/// pool (a thread per core), 1 serially, n a pool of n threads (at most 1024), as
/// `options->threads` of nbhd_dynamic_create. A loaded tree (nbhd_dynamic_load) starts at 0
/// whatever its file says; this changes it. Answers do not depend on it.
///
/// Errors, with nothing changed: NULL_POINTER, MISALIGNED_POINTER, INVALID_OPTION (above
/// 1024).
///
/// # Safety
/// `tree` must be NULL or a live handle not in use by another thread.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_set_threads(
    tree: *mut nbhd_dynamic_tree,
    threads: usize,
) -> nbhd_status {
    guard("nbhd_dynamic_set_threads", || {
        super::args::check_ptr(tree.cast_const(), "tree")?;
        // SAFETY: non-NULL and aligned (checked); a live handle used by no other thread
        // (caller).
        let tree = unsafe { &mut *tree };
        tree.inner.set_threads(threads)?;
        Ok(())
    })
}

/// Frees a dynamic tree. NULL is ignored.
///
/// # Safety
/// `tree` must be NULL or a handle from nbhd_dynamic_create not freed before, in use by no
/// other thread.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_free(tree: *mut nbhd_dynamic_tree) {
    guard_value("nbhd_dynamic_free", (), || {
        if tree.is_null() {
            return;
        }
        if (tree as usize) % std::mem::align_of::<nbhd_dynamic_tree>() != 0 {
            // Not a handle of ours: freeing it would corrupt the heap. Leak it, and say so.
            let _ = guard("nbhd_dynamic_free", || {
                super::args::check_ptr(tree.cast_const(), "tree")
            });
            return;
        }
        // SAFETY: `tree` came from Box::into_raw in nbhd_dynamic_create and is freed only once
        // (caller).
        drop(unsafe { Box::from_raw(tree) });
    })
}

/// Writes the size and shape of `tree` to `*out_stats`.
///
/// Errors: NULL_POINTER, MISALIGNED_POINTER.
///
/// # Safety
/// `tree` must be NULL or a live handle; `out_stats` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_tree_stats(
    tree: *const nbhd_dynamic_tree,
    out_stats: *mut nbhd_dynamic_stats,
) -> nbhd_status {
    guard("nbhd_dynamic_tree_stats", || {
        // SAFETY: `out_stats` is NULL or writable (caller).
        let out = unsafe { init_out(out_stats, "out_stats", nbhd_dynamic_stats::default()) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let tree = unsafe { deref(tree, "tree") }?;
        let index = &tree.inner;
        let (scalar_type, dim) = (index.scalar_type().into(), index.dim());
        let s = index
            .growing_stats()
            .expect("an nbhd_dynamic_tree holds a growing tree");
        let stats = nbhd_dynamic_stats {
            live: s.live,
            next_index: s.next_index as usize,
            trees: s.trees.len(),
            removed_held: s.trees.iter().map(|t| t.1).sum(),
            dim,
            scalar_type,
        };
        // SAFETY: `out` was checked by `init_out`.
        unsafe { out.write(stats) };
        Ok(())
    })
}

/// The `k` live points nearest to the point `query` (`dim` values of the tree's scalar type).
/// Arguments, results, buffers and errors as nbhd_tree_knn; an empty tree gives `*count` 0.
///
/// # Safety
/// As nbhd_tree_knn, with `tree` a live dynamic tree not being changed by another thread.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_knn(
    tree: *const nbhd_dynamic_tree,
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
        single_query(
            "nbhd_dynamic_knn",
            tree,
            At::Point(query),
            NeighborhoodSpec::knn(k),
            out,
        )
    }
}

/// The neighbourhood `*spec` of the point `query` among the live points under `*options`
/// (NULL: the defaults); as nbhd_tree_search.
///
/// # Safety
/// As nbhd_tree_search, with `tree` a live dynamic tree not being changed by another thread.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_search(
    tree: *const nbhd_dynamic_tree,
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
    unsafe { search("nbhd_dynamic_search", tree, query, spec, options, out) }
}

/// All live points within `radius` of the point `query`; as nbhd_tree_radius.
///
/// # Safety
/// As nbhd_dynamic_knn.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_radius(
    tree: *const nbhd_dynamic_tree,
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
    unsafe { single_query("nbhd_dynamic_radius", tree, At::Point(query), nbhd, out) }
}

/// The `k` nearest among the live points within `radius` of the point `query`; as
/// nbhd_tree_knn_radius.
///
/// # Safety
/// As nbhd_dynamic_knn.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_knn_radius(
    tree: *const nbhd_dynamic_tree,
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
    unsafe { single_query("nbhd_dynamic_knn_radius", tree, At::Point(query), nbhd, out) }
}

/// The `k` nearest neighbours of the live point `index`, optionally without the point itself;
/// as nbhd_tree_knn_index, plus REMOVED_POINT for a removed index.
///
/// # Safety
/// As nbhd_dynamic_knn (there is no `query` pointer).
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_knn_index(
    tree: *const nbhd_dynamic_tree,
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
        single_query(
            "nbhd_dynamic_knn_index",
            tree,
            at,
            NeighborhoodSpec::knn(k),
            out,
        )
    }
}

/// All live points within `radius` of the live point `index`; as nbhd_tree_radius_index,
/// plus REMOVED_POINT.
///
/// # Safety
/// As nbhd_dynamic_knn (there is no `query` pointer).
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_radius_index(
    tree: *const nbhd_dynamic_tree,
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
    unsafe { single_query("nbhd_dynamic_radius_index", tree, at, nbhd, out) }
}

/// The `k` nearest within `radius` of the live point `index`; as
/// nbhd_tree_knn_radius_index, plus REMOVED_POINT.
///
/// # Safety
/// As nbhd_dynamic_knn (there is no `query` pointer).
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_dynamic_knn_radius_index(
    tree: *const nbhd_dynamic_tree,
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
    unsafe { single_query("nbhd_dynamic_knn_radius_index", tree, at, nbhd, out) }
}

/// The neighbourhood `*spec` of every live point, as a new table in `*out_table`: row i for
/// index i (nbhd_dynamic_stats.next_index rows; rows of removed and skipped points are
/// empty), the bytes a static tree over the live points gives. Options, errors and ownership
/// as nbhd_tree_neighborhoods.
///
/// # Safety
/// As nbhd_tree_neighborhoods, with `tree` a live dynamic tree not being changed.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_neighborhoods(
    tree: *const nbhd_dynamic_tree,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `neighborhoods` requires.
    unsafe { neighborhoods("nbhd_dynamic_neighborhoods", tree, spec, options, out_table) }
}

/// The neighbourhood `*spec` of each point of `*queries` among the live points, as a new
/// table (row i for query i); as nbhd_tree_neighborhoods_of.
///
/// # Safety
/// As nbhd_tree_neighborhoods_of, with `tree` a live dynamic tree not being changed.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_neighborhoods_of(
    tree: *const nbhd_dynamic_tree,
    queries: *const nbhd_points,
    spec: *const nbhd_neighborhood_spec,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    let name = "nbhd_dynamic_neighborhoods_of";
    // SAFETY: the caller's contract is the one `neighborhoods_of` requires.
    unsafe { neighborhoods_of(name, tree, queries, spec, options, out_table) }
}
