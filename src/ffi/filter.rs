//! The spacing estimate and the point filters (outlier removal, voxel-grid downsampling)
//! of `src/filter/`, over a built tree.

use super::args::{deref, init_out};
use super::status::{guard, nbhd_status};
use super::tree::{nbhd_tree, with_tree};

/// The nearest-neighbour spacing of a point set: the distance of each point to its nearest
/// other point, summarised. `mean` is the h of every relative length (epsilon = 6 h).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_spacing {
    /// Mean nearest-neighbour distance h, summed in index order.
    pub mean: f64,
    /// Median nearest-neighbour distance (the mean of the middle two for an even count).
    pub median: f64,
    /// Number of points the distances were taken over (the tree's points).
    pub points: usize,
}

/// The nearest-neighbour spacing of the tree's points, computed on `threads` workers (0: a
/// thread per core); the same value for any thread count. Points skipped at build time are
/// left out.
///
/// Errors: NULL_POINTER (`tree`, `out`), MISALIGNED_POINTER, INVALID_OPTION (fewer than two
/// points in the tree, or threads above NBHD_MAX_THREADS). On error `*out` is all zero.
///
/// # Safety
/// `tree` must be NULL or a live handle; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_tree_spacing(
    tree: *const nbhd_tree,
    threads: usize,
    out: *mut nbhd_spacing,
) -> nbhd_status {
    guard("nbhd_tree_spacing", || {
        // SAFETY: `out` is NULL or writable (caller).
        let out = unsafe { init_out(out, "out", nbhd_spacing::default()) }?;
        // SAFETY: `tree` is NULL or a live handle (caller).
        let tree = unsafe { deref(tree, "tree") }?;
        let s = with_tree!(&tree.inner, t => t.spacing(threads))?;
        // SAFETY: `out` is non-NULL, aligned and writable (checked by init_out).
        unsafe {
            out.write(nbhd_spacing {
                mean: s.mean,
                median: s.median,
                points: s.points,
            })
        };
        Ok(())
    })
}
