//! Pair queries (scipy's `query_pairs`, `query_ball_tree`, `sparse_distance_matrix`,
//! `count_neighbors`): the pairs within a radius in one tree or between two, as tables, and
//! pair counts in bins of radii, with or without weights. Each measures by the tree passed
//! first (its metric under the options' `query`, its periodic box).

use super::args::{deref, init_out, read_slice};
use super::dynamic::nbhd_dynamic_tree;
use super::status::{guard, nbhd_status};
use super::table::{hand_out, nbhd_neighborhoods};
use super::tree::{nbhd_tree, IndexHandle};
use super::types::{nbhd_table_options, read_table_options};
use crate::index::PairWeights;

/// Weights of the points of the two trees of nbhd_tree_weigh_pairs: `tree_weights[i]` for the
/// point with index i of the first tree (`tree_count` values, one per index given to its
/// build or insert), `other_weights[j]` for the second. A NULL array weighs every point 1
/// (its count is then ignored).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_pair_weights {
    /// Weights of the first tree's points, or NULL.
    pub tree_weights: *const f64,
    /// Number of values at `tree_weights`.
    pub tree_count: usize,
    /// Weights of the second tree's points, or NULL.
    pub other_weights: *const f64,
    /// Number of values at `other_weights`.
    pub other_count: usize,
}

/// Every pair i < j of points of `tree` within `radius` of each other (inclusive, scipy's
/// `query_pairs`) as a new table in `*out_table`: row i (one per index, as
/// nbhd_tree_neighborhoods) holds the j > i in ascending order (not by distance), with the
/// pair's key in the distances (squared for the Euclidean metric, the distance for p = 1 and
/// infinity, the sum of |x_j|^p otherwise). `options` may be NULL; its `query` sets the
/// metric, eps (every pair within radius * (1 + eps): inside scipy's contract, all within
/// radius / (1 + eps) and none beyond radius * (1 + eps)) and a strict radius; `exclude_self`
/// does not apply. Identical for any number of threads.
///
/// On any error `*out_table` is set to NULL (if `out_table` is not NULL).
///
/// Errors: NULL_POINTER (`tree`, `out_table`), MISALIGNED_POINTER, INVALID_RADIUS (negative,
/// NaN or infinite, or a key that overflows the tree's type), INVALID_OPTION (the query
/// options), OUT_OF_MEMORY, THREAD_POOL.
///
/// Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
///
/// # Safety
/// `tree` NULL or a live handle; `options` NULL or readable; `out_table` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_pairs(
    tree: *const nbhd_tree,
    radius: f64,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `pairs` requires.
    unsafe { pairs("nbhd_tree_pairs", tree, radius, options, out_table) }
}

/// nbhd_tree_pairs for a growing tree (rows for every index ever inserted; removed points
/// have no pair).
///
/// # Safety
/// As nbhd_tree_pairs.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_pairs(
    tree: *const nbhd_dynamic_tree,
    radius: f64,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    // SAFETY: the caller's contract is the one `pairs` requires.
    unsafe { pairs("nbhd_dynamic_pairs", tree, radius, options, out_table) }
}

/// The body of nbhd_tree_pairs and nbhd_dynamic_pairs.
///
/// # Safety
/// As nbhd_tree_pairs.
unsafe fn pairs<H: IndexHandle>(
    func: &str,
    tree: *const H,
    radius: f64,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `out_table` is NULL or writable (caller).
        let out = unsafe { init_out(out_table, "out_table", std::ptr::null_mut()) }?;
        // SAFETY: `tree` is NULL or a live handle, `options` NULL or readable (caller).
        let (tree, options) = unsafe { (deref(tree, "tree")?, read_table_options(options)?) };
        let table = tree.index().pairs(radius, &options)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out(out, table) };
        Ok(())
    })
}

/// The pairs (i, j) of a point i of `tree` and a point j of `other` within `radius` of each
/// other (inclusive; scipy's `query_ball_tree` and `sparse_distance_matrix`), measured by
/// `tree` (its metric under `options->query`, its periodic box; `other`'s box is not used), as
/// a new table in `*out_table`: row i (one per index of `tree`) holds `other`'s indices j
/// ascending, with the pair's key (see nbhd_tree_pairs), zero distances included. Both trees
/// must have the same dimension and scalar type. Identical for any number of threads.
///
/// On any error `*out_table` is set to NULL (if `out_table` is not NULL).
///
/// Errors: as nbhd_tree_pairs; NULL_POINTER (`other`), DIMENSION_MISMATCH, INVALID_OPTION
/// (trees of different scalar types).
///
/// Ownership: the caller owns `*out_table` and frees it with nbhd_neighborhoods_free.
///
/// # Safety
/// As nbhd_tree_pairs; `other` NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_pairs_with(
    tree: *const nbhd_tree,
    other: *const nbhd_tree,
    radius: f64,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    let name = "nbhd_tree_pairs_with";
    // SAFETY: the caller's contract is the one `pairs_with` requires.
    unsafe { pairs_with(name, tree, other, radius, options, out_table) }
}

/// nbhd_tree_pairs_with for two growing trees.
///
/// # Safety
/// As nbhd_tree_pairs_with.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_pairs_with(
    tree: *const nbhd_dynamic_tree,
    other: *const nbhd_dynamic_tree,
    radius: f64,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    let name = "nbhd_dynamic_pairs_with";
    // SAFETY: the caller's contract is the one `pairs_with` requires.
    unsafe { pairs_with(name, tree, other, radius, options, out_table) }
}

/// The body of nbhd_tree_pairs_with and nbhd_dynamic_pairs_with.
///
/// # Safety
/// As nbhd_tree_pairs_with.
unsafe fn pairs_with<H: IndexHandle>(
    func: &str,
    tree: *const H,
    other: *const H,
    radius: f64,
    options: *const nbhd_table_options,
    out_table: *mut *mut nbhd_neighborhoods,
) -> nbhd_status {
    guard(func, || {
        // SAFETY: `out_table` is NULL or writable (caller).
        let out = unsafe { init_out(out_table, "out_table", std::ptr::null_mut()) }?;
        // SAFETY: the handles are NULL or live, `options` NULL or readable (caller).
        let (tree, other, options) = unsafe {
            (
                deref(tree, "tree")?,
                deref(other, "other")?,
                read_table_options(options)?,
            )
        };
        let table = tree.index().pairs_with(other.index(), radius, &options)?;
        // SAFETY: `out` was checked by `init_out`.
        unsafe { hand_out(out, table) };
        Ok(())
    })
}

/// How many pairs (i, j) of a point of `tree` and a point of `other` lie within each radius of
/// `radii[0 .. radius_count]` (scipy's `count_neighbors`), measured by `tree` as
/// nbhd_tree_pairs_with, written to `counts[0 .. radius_count]`. `other` may be `tree` itself
/// (then each point counts with itself and each pair twice, as scipy). `cumulative`: counts[k]
/// is the number of pairs at distance <= radii[k] (radii in any order); otherwise the number in
/// (radii[k-1], radii[k]] ([0, radii[0]] for k = 0; radii non-decreasing; of equal radii the
/// first gets the count, the others 0). A negative radius counts nothing, +infinity every
/// pair; `options->query.strict` makes every radius exclusive. Exact and identical for any
/// number of threads.
///
/// Errors: NULL_POINTER (`tree`, `other`, `radii` or `counts` with radius_count > 0),
/// MISALIGNED_POINTER, INVALID_RADIUS (a NaN radius), INVALID_OPTION (decreasing radii when
/// not cumulative, eps > 0: counts are exact, trees of different scalar types),
/// DIMENSION_MISMATCH, THREAD_POOL. `counts` is untouched on error.
///
/// # Safety
/// `tree`, `other` NULL or live handles; `radii` NULL or readable and `counts` NULL or
/// writable for `radius_count` values; `options` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_count_pairs(
    tree: *const nbhd_tree,
    other: *const nbhd_tree,
    radii: *const f64,
    radius_count: usize,
    cumulative: bool,
    options: *const nbhd_table_options,
    counts: *mut u64,
) -> nbhd_status {
    let name = "nbhd_tree_count_pairs";
    let request = Count {
        radii,
        radius_count,
        cumulative,
        weights: std::ptr::null(),
        options,
        counts,
        sums: std::ptr::null_mut(),
        weighted: false,
    };
    // SAFETY: the caller's contract is the one `count` requires.
    unsafe { count(name, tree, other, request) }
}

/// nbhd_tree_count_pairs with weights (scipy's `count_neighbors` with `weights`): each pair
/// (i, j) adds tree_weights[i] * other_weights[j] (see nbhd_pair_weights; `weights` NULL
/// weighs every point 1), and sums[k] is the correctly rounded sum of those products (an exact
/// sum: the same bits for any number of threads).
///
/// Errors: those of nbhd_tree_count_pairs; INVALID_OPTION (a weight array whose count is not
/// the number of indices of its tree, or a weight that is NaN or infinite).
///
/// # Safety
/// As nbhd_tree_count_pairs, `sums` for `counts`; `weights` NULL or readable, its arrays NULL
/// or readable for their counts.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_tree_weigh_pairs(
    tree: *const nbhd_tree,
    other: *const nbhd_tree,
    radii: *const f64,
    radius_count: usize,
    cumulative: bool,
    weights: *const nbhd_pair_weights,
    options: *const nbhd_table_options,
    sums: *mut f64,
) -> nbhd_status {
    let name = "nbhd_tree_weigh_pairs";
    let request = Count {
        radii,
        radius_count,
        cumulative,
        weights,
        options,
        counts: std::ptr::null_mut(),
        sums,
        weighted: true,
    };
    // SAFETY: the caller's contract is the one `count` requires.
    unsafe { count(name, tree, other, request) }
}

/// nbhd_tree_count_pairs for two growing trees.
///
/// # Safety
/// As nbhd_tree_count_pairs.
#[no_mangle]
pub unsafe extern "C" fn nbhd_dynamic_count_pairs(
    tree: *const nbhd_dynamic_tree,
    other: *const nbhd_dynamic_tree,
    radii: *const f64,
    radius_count: usize,
    cumulative: bool,
    options: *const nbhd_table_options,
    counts: *mut u64,
) -> nbhd_status {
    let name = "nbhd_dynamic_count_pairs";
    let request = Count {
        radii,
        radius_count,
        cumulative,
        weights: std::ptr::null(),
        options,
        counts,
        sums: std::ptr::null_mut(),
        weighted: false,
    };
    // SAFETY: the caller's contract is the one `count` requires.
    unsafe { count(name, tree, other, request) }
}

/// nbhd_tree_weigh_pairs for two growing trees.
///
/// # Safety
/// As nbhd_tree_weigh_pairs.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn nbhd_dynamic_weigh_pairs(
    tree: *const nbhd_dynamic_tree,
    other: *const nbhd_dynamic_tree,
    radii: *const f64,
    radius_count: usize,
    cumulative: bool,
    weights: *const nbhd_pair_weights,
    options: *const nbhd_table_options,
    sums: *mut f64,
) -> nbhd_status {
    let name = "nbhd_dynamic_weigh_pairs";
    let request = Count {
        radii,
        radius_count,
        cumulative,
        weights,
        options,
        counts: std::ptr::null_mut(),
        sums,
        weighted: true,
    };
    // SAFETY: the caller's contract is the one `count` requires.
    unsafe { count(name, tree, other, request) }
}

/// The arguments of a count as C passed them: weighted into `sums`, or unweighted into
/// `counts`.
struct Count {
    radii: *const f64,
    radius_count: usize,
    cumulative: bool,
    weights: *const nbhd_pair_weights,
    options: *const nbhd_table_options,
    counts: *mut u64,
    sums: *mut f64,
    weighted: bool,
}

/// The weights behind `w` (NULL: none), checked.
///
/// # Safety
/// `w` NULL or readable, its arrays NULL or readable for their counts.
unsafe fn read_weights<'a>(
    w: *const nbhd_pair_weights,
) -> Result<PairWeights<'a>, super::status::FfiError> {
    if w.is_null() {
        return Ok(PairWeights::default());
    }
    // SAFETY: non-NULL here, readable (caller).
    let w = unsafe { deref(w, "weights") }?;
    let side = |p: *const f64, n: usize, arg| {
        if p.is_null() {
            return Ok(None);
        }
        // SAFETY: non-NULL, readable for `n` doubles (caller).
        unsafe { read_slice(p, n, arg) }.map(Some)
    };
    Ok(PairWeights {
        this: side(w.tree_weights, w.tree_count, "weights->tree_weights")?,
        other: side(w.other_weights, w.other_count, "weights->other_weights")?,
    })
}

/// The body of the four counts: weighted into `c.sums`, or unweighted into `c.counts`.
///
/// # Safety
/// As nbhd_tree_weigh_pairs (`c.weights` NULL for the unweighted counts).
unsafe fn count<H: IndexHandle>(
    func: &str,
    tree: *const H,
    other: *const H,
    c: Count,
) -> nbhd_status {
    let Count {
        radii,
        radius_count,
        cumulative,
        weights,
        options,
        counts,
        sums,
        weighted,
    } = c;
    guard(func, || {
        // SAFETY: the handles are NULL or live; `radii`, `options` and `weights` NULL or
        // readable (caller).
        let (tree, other, radii, options, weights) = unsafe {
            (
                deref(tree, "tree")?,
                deref(other, "other")?,
                read_slice(radii, radius_count, "radii")?,
                read_table_options(options)?,
                read_weights(weights)?,
            )
        };
        let (a, b) = (tree.index(), other.index());
        if weighted {
            // SAFETY: `sums` NULL or writable for `radius_count` doubles (caller).
            let target = unsafe { counts_out(sums, radius_count, "sums") }?;
            let got = a.weigh_pairs_with(b, radii, weights, cumulative, &options)?;
            target.copy_from_slice(&got);
        } else {
            // SAFETY: `counts` NULL or writable for `radius_count` values (caller).
            let target = unsafe { counts_out(counts, radius_count, "counts") }?;
            let got = a.count_pairs_with(b, radii, cumulative, &options)?;
            target.copy_from_slice(&got);
        }
        Ok(())
    })
}

/// The caller's output array of `n` values, checked (NULL allowed for `n` 0).
///
/// # Safety
/// `p` NULL or writable for `n` values of `T`, not otherwise referred to during `'a`.
unsafe fn counts_out<'a, T>(
    p: *mut T,
    n: usize,
    arg: &str,
) -> Result<&'a mut [T], super::status::FfiError> {
    // SAFETY: `p` NULL or valid for `n` values (caller); the read checks NULL, alignment and
    // size.
    let read = unsafe { read_slice(p.cast_const(), n, arg) }?;
    // SAFETY: the same memory, writable and not otherwise referred to (caller).
    Ok(unsafe { std::slice::from_raw_parts_mut(read.as_ptr().cast_mut(), read.len()) })
}
