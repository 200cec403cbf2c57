//! Voxel-grid downsampling: PCL's `VoxelGrid` (the centroid of every occupied voxel) and the
//! variant that keeps, for every voxel, the original point nearest its centroid.
//!
//! The arithmetic is PCL 1.13's (`pcl/filters/impl/voxel_grid.hpp`, `applyFilter`), carried out
//! in the point buffer's own scalar type `T` (PCL's is `float`), so that an `f32` buffer gets
//! PCL's voxels bit for bit:
//!
//! - `inv_a = 1 / leaf_a`, with `leaf_a` first rounded to `T`;
//! - `b_min_a = ⌊min_a · inv_a⌋`, `b_max_a = ⌊max_a · inv_a⌋` over the finite points;
//! - a point's voxel coordinate `i_a = ⌊x_a · inv_a⌋ − b_min_a`, its linear index
//!   `Σ_a i_a · Π_{b<a} (b_max_b − b_min_b + 1)` (x fastest);
//! - voxels are output in ascending linear index; a voxel's centroid is the sum of its points
//!   in `T`, divided by the count rounded to `T`.
//!
//! Within a voxel nbhd sums in ascending caller index. PCL sorts its (voxel, point) pairs with
//! an unstable sort, so its summation order — and with it the last bits of a centroid — is not
//! defined; `cpp_examples/compare_voxel.cpp` checks the voxels, counts and order for equality
//! and the centroids against the rounding bound of the two orders.

use rayon::prelude::*;

use crate::error::{NbhdError, Result};
use crate::points::PointsView;
use crate::scalar::{Scalar, ScalarType};

/// Options of [`voxel_grid`].
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGridOptions {
    /// Edge length of a voxel: one value for a cube, or one per coordinate (PCL's
    /// `setLeafSize(lx, ly, lz)`). Each is finite and > 0, also after rounding to the points'
    /// scalar type.
    pub leaf: Vec<f64>,
    /// Voxels with fewer points are left out (PCL's `setMinimumPointsNumberPerVoxel`; 0 and 1
    /// both keep every occupied voxel).
    pub min_points_per_voxel: usize,
    /// Worker threads (0: the current pool). The result is the same for any count.
    pub threads: usize,
}

impl VoxelGridOptions {
    /// Cubic voxels of edge `leaf`, every occupied voxel kept, the current pool.
    pub fn cube(leaf: f64) -> Self {
        Self {
            leaf: vec![leaf],
            min_points_per_voxel: 0,
            threads: 0,
        }
    }
}

/// The occupied voxels of a point set, in ascending linear voxel index (x fastest).
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGrid<T> {
    /// Dimension of the points.
    pub dim: usize,
    /// `dim` values per voxel: the centroid of its points (PCL's `VoxelGrid` output).
    pub centroids: Vec<T>,
    /// Voxel `v`'s points are `members[offsets[v] .. offsets[v + 1]]` (`voxels() + 1` values).
    pub offsets: Vec<usize>,
    /// The caller's indices of the points of each voxel, ascending within a voxel.
    pub members: Vec<u32>,
    /// For each voxel, the caller's index of its point nearest the centroid (Euclidean distance
    /// taken in `f64`; ties by the smaller index): original points, whose attributes are kept.
    pub nearest: Vec<u32>,
    /// `dim` values per voxel: its voxel numbers `⌊x_a · inv_a⌋` along each coordinate, which do
    /// not depend on the other points (Open3D's `grid_index` less the grid's origin). Voxels
    /// computed from parts of a cloud (tiles) line up by them, and sorting them with the last
    /// coordinate first gives the ascending linear index of the whole cloud.
    pub cells: Vec<i64>,
    /// Number of points the caller passed in.
    pub source_len: usize,
}

impl<T: Scalar> VoxelGrid<T> {
    /// Number of voxels output.
    pub fn len(&self) -> usize {
        self.nearest.len()
    }

    /// Whether no voxel was output (every point non-finite, or every voxel below the minimum).
    pub fn is_empty(&self) -> bool {
        self.nearest.is_empty()
    }

    /// Centroid of voxel `v`.
    pub fn centroid(&self, v: usize) -> &[T] {
        &self.centroids[v * self.dim..(v + 1) * self.dim]
    }

    /// The caller's indices of voxel `v`'s points, ascending.
    pub fn members_of(&self, v: usize) -> &[u32] {
        &self.members[self.offsets[v]..self.offsets[v + 1]]
    }

    /// Voxel numbers of voxel `v` (see [`VoxelGrid::cells`]).
    pub fn cells_of(&self, v: usize) -> &[i64] {
        &self.cells[v * self.dim..(v + 1) * self.dim]
    }
}

/// Exactly representable integers of `T` reach 2^MANTISSA.
fn mantissa_bits<T: Scalar>() -> u32 {
    match T::TYPE {
        ScalarType::F32 => 24,
        ScalarType::F64 => 53,
    }
}

fn type_name<T: Scalar>() -> &'static str {
    match T::TYPE {
        ScalarType::F32 => "f32",
        ScalarType::F64 => "f64",
    }
}

/// Points per piece of the parallel passes (fixed, so the split never depends on the threads).
const CHUNK: usize = 1 << 14;

/// The grid of a point set: per coordinate the inverse leaf, the lower voxel bound and the
/// multiplier of the linear index.
struct Grid<T> {
    inv: Vec<T>,
    low: Vec<i64>,
    mul: Vec<u64>,
    /// Number of voxels of the grid's bounding box (`Π (b_max − b_min + 1)`).
    cells: u64,
}

/// Per coordinate min and max over the finite points (`None` when there is none).
fn bounds<T: Scalar>(view: &PointsView<'_>) -> Option<(Vec<T>, Vec<T>)> {
    let d = view.dim();
    let n = view.len();
    let pieces: Vec<Option<(Vec<T>, Vec<T>)>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut p = vec![T::ZERO; d];
            let mut acc: Option<(Vec<T>, Vec<T>)> = None;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                view.read_point(i, &mut p);
                if !p.iter().all(|x| x.is_finite()) {
                    continue;
                }
                match &mut acc {
                    None => acc = Some((p.clone(), p.clone())),
                    Some((lo, hi)) => {
                        for a in 0..d {
                            lo[a] = lo[a].min_of(p[a]);
                            hi[a] = hi[a].max_of(p[a]);
                        }
                    }
                }
            }
            acc
        })
        .collect();
    pieces
        .into_iter()
        .flatten()
        .reduce(|(mut lo, mut hi), (l, h)| {
            for a in 0..d {
                lo[a] = lo[a].min_of(l[a]);
                hi[a] = hi[a].max_of(h[a]);
            }
            (lo, hi)
        })
}

fn leaf_error(reason: String) -> NbhdError {
    NbhdError::InvalidOption {
        name: "leaf",
        reason,
    }
}

/// The leaf sizes per coordinate, checked: finite and > 0 in `T`, with a finite inverse.
/// Refuses a number of leaf sizes other than one (a cube) or one per coordinate: before the
/// sizes are read, so that the C ABI reads no more than a valid count.
pub(crate) fn check_leaf_count(n: usize, d: usize) -> Result<()> {
    if n == 1 || n == d {
        return Ok(());
    }
    Err(leaf_error(format!(
        "{n} leaf sizes given for points of dimension {d} (give one, or one per coordinate)"
    )))
}

fn inverse_leaf<T: Scalar>(leaf: &[f64], d: usize) -> Result<Vec<T>> {
    check_leaf_count(leaf.len(), d)?;
    let per_axis: Vec<f64> = match leaf.len() {
        1 => vec![leaf[0]; d],
        _ => leaf.to_vec(),
    };
    per_axis
        .iter()
        .enumerate()
        .map(|(a, &l)| {
            let lt = T::from_f64(l);
            if !(l.is_finite() && l > 0.0 && lt.to_f64() > 0.0 && lt.is_finite()) {
                return Err(leaf_error(format!(
                    "leaf size {l} of coordinate {a} is not a finite length > 0 in {}",
                    type_name::<T>()
                )));
            }
            // 1/leaf rounded once to T (in f64 and then to f32 is the f32 quotient: double
            // rounding is innocuous for a quotient when 53 >= 2·24 + 2).
            let inv = T::from_f64(1.0 / lt.to_f64());
            if !inv.is_finite() {
                return Err(leaf_error(format!(
                    "leaf size {l} of coordinate {a} has no finite inverse in {}",
                    type_name::<T>()
                )));
            }
            Ok(inv)
        })
        .collect()
}

/// `⌊x · inv⌋` as PCL computes it: the product rounded to `T`, then the floor (exact in f64).
#[inline]
fn cell<T: Scalar>(x: T, inv: T) -> f64 {
    (x * inv).to_f64().floor()
}

fn grid<T: Scalar>(lo: &[T], hi: &[T], inv: Vec<T>) -> Result<Grid<T>> {
    let d = inv.len();
    let limit = (1u64 << mantissa_bits::<T>()) as f64;
    let mut low = Vec::with_capacity(d);
    let mut mul = Vec::with_capacity(d);
    let mut cells: u64 = 1;
    for a in 0..d {
        let (b0, b1) = (cell(lo[a], inv[a]), cell(hi[a], inv[a]));
        // Every voxel coordinate must be an exact integer of T, and so must the difference
        // PCL takes in T (⌊x·inv⌋ − b_min): beyond 2^24 (f32) PCL's voxels are rounded.
        if !(b0.abs() <= limit && b1.abs() <= limit && b1 - b0 < limit) {
            return Err(leaf_error(format!(
                "the leaf is too small for the points' extent: along coordinate {a} the points \
                 span [{}, {}], voxel numbers {b0} to {b1}, beyond the 2^{} that {} represents \
                 exactly (use a larger leaf{})",
                lo[a],
                hi[a],
                mantissa_bits::<T>(),
                type_name::<T>(),
                if T::TYPE == ScalarType::F32 {
                    " or f64 points"
                } else {
                    ""
                }
            )));
        }
        mul.push(cells);
        let div = (b1 - b0) as u64 + 1;
        cells = cells.checked_mul(div).ok_or_else(|| {
            leaf_error(format!(
                "the leaf is too small for the points' extent: the bounding box holds more \
                 than 2^64 voxels (through coordinate {a}: {div} voxels along it)"
            ))
        })?;
        low.push(b0 as i64);
    }
    Ok(Grid {
        inv,
        low,
        mul,
        cells,
    })
}

/// Voxel-grid downsampling (PCL's `VoxelGrid`, Open3D's `voxel_down_sample`): the occupied
/// voxels of the finite points, in ascending linear voxel index, each with its centroid (PCL's
/// output), its members and the member nearest the centroid (the index-returning variant).
/// The arithmetic is PCL's in `T`, see the module documentation; read an `f32` buffer with
/// `T = f32` for PCL's voxels exactly. Points with a NaN or infinite coordinate belong to no
/// voxel (PCL skips them as well when the cloud is not marked dense). Identical for any thread
/// count.
///
/// Errors: a leaf size that is NaN, ≤ 0 or infinite (also after rounding to `T`), or whose
/// count does not match the dimension; a leaf so small for the points' extent that a voxel
/// number leaves the exact integers of `T` (2^24 for f32, 2^53 for f64) or the bounding box
/// holds more than 2^64 voxels (all [`NbhdError::InvalidOption`] naming `leaf`); too many
/// threads. (PCL 1.13 instead warns and returns the input unchanged when
/// `Π (⌊(max − min) · inv⌋ + 1)` exceeds 2^31 − 1; nbhd's 64-bit voxel numbers go further.)
///
/// ```
/// use nbhd::filter::{voxel_grid, VoxelGridOptions};
/// use nbhd::PointsView;
///
/// let pts = [0.1f32, 0.1, 0.2, 0.3, 1.5, 0.5];
/// let grid = voxel_grid::<f32>(&PointsView::from_flat(&pts, 2)?, &VoxelGridOptions::cube(1.0))?;
/// assert_eq!(grid.len(), 2);
/// assert_eq!(grid.members_of(0), [0, 1]);
/// let c = grid.centroid(0);
/// assert!((c[0] - 0.15).abs() < 1e-6 && (c[1] - 0.2).abs() < 1e-6);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn voxel_grid<T: Scalar>(
    view: &PointsView<'_>,
    options: &VoxelGridOptions,
) -> Result<VoxelGrid<T>> {
    crate::parallel::check_threads(options.threads)?;
    let d = view.dim();
    let inv = inverse_leaf::<T>(&options.leaf, d)?;
    crate::parallel::with_threads(options.threads, || run(view, options, inv))?
}

/// The voxel grid of the finite points of `view` with the inverse leaf `inv` (inside the pool).
fn run<T: Scalar>(
    view: &PointsView<'_>,
    options: &VoxelGridOptions,
    inv: Vec<T>,
) -> Result<VoxelGrid<T>> {
    let d = view.dim();
    let n = view.len();
    let empty = || VoxelGrid {
        dim: d,
        centroids: Vec::new(),
        offsets: vec![0],
        members: Vec::new(),
        nearest: Vec::new(),
        cells: Vec::new(),
        source_len: n,
    };
    let Some((lo, hi)) = bounds::<T>(view) else {
        return Ok(empty());
    };
    let g = grid(&lo, &hi, inv)?;
    let pairs = sorted_voxel_pairs(view, &g);
    let starts = voxel_runs(&pairs, options.min_points_per_voxel);
    let voxels = starts.len() / 2;
    if voxels == 0 {
        return Ok(empty());
    }
    let per_voxel: Vec<(Vec<T>, u32)> = (0..voxels)
        .into_par_iter()
        .map(|v| centroid_and_nearest(view, &pairs[starts[2 * v]..starts[2 * v + 1]]))
        .collect();
    let mut out = VoxelGrid {
        dim: d,
        centroids: Vec::with_capacity(voxels * d),
        offsets: Vec::with_capacity(voxels + 1),
        members: Vec::with_capacity(pairs.len()),
        nearest: Vec::with_capacity(voxels),
        cells: Vec::with_capacity(voxels * d),
        source_len: n,
    };
    out.offsets.push(0);
    for (v, (c, near)) in per_voxel.into_iter().enumerate() {
        out.centroids.extend_from_slice(&c);
        out.nearest.push(near);
        out.cells.extend(g.cells_of(pairs[starts[2 * v]].0));
        out.members.extend(
            pairs[starts[2 * v]..starts[2 * v + 1]]
                .iter()
                .map(|&(_, i)| i),
        );
        out.offsets.push(out.members.len());
    }
    Ok(out)
}

impl<T: Scalar> Grid<T> {
    /// The voxel numbers `⌊x_a · inv_a⌋` of the voxel with linear number `key`.
    fn cells_of(&self, key: u64) -> impl Iterator<Item = i64> + '_ {
        let d = self.low.len();
        (0..d).map(move |a| {
            let along = match self.mul.get(a + 1) {
                Some(&next) => (key % next) / self.mul[a],
                None => key / self.mul[a],
            };
            along as i64 + self.low[a]
        })
    }

    /// The linear number of the voxel holding the finite point `p`.
    fn key(&self, p: &[T]) -> u64 {
        let mut k = 0u64;
        for (a, &x) in p.iter().enumerate() {
            let i = cell(x, self.inv[a]) as i64 - self.low[a];
            k += i as u64 * self.mul[a];
        }
        k
    }
}

/// The (voxel, index) pairs of the finite points of `view`, sorted: by voxel, then by index.
fn sorted_voxel_pairs<T: Scalar>(view: &PointsView<'_>, g: &Grid<T>) -> Vec<(u64, u32)> {
    let d = view.dim();
    let n = view.len();
    // index order within a piece
    let mut pairs: Vec<(u64, u32)> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .flat_map_iter(|c| {
            let mut p = vec![T::ZERO; d];
            let mut out = Vec::with_capacity(CHUNK.min(n - c * CHUNK));
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                view.read_point(i, &mut p);
                if p.iter().all(|x| x.is_finite()) {
                    out.push((g.key(&p), i as u32));
                }
            }
            out
        })
        .collect();
    debug_assert!(pairs.iter().all(|&(k, _)| k < g.cells));
    // distinct pairs: the unstable sort has one result. With at most 2^32 voxels a pair packs
    // into one u64 (voxel above index), whose order is the pairs' order and sorts faster.
    if g.cells <= 1 << 32 {
        let mut packed: Vec<u64> = pairs.par_iter().map(|&(k, i)| k << 32 | i as u64).collect();
        packed.par_sort_unstable();
        pairs
            .par_iter_mut()
            .zip(packed.par_iter())
            .for_each(|(p, &k)| *p = (k >> 32, k as u32));
    } else {
        pairs.par_sort_unstable();
    }
    pairs
}

/// The runs of one voxel in the sorted `pairs` that hold at least `min_points` points, as
/// `[start, end)` bounds one after the other.
fn voxel_runs(pairs: &[(u64, u32)], min_points: usize) -> Vec<usize> {
    let mut starts: Vec<usize> = Vec::new();
    let mut s = 0;
    while s < pairs.len() {
        let mut e = s + 1;
        while e < pairs.len() && pairs[e].0 == pairs[s].0 {
            e += 1;
        }
        if e - s >= min_points {
            starts.push(s);
            starts.push(e);
        }
        s = e;
    }
    starts
}

/// The centroid of the points of one voxel's `run` and the member nearest to it (the lowest
/// index of equal distances).
fn centroid_and_nearest<T: Scalar>(view: &PointsView<'_>, run: &[(u64, u32)]) -> (Vec<T>, u32) {
    let d = view.dim();
    let mut p = vec![T::ZERO; d];
    let mut sum = vec![T::ZERO; d];
    for &(_, i) in run {
        view.read_point(i as usize, &mut p);
        for a in 0..d {
            sum[a] = sum[a] + p[a];
        }
    }
    // PCL divides by the count as a float; a quotient in f64 rounded to f32 is the
    // f32 quotient (53 >= 2·24 + 2).
    let count = T::from_f64(run.len() as f64).to_f64();
    let c: Vec<T> = sum
        .iter()
        .map(|s| T::from_f64(s.to_f64() / count))
        .collect();
    let mut best = (f64::INFINITY, u32::MAX);
    for &(_, i) in run {
        view.read_point(i as usize, &mut p);
        let mut d2 = 0.0;
        for a in 0..d {
            let t = p[a].to_f64() - c[a].to_f64();
            d2 += t * t;
        }
        // ascending indices: the first of equal distances stays
        // (a centroid overflowed to infinity gives NaN distances: the first member)
        if d2 < best.0 || best.1 == u32::MAX {
            best = (d2, i);
        }
    }
    (c, best.1)
}
