//! The `k` nearest other points of every point, exact in `f64`, found by a search in `f32`:
//! the neighbourhoods of the robust smoothing (`robust/rows.rs`) and of the normals
//! (`normals.rs`).
//!
//! The grouped all-point search (`tree/group_search.rs`) answers a table faster in `f32` than
//! in `f64` (half the bytes per coordinate and per row entry, one 64-bit key per candidate),
//! and the search is most of the time of the normals and a large part of a robust run. So the
//! points, centred on their bounding box, are searched in `f32` for `k + MARGIN` candidates
//! each; the candidates are re-measured in `f64` and the first `k` kept. That they are the
//! exact `k` nearest is *proven* row by row with a bound on the `f32` rounding (see
//! [`f32_error`]): every point outside a row's candidates has an `f32` squared distance of at
//! least `B`, the row's last, so an exact one of at least `B − err(B)`; when the `k`-th `f64`
//! distance lies below that, no outside point can come before it. Rows the bound does not
//! settle (ties or near-ties around the `k`-th place, points of coordinates large against
//! their spacing) are searched again with an `f64` tree. The rows are therefore exactly those
//! of an `f64` search, in its `(sq_dist, index)` order with the same `f64` distances: the
//! results computed from them do not change.

use std::ops::Range;

use crate::error::{NbhdError, Result};
use crate::prefetch::prefetch_at;
use crate::query::{Neighbor, Neighborhood, Query};
use crate::table::{try_zeroed, NeighborTable};
use crate::{BuildOptions, KdTree, PointsView};
use glam::DVec3;
use rayon::prelude::*;

/// Candidates searched beyond the `k` kept: the margin between the `k`-th and the last
/// candidate's distance that proves a row exact. On a surface the squared distance of the
/// `j`-th neighbour grows about like `j`, so at `k` = 48 four more leave a gap of about 8 %,
/// against an `f32` rounding of about `1e-6` of the distance.
const MARGIN: usize = 4;

/// The `k` nearest other points of every point of `points`, each row by `(f64 sq_dist, caller's
/// index)`, as [`super::robust`]'s rows need them.
pub(super) struct Nearest {
    /// The caller's index of the point stored at each position (the `f32` tree's order).
    pub(super) order: Vec<u32>,
    /// Row length: `k`, or every other point when there are fewer.
    pub(super) width: usize,
    /// Stored positions of each stored point's `width` nearest others, `width` per row.
    pub(super) index: Vec<u32>,
    /// Squared distance of each point (by caller index) to its nearest other point.
    pub(super) nearest: Vec<Option<f64>>,
    /// Squared distance of each stored point to the last of its row (0 for empty rows).
    pub(super) farthest: Vec<f64>,
}

/// Stored points searched at once by [`nearest_others`]: large enough to keep both threads
/// busy and the grouped search's sharing effective, small enough that the block's table
/// (about 400 bytes per point at k = 48 in `f32`) stays a few tens of MB.
const SEARCH_BLOCK: usize = 1 << 16;

/// The `k` nearest other points of every point, all rows held (see [`by_blocks`]).
pub(super) fn nearest_others(points: &[DVec3], k: usize) -> Result<Nearest> {
    let n = points.len();
    let width = k.min(n.saturating_sub(1));
    let mut index = try_zeroed(entries(n, width)?, WHAT)?;
    let mut nearest = vec![None; n];
    let mut farthest = vec![0.0; n];
    let mut position: Option<Vec<u32>> = None;
    let order = by_blocks(points, k, SEARCH_BLOCK, &mut |block| {
        let position = position.get_or_insert_with(|| super::positions_of(block.order));
        let rows = &mut index[block.positions.start * width..block.positions.end * width];
        rows.par_iter_mut()
            .zip(block.rows)
            .with_min_len(4096)
            .for_each(|(slot, &j)| *slot = position[j as usize]);
        for (r, pos) in block.positions.clone().enumerate() {
            nearest[block.order[pos] as usize] = block.nearest[r];
            farthest[pos] = block.farthest[r];
        }
        Ok(())
    })?
    .order;
    Ok(Nearest {
        order,
        width,
        index,
        nearest,
        farthest,
    })
}

/// The `k` nearest other points of every point as a table over the caller's indices (row `i`
/// for point `i`, by `(f64 sq_dist, index)`): exactly the table of an `f64` tree. Also returns
/// the search tree's order (the caller's index of the point stored at each position).
pub(crate) fn nearest_table(points: &[DVec3], k: usize) -> Result<(NeighborTable<f64>, Vec<u32>)> {
    let n = points.len();
    let width = k.min(n.saturating_sub(1));
    let entries = entries(n, width)?;
    let (mut index, mut sq_dist) = (try_zeroed(entries, WHAT)?, try_zeroed(entries, WHAT)?);
    let order = by_blocks(points, k, SEARCH_BLOCK, &mut |block| {
        for (r, pos) in block.positions.clone().enumerate() {
            let at = block.order[pos] as usize * width;
            index[at..at + width].copy_from_slice(block.row(r));
            sq_dist[at..at + width].copy_from_slice(block.dists_of(r));
        }
        Ok(())
    })?
    .order;
    let offsets = (0..=n).map(|i| i * width).collect();
    // one row of `width` per point: the parts always fit
    let table = NeighborTable::from_parts(offsets, index, sq_dist).unwrap_or_default();
    Ok((table, order))
}

/// The exact rows of a run of consecutive tree positions.
pub(super) struct Block<'a> {
    /// The caller's index of the point stored at each position (the whole tree's order).
    pub(super) order: &'a [u32],
    /// The tree positions of the block's points.
    pub(super) positions: Range<usize>,
    /// Row length: `k`, or every other point when there are fewer.
    pub(super) width: usize,
    /// Each point's `width` nearest others, caller indices by `(f64 sq_dist, index)`, and
    /// their squared distances.
    pub(super) rows: &'a [u32],
    pub(super) dists: &'a [f64],
    /// Each point's squared distance to its first and its last neighbour (`None` and 0 for
    /// an empty row).
    pub(super) nearest: &'a [Option<f64>],
    pub(super) farthest: &'a [f64],
}

impl Block<'_> {
    /// The row of the block's `r`-th point.
    pub(super) fn row(&self, r: usize) -> &[u32] {
        &self.rows[r * self.width..(r + 1) * self.width]
    }

    /// The squared distances of [`Block::row`].
    pub(super) fn dists_of(&self, r: usize) -> &[f64] {
        &self.dists[r * self.width..(r + 1) * self.width]
    }
}

/// The `k` nearest other points of every point of `points` (a nonempty set of finite points),
/// handed to `consume` a block of `block` consecutive positions of the `f32` tree at a time, so
/// that no table of every row is ever held (at a million points and k = 48, 576 MB) and a
/// block's rows are consumed while in cache. Returns the search (its tree's order, and rows
/// again on request).
pub(super) fn by_blocks(
    points: &[DVec3],
    k: usize,
    block: usize,
    consume: &mut dyn FnMut(&Block<'_>) -> Result<()>,
) -> Result<Searched> {
    let n = points.len();
    let (centre, extent) = centre_and_extent(points);
    // false for a NaN extent too (coordinates whose centre overflows)
    let fits_f32 = extent <= F32_EXTENT;
    if !fits_f32 {
        return by_blocks_in_f64(points, k, block, consume);
    }
    let mut flat = vec![0f32; points.len() * 3];
    flat.par_chunks_mut(3)
        .zip(points.par_iter())
        .with_min_len(4096)
        .for_each(|(f, p)| {
            for (f, c) in f.iter_mut().zip((*p - centre).to_array()) {
                *f = c as f32;
            }
        });
    let tree = KdTree::<f32>::build(&PointsView::from_flat(&flat, 3)?, &BuildOptions::default())?;
    drop(flat);
    let order = tree.tree_order().to_vec();
    let width = k.min(n.saturating_sub(1));
    // with every other point among the candidates, a row is exact without a proof
    let searched = (width + MARGIN).min(n.saturating_sub(1));
    let proof = Proof {
        width,
        searched,
        complete: searched == n.saturating_sub(1),
        extent,
    };
    // the f64 tree of the rows the proof does not settle, built when the first one needs it
    let mut exact: Option<KdTree<f64>> = None;
    let (mut rows, mut dists) = (Vec::new(), Vec::new());
    let mut each = |positions: Range<usize>, table: NeighborTable<f32>| {
        let len = entries(positions.len(), width)?;
        try_resize(&mut rows, len)?;
        try_resize(&mut dists, len)?;
        if width == 0 {
            // no other point: empty rows, exact
            let none = vec![None; positions.len()];
            let zero = vec![0.0; positions.len()];
            return consume(&Block {
                order: &order,
                positions,
                width,
                rows: &rows,
                dists: &dists,
                nearest: &none,
                farthest: &zero,
            });
        }
        let found: Vec<(Option<f64>, f64, bool)> = rows
            .par_chunks_mut(width)
            .zip(dists.par_chunks_mut(width))
            .enumerate()
            .map_init(Vec::new, |scratch, (r, (row, dist))| {
                if r + PREFETCH_ROWS < table.len() {
                    prefetch_at(points, table.indices_of(r + PREFETCH_ROWS));
                }
                let o = order[positions.start + r];
                let last = table.sq_dists_of(r).last().map_or(0.0, |&d| f64::from(d));
                let proven = proof.settle(points, o, table.indices_of(r), last, scratch);
                for ((slot, d), &(e, j)) in row.iter_mut().zip(dist.iter_mut()).zip(scratch.iter())
                {
                    (*slot, *d) = (j, e);
                }
                let kth = scratch.get(width.wrapping_sub(1)).map_or(0.0, |e| e.0);
                (scratch.first().map(|e| e.0), kth, proven)
            })
            .collect();
        let (mut nearest, mut farthest): (Vec<Option<f64>>, Vec<f64>) =
            found.iter().map(|&(d, kth, _)| (d, kth)).unzip();
        let unproven: Vec<usize> = (0..positions.len()).filter(|&r| !found[r].2).collect();
        if !unproven.is_empty() {
            let tree = match &mut exact {
                Some(t) => t,
                None => exact.insert(f64_tree(points)?),
            };
            let searched = search_in_f64(tree, &order[positions.clone()], &unproven, width)?;
            for (&r, row) in unproven.iter().zip(searched) {
                let slots = rows[r * width..(r + 1) * width].iter_mut();
                for ((slot, d), nb) in slots.zip(&mut dists[r * width..]).zip(&row) {
                    (*slot, *d) = (nb.index, nb.sq_dist);
                }
                nearest[r] = row.first().map(|nb| nb.sq_dist);
                farthest[r] = row.last().map_or(0.0, |nb| nb.sq_dist);
            }
        }
        consume(&Block {
            order: &order,
            positions,
            width,
            rows: &rows,
            dists: &dists,
            nearest: &nearest,
            farthest: &farthest,
        })
    };
    if searched == 0 {
        // a single point: no other points, one empty row
        each(0..n, NeighborTable::default())?;
    } else {
        tree.neighborhoods_by_blocks(Neighborhood::Knn { k: searched }, true, block, &mut each)?;
    }
    Ok(Searched {
        order,
        width,
        tree: SearchTree::F32 {
            tree,
            proof,
            exact: exact.map(Box::new),
        },
    })
}

/// What [`by_blocks`] searched with, kept to give rows once more after the blocks: a caller that
/// learns only at the end which rows it needs again (the rows cut by a length known once every
/// row was seen, `normals.rs`) gets them from the same tree, proven exact the same way, rather
/// than from a second tree of every point.
pub(super) struct Searched {
    /// The caller's index of the point stored at each position (the search tree's order).
    pub(super) order: Vec<u32>,
    /// Row length: `k`, or every other point when there are fewer.
    width: usize,
    tree: SearchTree,
}

/// The tree of a [`Searched`].
enum SearchTree {
    /// The `f32` search of the centred points, with the `f64` tree of the rows its proof did not
    /// settle once one needed it.
    F32 {
        tree: KdTree<f32>,
        proof: Proof,
        exact: Option<Box<KdTree<f64>>>,
    },
    /// The `f64` search of points too far out for `f32`.
    F64(KdTree<f64>),
}

impl Searched {
    /// The rows of the points at the tree positions `positions`, exactly as the blocks gave them:
    /// the `width` nearest other points of each by `(f64 sq_dist, index)`.
    pub(super) fn rows_at(
        &self,
        points: &[DVec3],
        positions: &[usize],
    ) -> Result<Vec<Vec<Neighbor<f64>>>> {
        let (order, width) = (&self.order, self.width);
        if width == 0 {
            return Ok(vec![Vec::new(); positions.len()]);
        }
        let (tree, proof, exact) = match &self.tree {
            SearchTree::F64(tree) => {
                return positions
                    .par_iter()
                    .map(|&pos| knn_at(tree, pos, order[pos], width))
                    .collect();
            }
            SearchTree::F32 { tree, proof, exact } => (tree, proof, exact),
        };
        let mut settled: Vec<(Vec<Neighbor<f64>>, bool)> = positions
            .par_iter()
            .map_init(Vec::new, |scratch, &pos| {
                let o = order[pos];
                let found = knn_at(tree, pos, o, proof.searched)?;
                let last = found.last().map_or(0.0, |c| f64::from(c.sq_dist));
                let ids: Vec<u32> = found.iter().map(|c| c.index).collect();
                let proven = proof.settle(points, o, &ids, last, scratch);
                let row = scratch
                    .iter()
                    .map(|&(sq_dist, index)| Neighbor { index, sq_dist })
                    .collect();
                Ok((row, proven))
            })
            .collect::<Result<_>>()?;
        let unproven: Vec<usize> = (0..positions.len()).filter(|&r| !settled[r].1).collect();
        if !unproven.is_empty() {
            let built;
            let tree = match exact {
                Some(t) => &**t,
                None => {
                    built = f64_tree(points)?;
                    &built
                }
            };
            let callers: Vec<u32> = positions.iter().map(|&pos| order[pos]).collect();
            let searched = search_in_f64(tree, &callers, &unproven, width)?;
            for (&r, row) in unproven.iter().zip(searched) {
                settled[r].0 = row;
            }
        }
        Ok(settled.into_iter().map(|(row, _)| row).collect())
    }
}

/// The `k` nearest other points of the point at tree position `pos` (caller index `o`).
fn knn_at<T: crate::scalar::Scalar>(
    tree: &KdTree<T>,
    pos: usize,
    o: u32,
    k: usize,
) -> Result<Vec<Neighbor<T>>> {
    let mut row = Vec::with_capacity(k);
    let query = Query::Point {
        coords: tree.point_at(pos),
        exclude: Some(o),
    };
    tree.knn(query, k, &mut row)?;
    Ok(row)
}

/// How a row of `f32` candidates is made exact: re-measured in `f64`, the first `width` kept, and
/// proven the exact nearest by [`proves`] (or by holding every other point).
struct Proof {
    /// Row length: `k`, or every other point when there are fewer.
    width: usize,
    /// Candidates searched: `width` and a margin, or every other point.
    searched: usize,
    /// Whether the candidates are every other point (a row exact without a proof).
    complete: bool,
    /// The largest coordinate relative to the centre ([`f32_error`]).
    extent: f64,
}

impl Proof {
    /// The candidates `ids` of the point with caller index `o` (the last at `f32` squared
    /// distance `last`) re-measured into `out` (see [`keep_nearest`]); whether they are proven
    /// the exact `width` nearest.
    fn settle(
        &self,
        points: &[DVec3],
        o: u32,
        ids: &[u32],
        last: f64,
        out: &mut Vec<(f64, u32)>,
    ) -> bool {
        keep_nearest(points, o, ids, self.width, out);
        let kth = out.get(self.width.wrapping_sub(1)).map_or(0.0, |e| e.0);
        self.complete || proves(kth, last, self.extent)
    }
}

/// Rows ahead whose candidates' `f64` points are requested before the row is re-measured:
/// the candidates lie all over the caller's array, and waiting for them was 7 % of the normals.
const PREFETCH_ROWS: usize = 4;

/// What the rows' memory is, in an [`NbhdError::OutOfMemory`].
const WHAT: &str = "the nearest-neighbour rows (points × min(k, points − 1) entries)";

/// `rows × width` entries, or [`NbhdError::OutOfMemory`] where the count overflows.
fn entries(rows: usize, width: usize) -> Result<usize> {
    rows.checked_mul(width).ok_or(NbhdError::OutOfMemory {
        what: WHAT,
        bytes: rows as u128 * width as u128 * 12,
    })
}

/// `v` resized to `n` elements, refused with [`NbhdError::OutOfMemory`] rather than aborting
/// where the memory is not there.
fn try_resize<V: Clone + Default>(v: &mut Vec<V>, n: usize) -> Result<()> {
    if let Some(more) = n.checked_sub(v.len()).filter(|&m| m > 0) {
        v.try_reserve_exact(more)
            .map_err(|_| NbhdError::OutOfMemory {
                what: WHAT,
                bytes: n as u128 * std::mem::size_of::<V>() as u128,
            })?;
    }
    v.resize(n, V::default());
    Ok(())
}

/// Largest coordinate (relative to the centre) searched in `f32`: far below `f32::MAX`, so
/// that no squared distance overflows; beyond it every row is searched in `f64`.
const F32_EXTENT: f64 = 1e18;

/// [`by_blocks`] with an `f64` search throughout (coordinates too large for `f32`).
fn by_blocks_in_f64(
    points: &[DVec3],
    k: usize,
    block: usize,
    consume: &mut dyn FnMut(&Block<'_>) -> Result<()>,
) -> Result<Searched> {
    let tree = f64_tree(points)?;
    let order = tree.tree_order().to_vec();
    let width = k.min(points.len().saturating_sub(1));
    let mut each = |positions: Range<usize>, table: NeighborTable<f64>| {
        let (nearest, farthest): (Vec<Option<f64>>, Vec<f64>) = (0..positions.len())
            .map(|r| {
                let d = table.sq_dists_of(r);
                (d.first().copied(), d.last().copied().unwrap_or(0.0))
            })
            .unzip();
        let (_, rows, dists) = table.into_parts();
        consume(&Block {
            order: &order,
            positions,
            width,
            rows: &rows,
            dists: &dists,
            nearest: &nearest,
            farthest: &farthest,
        })
    };
    tree.neighborhoods_by_blocks(
        Neighborhood::Knn { k: width.max(1) },
        true,
        block,
        &mut each,
    )?;
    Ok(Searched {
        order,
        width,
        tree: SearchTree::F64(tree),
    })
}

/// The candidates `ids` of the point with caller index `o`, re-measured in `f64` and sorted by
/// `(sq_dist, index)` into `out`, the first `width` of them kept.
fn keep_nearest(points: &[DVec3], o: u32, ids: &[u32], width: usize, out: &mut Vec<(f64, u32)>) {
    let p = points[o as usize];
    out.clear();
    out.extend(
        ids.iter()
            .map(|&j| (points[j as usize].distance_squared(p), j)),
    );
    // nearly sorted already (the f32 order): an insertion sort is about one pass
    for i in 1..out.len() {
        let item = out[i];
        // in place already (the common case): nothing to move
        if !crate::query::order::precedes(item, out[i - 1]) {
            continue;
        }
        let mut j = i;
        while j > 0 && crate::query::order::precedes(item, out[j - 1]) {
            out[j] = out[j - 1];
            j -= 1;
        }
        out[j] = item;
    }
    out.truncate(width);
}

/// An `f64` tree over the caller's points.
fn f64_tree(points: &[DVec3]) -> Result<KdTree<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    KdTree::<f64>::build(&PointsView::from_flat(&flat, 3)?, &BuildOptions::default())
}

/// The rows `unproven` (offsets into `callers`, the caller's indices of a block) searched again
/// with the `f64` tree `tree`: the `width` nearest other points of each, in the order the proven
/// rows hold them.
fn search_in_f64(
    tree: &KdTree<f64>,
    callers: &[u32],
    unproven: &[usize],
    width: usize,
) -> Result<Vec<Vec<Neighbor<f64>>>> {
    unproven
        .par_iter()
        .map(|&r| {
            let mut row = Vec::with_capacity(width);
            tree.knn(Query::stored_excluding_self(callers[r]), width, &mut row)
                .map(|()| row)
        })
        .collect()
}

/// The centre of the bounding box of `points` and the largest distance of a coordinate from
/// it: the points are searched relative to the centre, so the `f32` rounding of a coordinate is
/// at most `extent · 2⁻²⁴`.
fn centre_and_extent(points: &[DVec3]) -> (DVec3, f64) {
    let empty = || (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    // minima and maxima are exact: the same box whatever the split into parallel parts
    let (lo, hi) = points
        .par_iter()
        .with_min_len(4096)
        .fold(empty, |(lo, hi), &p| (lo.min(p), hi.max(p)))
        .reduce(empty, |a, b| (a.0.min(b.0), a.1.max(b.1)));
    let centre = (lo + hi) * 0.5;
    let extent = (hi - centre).max(centre - lo).max_element();
    (centre, extent)
}

/// Whether a row whose `k`-th `f64` squared distance is `kth` and whose last `f32` candidate
/// is at `f32` squared distance `last` holds the exact `k` nearest: every point outside the
/// candidates is at `f32` squared distance ≥ `last`, so at an exact one of at least
/// `last − err(last)` (`err` grows slower than its argument in the range [`f32_error`] admits),
/// and its `f64` distance (computed with a relative error below 1e-15) then exceeds `kth`.
fn proves(kth: f64, last: f64, extent: f64) -> bool {
    match f32_error(last, extent) {
        Some(err) => kth * (1.0 + 1e-14) < (last - err) * (1.0 - 1e-14),
        None => false,
    }
}

/// An upper bound on the difference between the `f32` squared distance `g` of two points and
/// their exact squared distance, the coordinates (relative to the centre, at most `extent` in
/// magnitude) rounded to `f32` and the distance computed in `f32` as the tree computes it
/// (three differences, squares and sums). `None` where `g` is too small against the rounding of
/// the coordinates for the bound to be useful (copies and near-copies of a point).
///
/// With `u = 2⁻²⁴`: each rounded coordinate is off by at most `u·extent`, so each difference
/// `t` by at most `e = 2u·extent + u·|t|` (the two roundings, then the subtraction's); the
/// sum of the three squares by at most `e (2√3 √d + 3e)`, and the three squares and two sums
/// add a relative `3u`. The result is doubled for safety.
fn f32_error(g: f64, extent: f64) -> Option<f64> {
    let u = f64::from(f32::EPSILON) / 2.0;
    // g is within 6 % of the exact d where the bound is used (√g ≥ 64 e): bound |t| by 1.1 g
    let r = (1.1 * g).sqrt();
    let e = 2.0 * u * extent + u * r;
    if g.is_nan() || g.sqrt() < 64.0 * e {
        return None;
    }
    Some(2.0 * (e * (2.0 * 3f64.sqrt() * r + 3.0 * e) + 3.0 * u * 1.1 * g))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows of `nearest_others` as sets of caller indices, against brute force.
    fn assert_exact(points: &[DVec3], k: usize) {
        let found = nearest_others(points, k).unwrap();
        let w = found.width;
        for (pos, &o) in found.order.iter().enumerate() {
            let mut got: Vec<u32> = found.index[pos * w..(pos + 1) * w]
                .iter()
                .map(|&s| found.order[s as usize])
                .collect();
            got.sort_unstable();
            let p = points[o as usize];
            let mut all: Vec<(f64, u32)> = (0..points.len() as u32)
                .filter(|&j| j != o)
                .map(|j| (points[j as usize].distance_squared(p), j))
                .collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut want: Vec<u32> = all[..w].iter().map(|e| e.1).collect();
            want.sort_unstable();
            assert_eq!(got, want, "row of point {o}");
            assert_eq!(found.nearest[o as usize], all.first().map(|e| e.0));
        }
        assert_rows_again(points, k);
    }

    /// `Searched::rows_at` gives the rows the blocks gave, bit for bit, for positions asked in
    /// any order.
    fn assert_rows_again(points: &[DVec3], k: usize) {
        let mut blocks: Vec<Vec<Neighbor<f64>>> = Vec::new();
        let searched = by_blocks(points, k, 700, &mut |b| {
            for r in 0..b.positions.len() {
                let row = b.row(r).iter().zip(b.dists_of(r));
                blocks.push(
                    row.map(|(&index, &sq_dist)| Neighbor { index, sq_dist })
                        .collect(),
                );
            }
            Ok(())
        })
        .unwrap();
        let asked: Vec<usize> = (0..points.len()).rev().step_by(3).collect();
        let again = searched.rows_at(points, &asked).unwrap();
        for (&pos, row) in asked.iter().zip(&again) {
            assert_eq!(row, &blocks[pos], "row at position {pos}");
        }
    }

    fn noisy_sphere(n: usize, offset: f64) -> Vec<DVec3> {
        // a deterministic sequence of directions (golden angle) with a radial wobble
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let a = i as f64 * 2.399_963_229_728_653;
                let r = (1.0 - z * z).sqrt();
                let wobble = 1.0 + 0.01 * ((i * 7919 % 101) as f64 / 101.0 - 0.5);
                DVec3::new(r * a.cos(), r * a.sin(), z) * wobble + DVec3::splat(offset)
            })
            .collect()
    }

    #[test]
    fn rows_are_the_exact_nearest_on_a_surface() {
        assert_exact(&noisy_sphere(3000, 0.0), 24);
    }

    #[test]
    fn rows_are_exact_far_from_the_origin() {
        // coordinates of about 1e5 with a spacing of about 0.05: many rows left to f64
        assert_exact(&noisy_sphere(2000, 1e5), 16);
    }

    #[test]
    fn rows_are_exact_beyond_the_range_of_the_f32_search() {
        // coordinates of about 1e20: searched in f64 throughout
        let huge: Vec<DVec3> = noisy_sphere(500, 0.0).iter().map(|&p| p * 1e20).collect();
        assert_exact(&huge, 16);
    }

    #[test]
    fn rows_are_exact_where_f32_cannot_tell_points_apart() {
        // two clusters 2e5 apart, each 400 points within 1e-3: f32 resolves about 0.008 out
        // there, so the f32 candidates are the copies it sees and only the f64 search is right
        let cluster = |x: f64| {
            noisy_sphere(400, 0.0)
                .into_iter()
                .map(move |p| p * 5e-4 + DVec3::new(x, 0.0, 0.0))
        };
        let pts: Vec<DVec3> = cluster(1e5).chain(cluster(-1e5)).collect();
        assert_exact(&pts, 10);
    }

    #[test]
    fn rows_are_exact_on_a_grid_of_ties() {
        let grid: Vec<DVec3> = (0..1000)
            .map(|i| DVec3::new((i % 10) as f64, (i / 10 % 10) as f64, (i / 100) as f64))
            .collect();
        assert_exact(&grid, 12);
    }

    #[test]
    fn rows_are_exact_with_copies_and_few_points() {
        let mut pts = noisy_sphere(300, 0.0);
        pts.extend(std::iter::repeat_n(DVec3::new(1.0, 0.0, 0.0), 40));
        assert_exact(&pts, 24);
        assert_exact(&noisy_sphere(20, 0.0), 24);
        assert_exact(&noisy_sphere(2, 0.0), 24);
        assert_exact(&noisy_sphere(1, 0.0), 24);
    }

    #[test]
    fn the_error_bound_covers_the_f32_distance() {
        let extent: f64 = 3.0;
        for i in 0..10_000u32 {
            let f = |s: u32| {
                ((s.wrapping_mul(2_654_435_761) >> 8) as f64 / (1u64 << 24) as f64) * 2.0 - 1.0
            };
            let a = DVec3::new(f(i), f(i + 17), f(i + 91)) * extent;
            let b = a + DVec3::new(f(i + 5), f(i + 3), f(i + 7)) * 1e-3;
            let (a32, b32) = (a.as_vec3(), b.as_vec3());
            let d = a.distance_squared(b);
            let g = f64::from(a32.distance_squared(b32));
            if let Some(err) = f32_error(g, extent) {
                assert!((g - d).abs() <= err, "{g} {d} {err}");
            }
        }
    }
}
