//! A k-d tree that grows and shrinks: points are inserted in batches (a scan frame) and removed
//! by index, and every query answers exactly what a static [`KdTree`] over the live points
//! answers.
//!
//! The design is the logarithmic method (Bentley and Saxe, *Decomposable searching problems I:
//! static-to-dynamic transformation*, J. Algorithms 1980): a forest of static trees, each
//! built by [`KdTree::build`] (the fast, parallel build, so every tree has the static tree's
//! layout and query speed), of geometrically growing sizes.
//!
//! - **Insertion.** A batch becomes a new tree of its own; then, while an older tree holds
//!   fewer than [`GROWTH`] times the live points of the next newer one, the two are merged
//!   (rebuilt as one). With batches of equal size and factor g this is a base-g counter: a point
//!   takes part in O(g · log_g(n / batch)) builds, and the forest holds O(log_g(n / batch))
//!   trees. A larger factor ([`DynamicKdTree::set_growth`]) keeps fewer, larger trees (faster
//!   queries) for more rebuilding; the default 4 was chosen by measurement (`benches/dynamic.rs`,
//!   README "Trees that grow and shrink"): against 2 it cut queries on the grown tree from
//!   1.5× to 1.2× a static tree's and both benchmarks' totals by about 10%.
//! - **Removal.** A removed point becomes a tombstone: its tree keeps it, and every search
//!   skips it. A tree whose tombstones outnumber its live points is rebuilt over the live
//!   ones, so tombstones never cost a search more than a factor 2; a tree whose points are all
//!   removed is dropped.
//! - **Search.** One result set (`src/query/result_set.rs`) is filled by the descents of all
//!   trees in turn, largest first, skipping a tree whose bounding box is farther than the
//!   set's current bound. The set orders by `(sq_dist, index)` (`src/query/order.rs`), so the
//!   result is the static tree's, whatever the trees. A dense batch of queries is answered in
//!   groups of nearby queries, each group descending every tree once (`batch.rs`).
//!
//! **Indices.** The points of a batch get consecutive indices, continuing from the previous
//! batch: the first batch gets `0..n`. A point keeps its index until it is removed, and a
//! removed index is never given again (it names nothing from then on: a query or removal
//! naming it is refused with [`NbhdError::RemovedPoint`]). Tables have one row per index ever
//! given (`0..next_index()`), empty for points not live — as a static tree built over all
//! those points with the removed ones skipped. At most `u32::MAX` indices can ever be given.
//!
//! **Non-finite points** follow the build option [`BuildOptions::non_finite`], as in a static
//! build: with `Reject` a batch holding a NaN or infinite coordinate is refused whole
//! ([`NbhdError::NonFinite`] naming its position in the batch) and nothing is inserted; with
//! `Skip` such a point still takes its index but is not live (a query by that index is
//! refused with [`NbhdError::SkippedPoint`]).
//!
//! Memory: the coordinates of the indices from the oldest live point on (removed ones too,
//! until the oldest live point moves past them), the trees' own copies, and two bits per index
//! ever given.

mod batch;
mod persist;
mod search;

use std::any::Any;
use std::sync::{Arc, OnceLock};

use crate::error::{NbhdError, Result};
use crate::metric::Period;
use crate::packed::NonFinitePolicy;
use crate::points::{point_bytes, PointsView};
use crate::scalar::Scalar;
use crate::tree::{BuildOptions, KdTree};

pub use persist::{SavedDynamicInfo, DYNAMIC_FORMAT_VERSION};

/// The default growth factor: two neighbouring trees are merged when the older holds fewer than
/// `GROWTH` times the live points of the newer, so sizes at least quadruple from the newest
/// tree to the oldest (chosen by measurement, see the module documentation).
pub const GROWTH: usize = 4;

/// One tree of the forest: the indices `lo..hi` it was built over (those live at its build),
/// its live and removed counts, and its bounding box.
#[derive(Clone, Debug)]
struct Part<T> {
    tree: Arc<KdTree<T>>,
    /// First index covered; the tree's own caller indices are `index - lo`.
    lo: u32,
    /// One past the last index covered.
    hi: u32,
    /// Points of the tree still live.
    live: usize,
    /// Points of the tree removed since its build (tombstones).
    dead: usize,
    /// Smallest coordinates of the tree's points.
    bbox_lo: Vec<T>,
    /// Largest coordinates of the tree's points.
    bbox_hi: Vec<T>,
    /// The tree prepared for the grouped batch search (`batch.rs`, its cells of the forest's
    /// dimension), made on first use.
    cells: Arc<OnceLock<Box<dyn Any + Send + Sync>>>,
}

impl<T: Scalar> Part<T> {
    /// A tree covering the indices `lo..hi`, `live` of its points live.
    fn new(tree: KdTree<T>, lo: u32, hi: u32, live: usize) -> Self {
        let (bbox_lo, bbox_hi) = tree.bounding_box();
        Self {
            dead: tree.len() - live,
            live,
            tree: Arc::new(tree),
            lo,
            hi,
            bbox_lo,
            bbox_hi,
            cells: Arc::default(),
        }
    }
}

/// Size and shape of a dynamic tree.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DynamicStats {
    /// Live points.
    pub live: usize,
    /// Indices given so far (live, removed and skipped points).
    pub next_index: u32,
    /// `(live, removed)` points of every tree, oldest first.
    pub trees: Vec<(usize, usize)>,
}

/// A k-d tree accepting insertions (in batches) and removals (by index); see the module
/// documentation for the method and the index rule. Queries take `&self` and may run from
/// many threads at once; insertion and removal take `&mut self`.
#[derive(Clone, Debug)]
pub struct DynamicKdTree<T> {
    dim: usize,
    options: BuildOptions,
    /// Coordinates of the indices `base..next`, `dim` each; NaN for points not live.
    store: Vec<T>,
    base: u32,
    next: u32,
    /// One bit per index given: set if the point is not live (removed or skipped).
    not_live: Vec<u64>,
    /// One bit per index given: set if the point was skipped at insertion (non-finite).
    skipped: Vec<u64>,
    /// The trees, oldest first; their index ranges are disjoint and increasing.
    parts: Vec<Part<T>>,
    live: usize,
    /// Neighbouring trees merge while the older holds fewer than `growth` times the newer.
    growth: usize,
    /// The periodic box every tree of the forest shares ([`DynamicKdTree::new_periodic`]).
    period: Option<Period<T>>,
}

#[inline(always)]
fn bit(bits: &[u64], i: u32) -> bool {
    bits[(i >> 6) as usize] >> (i & 63) & 1 == 1
}

#[inline(always)]
fn set_bit(bits: &mut [u64], i: u32, on: bool) {
    let w = &mut bits[(i >> 6) as usize];
    if on {
        *w |= 1 << (i & 63);
    } else {
        *w &= !(1 << (i & 63));
    }
}

impl<T: Scalar> DynamicKdTree<T> {
    /// An empty tree of dimension `dim` whose trees are built with `options` (pivot, median,
    /// leaf size and threads; `non_finite` decides what an inserted non-finite point does).
    ///
    /// Errors: [`NbhdError::ZeroDimension`], [`NbhdError::SizeOverflow`] for a dimension
    /// whose point does not fit in the address space (as a [`PointsView`] of it is refused:
    /// no point could ever be inserted or asked about), and those of [`BuildOptions::validate`].
    pub fn new(dim: usize, options: &BuildOptions) -> Result<Self> {
        options.validate()?;
        if dim == 0 {
            return Err(NbhdError::ZeroDimension);
        }
        point_bytes(dim, T::TYPE)?;
        Ok(Self {
            dim,
            options: *options,
            store: Vec::new(),
            base: 0,
            next: 0,
            not_live: Vec::new(),
            skipped: Vec::new(),
            parts: Vec::new(),
            live: 0,
            growth: GROWTH,
            period: None,
        })
    }

    /// An empty periodic tree (a torus, as [`KdTree::build_periodic`]): `boxsize` holds the box
    /// size of every axis (or one for all), 0 or +∞ for an open axis; every inserted point
    /// must lie in `[0, L)` on the periodic axes, and queries are wrapped into the box.
    ///
    /// ```
    /// use nbhd::{BuildOptions, DynamicKdTree, NeighborIndex, Query};
    ///
    /// let mut tree = DynamicKdTree::<f64>::new_periodic(1, &BuildOptions::default(), &[1.0])?;
    /// tree.insert_flat(&[0.05, 0.5])?;
    /// tree.insert_flat(&[0.97])?;
    /// let mut out = Vec::new();
    /// tree.knn(Query::point(&[1.0]), 2, &mut out)?; // 1.0 wraps to 0
    /// assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), [2, 0]);
    /// assert!(tree.insert_flat(&[1.0]).is_err()); // outside [0, 1)
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`DynamicKdTree::new`] and of the box ([`Period::new`]).
    pub fn new_periodic(dim: usize, options: &BuildOptions, boxsize: &[f64]) -> Result<Self> {
        let mut tree = Self::new(dim, options)?;
        tree.period = Period::new(boxsize, dim)?;
        Ok(tree)
    }

    /// The periodic box of the tree, if it has one ([`DynamicKdTree::new_periodic`]).
    pub fn period(&self) -> Option<&Period<T>> {
        self.period.as_ref()
    }

    /// Sets the growth factor (at least 2; [`GROWTH`] by default): from the next insertion or
    /// removal on, neighbouring trees merge while the older holds fewer than `growth` times the
    /// live points of the newer. Larger values keep fewer, larger trees — queries visit fewer
    /// trees — at the price of more rebuilding. Results do not depend on it.
    ///
    /// Errors: [`NbhdError::InvalidOption`] below 2.
    pub fn set_growth(&mut self, growth: usize) -> Result<()> {
        if growth < 2 {
            return Err(NbhdError::InvalidOption {
                name: "growth",
                reason: format!("must be at least 2 (got {growth})"),
            });
        }
        self.growth = growth;
        Ok(())
    }

    /// Sets the worker threads of the builds that insertions and removals run (0: the current
    /// rayon pool, 1: serially, n: a pool of n; at most [`crate::MAX_THREADS`]), as
    /// [`BuildOptions::threads`] at [`Self::new`]. A loaded tree starts at 0 whatever its file
    /// says (a file is untrusted input), so this is how a loaded tree gets another count.
    /// Results do not depend on it.
    ///
    /// Errors: [`NbhdError::InvalidOption`] above [`crate::MAX_THREADS`].
    pub fn set_threads(&mut self, threads: usize) -> Result<()> {
        crate::parallel::check_threads(threads)?;
        self.options.threads = threads;
        Ok(())
    }

    /// Dimension of the points.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The options the trees are built with.
    pub fn options(&self) -> &BuildOptions {
        &self.options
    }

    /// Live points.
    pub fn len(&self) -> usize {
        self.live
    }

    /// `true` if no point is live.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// The index the next inserted point will get: the number of indices given so far.
    pub fn next_index(&self) -> u32 {
        self.next
    }

    /// Whether `index` names a live point.
    pub fn is_live(&self, index: u32) -> bool {
        index < self.next && !bit(&self.not_live, index)
    }

    /// Coordinates of the live point `index`.
    pub fn point(&self, index: u32) -> Option<&[T]> {
        self.is_live(index).then(|| self.stored(index))
    }

    /// Coordinates kept for `index` (NaN if not live); `index` must be at least `base`.
    #[inline]
    fn stored(&self, index: u32) -> &[T] {
        let at = (index - self.base) as usize * self.dim;
        &self.store[at..at + self.dim]
    }

    /// Live and removed points of every tree.
    pub fn stats(&self) -> DynamicStats {
        DynamicStats {
            live: self.live,
            next_index: self.next,
            trees: self.parts.iter().map(|p| (p.live, p.dead)).collect(),
        }
    }

    /// Why `index` cannot be queried or removed, if it cannot.
    fn check_live(&self, index: u32) -> Result<()> {
        if index >= self.next {
            Err(NbhdError::IndexOutOfRange {
                index: index as usize,
                count: self.next as usize,
            })
        } else if bit(&self.skipped, index) {
            Err(NbhdError::SkippedPoint {
                index: index as usize,
            })
        } else if bit(&self.not_live, index) {
            Err(NbhdError::RemovedPoint {
                index: index as usize,
            })
        } else {
            Ok(())
        }
    }

    /// Inserts the points of `view` (converted to `T`) and returns the index of the first:
    /// the batch gets the indices `first..first + view.len()`, in order. A batch of no point
    /// inserts nothing and returns the next index.
    ///
    /// Errors, with nothing inserted: [`NbhdError::DimensionMismatch`];
    /// [`NbhdError::NonFinite`] naming the position in the batch of the first non-finite
    /// point (under [`NonFinitePolicy::Reject`]); [`NbhdError::OutsidePeriod`] naming the
    /// position of the first point outside the box of a periodic tree; [`NbhdError::TooManyPoints`] if the indices
    /// would pass `u32::MAX - 1`; [`NbhdError::OutOfMemory`]; [`NbhdError::ThreadPool`].
    ///
    /// ```
    /// use nbhd::{BuildOptions, DynamicKdTree, NeighborIndex, PointsView, Query};
    ///
    /// let mut tree = DynamicKdTree::<f64>::new(2, &BuildOptions::default())?;
    /// assert_eq!(tree.insert(&PointsView::from_flat(&[0.0, 0.0, 1.0, 0.0], 2)?)?, 0);
    /// assert_eq!(tree.insert(&PointsView::from_flat(&[5.0, 5.0], 2)?)?, 2);
    /// tree.remove(&[1])?;
    /// let mut out = Vec::new();
    /// tree.knn(Query::point(&[0.9, 0.0]), 1, &mut out)?;
    /// assert_eq!(out[0].index, 0); // index 1 is removed; the others keep theirs
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    pub fn insert(&mut self, view: &PointsView<'_>) -> Result<u32> {
        if view.dim() != self.dim {
            return Err(NbhdError::DimensionMismatch {
                expected: self.dim,
                got: view.dim(),
            });
        }
        let n = view.len();
        if n == 0 {
            return Ok(self.next);
        }
        let first = self.next;
        let end = u64::from(first) + n as u64;
        if end > u64::from(u32::MAX) {
            return Err(NbhdError::TooManyPoints {
                count: end as usize,
                max: u32::MAX as usize,
            });
        }
        let d = self.dim;
        let mut coords: Vec<T> = Vec::new();
        coords
            .try_reserve_exact(n * d)
            .and_then(|_| self.store.try_reserve(n * d))
            .map_err(|_| NbhdError::OutOfMemory {
                what: "the coordinates of the inserted points",
                bytes: (n * d * std::mem::size_of::<T>()) as u128 * 2,
            })?;
        coords.resize(n * d, T::ZERO);
        let mut skipped = Vec::new();
        for (i, p) in coords.chunks_exact_mut(d).enumerate() {
            view.read_point(i, p);
            if let Some(coordinate) = p.iter().position(|c| !c.is_finite()) {
                if self.options.non_finite == NonFinitePolicy::Reject {
                    return Err(NbhdError::NonFinite {
                        index: i,
                        coordinate,
                    });
                }
                p.fill(T::from_f64(f64::NAN));
                skipped.push(first + i as u32);
            } else if let Some(j) = self.period.as_ref().and_then(|b| b.outside(p)) {
                return Err(NbhdError::OutsidePeriod {
                    index: i,
                    coordinate: j,
                    value: p[j].to_f64(),
                    size: self.period.as_ref().map_or(0.0, |b| b.sizes()[j]),
                });
            }
        }
        // Commit the points, then build; undone if a build fails.
        self.store.extend_from_slice(&coords);
        drop(coords);
        let words = (end as usize).div_ceil(64);
        self.not_live.resize(words, 0);
        self.skipped.resize(words, 0);
        for &s in &skipped {
            set_bit(&mut self.not_live, s, true);
            set_bit(&mut self.skipped, s, true);
        }
        self.next = end as u32;
        let added = n - skipped.len();
        let built = (|| {
            let mut parts = self.parts.clone();
            if added > 0 {
                parts.push(self.build_part(first, self.next)?);
            }
            self.normalized(parts)
        })();
        match built {
            Ok(parts) => {
                self.parts = parts;
                self.live += added;
                self.release_prefix();
                Ok(first)
            }
            Err(e) => {
                self.store.truncate((first - self.base) as usize * d);
                for &s in &skipped {
                    set_bit(&mut self.not_live, s, false);
                    set_bit(&mut self.skipped, s, false);
                }
                self.next = first;
                self.not_live.truncate((first as usize).div_ceil(64));
                self.skipped.truncate((first as usize).div_ceil(64));
                Err(e)
            }
        }
    }

    /// Inserts packed coordinates `[x0, y0, z0, x1, ...]`; see [`Self::insert`].
    pub fn insert_flat(&mut self, coords: &[T]) -> Result<u32> {
        self.insert(&PointsView::from_flat(coords, self.dim)?)
    }

    /// Removes the live points `indices` (in any order). Their indices are never given again.
    ///
    /// Errors, with nothing removed: [`NbhdError::IndexOutOfRange`] for an index not given
    /// yet, [`NbhdError::RemovedPoint`] for one already removed or named twice,
    /// [`NbhdError::SkippedPoint`] for a non-finite point skipped at insertion,
    /// [`NbhdError::ThreadPool`] if a rebuild cannot get its threads.
    pub fn remove(&mut self, indices: &[u32]) -> Result<()> {
        for &i in indices {
            self.check_live(i)?;
        }
        let mut sorted = indices.to_vec();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(NbhdError::RemovedPoint {
                index: w[0] as usize,
            });
        }
        let old_parts = self.parts.clone();
        let mut saved = Vec::with_capacity(sorted.len() * self.dim);
        let mut p = 0;
        for &i in &sorted {
            while self.parts[p].hi <= i {
                p += 1;
            }
            let part = &mut self.parts[p];
            part.live -= 1;
            part.dead += 1;
            set_bit(&mut self.not_live, i, true);
            let at = (i - self.base) as usize * self.dim;
            saved.extend_from_slice(&self.store[at..at + self.dim]);
            self.store[at..at + self.dim].fill(T::from_f64(f64::NAN));
        }
        let parts = std::mem::take(&mut self.parts);
        match self.normalized(parts) {
            Ok(parts) => {
                self.parts = parts;
                self.live -= sorted.len();
                self.release_prefix();
                Ok(())
            }
            Err(e) => {
                self.parts = old_parts;
                for (&i, c) in sorted.iter().zip(saved.chunks_exact(self.dim)) {
                    set_bit(&mut self.not_live, i, false);
                    let at = (i - self.base) as usize * self.dim;
                    self.store[at..at + self.dim].copy_from_slice(c);
                }
                Err(e)
            }
        }
    }

    /// A tree over the live points of the indices `lo..hi` (at least one).
    fn build_part(&self, lo: u32, hi: u32) -> Result<Part<T>> {
        let d = self.dim;
        let (a, b) = ((lo - self.base) as usize * d, (hi - self.base) as usize * d);
        let view = PointsView::from_flat(&self.store[a..b], d)?;
        // The points not live are NaN in the store: the build skips them, and every other
        // point keeps its offset from `lo` as its caller index.
        let options = BuildOptions {
            non_finite: NonFinitePolicy::Skip,
            ..self.options
        };
        let mut tree = KdTree::build(&view, &options)?;
        if let Some(period) = &self.period {
            tree = tree.with_period(period.clone())?;
        }
        let live = tree.len();
        Ok(Part::new(tree, lo, hi, live))
    }

    /// The forest `parts` with empty trees dropped, trees rebuilt whose removed points
    /// outnumber their live ones, and neighbours merged until every tree holds at least
    /// `growth` times the live points of the next newer one. One build per step, newest
    /// first; every step drops a tree or all tombstones of one, so it ends.
    fn normalized(&self, mut parts: Vec<Part<T>>) -> Result<Vec<Part<T>>> {
        loop {
            parts.retain(|p| p.live > 0);
            let merge = (0..parts.len().saturating_sub(1))
                .rev()
                .find(|&i| parts[i].live < self.growth.saturating_mul(parts[i + 1].live));
            if let Some(i) = merge {
                let merged = self.build_part(parts[i].lo, parts[i + 1].hi)?;
                parts.splice(i..i + 2, [merged]);
                continue;
            }
            if let Some(i) = parts.iter().rposition(|p| p.dead > p.live) {
                parts[i] = self.build_part(parts[i].lo, parts[i].hi)?;
                continue;
            }
            return Ok(parts);
        }
    }

    /// Frees the coordinates of the indices before the oldest tree (none of them is live)
    /// once they are at least half of those kept.
    fn release_prefix(&mut self) {
        let new_base = self.parts.first().map_or(self.next, |p| p.lo);
        let dropped = (new_base - self.base) as usize;
        let kept = (self.next - self.base) as usize;
        if dropped > 0 && 2 * dropped >= kept {
            self.store.drain(..dropped * self.dim);
            self.base = new_base;
        }
    }
}
