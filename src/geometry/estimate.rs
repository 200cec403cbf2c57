//! Normals of a point set (thesis eq. 2.8–2.10), the one function every front door calls for
//! them ([`estimate_normals`]: `nbhd_estimate_normals`, Python's `nbhd.normals`, the command
//! `nbhd normals`), and what PCL's `NormalEstimation` computes: per point the unit eigenvector
//! of the smallest eigenvalue of the covariance of the point and its ε-k-neighbourhood, the
//! surface variation `λ0/(λ0 + λ1 + λ2)` (PCL's `curvature`) and the degeneracy flags —
//! nothing of the principal curvatures, the feature criteria or the tangent frame that the
//! smoothing's analysis (`src/smooth/`) adds.
//!
//! The normal and eigenvalues are those of [`super::normals::local_frame`] bit for bit (the
//! smallest eigenvector in closed form, the Jacobi iteration where the closed form declines),
//! so a normal from here equals the one the smoothing's analysis reports. Every point's arithmetic
//! depends on its row only, so the result is identical for any number of threads.

use super::neighbors::{cut_to, mean_spacing_of};
use super::normals::{quotient_of, NormalCovariance, FLAG_SKIPPED};
use super::orientation::{orient_normals_with_progress, Orientation};
use super::source::{knn_rows, Neighbors, SearchMethod};
use crate::error::{NbhdError, Result};
use crate::index::{check_spacing, Length};
use crate::packed::{finite_subset, NonFinitePolicy};
use crate::prefetch::prefetch_at;
use crate::progress::{progress_in_units, relay, Stage};
use crate::scatter::{BlockScatter, Targets};
use crate::table::try_filled_par;
use crate::tree::exact_knn;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Settings of [`estimate_normals`]. `Default` gives the 15 nearest other points within 6 h
/// (`h` the mean spacing), unoriented, non-finite points rejected, the current thread pool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalOptions {
    /// Maximum valence `k` (≥ 1): at most the `k` nearest other points.
    pub k: usize,
    /// Influence radius `ε` (> 0, finite), in the points' units or multiples of `h`.
    pub epsilon: Length,
    /// Orientation of the normals.
    pub orientation: Orientation,
    /// Points with a NaN or infinite coordinate: refused, or skipped (their estimate is NaN
    /// with [`FLAG_SKIPPED`]).
    pub non_finite: NonFinitePolicy,
    /// Worker threads: 0 the current rayon pool, n ≥ 1 a pool of n threads. Results are
    /// identical for every value.
    pub threads: usize,
}

impl Default for NormalOptions {
    fn default() -> Self {
        Self {
            k: 15,
            epsilon: Length::Relative(6.0),
            orientation: Orientation::Unoriented,
            non_finite: NonFinitePolicy::Reject,
            threads: 0,
        }
    }
}

impl NormalOptions {
    /// Checks `k ≥ 1` ([`NbhdError::ZeroK`]) and a finite `ε > 0`
    /// ([`NbhdError::InvalidOption`] naming `epsilon`).
    pub fn validate(&self) -> Result<()> {
        if self.k == 0 {
            return Err(NbhdError::ZeroK);
        }
        let eps = match self.epsilon {
            Length::Absolute(v) | Length::Relative(v) => v,
        };
        if !(eps.is_finite() && eps > 0.0) {
            return Err(NbhdError::InvalidOption {
                name: "epsilon",
                reason: format!("{eps} must be finite and > 0"),
            });
        }
        Ok(())
    }
}

/// One point's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalEstimate {
    /// Unit normal (eq. 2.10), oriented as the options ask; NaN for a skipped point.
    pub normal: DVec3,
    /// The surface variation `λ0/(λ0 + λ1 + λ2)` of the covariance eigenvalues (0 on a plane,
    /// at most 1/3): PCL's `curvature`, the smoothing's `PointOutput::covariance_quotient`.
    pub surface_variation: f64,
    /// `geometry::normals::FLAG_*` bits, 0 for a well-defined normal.
    pub flags: u8,
}

impl NormalEstimate {
    /// The estimate of a point skipped for a non-finite coordinate.
    fn skipped() -> Self {
        Self {
            normal: DVec3::splat(f64::NAN),
            surface_variation: f64::NAN,
            flags: FLAG_SKIPPED,
        }
    }
}

/// What [`estimate_normals`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalsResult {
    /// One estimate per input point, in input order.
    pub normals: Vec<NormalEstimate>,
    /// Mean nearest-neighbour spacing `h` of the (finite) input.
    pub spacing: f64,
    /// Absolute ε used.
    pub epsilon: f64,
}

/// The normals of `points` over their ε-k-neighbourhoods (`options`), one estimate per point
/// in input order, identical for any number of threads.
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::{estimate_normals, NormalOptions};
///
/// // a noiseless patch of the plane z = 0
/// let points: Vec<DVec3> = (0..400)
///     .map(|i| DVec3::new((i % 20) as f64, (i / 20) as f64, 0.0))
///     .collect();
/// let result = estimate_normals(&points, &NormalOptions::default())?;
/// assert_eq!(result.spacing, 1.0);
/// for e in &result.normals {
///     assert!(e.normal.z.abs() > 1.0 - 1e-12 && e.surface_variation < 1e-12);
/// }
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
///
/// Errors: those of [`NormalOptions::validate`], [`NbhdError::EmptyInput`],
/// [`NbhdError::NonFinite`] (unless `options.non_finite` skips such points),
/// [`NbhdError::InvalidOption`] for a relative `ε` without a spacing (fewer than two distinct
/// points), [`NbhdError::Degenerate`] when no neighbourhood reaches 3 points,
/// [`NbhdError::ThreadPool`].
pub fn estimate_normals(points: &[DVec3], options: &NormalOptions) -> Result<NormalsResult> {
    estimate_normals_from(points, Neighbors::default(), options, &mut |_, _| true)
}

/// [`estimate_normals`] from the neighbourhoods `neighbors` (the call's own search by default,
/// or a caller's table: see [`Neighbors`]) with a progress callback, called with the fraction
/// done (0 to 1) and the stage on the thread that runs the computation; returning `false`
/// stops the run with [`NbhdError::Cancelled`].
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::{estimate_normals_from, Neighbors, NormalOptions};
///
/// let points: Vec<DVec3> = (0..400)
///     .map(|i| DVec3::new((i % 20) as f64, 0.0, (i / 20) as f64))
///     .collect();
/// let options = NormalOptions::default();
/// let result = estimate_normals_from(&points, Neighbors::default(), &options, &mut |_, _| true)?;
/// assert!(result.normals.iter().all(|e| e.normal.y.abs() > 1.0 - 1e-12));
/// // a callback that answers false stops the run
/// let stop = estimate_normals_from(&points, Neighbors::default(), &options, &mut |_, _| false);
/// assert!(matches!(stop, Err(nbhd::NbhdError::Cancelled)));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn estimate_normals_from(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &NormalOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<NormalsResult> {
    crate::parallel::with_threads(options.threads, || {
        options.validate()?;
        match finite_subset(points, options.non_finite)? {
            None => normals_finite(points, neighbors, options, progress),
            Some((index, finite)) => {
                let mut holder = None;
                let neighbors =
                    super::source::for_finite_subset(neighbors, &index, points.len(), &mut holder)?;
                let mut result = normals_finite(&finite, neighbors, options, progress)?;
                let mut all = vec![NormalEstimate::skipped(); points.len()];
                for (&i, e) in index.iter().zip(&result.normals) {
                    all[i] = *e;
                }
                result.normals = all;
                Ok(result)
            }
        }
    })?
}

/// [`estimate_normals_from`] on finite points (nonempty, every coordinate finite:
/// `finite_subset` checked or chose them, so they are not scanned again).
fn normals_finite(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    options: &NormalOptions,
    progress: &mut (dyn FnMut(f64, Stage) -> bool + Send),
) -> Result<NormalsResult> {
    let mut report = progress_in_units(1.0, progress);
    report(0.0, Stage::Neighbors)?;
    if neighbors == Neighbors::Search(SearchMethod::KdTree)
        && options.orientation == Orientation::Unoriented
    {
        return normals_in_tree_order(points, options, &mut report);
    }
    let (knn, _) = knn_rows(points, neighbors, options.k)?;
    let h = mean_spacing_of(&knn);
    let relative = matches!(options.epsilon, Length::Relative(_));
    check_spacing(h, relative)?;
    let eps = options.epsilon.resolve(h);
    // each row's within-ε prefix (rows are nearest first): the ε-k-neighbourhood, read in
    // place rather than copied into a cut table
    let e2 = eps * eps;
    let within = |i: usize| {
        let d = knn.sq_dists_of(i);
        if d.last().is_none_or(|&x| x <= e2) {
            d.len()
        } else {
            d.partition_point(|&x| x <= e2)
        }
    };
    let largest = (0..knn.len())
        .into_par_iter()
        .map(within)
        .max()
        .unwrap_or(0);
    let refusal = Refusal {
        points: knn.len(),
        largest,
        epsilon: eps,
        spacing: h,
        relative,
    };
    refusal.too_few()?;
    report(0.5, Stage::Outputs)?;
    // in the caller's order: the rows are read in the order the table stores them, and the
    // neighbours' reads, independent of one another, overlap (measured faster than the tree's
    // order, which reads nearby points from cache but each row from afar, on random-order
    // clouds); each offset is read once into the worker's buffer
    let mut estimates = estimates_of_rows(points, points.len(), 1024, |i| {
        (points[i], &knn.indices_of(i)[..within(i)])
    });
    refusal.all_flagged(&estimates)?;
    report(0.6, Stage::Outputs)?;
    if options.orientation == Orientation::Unoriented {
        report(1.0, Stage::Done)?;
        return Ok(NormalsResult {
            normals: estimates,
            spacing: h,
            epsilon: eps,
        });
    }
    // the orientation's graph is the ε-k-neighbourhoods themselves
    let table = cut_to(knn, eps);
    let mut normals: Vec<DVec3> = estimates.iter().map(|e| e.normal).collect();
    orient_normals_with_progress(
        points,
        &table,
        &mut normals,
        options.orientation,
        &mut |f| report(0.6 + 0.4 * f, Stage::Outputs).is_ok(),
    )?;
    for (e, &n) in estimates.iter_mut().zip(&normals) {
        e.normal = n;
    }
    report(1.0, Stage::Done)?;
    Ok(NormalsResult {
        normals: estimates,
        spacing: h,
        epsilon: eps,
    })
}

/// Points per block of the fused search: each worker searches and consumes whole blocks, a
/// block's rows while they are still in its cache (about 1.4 MB at k = 15); 4096 and 16384
/// measured the same.
const BLOCK: usize = 8192;

/// What the smoothing's `check_not_degenerate` refuses, with the same message: no neighbourhood reaches
/// 3 points, or every estimate is flagged.
struct Refusal {
    points: usize,
    /// The most neighbours any point has within ε.
    largest: usize,
    epsilon: f64,
    spacing: f64,
    relative: bool,
}

impl Refusal {
    fn error(&self, flagged: usize) -> NbhdError {
        NbhdError::Degenerate {
            points: self.points,
            largest: self.largest + 1,
            flagged,
            epsilon: self.epsilon,
            spacing: self.spacing,
            relative: self.relative,
        }
    }

    /// No neighbourhood reaches 3 points (the point and two neighbours).
    fn too_few(&self) -> Result<()> {
        if self.largest + 1 < 3 {
            return Err(self.error(0));
        }
        Ok(())
    }

    /// Every estimate is flagged.
    fn all_flagged(&self, estimates: &[NormalEstimate]) -> Result<()> {
        let flagged = estimates.iter().filter(|e| e.flags != 0).count();
        if flagged == estimates.len() {
            return Err(self.error(flagged));
        }
        Ok(())
    }
}

/// The estimate of the point `p` from its neighbours `row` (caller indices, nearest first),
/// the arithmetic of [`estimates_of_rows`] exactly.
fn estimate_of(points: &[DVec3], p: DVec3, row: &[u32], buf: &mut Vec<DVec3>) -> NormalEstimate {
    estimate(covariance_of(points, p, row, buf).normal())
}

/// Points whose eigen-solves run together in [`estimates_of_rows`] (as in the robust smoothing,
/// `smooth/robust/planes.rs`).
const BATCH: usize = 16;

/// Rows ahead whose neighbours' points are requested before their covariance is summed.
const PREFETCH_ROWS: usize = 4;

/// The estimates of `n` points, point `r` at `p` with its neighbours `row` (caller indices,
/// nearest first) as `point(r)` gives them, in parallel over batches of [`BATCH`] points of at
/// least `min_len` points a task: the covariances of a batch, then their eigenvectors together
/// (`NormalCovariance::normals`). Each estimate depends on its own row only: [`estimate_of`]'s
/// bits, for any number of threads.
fn estimates_of_rows<'a>(
    points: &[DVec3],
    n: usize,
    min_len: usize,
    point: impl Fn(usize) -> (DVec3, &'a [u32]) + Sync,
) -> Vec<NormalEstimate> {
    let mut out = vec![NormalEstimate::skipped(); n];
    out.par_chunks_mut(BATCH)
        .enumerate()
        .with_min_len(min_len.div_ceil(BATCH))
        .for_each_init(Vec::new, |buf: &mut Vec<DVec3>, (b, batch)| {
            // the lanes past the last point (of the last batch only) stay zero
            let mut c = [NormalCovariance::default(); BATCH];
            for (l, c) in c.iter_mut().enumerate().take(batch.len()) {
                let i = b * BATCH + l;
                if i + PREFETCH_ROWS < n {
                    prefetch_at(points, point(i + PREFETCH_ROWS).1);
                }
                let (p, row) = point(i);
                *c = covariance_of(points, p, row, buf);
            }
            for (e, normal) in batch.iter_mut().zip(NormalCovariance::normals(&c)) {
                *e = estimate(normal);
            }
        });
    out
}

/// The covariance of the point `p` and its neighbours `row`, their offsets read into `buf`.
#[inline]
fn covariance_of(
    points: &[DVec3],
    p: DVec3,
    row: &[u32],
    buf: &mut Vec<DVec3>,
) -> NormalCovariance {
    buf.clear();
    buf.extend(row.iter().map(|&j| points[j as usize] - p));
    NormalCovariance::of(buf.iter().copied(), buf.len() + 1)
}

/// The estimate of a normal, eigenvalues and flags.
#[inline]
fn estimate((normal, values, flags): (DVec3, DVec3, u8)) -> NormalEstimate {
    NormalEstimate {
        normal,
        surface_variation: quotient_of(values),
        flags,
    }
}

/// The unoriented normals of the call's own k-d tree search, bit for bit those of the table
/// path of [`normals_finite`], without the table of every point: the rows come a block of
/// consecutive tree positions at a time (`nearest.rs`: an `f32` search proven exact in `f64`)
/// and are consumed while in cache, in tree order, so that a block's neighbours are a few
/// nearby points read again and again rather than points all over the caller's array. ε is
/// known only once the spacing is (the mean over every row's nearest neighbour), so each row
/// is consumed whole and the rows that ε cuts (rare for the default 6h; their last neighbour
/// lies beyond ε) are searched again, on the blocks' own tree (`Searched::rows_at`: a second
/// tree of every point for the 0.2 % of rows the 1M torus has cut cost a sixth of the call), and
/// consumed cut. Whole blocks run in parallel (`nearest::Blocks::for_each`), so the threads
/// never wait for one another between blocks: with a fork and join for each step of each block,
/// another process on one core made two threads slower than one (`docs/speed-log.md`, round 10).
fn normals_in_tree_order(
    points: &[DVec3],
    options: &NormalOptions,
    report: &mut (dyn FnMut(f64, Stage) -> Result<()> + Send),
) -> Result<NormalsResult> {
    let n = points.len();
    let k = options.k;
    // each block's estimates and nearest distances go to the caller's order as they are made
    // (written while the block is in cache, rather than gathered at random afterwards); the
    // farthest distances stay in tree order, where the cut rows are found
    let mut estimates = try_filled_par(n, NormalEstimate::skipped(), "the normals")?;
    let mut nearest = try_filled_par(n, None, "the nearest-neighbour distances")?;
    let mut farthest_in_tree = try_filled_par(n, 0.0, "the farthest-neighbour distances")?;
    let mut blocks_done = |f: f64| report(0.9 * f, Stage::Neighbors);
    let searched = exact_knn::by_blocks(points, k, BLOCK, |blocks| {
        let targets = Targets::check(blocks.order(), n)?;
        let bounds = blocks.bounds();
        let est = BlockScatter::to_targets(&mut estimates, &targets, bounds, 1)?;
        let near = BlockScatter::to_targets(&mut nearest, &targets, bounds, 1)?;
        let far = BlockScatter::in_place(&mut farthest_in_tree, bounds, 1)?;
        let done = AtomicUsize::new(0);
        relay(&mut blocks_done, |relay| {
            blocks.for_each(&|b| {
                let start = b.positions.start;
                let block = estimates_of_rows(points, b.positions.len(), 256, |r| {
                    (points[b.order[start + r] as usize], b.row(r))
                });
                est.write(b.index, block.into_iter())?;
                // the distances themselves, for the mean spacing
                near.write(b.index, b.nearest.iter().map(|d| d.map(f64::sqrt)))?;
                far.write(b.index, b.farthest.iter().copied())?;
                let done = done.fetch_add(b.positions.len(), Ordering::Relaxed);
                relay.tick((done + b.positions.len()) as f64 / n as f64)
            })
        })
    })?;
    let order = &searched.order;
    // the mean nearest-neighbour spacing, summed in caller order as on the table path
    let h = crate::index::mean_distance(nearest.into_iter().flatten());
    let relative = matches!(options.epsilon, Length::Relative(_));
    check_spacing(h, relative)?;
    let eps = options.epsilon.resolve(h);
    let e2 = eps * eps;
    // rows that ε cuts (found in tree order): their rows again from the blocks' search,
    // consumed up to ε
    let cut: Vec<usize> = (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .filter(|&pos| farthest_in_tree[pos] > e2)
        .collect();
    let rows = searched.rows_at(points, &cut)?;
    let recomputed: Vec<(NormalEstimate, usize)> = cut
        .par_iter()
        .zip(&rows)
        .with_min_len(64)
        .map_init(Vec::new, |buf, (&pos, found)| {
            let i = order[pos] as usize;
            let within = found.partition_point(|x| x.sq_dist <= e2);
            let ids: Vec<u32> = found[..within].iter().map(|x| x.index).collect();
            (estimate_of(points, points[i], &ids, buf), within)
        })
        .collect();
    // every row has its k nearest others (all others where there are fewer); an uncut one
    // holds them all within ε
    let uncut = farthest_in_tree.par_iter().any(|&f| f <= e2);
    let mut largest = if uncut { k.min(n - 1) } else { 0 };
    for (&pos, &(e, within)) in cut.iter().zip(&recomputed) {
        estimates[order[pos] as usize] = e;
        largest = largest.max(within);
    }
    let refusal = Refusal {
        points: n,
        largest,
        epsilon: eps,
        spacing: h,
        relative,
    };
    refusal.too_few()?;
    refusal.all_flagged(&estimates)?;
    report(1.0, Stage::Done)?;
    Ok(NormalsResult {
        normals: estimates,
        spacing: h,
        epsilon: eps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{sample, Shape, Torus};
    use crate::smooth::{analyze, SmoothOptions};

    #[test]
    fn blocks_of_the_fused_path_equal_the_table_path() {
        // more than two blocks of `BLOCK` tree positions, the last one partial
        let s = sample(&Torus::new(1.0, 0.4), 2 * BLOCK + 1234, 11);
        let opts = SmoothOptions::default();
        let full = analyze(&s.points, &opts).unwrap();
        for threads in [1, 2] {
            let got = estimate_normals(
                &s.points,
                &SmoothOptions { threads, ..opts }.normal_options(),
            )
            .unwrap();
            assert_same_as_analysis(&got, &full);
        }
    }

    /// `got` holds the spacing, ε and per-point normals, surface variations and flags of `full`.
    fn assert_same_as_analysis(got: &NormalsResult, full: &crate::smooth::SmoothResult) {
        assert_eq!((got.spacing, got.epsilon), (full.spacing, full.epsilon));
        assert_eq!(got.normals.len(), full.outputs.len());
        for (g, f) in got.normals.iter().zip(&full.outputs) {
            assert_eq!(g.normal, f.normal);
            assert_eq!(g.surface_variation, f.covariance_quotient);
            assert_eq!(g.flags, f.normal_flags);
        }
    }

    /// Far from the origin (coordinates large against the spacing: many rows the `f32` search
    /// does not prove) and beyond what the `f32` search takes (rows from an `f64` search
    /// throughout), the normals are those of the table path.
    #[test]
    fn far_from_the_origin_and_huge_equal_the_table_path() {
        let s = sample(&Torus::new(1.0, 0.4), 2000, 5);
        for (offset, scale) in [(1e6, 1.0), (0.0, 1e19)] {
            let far: Vec<DVec3> = s.points.iter().map(|&p| p * scale + offset).collect();
            let opts = SmoothOptions {
                epsilon: Length::Absolute(0.2 * scale),
                ..SmoothOptions::default()
            };
            let full = analyze(&far, &opts).unwrap();
            let got = estimate_normals(&far, &opts.normal_options()).unwrap();
            assert_same_as_analysis(&got, &full);
        }
    }

    #[test]
    fn equals_the_full_analysis_bit_for_bit_for_any_threads() {
        let torus = Torus::new(1.0, 0.4);
        let s = sample(&torus, 3000, 7);
        for (orientation, eps) in [
            (Orientation::Unoriented, Length::Relative(6.0)),
            // the fused tree-order path with rows cut by ε (searched again)
            (Orientation::Unoriented, Length::Relative(1.5)),
            (Orientation::Propagate, Length::Relative(6.0)),
            // rows cut by ε
            (Orientation::AwayFrom(DVec3::ZERO), Length::Relative(2.5)),
        ] {
            let opts = SmoothOptions {
                orientation,
                epsilon: eps,
                ..SmoothOptions::default()
            };
            let full = analyze(&s.points, &opts).unwrap();
            for threads in [1, 2, 3] {
                let got = estimate_normals(
                    &s.points,
                    &SmoothOptions { threads, ..opts }.normal_options(),
                )
                .unwrap();
                assert_same_as_analysis(&got, &full);
            }
            if orientation == Orientation::Propagate {
                // consistent on the closed torus: every normal outward
                let outward = full
                    .outputs
                    .iter()
                    .zip(&s.points)
                    .filter(|(o, &p)| o.normal.dot(torus.closest(p).normal) > 0.0)
                    .count();
                assert_eq!(outward, s.points.len());
            }
        }
    }
}
