//! The PCA sweep baseline (thesis Section 5.1, Algorithm 8): the points are sorted by their
//! projection on the principal axis of largest variance of the whole set; a query only looks at
//! the points whose projection on that axis lies within the search radius of the query's, skips
//! those whose projection on any other principal axis is farther off than the radius, and
//! decides on the rest by the exact distance.
//!
//! Results are identical to [`BruteForce`](super::brute::BruteForce): the last word is always
//! the same `sq_dist(q, x) ≤ bound` test in the scalar type `T`. Projections are computed in
//! `f64` and are rounded, so every pruning test is widened by a margin that covers the rounding
//! of the projections and of `sq_dist` itself (see `Margins`): a point is pruned only if its
//! computed squared distance is certainly above the bound.
//!
//! - Radius queries scan the window `[q·a₁ − ε, q·a₁ + ε]` (found by binary search) in order.
//! - k-nearest and ε-k queries sweep outward from the query's position on the first axis,
//!   always taking the side whose next projection is closer, and stop when that gap exceeds the
//!   current bound of the heap (the radius until `k` candidates are held, then the k-th
//!   distance).

use super::brute::sq_dist;
use super::{Neighbor, NeighborHeap, NeighborSearch, Neighborhood, Query};
use crate::error::Result;
use crate::linalg::sym_eigen;
use crate::packed::{NonFinitePolicy, PackedPoints};
use crate::points::PointsView;
use crate::query::resolve_query;
use crate::scalar::{Scalar, ScalarType};

/// Coordinates at least this large (in absolute value) switch pruning off: projections and
/// their error bounds could overflow. Queries then scan every point (still exact).
const PRUNE_LIMIT: f64 = 1e300;

/// Answers queries by a sweep along the principal axis of largest variance (thesis
/// Algorithm 8), with the same results as brute force.
///
/// ```
/// use nbhd::{Neighborhood, NeighborSearch, NonFinitePolicy, PcaSweep, PointsView, Query};
///
/// let pts = [[0.0f32, 0.0], [1.0, 0.0], [0.0, 2.0], [3.0, 3.0]];
/// let view = PointsView::from_rows(&pts)?;
/// let pca = PcaSweep::<f32>::new(&view, NonFinitePolicy::Reject)?;
/// let mut out = Vec::new();
/// pca.search(Query::stored_excluding_self(0), Neighborhood::Knn { k: 2 }, &mut out)?;
/// let found: Vec<(u32, f32)> = out.iter().map(|n| (n.index, n.sq_dist)).collect();
/// assert_eq!(found, [(1, 1.0), (2, 4.0)]);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PcaSweep<T> {
    /// The points, reordered by ascending projection on the first axis (ties by input order).
    packed: PackedPoints<T>,
    /// Slot of every caller index (`u32::MAX` for skipped points).
    slot_of: Vec<u32>,
    /// Principal axes as rows of a `d × d` matrix, by descending variance, unit length.
    axes: Vec<f64>,
    /// Projection of each slot on the first axis, ascending.
    first: Vec<f64>,
    /// Projections of each slot on axes `2..=d`, `d − 1` per slot.
    others: Vec<f64>,
    /// Upper bound of the Euclidean norm of every stored point.
    max_norm: f64,
    /// `false` if the coordinates are too large for safe projection bounds.
    prune: bool,
}

impl<T: Scalar> PcaSweep<T> {
    /// Copies the points of `view` (non-finite points handled by `policy`), computes the
    /// principal axes of the whole set about its barycentre and sorts the points along the
    /// first one. `O(n d² + n log n)`.
    pub fn new(view: &PointsView<'_>, policy: NonFinitePolicy) -> Result<Self> {
        let packed = PackedPoints::<T>::from_view(view, policy)?;
        if packed.len() == 0 {
            // No principal axes without a point.
            return Err(crate::error::NbhdError::EmptyInput);
        }
        let (n, d) = (packed.len(), packed.dim);
        let max_abs = packed
            .coords
            .iter()
            .fold(0.0f64, |m, c| m.max(c.to_f64().abs()));
        let prune = max_abs < PRUNE_LIMIT;
        let axes = principal_axes(&packed, max_abs);

        let proj: Vec<f64> = (0..n)
            .flat_map(|s| {
                let p = packed.point(s);
                axes.chunks_exact(d).map(move |a| project(p, a))
            })
            .collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_unstable_by(|&a, &b| {
            proj[a as usize * d]
                .total_cmp(&proj[b as usize * d])
                .then(a.cmp(&b))
        });

        let mut coords = Vec::with_capacity(n * d);
        let mut ids = Vec::with_capacity(n);
        let mut first = Vec::with_capacity(n);
        let mut others = Vec::with_capacity(n * (d - 1));
        for &s in &order {
            let s = s as usize;
            coords.extend_from_slice(packed.point(s));
            ids.push(packed.ids[s]);
            first.push(proj[s * d]);
            others.extend_from_slice(&proj[s * d + 1..(s + 1) * d]);
        }
        let packed = PackedPoints {
            coords,
            ids,
            dim: d,
            source_len: packed.source_len,
        };
        let slot_of = packed.slots_by_caller_index();
        Ok(Self {
            packed,
            slot_of,
            axes,
            first,
            others,
            max_norm: (d as f64).sqrt() * max_abs,
            prune,
        })
    }

    /// The principal axes, row `i` (`d` values) being the unit direction of the `i`-th largest
    /// variance of the point set.
    pub fn axes(&self) -> &[f64] {
        &self.axes
    }

    /// Offers every point to the heap (no pruning): the fallback for coordinates too large
    /// for safe projection bounds.
    fn scan_all(&self, q: &[T], exclude: Option<u32>, heap: &mut NeighborHeap<'_, T>) {
        let packed = &self.packed;
        for slot in 0..packed.len() {
            let id = packed.ids[slot];
            if Some(id) != exclude {
                heap.push(id, sq_dist(q, packed.point(slot)));
            }
        }
    }

    /// Offers `slot` to the heap unless it is excluded or its projection on an axis other
    /// than the first is more than `w` away from the query's.
    #[inline]
    fn offer(
        &self,
        slot: usize,
        q: &[T],
        pq_others: &[f64],
        w: f64,
        exclude: Option<u32>,
        heap: &mut NeighborHeap<'_, T>,
    ) {
        let id = self.packed.ids[slot];
        if Some(id) == exclude {
            return;
        }
        let m = pq_others.len();
        let po = &self.others[slot * m..(slot + 1) * m];
        // Projections are finite here (see `search`), so no gap is NaN.
        if po.iter().zip(pq_others).any(|(&p, &pq)| (p - pq).abs() > w) {
            return;
        }
        heap.push(id, sq_dist(q, self.packed.point(slot)));
    }

    /// All points within the radius: the window of the first axis, scanned in order.
    fn radius_window(
        &self,
        q: &[T],
        pq: &[f64],
        m: &Margins,
        exclude: Option<u32>,
        heap: &mut NeighborHeap<'_, T>,
    ) {
        let w = m.window(heap.bound());
        let pq1 = pq[0];
        // fl(pq1 − p) and fl(p − pq1) are monotone in p, so both predicates split the sorted
        // projections into a true prefix and a false suffix.
        let lo = self.first.partition_point(|&p| pq1 - p > w);
        let hi = self.first.partition_point(|&p| p - pq1 <= w);
        for slot in lo..hi.max(lo) {
            self.offer(slot, q, &pq[1..], w, exclude, heap);
        }
    }

    /// k nearest (within the radius, if any): outward sweep on the first axis, nearest
    /// projection first, until the gap exceeds the current bound of the heap.
    fn sweep(
        &self,
        q: &[T],
        pq: &[f64],
        m: &Margins,
        exclude: Option<u32>,
        heap: &mut NeighborHeap<'_, T>,
    ) {
        let pq1 = pq[0];
        let n = self.first.len();
        let start = self.first.partition_point(|&p| p < pq1);
        let (mut l, mut r) = (start, start);
        let mut bound = heap.bound();
        let mut w = m.window(bound);
        loop {
            let gl = if l > 0 {
                pq1 - self.first[l - 1]
            } else {
                f64::INFINITY
            };
            let gr = if r < n {
                self.first[r] - pq1
            } else {
                f64::INFINITY
            };
            let slot = if gl <= gr {
                if l == 0 || gl > w {
                    break;
                }
                l -= 1;
                l
            } else {
                if gr > w {
                    break;
                }
                r += 1;
                r - 1
            };
            self.offer(slot, q, &pq[1..], w, exclude, heap);
            let b = heap.bound();
            if b != bound {
                bound = b;
                w = m.window(bound);
            }
        }
    }
}

/// The widening of projection tests that makes them conservative.
///
/// If the squared distance computed in `T` (as [`sq_dist`] does) is at most `B`, then the exact
/// distance is at most `(√B + √(d·η)) (1 + γ)` with `γ ≈ (d + 3) u_T` the relative rounding of the
/// differences, squares and sum and `η` the smallest positive subnormal of `T` (squares that
/// underflow). The projection of a point `x` computed in `f64` on a unit axis `a` is off by at
/// most about `d · u₆₄ · ‖x‖`, and the gap between two projections is rounded once more.
/// The window below bounds all of that generously:
/// `w(B) = (√B + √(d·η)) (1 + rel) + abs`, `rel = 8 (d + 4) (ε_T + ε₆₄)`,
/// `abs = 16 (d + 2) ε₆₄ (max ‖x‖ + ‖q‖)` (ε = machine epsilon = 2u).
struct Margins {
    rel: f64,
    abs: f64,
}

impl Margins {
    fn new<T: Scalar>(d: usize, max_norm: f64, q_norm: f64) -> Self {
        let (eps_t, eta) = match T::TYPE {
            ScalarType::F32 => (f32::EPSILON as f64, f32::from_bits(1) as f64),
            ScalarType::F64 => (f64::EPSILON, f64::from_bits(1)),
        };
        let df = d as f64;
        let rel = 8.0 * (df + 4.0) * (eps_t + f64::EPSILON);
        let underflow = (df * eta).sqrt() * (1.0 + rel);
        let abs = underflow + 16.0 * (df + 2.0) * f64::EPSILON * (max_norm + q_norm) + 1e-300;
        Self { rel, abs }
    }

    /// Largest projection gap a point with computed squared distance `≤ bound` can have.
    #[inline]
    fn window<T: Scalar>(&self, bound: T) -> f64 {
        let b = bound.to_f64();
        if b.is_finite() {
            b.max(0.0).sqrt() * (1.0 + self.rel) + self.abs
        } else {
            f64::INFINITY
        }
    }
}

/// Projection of `p` on the axis `a`, in `f64`; the same function for stored and query points.
#[inline]
fn project<T: Scalar>(p: &[T], a: &[f64]) -> f64 {
    p.iter()
        .zip(a)
        .fold(0.0, |acc, (&x, &y)| acc + x.to_f64() * y)
}

/// Unit principal axes of the points (rows, descending variance) from the covariance about the
/// barycentre (thesis eq. (2.8) over the whole set), computed on coordinates scaled by
/// `1 / max_abs` so that no square overflows. Any unit vectors make the sweep exact; the
/// principal ones make it fast. Falls back to the coordinate axes if anything is not finite.
fn principal_axes<T: Scalar>(packed: &PackedPoints<T>, max_abs: f64) -> Vec<f64> {
    let (n, d) = (packed.len(), packed.dim);
    let mut identity = vec![0.0; d * d];
    for i in 0..d {
        identity[i * d + i] = 1.0;
    }
    let scale = if max_abs > 0.0 && (1.0 / max_abs).is_finite() {
        1.0 / max_abs
    } else {
        1.0
    };
    let mut mean = vec![0.0f64; d];
    for s in 0..n {
        for (m, x) in mean.iter_mut().zip(packed.point(s)) {
            *m += x.to_f64() * scale;
        }
    }
    for m in &mut mean {
        *m /= n as f64;
    }
    let mut cov = vec![0.0f64; d * d];
    let mut diff = vec![0.0f64; d];
    for s in 0..n {
        for ((t, x), m) in diff.iter_mut().zip(packed.point(s)).zip(&mean) {
            *t = x.to_f64() * scale - m;
        }
        for i in 0..d {
            for j in i..d {
                cov[i * d + j] += diff[i] * diff[j];
            }
        }
    }
    for i in 0..d {
        for j in 0..i {
            cov[i * d + j] = cov[j * d + i];
        }
    }
    if cov.iter().any(|c| !c.is_finite()) {
        return identity;
    }
    let eig = sym_eigen(&cov, d);
    let mut axes = Vec::with_capacity(d * d);
    for i in (0..d).rev() {
        let v = &eig.vectors[i * d..(i + 1) * d];
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.5) {
            return identity;
        }
        axes.extend(v.iter().map(|x| x / norm));
    }
    axes
}

impl<T: Scalar> NeighborSearch<T> for PcaSweep<T> {
    fn dim(&self) -> usize {
        self.packed.dim
    }

    fn source_len(&self) -> usize {
        self.packed.source_len
    }

    fn search(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        nbhd.validate()?;
        let packed = &self.packed;
        let d = packed.dim;
        let (q, exclude) = resolve_query(query, d, packed.source_len, &self.slot_of, |s| {
            packed.point(s)
        })?;
        let (k, sq_radius) = nbhd.limits();
        let mut heap = NeighborHeap::new(out, k, sq_radius);

        let q_max = q.iter().fold(0.0f64, |m, c| m.max(c.to_f64().abs()));
        let mut stack = [0.0f64; 8];
        let mut spill = Vec::new();
        let pq: &mut [f64] = if d <= stack.len() {
            &mut stack[..d]
        } else {
            spill.resize(d, 0.0);
            &mut spill
        };
        for (p, a) in pq.iter_mut().zip(self.axes.chunks_exact(d)) {
            *p = project(q, a);
        }
        // Pruning needs finite projections of the stored points (`prune`) and of the query; then
        // every gap is finite and no pruning test sees a NaN.
        if !self.prune || q_max >= PRUNE_LIMIT || pq.iter().any(|p| !p.is_finite()) {
            self.scan_all(q, exclude, &mut heap);
        } else {
            let m = Margins::new::<T>(d, self.max_norm, (d as f64).sqrt() * q_max);
            match nbhd {
                Neighborhood::Radius { .. } => self.radius_window(q, pq, &m, exclude, &mut heap),
                _ => self.sweep(q, pq, &m, exclude, &mut heap),
            }
        }
        if nbhd.is_sorted() {
            heap.finish();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
