//! The neighbourhoods of the robust smoothing, found once and kept up to date.
//!
//! The first iteration searches the `k_plane` nearest other points of every point (Section
//! 2.1.1). Later iterations keep each point's set of candidates and only re-measure and re-sort
//! it on the moved points, then cut it at ε: the robust step moves points across the surface
//! (along normals, by a fraction of a spacing after the first iteration), so a point's nearest
//! neighbours stay among the candidates of its first search — 'Update Neighbors' (Section 7.3)
//! without a second search. Measured on the analytic shapes at 20k points, this leaves the
//! quality equal or better than a fresh search every iteration (docs/smoothing-results.md).
//!
//! The points are stored in the k-d tree's order, so the neighbours of a point lie close in
//! memory; every row keeps the `(sq_dist, index)` order of the caller's indices.

use crate::error::Result;
use crate::table::NeighborTable;
use glam::DVec3;
use rayon::prelude::*;

/// The neighbour rows of every stored point: row `s` lists the stored positions of the
/// candidates of the point stored at `s`, nearest first; only the first `len[s]` (those within
/// ε) are its wide neighbourhood. Distances are not kept (they change with every iteration and
/// are measured where needed): at a million points and `k_plane` = 48 they would add 384 MB.
pub(super) struct Rows {
    /// Room per row: the longest row's number of candidates (the `k_plane` nearest other
    /// points, fewer in a caller's table).
    width: usize,
    /// Stored positions of the candidates, `width` per row (the first `candidates[s]` used).
    index: Vec<u32>,
    /// How many candidates a row has.
    candidates: Vec<u32>,
    /// How many of a row's candidates lie within ε.
    len: Vec<u32>,
    /// Squared distance of each row's last candidate, from the search that found the rows
    /// (sorted, on the points as searched), until the first cut at ε uses it.
    searched_farthest: Option<Vec<f64>>,
}

impl Rows {
    /// The rows of `table` (over the caller's indices, nearest first) for the points stored as
    /// `order` says (`order[s]` is the caller's index of the point stored at `s`), not yet cut
    /// at ε (see [`Rows::update`]).
    pub(super) fn in_stored_order(table: &NeighborTable<f64>, order: &[u32]) -> Self {
        let width = table.max_row_len();
        let position = super::super::positions_of(order);
        let mut index = Vec::with_capacity(order.len() * width);
        let mut candidates = Vec::with_capacity(order.len());
        for &o in order {
            let row = table.indices_of(o as usize);
            index.extend(row.iter().map(|&j| position[j as usize]));
            // padding: never read (`candidates` bounds every row)
            index.resize(index.len() + width - row.len(), 0);
            candidates.push(row.len() as u32);
        }
        let len = candidates.clone();
        Self {
            width,
            index,
            candidates,
            len,
            searched_farthest: None,
        }
    }

    /// The `k` nearest other points of every point by the k-d tree (`smooth/nearest.rs`: an `f32`
    /// search proven exact in `f64`), the points stored in the tree's order (returned), and each
    /// point's squared distance to its nearest (by caller index), searched in blocks of stored
    /// points, so that no table of all rows and distances is ever held (at a million points and
    /// k = 48, 576 MB). Sorted, but not yet cut at ε (see [`Rows::cut`]).
    pub(super) fn search(points: &[DVec3], k: usize) -> Result<(Self, Vec<u32>, Vec<Option<f64>>)> {
        let found = super::super::nearest::nearest_others(points, k)?;
        let candidates = vec![found.width as u32; points.len()];
        let len = candidates.clone();
        Ok((
            Self {
                width: found.width,
                index: found.index,
                candidates,
                len,
                searched_farthest: Some(found.farthest),
            },
            found.order,
            found.nearest,
        ))
    }

    /// The rows' parts, as `robust/row_file.rs` keeps them: the row width, the candidates
    /// (`width` per row), each row's candidate count and count within ε, and the searched
    /// farthest squared distances (`None` once cut).
    #[allow(clippy::type_complexity)]
    pub(super) fn as_parts(&self) -> (usize, &[u32], &[u32], &[u32], Option<&[f64]>) {
        (
            self.width,
            &self.index,
            &self.candidates,
            &self.len,
            self.searched_farthest.as_deref(),
        )
    }

    /// The rows of [`Rows::as_parts`]'s parts; `None` unless they are consistent: one count
    /// of each kind per row, `len ≤ candidates ≤ width`, every candidate a stored position.
    pub(super) fn from_parts(
        width: usize,
        index: Vec<u32>,
        candidates: Vec<u32>,
        len: Vec<u32>,
        farthest: Option<Vec<f64>>,
    ) -> Option<Self> {
        let n = candidates.len();
        let fits = index.len() == n.checked_mul(width)?
            && len.len() == n
            && farthest.as_ref().is_none_or(|f| f.len() == n)
            && candidates
                .iter()
                .zip(&len)
                .all(|(&c, &l)| l <= c && c as usize <= width)
            && index.iter().all(|&j| (j as usize) < n);
        fits.then_some(Self {
            width,
            index,
            candidates,
            len,
            searched_farthest: farthest,
        })
    }

    /// The wide neighbourhood of the point stored at `s`: stored positions, nearest first.
    #[inline]
    pub(super) fn wide(&self, s: usize) -> &[u32] {
        &self.index[s * self.width..s * self.width + self.len[s] as usize]
    }

    /// Every candidate of the point stored at `s`, within ε or not, in the row's order: the
    /// set of the first search, which the iterations re-sort but never change
    /// (`robust/reach.rs`).
    pub(super) fn candidates(&self, s: usize) -> &[u32] {
        &self.index[s * self.width..s * self.width + self.candidates[s] as usize]
    }

    /// The first `k` of [`Rows::wide`]: the umbrella neighbourhood `N_i`.
    #[inline]
    pub(super) fn narrow(&self, s: usize, k: usize) -> &[u32] {
        let row = self.wide(s);
        &row[..row.len().min(k)]
    }

    /// Keeps only the first `k` candidates of every row (rows are sorted: the `k` nearest).
    pub(super) fn shrink(&mut self, k: usize) {
        let k = k as u32;
        for (c, l) in self.candidates.iter_mut().zip(&mut self.len) {
            *c = (*c).min(k);
            *l = (*l).min(k);
        }
    }

    /// The largest number of neighbours any point has within ε.
    pub(super) fn max_len(&self) -> usize {
        self.len.iter().copied().max().unwrap_or(0) as usize
    }

    /// The largest number of neighbours any point has in its first `k`.
    pub(super) fn max_narrow_len(&self, k: usize) -> usize {
        self.len
            .iter()
            .map(|&l| (l as usize).min(k))
            .max()
            .unwrap_or(0)
    }

    /// The smallest number of neighbours any point has in its first `k`.
    pub(super) fn min_narrow_len(&self, k: usize) -> usize {
        self.len
            .iter()
            .map(|&l| (l as usize).min(k))
            .min()
            .unwrap_or(0)
    }

    /// The first cut of the rows at `eps`, on the points they were found for (stored order):
    /// a row from [`Rows::search`] whose last candidate lies within ε is already sorted and
    /// whole, and is left as it is; every other row is re-measured as [`Rows::update`] does.
    pub(super) fn cut(&mut self, points: &[DVec3], order: &[u32], eps: f64) {
        let settled = self.searched_farthest.take();
        self.update_unless(points, order, eps, |s| {
            settled.as_ref().is_some_and(|f| f[s] <= eps * eps)
        });
    }

    /// Re-measures every row on `points` (stored order), re-sorts it by `(sq_dist, index)` with
    /// the caller's indices `order`, and cuts it at `eps`. Each row is its own work, so the
    /// result does not depend on the number of threads.
    pub(super) fn update(&mut self, points: &[DVec3], order: &[u32], eps: f64) {
        self.searched_farthest = None;
        self.update_unless(points, order, eps, |_| false);
    }

    /// [`Rows::update`] of the rows `s` but those for which `whole(s)`: those keep all their
    /// candidates, in their order.
    fn update_unless(
        &mut self,
        points: &[DVec3],
        order: &[u32],
        eps: f64,
        whole: impl Fn(usize) -> bool + Sync,
    ) {
        let e2 = eps * eps;
        let width = self.width.max(1);
        let candidates = &self.candidates;
        self.index
            .par_chunks_mut(width)
            .zip(self.len.par_iter_mut())
            .enumerate()
            .for_each_init(RowSort::default, |sort, (s, (index, len))| {
                if whole(s) {
                    *len = candidates[s];
                    return;
                }
                let index = &mut index[..candidates[s] as usize];
                let p = points[s];
                sort.row(index, |j| points[j].distance_squared(p), order);
                *len = sort.within(e2) as u32;
            });
    }

    /// The first `k` neighbours of every point within ε as a table over the caller's indices
    /// (row `i` for the caller's point `i`), for the per-point outputs; `points` in stored order.
    pub(super) fn narrow_table(
        &self,
        points: &[DVec3],
        k: usize,
        order: &[u32],
    ) -> NeighborTable<f64> {
        let position = super::super::positions_of(order);
        let mut offsets = Vec::with_capacity(order.len() + 1);
        offsets.push(0);
        let (mut index, mut sq_dist) = (Vec::new(), Vec::new());
        for s in position.iter().map(|&s| s as usize) {
            let row = self.narrow(s, k);
            index.extend(row.iter().map(|&j| order[j as usize]));
            sq_dist.extend(
                row.iter()
                    .map(|&j| points[j as usize].distance_squared(points[s])),
            );
            offsets.push(index.len());
        }
        NeighborTable::from_parts(offsets, index, sq_dist).unwrap_or_default()
    }
}

/// The scratch of the row sorts of one worker: a row's keys, sorted by [`RowSort::row`].
#[derive(Default)]
struct RowSort {
    keys: Vec<RowKey>,
    spare: Vec<RowKey>,
    buckets: Vec<u32>,
    counts: Vec<u32>,
}

impl RowSort {
    /// Sorts one row of stored positions by `(sq_dist, caller's index)`, the one order of
    /// `src/query/order.rs`, with `sq_dist(j)` the squared distance of stored point `j`; keeps
    /// the row's [`RowKey`]s, sorted. The keys are compared as integers: one comparison per
    /// pair instead of a distance comparison and, on ties, two lookups of caller's indices.
    ///
    /// Rows are nearly sorted after a step that moved points by a fraction of a spacing, so an
    /// insertion sort is about one pass; after a step of a spacing or more (the first ones on
    /// noise of several spacings, with rows of 144) the rows are shuffled, and an insertion
    /// sort costs up to n²/4 moves. Such a row (more than one descent in [`SHUFFLED`] keys), or
    /// one the insertion sort cannot order in [`SORT_MOVES`]·n moves, is distributed by
    /// distance instead ([`RowSort::distribute`]). The keys are distinct, so both give the same
    /// order.
    fn row(&mut self, index: &mut [u32], sq_dist: impl Fn(usize) -> f64, order: &[u32]) {
        self.keys.clear();
        self.keys.extend(
            index
                .iter()
                .map(|&j| row_key(sq_dist(j as usize), order[j as usize], j)),
        );
        let n = self.keys.len();
        let descents = self.keys.windows(2).filter(|w| w[1] < w[0]).count();
        if SHUFFLED * descents > n || !insertion_sort(&mut self.keys, SORT_MOVES * n) {
            self.distribute();
        }
        for (j, &k) in index.iter_mut().zip(&self.keys) {
            *j = k as u32;
        }
    }

    /// How many keys of the sorted row lie within the squared distance `sq_radius`.
    fn within(&self, sq_radius: f64) -> usize {
        self.keys.partition_point(|&k| sq_dist_of(k) <= sq_radius)
    }

    /// Sorts the keys by distributing them into as many buckets as there are keys, of equal
    /// widths in squared distance, and sorting the buckets' concatenation by insertion, which
    /// then moves keys only within a bucket: about one key per bucket on a surface (the
    /// squared distance of the j-th neighbour grows about like j) and in a ball of noise (like
    /// j^(2/3)), so a pass over the row, where a comparison sort takes n log n comparisons.
    /// The bucket `min(⌊d · n / (SPAN · mean)⌋, n − 1)` never decreases as `d` grows (each
    /// rounding is monotone), so the buckets are in order; squared distances beyond [`SPAN`]
    /// times the mean (candidates that moved away) share the last bucket, and rows of copies
    /// of a point or of an infinite mean the first: those are sorted by insertion alone.
    fn distribute(&mut self) {
        let n = self.keys.len();
        let mean = self.keys.iter().map(|&k| sq_dist_of(k)).sum::<f64>() / n as f64;
        let scale = if mean > 0.0 {
            n as f64 / (SPAN * mean)
        } else {
            0.0
        };
        let last = n.saturating_sub(1) as u32;
        self.buckets.clear();
        self.buckets.extend(
            self.keys
                .iter()
                .map(|&k| ((sq_dist_of(k) * scale) as u32).min(last)),
        );
        self.counts.clear();
        self.counts.resize(n + 1, 0);
        for &b in &self.buckets {
            self.counts[b as usize + 1] += 1;
        }
        for b in 1..=n {
            self.counts[b] += self.counts[b - 1];
        }
        self.spare.resize(n, 0);
        for (&k, &b) in self.keys.iter().zip(&self.buckets) {
            let at = &mut self.counts[b as usize];
            self.spare[*at as usize] = k;
            *at += 1;
        }
        std::mem::swap(&mut self.keys, &mut self.spare);
        insertion_sort(&mut self.keys, usize::MAX);
    }
}

/// A row entry as one integer that orders as `(sq_dist, caller's index)`: the key of
/// `src/query/order.rs` above the stored position (which the caller's index determines, so it
/// never decides the order).
type RowKey = u128;

/// The [`RowKey`] of stored point `j` (the caller's `caller`) at squared distance `sq_dist`.
#[inline(always)]
fn row_key(sq_dist: f64, caller: u32, j: u32) -> RowKey {
    (crate::query::order::key64(sq_dist, caller) << 32) | RowKey::from(j)
}

/// The squared distance of a [`RowKey`].
#[inline(always)]
fn sq_dist_of(key: RowKey) -> f64 {
    crate::query::order::unkey64::<f64>(key >> 32).0
}

/// Sorts `keys` by insertion while that takes at most `budget` moves; false (the keys left
/// partly sorted, each key still once) once it would take more.
fn insertion_sort(keys: &mut [RowKey], budget: usize) -> bool {
    let mut budget = budget;
    for i in 1..keys.len() {
        let item = keys[i];
        // in place already (the common case): nothing to move
        if item > keys[i - 1] {
            continue;
        }
        let mut j = i;
        while j > 0 && item < keys[j - 1] {
            keys[j] = keys[j - 1];
            j -= 1;
        }
        keys[j] = item;
        budget = budget.saturating_sub(i - j);
        if budget == 0 {
            return false;
        }
    }
    true
}

/// Moves per entry an insertion sort of a row may take before [`RowSort::row`] turns to
/// [`RowSort::distribute`].
const SORT_MOVES: usize = 4;

/// The squared distances [`RowSort::distribute`] spreads over its buckets, in units of their
/// mean: 2 on a surface (the squared distance of the j-th neighbour grows about like j), 5/3
/// in a ball of noise; a candidate that moved away goes to the last bucket.
const SPAN: f64 = 2.0;

/// A row with more than one descent (a key below its predecessor) per this many keys is
/// distributed at once, without trying the insertion sort first.
const SHUFFLED: usize = 3;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_resort_by_distance_then_caller_index() {
        // four points on a line; stored in reverse order
        let order = [3u32, 2, 1, 0];
        let pts_in = [0.0, 1.0, 2.0, 3.0].map(|x| DVec3::new(x, 0.0, 0.0));
        let table = crate::geometry::neighbors::neighbor_table(
            &pts_in,
            crate::Neighborhood::Knn { k: 3 },
            true,
        )
        .unwrap();
        let mut rows = Rows::in_stored_order(&table, &order);
        let stored: Vec<DVec3> = order.iter().map(|&o| pts_in[o as usize]).collect();
        // caller's point 1 (stored at 2): neighbours 0 and 2 tie at distance 1, then 3
        assert_eq!(rows.wide(2), &[3, 1, 0]);
        // move caller's point 0 to x = 1.5: now point 1's nearest are 0 (0.25) then 2 (1)
        let mut moved = stored.clone();
        moved[3] = DVec3::new(1.5, 0.0, 0.0);
        rows.update(&moved, &order, 1.2);
        assert_eq!(rows.wide(2), &[3, 1]); // 3 (caller's 3, at 2.0) is beyond ε = 1.2
        assert_eq!(rows.narrow(2, 1), &[3]);
        let t = rows.narrow_table(&moved, 2, &order);
        assert_eq!(t.indices_of(1), &[0, 2]);
        assert_eq!(t.sq_dists_of(1), &[0.25, 1.0]);
        assert_eq!(rows.min_narrow_len(5), 1);
    }

    /// Nearly sorted rows (insertion sort within its budget) and shuffled ones (the
    /// distribution by distance), with ties: both the order of `(sq_dist, caller's index)`.
    #[test]
    fn row_sort_orders_any_row_with_ties_by_caller_index() {
        let n = 144u32;
        // caller's index of stored point j: a permutation, so ties are broken by it
        let order: Vec<u32> = (0..n).map(|j| (j * 89) % n).collect();
        let mut sort = RowSort::default();
        // squared distances in steps with ties; all equal; one candidate far away; one at
        // an infinite distance (coordinates near the end of the range)
        let dists: [&dyn Fn(u32) -> f64; 4] = [
            &|j| f64::from(j / 4 + u32::from(j % 5 == 0)),
            &|_| 0.0,
            &|j| if j == 77 { 1e12 } else { f64::from(j % 50) },
            &|j| if j == 3 { f64::INFINITY } else { f64::from(j) },
        ];
        for dist in dists {
            for shuffle in [1u32, 7, 61] {
                // shuffle 1 leaves the row nearly sorted: each entry a few places off
                let index: Vec<u32> = (0..n).map(|j| (j * shuffle + j % 3) % n).collect();
                let mut want: Vec<(f64, u32)> = index.iter().map(|&j| (dist(j), j)).collect();
                want.sort_by(|a, b| {
                    a.0.total_cmp(&b.0)
                        .then(order[a.1 as usize].cmp(&order[b.1 as usize]))
                });
                let mut idx = index.clone();
                sort.row(&mut idx, |j| dist(j as u32), &order);
                let got: Vec<(f64, u32)> = sort
                    .keys
                    .iter()
                    .map(|&k| (sq_dist_of(k), k as u32))
                    .collect();
                assert_eq!(got, want, "shuffle {shuffle}");
                assert!(idx.iter().zip(&want).all(|(&j, w)| j == w.1));
                let within = want.iter().filter(|w| w.0 <= 20.0).count();
                assert_eq!(sort.within(20.0), within);
            }
        }
    }
}
