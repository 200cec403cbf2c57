//! The per-point work of the robust smoothing over one tile of a cloud: [`RobustTile`].
//!
//! A tile is a set of input points gathered from the cloud (all of it on one machine; a box of
//! it plus a halo when the cloud is split) of which it *owns* some. It computes the rounds of
//! `robust/run.rs` over every gathered point with the stage functions of the sibling modules
//! (the rows of `rows.rs`, the planes and normals of `planes.rs`, the step of `step.rs`, the
//! noise scale of `scales.rs`) and returns the owned points' values ([`TilePart`]); the halo
//! points only serve as neighbours. The points are kept in the k-d tree's order of the tile's
//! input, so that a point's neighbours lie close in memory.
//!
//! The same arithmetic runs on one machine and in a split cloud: every per-point value reads
//! the rows of its point and sums them in row order (`(sq_dist, index)`, with local indices
//! that ascend with the cloud's, so ties break alike), and the batched eigen-solves and step
//! lanes give each point what it would get alone. An owned point's value is therefore the
//! one-machine value whenever everything it reads is right in the tile, which
//! `robust/reach.rs` decides per point ([`TilePart::valid`]).

use super::planes::{covariance_planes, plane_distance, plane_distances, selected_normals, Plane};
use super::reach::{Reach, Region};
use super::row_file::{self, Kept, KeptRef, MeasuredKey};
use super::rows::Rows;
use super::run::{median, median_rank, Reduced, Round, RowSet};
use super::scales;
use super::step::step;
use super::{robust_outputs, RobustOptions};
use crate::error::{NbhdError, Result};
use crate::geometry::source::{knn_rows, Neighbors, SearchMethod};
use crate::select::radix::select_in_parts;
use crate::smooth::PointOutput;
use crate::sum::ExactSum;
use glam::DVec3;
use std::borrow::Cow;
use std::path::PathBuf;

/// One tile of a robust run (see the module documentation).
pub struct RobustTile<'a> {
    /// The gathered input points (the tile's local order: ascending in the cloud's order).
    input: Cow<'a, [DVec3]>,
    /// Where the rows come from (a search of the tile's own unless one machine was given a
    /// caller's table).
    neighbors: Neighbors<'a>,
    /// The box every gathered point lies in and every point of the cloud inside which was
    /// gathered; `None` when the tile is the whole cloud.
    region: Option<Region>,
    /// Local indices of the owned points, ascending; `None`: every point.
    owned: Option<Vec<u32>>,
    /// The rows and the points in stored order, from the first round on.
    state: Option<State>,
    /// A proxy given before the first round ([`RobustTile::set_current`]), in local order.
    pending: Option<(usize, Vec<DVec3>)>,
    /// The normals of the last step, given before the first round
    /// ([`RobustTile::set_normals`]), in local order.
    pending_normals: Option<Vec<DVec3>>,
    /// The proxy the run's rows shrank on, with its generation ([`RobustTile::set_shrink`]),
    /// in local order.
    shrink: Option<(usize, Vec<DVec3>)>,
    /// Whether the first search finds the wide rows, to stand in for the plain ones
    /// ([`RobustTile::search_wide_first`]).
    wide_first: bool,
    /// Where the searched rows are kept between the tasks of a split run
    /// ([`RobustTile::keep_rows_in`]).
    row_files: Option<PathBuf>,
}

/// The rows of a tile and the proxy they are measured on, in the k-d tree's order.
struct State {
    set: RowSet,
    rows: Rows,
    /// `order[s]`: the local index of the point stored at `s`.
    order: Vec<u32>,
    /// The proxy of generation `generation`, in stored order.
    cur: Vec<DVec3>,
    generation: usize,
    /// The generation the rows are measured on and cut at ε (`None`: as searched).
    measured_on: Option<usize>,
    /// The planes of [`Round::Measure`], kept for the step of the same generation.
    planes: Option<(usize, Vec<Plane>)>,
    /// The normals of the last step, in stored order.
    normals: Vec<DVec3>,
    /// Which stored points' values are right (`None`: all).
    reach: Option<Reach>,
    /// Stored positions of the owned points, in local order (`None`: all points).
    owned_at: Option<Vec<u32>>,
    /// Whether the rows are wide rows searched in place of the plain ones, which are their
    /// first `k_plane` on the input, until a round after [`Round::Start`] asks for either.
    stand_in: bool,
}

/// The owned points' part of one round (per point values in local order).
#[derive(Clone, Debug, Default)]
pub struct TilePart {
    /// Owned points.
    pub count: u64,
    /// Whether each owned point's value of this round is the one-machine value (empty: all
    /// are, the tile is the whole cloud).
    pub valid: Vec<bool>,
    /// The owned points' distance ratios ([`Round::Start`] with the noise scale,
    /// [`Round::Ratio`]; only points that have one) or plane distances ([`Round::Measure`]).
    pub values: Vec<f64>,
    /// The owned points' squared displacements ([`Round::Step`]).
    pub moved_sq: ExactSum,
    /// The longest owned row within ε ([`Round::Start`]).
    pub max_len: usize,
    /// The shortest owned row within ε, at most `k` ([`Round::Start`]).
    pub min_narrow: usize,
}

impl TilePart {
    /// Whether every owned point's value is right.
    pub fn all_valid(&self) -> bool {
        self.valid.iter().all(|&v| v)
    }
}

/// The parts of all tiles of one round reduced to what the run takes: the medians as exact
/// selections across the parts (one part is selected in place).
///
/// # Errors
///
/// Only those of a malformed part (a rank beyond the values).
pub fn reduce(round: &Round, parts: &mut [TilePart]) -> Result<Reduced> {
    let mut reduced = Reduced {
        count: parts.iter().map(|p| p.count).sum(),
        max_len: parts.iter().map(|p| p.max_len).max().unwrap_or(0),
        min_narrow: parts.iter().map(|p| p.min_narrow).min().unwrap_or(0),
        ..Reduced::default()
    };
    let value = match parts {
        [one] => median(&mut one.values),
        _ => {
            let values: Vec<&[f64]> = parts.iter().map(|p| p.values.as_slice()).collect();
            let n: usize = values.iter().map(|v| v.len()).sum();
            match n {
                0 => None,
                n => Some(select_in_parts(&values, median_rank(n as u64))?),
            }
        }
    };
    reduced.set_median(round, value);
    for p in parts.iter() {
        reduced.moved_sq.merge(&p.moved_sq);
    }
    Ok(reduced)
}

impl<'a> RobustTile<'a> {
    /// The whole cloud as one tile (one machine): every point owned, the rows from
    /// `neighbors`.
    pub fn whole(points: &'a [DVec3], neighbors: Neighbors<'a>) -> Self {
        Self {
            input: Cow::Borrowed(points),
            neighbors,
            region: None,
            owned: None,
            state: None,
            pending: None,
            pending_normals: None,
            shrink: None,
            wide_first: false,
            row_files: None,
        }
    }

    /// Has the first search find the wide rows (`WIDE`·`k_plane` nearest) instead of the
    /// plain ones, where the cloud is expected to read as a ball of noise
    /// (`scales::input_reads_as_ball`): rows are sorted by `(sq_dist, index)` on the input, so
    /// the first `k_plane` of a wide row are the plain row, and [`Round::Start`] reads those.
    /// If the run widens, its wide rows are already there (one search instead of two); if not,
    /// they are cut back to the plain rows. Either way every round reads the rows it would
    /// have read: the results are the same bits.
    pub(super) fn search_wide_first(&mut self) {
        self.wide_first = true;
    }

    /// A tile of a split cloud: `input` every finite point of the cloud inside `region`
    /// (closed), in the cloud's order; `owned[i]` whether the tile owns `input[i]` (each point
    /// of the cloud is owned by one tile).
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when `owned` has another length than `input` or a point
    /// lies outside the region or is not finite.
    pub fn gathered(input: Vec<DVec3>, owned: &[bool], region: Region) -> Result<Self> {
        let bad = |reason: &str| NbhdError::InvalidOption {
            name: "tile",
            reason: reason.into(),
        };
        if owned.len() != input.len() {
            return Err(bad("one owned flag per gathered point is needed"));
        }
        if !input.iter().all(|&p| region.contains(p)) {
            return Err(bad("gathered points must be finite and inside the region"));
        }
        let owned = (0..input.len() as u32)
            .filter(|&i| owned[i as usize])
            .collect();
        Ok(Self {
            input: Cow::Owned(input),
            neighbors: Neighbors::Search(SearchMethod::KdTree),
            region: Some(region),
            owned: Some(owned),
            state: None,
            pending: None,
            pending_normals: None,
            shrink: None,
            wide_first: false,
            row_files: None,
        })
    }

    /// Keeps the rows this tile searches in files in `dir` (one per row width), and reads
    /// them from there instead of searching when a tile of the same input and region made
    /// earlier wrote them (`robust/row_file.rs`): a driver that makes the tile anew at every
    /// round searches once per row set instead of once per round, with the same results.
    pub fn keep_rows_in(&mut self, dir: impl Into<PathBuf>) {
        self.row_files = Some(dir.into());
    }

    /// Each owned point's squared distance to its nearest other point (`None` without one),
    /// in local order, the input of the spacing h; and whether each is right (empty: all).
    /// Searches the plain rows (`k_plane` nearest) and keeps them for [`Round::Start`].
    /// Runs on the pool of `options.threads`, as [`RobustTile::round`].
    pub fn nearest(&mut self, options: &RobustOptions) -> Result<(Vec<Option<f64>>, Vec<bool>)> {
        crate::parallel::with_threads(options.threads, || self.nearest_here(options.k_plane))?
    }

    fn nearest_here(&mut self, k_plane: usize) -> Result<(Vec<Option<f64>>, Vec<bool>)> {
        let nearest = self.search(RowSet::Plain, k_plane)?;
        let st = self.state.as_ref().expect("searched");
        let valid = self.owned_valid(st, |r| r.cert());
        Ok(match &self.owned {
            None => (nearest, valid),
            Some(owned) => (owned.iter().map(|&i| nearest[i as usize]).collect(), valid),
        })
    }

    /// Searches the rows of `set` on the input (the `k_plane` nearest, `WIDE` times as many
    /// for the wide and shrunk rows) and stores the proxy in the new tree's order. Returns each
    /// gathered point's squared distance to its nearest, by local index.
    fn search(&mut self, set: RowSet, k_plane: usize) -> Result<Vec<Option<f64>>> {
        let stand_in = set == RowSet::Plain && std::mem::take(&mut self.wide_first);
        let set = if stand_in { RowSet::Wide } else { set };
        let k = searched_k(set, k_plane);
        let kept = match self.neighbors {
            Neighbors::Search(SearchMethod::KdTree) => self.searched_rows(k)?,
            neighbors => {
                let (knn, order) = knn_rows(&self.input, neighbors, k)?;
                let nearest = (0..knn.len())
                    .map(|i| knn.sq_dists_of(i).first().copied())
                    .collect();
                let rows = Rows::in_stored_order(&knn, &order);
                let reach = self.reach_of(&rows, &order, k);
                Kept {
                    rows,
                    order,
                    nearest,
                    reach,
                    measured: None,
                }
            }
        };
        let set = if set == RowSet::Plain {
            set
        } else {
            RowSet::Wide
        };
        Ok(self.install(kept, set, stand_in))
    }

    /// The reach flags of `rows` searched for `k` on the input (`order` the stored order), in
    /// a tile of a split cloud.
    fn reach_of(&self, rows: &Rows, order: &[u32], k: usize) -> Option<Reach> {
        self.region.as_ref().map(|region| {
            let input: Vec<DVec3> = order.iter().map(|&o| self.input[o as usize]).collect();
            Reach::new(&input, rows, k, region)
        })
    }

    /// Makes `kept` the tile's state, of row set `set` (a measure's own when `kept` holds
    /// one), on the proxy of the last state or the one given ([`RobustTile::set_current`]).
    /// Returns the nearest distances kept.
    fn install(&mut self, kept: Kept, set: RowSet, stand_in: bool) -> Vec<Option<f64>> {
        let Kept {
            rows,
            order,
            nearest,
            reach,
            measured,
        } = kept;
        let current = match self.state.take() {
            Some(st) if st.generation > 0 => {
                Some((st.generation, super::in_input_order(&st.cur, &st.order)))
            }
            Some(_) => None,
            None => self.pending.take(),
        };
        let (generation, cur) = match current {
            Some((g, local)) => (g, order.iter().map(|&o| local[o as usize]).collect()),
            None => (0, order.iter().map(|&o| self.input[o as usize]).collect()),
        };
        let owned_at = self.owned.as_ref().map(|owned| {
            let position = super::super::positions_of(&order);
            owned.iter().map(|&i| position[i as usize]).collect()
        });
        let normals = self
            .pending_normals
            .take()
            .map(|local| order.iter().map(|&o| local[o as usize]).collect())
            .unwrap_or_default();
        let (set, measured_on, planes) = match measured {
            Some((key, planes)) => (
                key.set,
                Some(key.generation),
                Some((key.generation, planes)),
            ),
            None => (set, None, None),
        };
        self.state = Some(State {
            set,
            rows,
            order,
            cur,
            generation,
            measured_on,
            planes,
            normals,
            reach,
            owned_at,
            stand_in,
        });
        nearest
    }

    /// [`Rows::search`] of the input for `k` with its reach, or the rows a tile of the same
    /// input and region kept in its row file ([`RobustTile::keep_rows_in`]); rows searched
    /// are written there. A file that cannot be written is left out: the next tile searches
    /// again.
    fn searched_rows(&self, k: usize) -> Result<Kept> {
        let file = self.row_files.as_ref().map(|dir| {
            let print = row_file::fingerprint(&self.input, k, self.region.as_ref());
            (dir.join(format!("rows_{k}.bin")), print)
        });
        if let Some((path, print)) = &file {
            if let Some(kept) = row_file::read(path, *print, self.input.len(), None) {
                return Ok(kept);
            }
        }
        let (rows, order, nearest) = Rows::search(&self.input, k)?;
        let reach = self.reach_of(&rows, &order, k);
        let kept = Kept {
            rows,
            order,
            nearest,
            reach,
            measured: None,
        };
        if let Some((path, print)) = &file {
            let _ = row_file::write(path, *print, &kept.borrowed());
        }
        Ok(kept)
    }

    /// The key under which a measure of `set` at `generation` on the proxy given to a fresh
    /// tile ([`RobustTile::set_current`], the input at generation 0) keeps its rows and planes.
    fn measured_key(&self, set: RowSet, generation: usize, eps: f64) -> Option<MeasuredKey> {
        let proxy = match &self.pending {
            Some((g, local)) if *g == generation => row_file::proxy_hash(local, |i| i as u32),
            None if generation == 0 => row_file::proxy_hash(&self.input, |i| i as u32),
            _ => return None,
        };
        Some(MeasuredKey {
            set,
            generation,
            eps: eps.to_bits(),
            proxy,
        })
    }

    /// Installs the rows and planes a measure of `set` at `generation` kept for the rounds
    /// after it on the same proxy (the step), when the tile is fresh and its files hold
    /// them; whether it did.
    fn kept_measured(&mut self, set: RowSet, generation: usize, eps: f64, k_plane: usize) -> bool {
        let searches = matches!(self.neighbors, Neighbors::Search(SearchMethod::KdTree));
        let Some(dir) = self
            .row_files
            .as_ref()
            .filter(|_| searches && self.state.is_none())
        else {
            return false;
        };
        let Some(key) = self.measured_key(set, generation, eps) else {
            return false;
        };
        let k = searched_k(set, k_plane);
        let print = row_file::fingerprint(&self.input, k, self.region.as_ref());
        let path = dir.join("measured.bin");
        match row_file::read(&path, print, self.input.len(), Some(key)) {
            Some(kept) => {
                self.install(kept, set, false);
                true
            }
            None => false,
        }
    }

    /// Keeps the rows as measured at `generation` and their `planes` in the tile's files, for
    /// the step of the same generation (a tile of a split run made anew for it).
    fn keep_measured(&self, generation: usize, eps: f64, k_plane: usize) {
        let (Some(dir), Some(st)) = (&self.row_files, &self.state) else {
            return;
        };
        let Some((_, planes)) = st.planes.as_ref().filter(|(g, _)| *g == generation) else {
            return;
        };
        let key = MeasuredKey {
            set: st.set,
            generation,
            eps: eps.to_bits(),
            proxy: row_file::proxy_hash(&st.cur, |s| st.order[s]),
        };
        let k = searched_k(st.set, k_plane);
        let print = row_file::fingerprint(&self.input, k, self.region.as_ref());
        let kept = KeptRef {
            rows: &st.rows,
            order: &st.order,
            nearest: &[],
            reach: st.reach.as_ref(),
            measured: Some((key, planes)),
        };
        let _ = row_file::write(&dir.join("measured.bin"), print, &kept);
    }

    /// The plain rows on the input, measured and cut at `eps`, for [`Round::Start`]: wide rows
    /// that stand in for them are kept whole (the round reads their first `k_plane`).
    fn start_rows(&mut self, eps: f64, k_plane: usize) -> Result<()> {
        match self.state.as_mut().filter(|st| st.stand_in) {
            Some(st) if st.generation != 0 => Err(out_of_turn("a start after a step")),
            Some(st) => {
                st.measure(eps);
                Ok(())
            }
            None => self.rows_on(RowSet::Plain, 0, eps, k_plane),
        }
    }

    /// The rows of `set` measured on the proxy of `generation` and cut at `eps`.
    fn rows_on(&mut self, set: RowSet, generation: usize, eps: f64, k_plane: usize) -> Result<()> {
        if let Some(st) = self.state.as_mut().filter(|st| st.stand_in) {
            // the run has chosen: the wide rows stay, or their first `k_plane` as sorted on
            // the input (stand-ins live on generation 0 only) are the plain rows
            st.stand_in = false;
            if set == RowSet::Plain {
                st.measure(eps);
                st.rows.shrink(k_plane);
                st.set = RowSet::Plain;
            }
        }
        let searched = |s: RowSet| s == RowSet::Plain;
        let fresh = self
            .state
            .as_ref()
            .is_none_or(|st| searched(st.set) != searched(set));
        if fresh && !self.kept_measured(set, generation, eps, k_plane) {
            self.search(set, k_plane)?;
        }
        let st = self.state.as_mut().expect("searched");
        if st.generation != generation {
            return Err(out_of_turn("a round of another generation"));
        }
        if let (RowSet::Shrunk { at }, RowSet::Wide) = (set, st.set) {
            // the wide rows' first `k_plane` as sorted on the proxy of `at`: the current one,
            // or the one given to a tile gathered after the shrink
            let current = if at == generation {
                None
            } else {
                let Some((_, local)) = self.shrink.take().filter(|(g, _)| *g == at) else {
                    return Err(out_of_turn(
                        "the rows shrink on the proxy of another generation",
                    ));
                };
                let proxy = st.order.iter().map(|&o| local[o as usize]).collect();
                Some(std::mem::replace(&mut st.cur, proxy))
            };
            st.generation = at;
            st.measure(eps);
            st.rows.shrink(k_plane);
            st.set = set;
            if let Some(cur) = current {
                st.cur = cur;
                st.generation = generation;
                st.measured_on = None;
            }
        }
        st.measure(eps);
        Ok(())
    }

    /// The owned points' flags of `reach` (empty: no region, all valid).
    fn owned_valid(&self, st: &State, of: impl Fn(&Reach) -> &[bool]) -> Vec<bool> {
        let Some(reach) = &st.reach else {
            return Vec::new();
        };
        let flags = of(reach);
        match &st.owned_at {
            None => flags.to_vec(),
            Some(at) => at.iter().map(|&s| flags[s as usize]).collect(),
        }
    }

    /// Sets the proxy of generation `generation`, in local order (the tiles that own the
    /// halo's points computed it): a split cloud's driver calls this after every step, and
    /// before the first round of a tile gathered anew (a wider halo) after the run started.
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when `current` has another length than the input.
    pub fn set_current(&mut self, generation: usize, current: &[DVec3]) -> Result<()> {
        if current.len() != self.input.len() {
            return Err(out_of_turn("a proxy of another length"));
        }
        match &mut self.state {
            Some(st) => {
                for (c, &o) in st.cur.iter_mut().zip(&st.order) {
                    *c = current[o as usize];
                }
                st.generation = generation;
                st.measured_on = None;
                st.planes = None;
            }
            None => self.pending = Some((generation, current.to_vec())),
        }
        Ok(())
    }

    /// Sets the normals of the step into the current generation, in local order, for a tile
    /// gathered after that step (a driver that keeps no tile between rounds): the
    /// [`RobustTile::finish`] of a run that stepped takes them (the owned points' are the
    /// ones it returns and its outputs read).
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when `normals` has another length than the input.
    pub fn set_normals(&mut self, normals: &[DVec3]) -> Result<()> {
        if normals.len() != self.input.len() {
            return Err(out_of_turn("normals of another length"));
        }
        match &mut self.state {
            Some(st) => st.normals = st.order.iter().map(|&o| normals[o as usize]).collect(),
            None => self.pending_normals = Some(normals.to_vec()),
        }
        Ok(())
    }

    /// Sets the proxy of generation `at`, in local order, on which the run's wide rows shrank
    /// ([`RowSet::Shrunk`]), for a tile gathered at a later generation: its wide rows are
    /// searched on the input, sorted on this proxy and cut to `k_plane` as the run's were.
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when `proxy` has another length than the input.
    pub fn set_shrink(&mut self, at: usize, proxy: &[DVec3]) -> Result<()> {
        if proxy.len() != self.input.len() {
            return Err(out_of_turn("a shrink proxy of another length"));
        }
        self.shrink = Some((at, proxy.to_vec()));
        Ok(())
    }

    /// The owned points of the current proxy, in local order.
    pub fn owned_points(&self) -> Vec<DVec3> {
        self.owned_of(|st| &st.cur)
    }

    /// The owned points' normals of the last step (empty before a step), in local order.
    pub fn owned_normals(&self) -> Vec<DVec3> {
        self.owned_of(|st| &st.normals)
    }

    /// The owned points' entries of a per-point array of the state (stored order), in local
    /// order; empty when the array is.
    fn owned_of(&self, of: impl Fn(&State) -> &Vec<DVec3>) -> Vec<DVec3> {
        let Some(st) = &self.state else {
            return Vec::new();
        };
        let values = of(st);
        if values.is_empty() {
            return Vec::new();
        }
        match &st.owned_at {
            None => super::in_input_order(values, &st.order),
            Some(at) => at.iter().map(|&s| values[s as usize]).collect(),
        }
    }

    /// Computes `round` (of the run with `options` and ε = `eps`) over the gathered points and
    /// returns the owned points' part, on the pool of `options.threads` (1: one worker, so a
    /// tile task of a distributed run holds one thread's buffers).
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] for [`Round::Done`] or a round of another generation than
    /// the tile's proxy; those of the search.
    pub fn round(&mut self, round: &Round, options: &RobustOptions, eps: f64) -> Result<TilePart> {
        crate::parallel::with_threads(options.threads, || self.round_here(round, options, eps))?
    }

    fn round_here(&mut self, round: &Round, options: &RobustOptions, eps: f64) -> Result<TilePart> {
        let kp = options.k_plane;
        match *round {
            Round::Start => {
                self.start_rows(eps, kp)?;
                Ok(self.start_part(options))
            }
            Round::Ratio { generation } => {
                self.rows_on(RowSet::Wide, generation, eps, kp)?;
                Ok(self.ratio_part(kp))
            }
            Round::Measure { generation, rows } => {
                self.rows_on(rows, generation, eps, kp)?;
                let part = self.measure_part(generation);
                self.keep_measured(generation, eps, kp);
                Ok(part)
            }
            Round::Step {
                generation,
                rows,
                sigma,
                k,
            } => {
                self.rows_on(rows, generation, eps, kp)?;
                Ok(self.step_part(generation, sigma, &RobustOptions { k, ..*options }))
            }
            Round::Finish { .. } | Round::Done => Err(out_of_turn("a round with no part")),
        }
    }

    /// [`Round::Start`]'s part: the row lengths and, with the noise scale, the ratios.
    fn start_part(&self, options: &RobustOptions) -> TilePart {
        let st = self.state.as_ref().expect("rows measured");
        let (max_len, min_narrow) = match &st.owned_at {
            // wide rows standing in for the plain ones: their first `k_plane`
            None if st.stand_in => (
                st.rows.max_narrow_len(options.k_plane),
                st.rows.min_narrow_len(options.k),
            ),
            None => (st.rows.max_len(), st.rows.min_narrow_len(options.k)),
            Some(at) => {
                let len = |&s: &u32| st.rows.wide(s as usize).len();
                let max = at.iter().map(len).max().unwrap_or(0);
                let min = at.iter().map(|s| len(s).min(options.k)).min();
                (max, min.unwrap_or(usize::MAX))
            }
        };
        let ratios = if options.noise_scale {
            self.ratio_part(options.k_plane)
        } else {
            self.part(|r| r.cert(), Vec::new())
        };
        TilePart {
            max_len,
            min_narrow,
            ..ratios
        }
    }

    /// The owned points' distance ratios on the current proxy and rows.
    fn ratio_part(&self, k_plane: usize) -> TilePart {
        let st = self.state.as_ref().expect("rows measured");
        let values = match &st.owned_at {
            None => scales::distance_ratios(&st.cur, &st.rows, k_plane),
            Some(at) => at
                .iter()
                .filter_map(|&s| scales::distance_ratio_at(&st.cur, &st.rows, k_plane, s as usize))
                .collect(),
        };
        self.part(|r| r.cert(), values)
    }

    /// [`Round::Measure`]'s part: the planes (kept for the step) and the owned points'
    /// distances to their own.
    fn measure_part(&mut self, generation: usize) -> TilePart {
        let st = self.state.as_mut().expect("rows measured");
        let planes = covariance_planes(&st.cur, &st.rows);
        let values = match &st.owned_at {
            None => plane_distances(&st.cur, &planes),
            Some(at) => at
                .iter()
                .map(|&s| plane_distance(st.cur[s as usize], &planes[s as usize]))
                .collect(),
        };
        st.planes = Some((generation, planes));
        self.part(|r| r.cert(), values)
    }

    /// [`Round::Step`]'s part: the selected normals (kept), the step into the next generation
    /// and the owned points' squared displacements.
    fn step_part(&mut self, generation: usize, sigma: f64, options: &RobustOptions) -> TilePart {
        let st = self.state.as_mut().expect("rows measured");
        let planes = match st.planes.take() {
            Some((g, planes)) if g == generation => planes,
            _ => covariance_planes(&st.cur, &st.rows),
        };
        let width = options.inlier_width * sigma;
        let candidates = options.k_plane.div_ceil(4);
        st.normals = selected_normals(&st.cur, &st.rows, &planes, width, candidates);
        drop(planes);
        let next = step(&st.cur, &st.rows, &st.normals, width, options);
        let mut moved_sq = ExactSum::new();
        match &st.owned_at {
            None => moved_sq.extend(
                next.iter()
                    .zip(&st.cur)
                    .map(|(a, b)| a.distance_squared(*b)),
            ),
            Some(at) => moved_sq.extend(at.iter().map(|&s| {
                let s = s as usize;
                next[s].distance_squared(st.cur[s])
            })),
        }
        st.cur = next;
        st.generation += 1;
        TilePart {
            moved_sq,
            ..self.part(Reach::step, Vec::new())
        }
    }

    /// A part with the owned count, the validity `of` the reach, and `values`.
    fn part(&self, of: impl Fn(&Reach) -> &[bool], values: Vec<f64>) -> TilePart {
        let st = self.state.as_ref().expect("rows measured");
        TilePart {
            count: self.owned.as_ref().map_or(st.cur.len(), Vec::len) as u64,
            valid: self.owned_valid(st, of),
            values,
            ..TilePart::default()
        }
    }

    /// [`Round::Finish`]: the points, the normals (the last step's, or the covariance normals
    /// of the proxy if no step was taken) and, with `options.outputs`, the per-point outputs
    /// with `lambda`, of the owned points in local order; whether each is right (empty: all).
    #[allow(clippy::type_complexity)]
    pub fn finish(
        self,
        round: &Round,
        options: &RobustOptions,
        eps: f64,
    ) -> Result<(Vec<DVec3>, Vec<DVec3>, Vec<PointOutput>, Vec<bool>)> {
        crate::parallel::with_threads(options.threads, || self.finish_here(round, options, eps))?
    }

    #[allow(clippy::type_complexity)]
    fn finish_here(
        mut self,
        round: &Round,
        options: &RobustOptions,
        eps: f64,
    ) -> Result<(Vec<DVec3>, Vec<DVec3>, Vec<PointOutput>, Vec<bool>)> {
        let Round::Finish {
            generation,
            rows,
            lambda,
        } = *round
        else {
            return Err(out_of_turn("a round that is not the last"));
        };
        let no_step = self.pending_normals.is_none()
            && self.state.as_ref().is_none_or(|st| st.normals.is_empty());
        if no_step || options.outputs || self.state.is_none() {
            self.rows_on(rows, generation, eps, options.k_plane)?;
        }
        let st = self.state.as_mut().expect("rows measured");
        if no_step {
            st.normals = covariance_planes(&st.cur, &st.rows)
                .iter()
                .map(|c| c.normal)
                .collect();
        }
        let valid = self.owned_valid(self.state.as_ref().expect("rows"), |r| r.cert());
        let State {
            rows,
            order,
            cur,
            normals,
            ..
        } = self.state.take().expect("rows measured");
        let points = super::in_input_order(&cur, &order);
        let normals = super::in_input_order(&normals, &order);
        let outputs = if options.outputs {
            let narrow = rows.narrow_table(&cur, options.k, &order);
            drop(rows); // the wide rows are done with: their memory goes to the outputs
            robust_outputs(&points, &narrow, &normals, lambda, options)?
        } else {
            Vec::new()
        };
        Ok(match &self.owned {
            None => (points, normals, outputs, valid),
            Some(owned) => {
                let outputs = if outputs.is_empty() {
                    outputs
                } else {
                    pick(&outputs, owned)
                };
                (pick(&points, owned), pick(&normals, owned), outputs, valid)
            }
        })
    }
}

/// The values of the owned points (local indices `owned`).
fn pick<T: Copy>(values: &[T], owned: &[u32]) -> Vec<T> {
    owned.iter().map(|&i| values[i as usize]).collect()
}

impl State {
    /// Measures the rows on the current proxy and cuts them at `eps`, unless they are already
    /// (the first cut of searched rows on the input keeps the rows that are whole).
    fn measure(&mut self, eps: f64) {
        match self.measured_on {
            Some(g) if g == self.generation => {}
            None if self.generation == 0 => self.rows.cut(&self.cur, &self.order, eps),
            _ => self.rows.update(&self.cur, &self.order, eps),
        }
        self.measured_on = Some(self.generation);
    }
}

/// How many nearest a search of `set` finds: `k_plane`, or `WIDE` times as many for the
/// wide rows (and the shrunk ones, which are cut from them).
fn searched_k(set: RowSet, k_plane: usize) -> usize {
    match set {
        RowSet::Plain => k_plane,
        _ => k_plane * scales::WIDE,
    }
}

fn out_of_turn(what: &str) -> NbhdError {
    NbhdError::InvalidOption {
        name: "robust tile",
        reason: format!("{what}: out of turn"),
    }
}
