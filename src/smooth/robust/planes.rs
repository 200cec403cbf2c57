//! Steps 2 and 3 of the robust smoothing (see the parent module): the covariance plane of every
//! point's wide neighbourhood, the noise estimate σ̂, and the feature-aware normal chosen among
//! candidate planes by a robust count of the points each explains.

use super::rows::Rows;
use crate::geometry::robust_plane::{smallest_eigenvectors, Neighborhood, WeightedSums};
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// The covariance plane of `N_i ∪ {p_i}` (eq. 2.8–2.10): unit normal (eq. 2.10) and the
/// barycentre it passes through (eq. 2.3).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Plane {
    pub(super) normal: DVec3,
    pub(super) barycentre: DVec3,
}

/// Points whose eigen-solves run together ([`smallest_eigenvectors`]): interleaved, their Newton
/// iterations keep the divider busy where one alone waits on it. Measured on the 80k torus of
/// `examples/robust_timing.rs` (one thread, CPU time in the solves): 4 lanes take 0.46 of the
/// time of one at a time, 8 lanes 0.31, 16 lanes 0.25, 32 lanes 0.24.
const BATCH: usize = 16;

/// Points per parallel task: whole batches, each task's in order.
const CHUNK: usize = 16 * BATCH;

/// The covariance plane of every stored point over its wide neighbourhood, in parallel over
/// chunks of points; within a chunk, the covariances of a batch of points and then their
/// eigenvectors together.
pub(super) fn covariance_planes(points: &[DVec3], rows: &Rows) -> Vec<Plane> {
    let mut planes = vec![Plane::default(); points.len()];
    planes.par_chunks_mut(CHUNK).enumerate().for_each_init(
        Neighborhood::default,
        |local, (c, chunk)| {
            for (b, batch) in chunk.chunks_mut(BATCH).enumerate() {
                let first = c * CHUNK + b * BATCH;
                // the lanes past the last point (of the last batch only) stay zero
                let mut matrices = [DMat3::ZERO; BATCH];
                for (l, plane) in batch.iter_mut().enumerate() {
                    let s = first + l;
                    local.fill(points, s, rows.wide(s));
                    let c = local
                        .covariance()
                        .expect("a neighbourhood holds its own point");
                    matrices[l] = c.matrix;
                    plane.barycentre = points[s] + c.sum / local.len() as f64;
                }
                for (plane, n) in batch.iter_mut().zip(smallest_eigenvectors(&matrices)) {
                    plane.normal = n;
                }
            }
        },
    );
    planes
}

/// The distance of every point to its own covariance plane: σ̂ is 1.4826 × their median (the
/// median absolute deviation of a normal distribution; `robust/run.rs`), which ignores the
/// minority of points at edges.
pub(super) fn plane_distances(points: &[DVec3], planes: &[Plane]) -> Vec<f64> {
    points
        .par_iter()
        .zip(planes)
        .map(|(&p, c)| plane_distance(p, c))
        .collect()
}

/// The distance of `p` to the plane `c`, `|⟨n, p − b⟩|`.
#[inline]
pub(super) fn plane_distance(p: DVec3, c: &Plane) -> f64 {
    c.normal.dot(p - c.barycentre).abs()
}

/// Support (biweight mass over the wide neighbourhood, as a fraction of its points, summed in
/// `f64` with the refit's weights) from which a point's own covariance plane is kept without
/// scoring the other candidates. With Gaussian
/// noise of σ̂ a perfect plane scores about 0.92 per point (`1 − 2σ̂²/w²` at width `w = 5σ̂`), so
/// 0.9 means "as well as the noise allows": a shifted neighbourhood could add at most a tenth.
/// Measured on the shapes of docs/smoothing-results.md (20k points, 0.3h and 1h): 73 % (cube) to
/// 98 % (torus) of the points skip the scoring, and RMS, edge RMS and normal error move by at
/// most 0.002h and 0.02°.
const SMOOTH_PATCH_SUPPORT: f64 = 0.9;

/// Lanes of the scoring loop: the points of a neighbourhood are scored eight at a time.
const LANES: usize = 8;

/// A point and its wide neighbours relative to the point. The scoring reads them coordinate by
/// coordinate in `f32` (relative coordinates of a few spacings: the rounding, 6e-8 of that, is
/// far below the inlier width), padded to a multiple of [`LANES`] with NaN, whose biweight is 0;
/// the refit reads them in `f64`.
#[derive(Default)]
struct Local {
    /// The points relative to the point, for the refit.
    points: Neighborhood,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

impl Local {
    /// The `f32` copies the scoring reads, of the points as filled.
    fn single_precision(&mut self) {
        let len = self.points.len();
        let padded = len.div_ceil(LANES) * LANES;
        for (v, f) in [
            (&mut self.x, &self.points.x),
            (&mut self.y, &self.points.y),
            (&mut self.z, &self.points.z),
        ] {
            v.clear();
            v.extend(f[..len].iter().map(|&c| c as f32));
            v.resize(padded, f32::NAN);
        }
    }

    /// `Σ biweight((⟨n, q⟩ − offset) / width)` over the local points `q`: how many of them the
    /// plane `⟨n, q⟩ = offset` explains. Summed in eight lanes and then lane by lane, the same
    /// order on every machine and thread. Where the processor has AVX, the eight lanes are one
    /// instruction each: the same operations on the same lanes, so the same bits (without FMA,
    /// which would round differently).
    fn score(&self, n: DVec3, offset: f64, width: f64) -> f32 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx() {
            // SAFETY: the processor supports AVX (checked just above).
            return unsafe { self.score_avx(n, offset, width) };
        }
        self.score_lanes(n, offset, width)
    }

    /// [`Local::score`] compiled for AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn score_avx(&self, n: DVec3, offset: f64, width: f64) -> f32 {
        self.score_lanes(n, offset, width)
    }

    /// The loop of [`Local::score`], inlined into each instruction set's version.
    #[inline(always)]
    fn score_lanes(&self, n: DVec3, offset: f64, width: f64) -> f32 {
        let (nx, ny, nz) = (n.x as f32, n.y as f32, n.z as f32);
        let (offset, inv) = (offset as f32, (1.0 / width) as f32);
        let mut acc = [0.0f32; LANES];
        let chunks = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES));
        for ((x, y), z) in chunks {
            for l in 0..LANES {
                let u = (nx * x[l] + ny * y[l] + nz * z[l] - offset) * inv;
                let v = 1.0 - u * u;
                acc[l] += if v > 0.0 { v * v } else { 0.0 };
            }
        }
        acc.iter().sum()
    }

    /// The normal of the covariance of the local points weighted by their biweight to the plane
    /// `⟨n, q⟩ = offset` (eq. 2.8–2.10 with a weight per point), or `None` if no point has
    /// weight.
    fn refit(&mut self, n: DVec3, offset: f64, width: f64) -> Option<DVec3> {
        self.points.weighted_normal(n, offset, width)
    }
}

/// Step 3 of the parent module: for each point the best-supported plane among its own
/// covariance plane and those of the farthest quarter of its wide neighbours, refitted over its
/// inliers. A point whose own plane reaches [`SMOOTH_PATCH_SUPPORT`] keeps it unscored against
/// the others. The candidates are the farthest neighbours because their neighbourhoods are shifted
/// the most: near an edge they are the ones that lie on one face; the nearer neighbours'
/// neighbourhoods overlap the point's own almost entirely and repeat its plane (measured: the
/// quality of docs/smoothing-results.md holds or improves with a quarter of the candidates, at a
/// quarter of the cost of scoring all). At most `candidates` of them are scored, evenly spread
/// over the quarter (the farthest included): a row widened by the noise scale has three times
/// as many, each scored over three times the points, and neighbours a third of a wide row's
/// spacing apart offer nearly the same plane (see [`candidate_stride`]). In parallel over
/// chunks of points; the refits of the points' own planes (most points) are solved a batch at a
/// time.
pub(super) fn selected_normals(
    points: &[DVec3],
    rows: &Rows,
    planes: &[Plane],
    width: f64,
    candidates: usize,
) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; points.len()];
    normals
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each_init(Local::default, |local, (c, chunk)| {
            let mut queue = Queue::default();
            for i in 0..chunk.len() {
                match local.select(points, rows, planes, width, candidates, c * CHUNK + i) {
                    Selected::Normal(n) => chunk[i] = n,
                    Selected::Own(sums, own) => queue.push(i, sums, own, chunk),
                }
            }
            queue.solve(chunk);
        });
    normals
}

/// A point's normal from [`Local::select`], or the refit of its own plane that it waits for.
enum Selected {
    Normal(DVec3),
    /// [`WeightedSums::normal`] of these sums, or where there is none, the plane's normal.
    Own(WeightedSums, DVec3),
}

impl Local {
    /// The normal of [`selected_normals`] for stored point `s`, or the sums of its own plane's
    /// refit.
    fn select(
        &mut self,
        points: &[DVec3],
        rows: &Rows,
        planes: &[Plane],
        width: f64,
        candidates: usize,
        s: usize,
    ) -> Selected {
        let row = rows.wide(s);
        self.points.fill(points, s, row);
        let p = points[s];
        // the plane of stored point c in coordinates relative to p: ⟨n, q⟩ = ⟨n, b − p⟩
        let plane_of = |c: usize| {
            let pl = planes[c];
            (pl.normal, pl.normal.dot(pl.barycentre - p))
        };
        let own = plane_of(s);
        let own_sums = self.points.weighted_sums(own.0, own.1, width);
        // a point its own plane explains almost entirely lies on a smooth patch: keep it
        let smooth = SMOOTH_PATCH_SUPPORT * self.points.len() as f64;
        if own_sums.weight >= smooth {
            return Selected::Own(own_sums, own.0);
        }
        self.single_precision();
        let mut best = (self.score(own.0, own.1, width), None);
        let far = &row[row.len() - row.len().div_ceil(4)..];
        let stride = candidate_stride(far.len(), candidates);
        for &j in far
            .iter()
            .skip((far.len() + stride - 1) % stride)
            .step_by(stride)
        {
            let candidate = plane_of(j as usize);
            let score = self.score(candidate.0, candidate.1, width);
            if score > best.0 {
                best = (score, Some(candidate));
            }
        }
        match best.1 {
            None => Selected::Own(own_sums, own.0),
            Some((n, offset)) => Selected::Normal(self.refit(n, offset, width).unwrap_or(n)),
        }
    }
}

/// The step between the candidates scored among the `far` farthest neighbours of a row, so that
/// at most `candidates` are (1 where the quarter holds no more, as in the plain rows: every one
/// is scored). While the rows are widened by the noise scale (`robust/scales.rs`) the quarter
/// holds three times `candidates`; scoring each of them over a row three times as long was
/// about nine times the plain rows' cost per point.
fn candidate_stride(far: usize, candidates: usize) -> usize {
    far.div_ceil(candidates.max(1)).max(1)
}

/// The points of a chunk that wait for their own plane's refit, until a batch of them is
/// solved together.
#[derive(Default)]
struct Queue {
    /// The refits' matrices ([`WeightedSums::centred`]).
    matrices: [DMat3; BATCH],
    /// Each one's place in the chunk and its plane's normal.
    at: [(usize, DVec3); BATCH],
    len: usize,
}

impl Queue {
    /// The normal of the point at `i` of the chunk `out`: [`WeightedSums::normal`] of `sums`, or
    /// where there is none, the plane's normal `own`. Queued, and solved once a batch is full.
    fn push(&mut self, i: usize, sums: WeightedSums, own: DVec3, out: &mut [DVec3]) {
        let Some(m) = sums.centred() else {
            out[i] = own;
            return;
        };
        self.matrices[self.len] = m;
        self.at[self.len] = (i, own);
        self.len += 1;
        if self.len == BATCH {
            self.solve(out);
        }
    }

    /// The normals of the queued points into `out`; empties the queue.
    fn solve(&mut self, out: &mut [DVec3]) {
        // the lanes past the last point (of a chunk's last batch) are solved as zero
        self.matrices[self.len..].fill(DMat3::ZERO);
        let normals = smallest_eigenvectors(&self.matrices);
        for (&(i, own), n) in self.at[..self.len].iter().zip(normals) {
            // as `WeightedSums::normal`: a normal that is not finite is none
            out[i] = if n.is_finite() { n } else { own };
        }
        self.len = 0;
    }
}

/// The biweight itself is defined once, in `geometry::robust_plane`; the scoring loop above
/// inlines its arithmetic (multiplying by the inverse width) so that it vectorises. This
/// checks that both agree.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::robust_plane::biweight;

    /// The candidates scored: every one of a plain row's quarter, a third of a wide row's
    /// (the farthest included), never more than asked for.
    #[test]
    fn candidates_spread_over_the_farthest_quarter() {
        let scored = |far: usize, candidates: usize| {
            let stride = candidate_stride(far, candidates);
            let picked: Vec<usize> = (0..far)
                .skip((far + stride - 1) % stride)
                .step_by(stride)
                .collect();
            assert!(picked.len() <= candidates.max(1), "{far} {candidates}");
            assert!(far == 0 || picked.last() == Some(&(far - 1)));
            picked
        };
        assert_eq!(scored(12, 12), (0..12).collect::<Vec<_>>());
        assert_eq!(scored(5, 12), (0..5).collect::<Vec<_>>());
        assert_eq!(scored(36, 12), (2..36).step_by(3).collect::<Vec<_>>());
        assert_eq!(scored(35, 12).len(), 12);
        assert!(scored(0, 12).is_empty());
        assert_eq!(scored(7, 0), [6]);
    }

    #[test]
    fn lane_scores_match_the_biweight_sum() {
        let pts: Vec<DVec3> = (0..11)
            .map(|i| DVec3::new(i as f64 * 0.3, (i * i) as f64 * 0.05, (i % 3) as f64 * 0.1))
            .collect();
        let row: Vec<u32> = (1..11).collect();
        let mut local = Local::default();
        local.points.fill(&pts, 0, &row);
        local.single_precision();
        assert_eq!(local.x.len(), 16);
        let n = DVec3::new(0.1, 0.2, 1.0).normalize();
        let expect: f64 = pts
            .iter()
            .map(|&q| biweight((n.dot(q - pts[0]) - 0.05) / 0.2))
            .sum();
        assert!((f64::from(local.score(n, 0.05, 0.2)) - expect).abs() < 1e-5);
        // the instruction set's version gives the portable loop's bits
        assert_eq!(
            local.score(n, 0.05, 0.2).to_bits(),
            local.score_lanes(n, 0.05, 0.2).to_bits()
        );
        // points on the plane z = 0 only: the refit finds it
        let flat: Vec<DVec3> = (0..9)
            .map(|i| DVec3::new((i % 3) as f64, (i / 3) as f64, 0.0))
            .chain([DVec3::new(0.5, 0.5, 3.0)])
            .collect();
        local.points.fill(&flat, 0, &(1..10).collect::<Vec<u32>>());
        local.single_precision();
        let r = local.refit(DVec3::Z, 0.0, 0.5).unwrap();
        assert!((r.z.abs() - 1.0).abs() < 1e-12);
        assert_eq!(local.refit(DVec3::Z, 100.0, 0.5), None);
    }
}
