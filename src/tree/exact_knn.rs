//! The `k` nearest other points of every point, exact in `f64`, found by a search in `f32`
//! ([`exact_knn_table`]): the fast all-point k-nearest table of 3-D `f64` points, what the
//! normals (`src/geometry/estimate.rs`), the smoothing's own search (`src/geometry/source.rs`)
//! and the robust smoothing (`src/smooth/robust/rows.rs`) take their neighbourhoods from.
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
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

use crate::error::{NbhdError, Result};
use crate::index::NeighborIndex;
use crate::points::PointsView;
use crate::prefetch::prefetch_at;
use crate::query::{Neighbor, Neighborhood, Query};
use crate::scatter::{inverse, BlockScatter, Targets};
use crate::table::{try_zeroed, NeighborTable};

use super::Blocks as TreeBlocks;
use super::{BuildOptions, KdTree};
use glam::DVec3;
use rayon::prelude::*;

/// Candidates searched beyond the `k` kept: the margin between the `k`-th and the last
/// candidate's distance that proves a row exact. On a surface the squared distance of the
/// `j`-th neighbour grows about like `j`, so at `k` = 48 four more leave a gap of about 8 %,
/// against an `f32` rounding of about `1e-6` of the distance.
const MARGIN: usize = 4;

/// The `k` nearest other points of every point of `points`, each row by `(f64 sq_dist, caller's
/// index)`, as the robust smoothing's rows (`src/smooth/robust/rows.rs`) need them.
pub(crate) struct Nearest {
    /// The caller's index of the point stored at each position (the `f32` tree's order).
    pub(crate) order: Vec<u32>,
    /// Row length: `k`, or every other point when there are fewer.
    pub(crate) width: usize,
    /// Stored positions of each stored point's `width` nearest others, `width` per row.
    pub(crate) index: Vec<u32>,
    /// Squared distance of each point (by caller index) to its nearest other point.
    pub(crate) nearest: Vec<Option<f64>>,
    /// Squared distance of each stored point to the last of its row (0 for empty rows).
    pub(crate) farthest: Vec<f64>,
}

/// Stored points searched at once by one worker in [`nearest_others`] and [`nearest_table`]:
/// large enough for the grouped search's sharing, small enough that a block's candidates and
/// rows (about 800 bytes per point at k = 48) stay in the worker's cache and a few MB, however
/// many workers there are.
const SEARCH_BLOCK: usize = 8192;

/// The `k` nearest other points of every point, all rows held (see [`by_blocks`]).
pub(crate) fn nearest_others(points: &[DVec3], k: usize) -> Result<Nearest> {
    let n = points.len();
    let width = k.min(n.saturating_sub(1));
    let mut index = try_zeroed(entries(n, width)?, WHAT)?;
    let mut nearest = vec![None; n];
    let mut farthest = vec![0.0; n];
    let order = by_blocks(points, k, SEARCH_BLOCK, |blocks| {
        let targets = Targets::check(blocks.order(), n)?;
        let position = inverse(&targets)?;
        let bounds = blocks.bounds();
        let rows = BlockScatter::in_place(&mut index, bounds, width)?;
        let near = BlockScatter::to_targets(&mut nearest, &targets, bounds, 1)?;
        let far = BlockScatter::in_place(&mut farthest, bounds, 1)?;
        blocks.for_each(&|block| {
            let b = block.index;
            rows.write(b, block.rows.iter().map(|&j| position[j as usize]))?;
            near.write(b, block.nearest.iter().copied())?;
            far.write(b, block.farthest.iter().copied())
        })
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

/// The `k` nearest other points of every point of `points` (a nonempty set of finite 3-D
/// points) as a table over the caller's indices, row `i` for point `i` ordered by
/// `(sq_dist, index)`: exactly the table an `f64` [`KdTree`] gives with `exclude_self`, the same
/// `f64` distances in the same order, found by a search in `f32` proven exact row by row (see
/// the module documentation; rows the proof does not settle are searched again in `f64`).
///
/// ```
/// use glam::DVec3;
/// use nbhd::tree::exact_knn_table;
/// use nbhd::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, TableOptions};
///
/// let points: Vec<DVec3> = (0..500)
///     .map(|i| {
///         let t = i as f64 * 0.1;
///         DVec3::new(1e4 + t.cos(), 2e4 + t.sin(), 0.01 * t)
///     })
///     .collect();
/// let table = exact_knn_table(&points, 8)?;
/// let rows: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
/// let tree = KdTree::<f64>::build(&PointsView::from_rows(&rows)?, &BuildOptions::default())?;
/// let want = tree.neighborhoods(Neighborhood::Knn { k: 8 }, &TableOptions::default())?;
/// assert_eq!(table, want);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
///
/// Errors: [`NbhdError::OutOfMemory`] for a table that cannot fit, those of the builds.
pub fn exact_knn_table(points: &[DVec3], k: usize) -> Result<NeighborTable<f64>> {
    Ok(nearest_table(points, k)?.0)
}

/// [`exact_knn_table`], and the search tree's order (the caller's index of the point stored
/// at each position).
pub(crate) fn nearest_table(points: &[DVec3], k: usize) -> Result<(NeighborTable<f64>, Vec<u32>)> {
    let n = points.len();
    let width = k.min(n.saturating_sub(1));
    let entries = entries(n, width)?;
    let (mut index, mut sq_dist) = (try_zeroed(entries, WHAT)?, try_zeroed(entries, WHAT)?);
    let order = by_blocks(points, k, SEARCH_BLOCK, |blocks| {
        let targets = Targets::check(blocks.order(), n)?;
        let rows = BlockScatter::to_targets(&mut index, &targets, blocks.bounds(), width)?;
        let dists = BlockScatter::to_targets(&mut sq_dist, &targets, blocks.bounds(), width)?;
        blocks.for_each(&|block| {
            rows.write(block.index, block.rows.iter().copied())?;
            dists.write(block.index, block.dists.iter().copied())
        })
    })?
    .order;
    let offsets = (0..=n).map(|i| i * width).collect();
    // one row of `width` per point: the parts always fit
    let table = NeighborTable::from_parts(offsets, index, sq_dist).unwrap_or_default();
    Ok((table, order))
}

/// The exact rows of a run of consecutive tree positions.
pub(crate) struct Block<'a> {
    /// The block's number among [`Blocks::bounds`].
    pub(crate) index: usize,
    /// The caller's index of the point stored at each position (the whole tree's order).
    pub(crate) order: &'a [u32],
    /// The tree positions of the block's points.
    pub(crate) positions: Range<usize>,
    /// Row length: `k`, or every other point when there are fewer.
    pub(crate) width: usize,
    /// Each point's `width` nearest others, caller indices by `(f64 sq_dist, index)`, and
    /// their squared distances.
    pub(crate) rows: &'a [u32],
    pub(crate) dists: &'a [f64],
    /// Each point's squared distance to its first and its last neighbour (`None` and 0 for
    /// an empty row).
    pub(crate) nearest: &'a [Option<f64>],
    pub(crate) farthest: &'a [f64],
}

impl Block<'_> {
    /// The row of the block's `r`-th point.
    pub(crate) fn row(&self, r: usize) -> &[u32] {
        &self.rows[r * self.width..(r + 1) * self.width]
    }
}

/// The `k` nearest other points of every point of `points` (a nonempty set of finite points),
/// a block of about `block` consecutive positions of the search tree at a time: `run` gets the
/// [`Blocks`] — the tree's order and the block bounds, known before any block is searched —
/// and has them searched ([`Blocks::for_each`], whole blocks in parallel), so that no table of
/// every row is ever held (at a million points and k = 48, 576 MB) and a block's rows are
/// consumed while in cache. Returns the search (its tree's order, and rows again on request).
pub(crate) fn by_blocks(
    points: &[DVec3],
    k: usize,
    block: usize,
    run: impl FnOnce(&Blocks<'_>) -> Result<()>,
) -> Result<Searched> {
    let n = points.len();
    let width = k.min(n.saturating_sub(1));
    let (centre, extent) = centre_and_extent(points);
    // false for a NaN extent too (coordinates whose centre overflows)
    let mut tree = if extent <= F32_EXTENT {
        // with every other point among the candidates, a row is exact without a proof
        let searched = (width + MARGIN).min(n.saturating_sub(1));
        let proof = Proof {
            width,
            searched,
            complete: searched == n.saturating_sub(1),
            extent,
        };
        SearchTree::F32 {
            tree: f32_tree(points, centre)?,
            proof,
            exact: None,
        }
    } else {
        SearchTree::F64(f64_tree(points)?)
    };
    let order = match &tree {
        SearchTree::F32 { tree, .. } => tree.tree_order().to_vec(),
        SearchTree::F64(tree) => tree.tree_order().to_vec(),
    };
    // the f64 tree of the rows the proof does not settle, built when the first one needs it
    let exact = OnceLock::new();
    match &tree {
        _ if width == 0 => run(&Blocks::new(points, &order, width, Source::Single, &exact))?,
        SearchTree::F32 { tree, proof, .. } => {
            let nbhd = Neighborhood::Knn { k: proof.searched };
            tree.with_blocks(nbhd, true, block, |tree_blocks| {
                let source = Source::F32(tree_blocks, proof);
                run(&Blocks::new(points, &order, width, source, &exact))
            })??
        }
        SearchTree::F64(tree) => {
            let nbhd = Neighborhood::Knn { k: width };
            tree.with_blocks(nbhd, true, block, |tree_blocks| {
                let source = Source::F64(tree_blocks);
                run(&Blocks::new(points, &order, width, source, &exact))
            })??
        }
    }
    if let SearchTree::F32 { exact: kept, .. } = &mut tree {
        *kept = exact.into_inner().map(Box::new);
    }
    Ok(Searched { order, width, tree })
}

/// The `f32` tree of `points` relative to `centre`.
fn f32_tree(points: &[DVec3], centre: DVec3) -> Result<KdTree<f32>> {
    let mut flat = vec![0f32; points.len() * 3];
    flat.par_chunks_mut(3)
        .zip(points.par_iter())
        .with_min_len(4096)
        .for_each(|(f, p)| {
            for (f, c) in f.iter_mut().zip((*p - centre).to_array()) {
                *f = c as f32;
            }
        });
    KdTree::<f32>::build(&PointsView::from_flat(&flat, 3)?, &BuildOptions::default())
}

/// The blocks of a [`by_blocks`] search: the search tree's order, the block bounds, and the
/// search of any block.
pub(crate) struct Blocks<'s> {
    points: &'s [DVec3],
    order: &'s [u32],
    width: usize,
    source: Source<'s>,
    /// The `f64` tree of the rows an `f32` proof does not settle, once one needed it.
    exact: &'s OnceLock<KdTree<f64>>,
}

/// Where the rows of a block come from.
enum Source<'s> {
    /// The `f32` tree's candidates, proven exact (or searched again in `f64`).
    F32(&'s TreeBlocks<'s, f32>, &'s Proof),
    /// The `f64` tree of points too far out for `f32`.
    F64(&'s TreeBlocks<'s, f64>),
    /// A single point: one block of one empty row.
    Single,
}

/// One worker's rows of a block, kept from block to block.
#[derive(Default)]
struct Rows {
    rows: Vec<u32>,
    dists: Vec<f64>,
    nearest: Vec<Option<f64>>,
    farthest: Vec<f64>,
}

impl<'s> Blocks<'s> {
    fn new(
        points: &'s [DVec3],
        order: &'s [u32],
        width: usize,
        source: Source<'s>,
        exact: &'s OnceLock<KdTree<f64>>,
    ) -> Self {
        Self {
            points,
            order,
            width,
            source,
            exact,
        }
    }

    /// The caller's index of the point stored at each position of the search tree.
    pub(crate) fn order(&self) -> &'s [u32] {
        self.order
    }

    /// Block `b` holds the tree positions `bounds[b]..bounds[b + 1]`.
    pub(crate) fn bounds(&self) -> &[usize] {
        match self.source {
            Source::F32(blocks, _) => blocks.bounds(),
            Source::F64(blocks) => blocks.bounds(),
            Source::Single => &[0, 1],
        }
    }

    /// Hands `consume` the exact rows of every block, whole blocks in parallel, in no
    /// particular order: the threads do not wait for each other from block to block, and a
    /// thread another process holds up delays only its own block. When a row needs the `f64`
    /// tree, which is not built yet, the blocks not yet begun are set aside, the tree is built
    /// once, and they are searched then.
    pub(crate) fn for_each(
        &self,
        consume: &(dyn Fn(&Block<'_>) -> Result<()> + Sync),
    ) -> Result<()> {
        let blocks = self.bounds().len() - 1;
        let stop = AtomicBool::new(false);
        let left = self.pass(&(0..blocks).collect::<Vec<_>>(), &stop, consume)?;
        if left.is_empty() {
            return Ok(());
        }
        if self.exact.get().is_none() {
            // built outside the parallel pass: no thread waits on another's build
            let _ = self.exact.set(f64_tree(self.points)?);
        }
        let left = self.pass(&left, &stop, consume)?;
        debug_assert!(left.is_empty(), "every block settled with the f64 tree");
        Ok(())
    }

    /// Consumes the blocks `blocks` in parallel; returns those set aside for the `f64` tree
    /// (none once it is built).
    fn pass(
        &self,
        blocks: &[usize],
        stop: &AtomicBool,
        consume: &(dyn Fn(&Block<'_>) -> Result<()> + Sync),
    ) -> Result<Vec<usize>> {
        let exact = self.exact.get();
        let left: Vec<Option<usize>> = blocks
            .par_iter()
            .map_init(Rows::default, |rows, &b| {
                if exact.is_none() && stop.load(Ordering::Relaxed) {
                    return Ok(Some(b));
                }
                if !self.rows_of(b, exact, rows)? {
                    stop.store(true, Ordering::Relaxed);
                    return Ok(Some(b));
                }
                consume(&Block {
                    index: b,
                    order: self.order,
                    positions: self.bounds()[b]..self.bounds()[b + 1],
                    width: self.width,
                    rows: &rows.rows,
                    dists: &rows.dists,
                    nearest: &rows.nearest,
                    farthest: &rows.farthest,
                })?;
                Ok(None)
            })
            .collect::<Result<_>>()?;
        Ok(left.into_iter().flatten().collect())
    }

    /// The exact rows of block `b` into `out`; `false` when a row needs the `f64` tree and
    /// `exact` is not given.
    fn rows_of(&self, b: usize, exact: Option<&KdTree<f64>>, out: &mut Rows) -> Result<bool> {
        let positions = self.bounds()[b]..self.bounds()[b + 1];
        let width = self.width;
        let len = entries(positions.len(), width)?;
        try_resize(&mut out.rows, len)?;
        try_resize(&mut out.dists, len)?;
        match self.source {
            Source::Single => {
                out.nearest = vec![None; positions.len()];
                out.farthest = vec![0.0; positions.len()];
                Ok(true)
            }
            Source::F64(blocks) => {
                let table = blocks.rows(b)?;
                (out.nearest, out.farthest) = (0..positions.len())
                    .map(|r| {
                        let d = table.sq_dists_of(r);
                        (d.first().copied(), d.last().copied().unwrap_or(0.0))
                    })
                    .unzip();
                let (_, rows, dists) = table.into_parts();
                (out.rows, out.dists) = (rows, dists);
                Ok(true)
            }
            Source::F32(blocks, proof) => {
                let table = blocks.rows(b)?;
                self.settle(positions, &table, proof, exact, out)
            }
        }
    }

    /// The `f32` candidates `table` of the points at `positions` re-measured and proven into
    /// `out`; the rows the proof does not settle searched again with `exact` (`false` when it
    /// is not given).
    fn settle(
        &self,
        positions: Range<usize>,
        table: &NeighborTable<f32>,
        proof: &Proof,
        exact: Option<&KdTree<f64>>,
        out: &mut Rows,
    ) -> Result<bool> {
        let (points, order, width) = (self.points, self.order, self.width);
        let found: Vec<(Option<f64>, f64, bool)> = out
            .rows
            .par_chunks_mut(width)
            .zip(out.dists.par_chunks_mut(width))
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
        (out.nearest, out.farthest) = found.iter().map(|&(d, kth, _)| (d, kth)).unzip();
        let unproven: Vec<usize> = (0..positions.len()).filter(|&r| !found[r].2).collect();
        if unproven.is_empty() {
            return Ok(true);
        }
        let Some(tree) = exact else {
            return Ok(false);
        };
        let searched = search_in_f64(tree, &order[positions], &unproven, width)?;
        for (&r, row) in unproven.iter().zip(searched) {
            let slots = out.rows[r * width..(r + 1) * width].iter_mut();
            for ((slot, d), nb) in slots.zip(&mut out.dists[r * width..]).zip(&row) {
                (*slot, *d) = (nb.index, nb.sq_dist);
            }
            out.nearest[r] = row.first().map(|nb| nb.sq_dist);
            out.farthest[r] = row.last().map_or(0.0, |nb| nb.sq_dist);
        }
        Ok(true)
    }
}

/// What [`by_blocks`] searched with, kept to give rows once more after the blocks: a caller that
/// learns only at the end which rows it needs again (the rows cut by a length known once every
/// row was seen, `normals.rs`) gets them from the same tree, proven exact the same way, rather
/// than from a second tree of every point.
pub(crate) struct Searched {
    /// The caller's index of the point stored at each position (the search tree's order).
    pub(crate) order: Vec<u32>,
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
    pub(crate) fn rows_at(
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
        let rows = std::sync::Mutex::new(vec![Vec::new(); points.len()]);
        let searched = by_blocks(points, k, 700, |blocks| {
            blocks.for_each(&|b| {
                let mut rows = rows.lock().unwrap();
                for (r, pos) in b.positions.clone().enumerate() {
                    let dists = &b.dists[r * b.width..(r + 1) * b.width];
                    let row = b.row(r).iter().zip(dists);
                    rows[pos] = row
                        .map(|(&index, &sq_dist)| Neighbor { index, sq_dist })
                        .collect();
                }
                Ok(())
            })
        })
        .unwrap();
        let blocks = rows.into_inner().unwrap();
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

    /// Rows longer than the sorted rows' 64 (the robust smoothing's wide rows, 3 · 48 + the
    /// margin), gathered first since those are.
    #[test]
    fn wide_rows_are_the_exact_nearest() {
        assert_exact(&noisy_sphere(3000, 0.0), 144);
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
