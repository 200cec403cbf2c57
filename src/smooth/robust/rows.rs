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

    /// The wide neighbourhood of the point stored at `s`: stored positions, nearest first.
    #[inline]
    pub(super) fn wide(&self, s: usize) -> &[u32] {
        &self.index[s * self.width..s * self.width + self.len[s] as usize]
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
            .for_each_init(Vec::new, |sq_dist, (s, (index, len))| {
                if whole(s) {
                    *len = candidates[s];
                    return;
                }
                let index = &mut index[..candidates[s] as usize];
                let p = points[s];
                sq_dist.clear();
                sq_dist.extend(
                    index
                        .iter()
                        .map(|&j| points[j as usize].distance_squared(p)),
                );
                sort_row(index, sq_dist, order);
                *len = sq_dist.iter().take_while(|&&d| d <= e2).count() as u32;
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

/// Insertion sort of one row by `(sq_dist, caller's index)`: rows are nearly sorted already
/// (points move a fraction of a spacing per iteration), so this is about one pass.
/// The caller's indices are looked up only where two distances tie.
fn sort_row(index: &mut [u32], sq_dist: &mut [f64], order: &[u32]) {
    let before = |a: (f64, u32), b: (f64, u32)| {
        a.0 < b.0 || (a.0 == b.0 && order[a.1 as usize] < order[b.1 as usize])
    };
    let n = index.len().min(sq_dist.len());
    for i in 1..n {
        let item = (sq_dist[i], index[i]);
        // in place already (the common case): nothing to move
        if !before(item, (sq_dist[i - 1], index[i - 1])) {
            continue;
        }
        let mut j = i;
        while j > 0 && before(item, (sq_dist[j - 1], index[j - 1])) {
            sq_dist[j] = sq_dist[j - 1];
            index[j] = index[j - 1];
            j -= 1;
        }
        sq_dist[j] = item.0;
        index[j] = item.1;
    }
}

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
}
