//! The neighbour index: one trait, [`NeighborIndex`], that holds every query of thesis
//! Chapter 5 once — the k nearest, all within a radius, the ε-k-neighbourhood, the points in
//! a box, the tables of every point, of a list of stored points and of a batch of query points,
//! and the spacing `h` — for every flavour of index: the static k-d tree (`src/tree/`) and the
//! growing tree, a forest of static trees with tombstones (`src/dynamic/`).
//!
//! A flavour provides only what it is: how its points are reached (the traversal that offers
//! candidates to a result set, the traversal of a box, the order its own points are visited
//! in) and, where it has one, a faster path for a table (the grouped searches of
//! `src/tree/group_search.rs`). Everything else — which result set a query fills, how rows are
//! sorted and written, how errors name their query, how boxes are checked and rows assembled —
//! is written here, once, as nanoflann's one `findNeighbors` serves every result set and its
//! forest adaptor answers through the same search. So both flavours answer every query, and
//! answer it identically: a growing tree gives the bytes of a static tree over its live points.
//!
//! Where each query is:
//! - `search.rs`: the single search ([`NeighborIndex::knn`], [`NeighborIndex::radius`],
//!   [`NeighborIndex::knn_radius`], [`NeighborIndex::search_with`], and `NeighborSearch::search`
//!   of both flavours);
//! - `in_box.rs`: box queries ([`NeighborIndex::in_box`], [`NeighborIndex::in_boxes`]);
//! - `tables.rs`: tables ([`NeighborIndex::neighborhoods`], [`NeighborIndex::neighborhoods_at`],
//!   [`NeighborIndex::neighborhoods_of`]);
//! - `spacing.rs`: the nearest-neighbour spacing ([`NeighborIndex::spacing`]);
//! - `pairs.rs`: pairs within a radius, in one index or between two, as tables or counted
//!   ([`NeighborIndex::pairs`], [`NeighborIndex::pairs_with`],
//!   [`NeighborIndex::count_pairs_with`], [`NeighborIndex::weigh_pairs_with`]).
//!
//! A metric (a Minkowski p-norm, `src/metric.rs`) and approximation are a parameter of the
//! traversal ([`NeighborIndex::visit_with`], the default Euclidean queries keeping
//! [`NeighborIndex::visit`] and its fast paths), so each query picks them up here rather than in
//! each flavour ([`NeighborIndex::search_with`], and tables through
//! [`TableOptions::query`](crate::TableOptions::query)). A periodic index (a torus,
//! [`NeighborIndex::period`]) answers every query that way too, the query wrapped into its box
//! first (`search.rs`), its traversal measuring nearest images. The seam for what comes next: a
//! new kind of result (pairs, counts) is a new result set (`src/query/result_set.rs`) filled by
//! the same traversal.

mod in_box;
mod pairs;
mod search;
mod spacing;
mod tables;

pub use in_box::IndexRows;
pub use pairs::PairWeights;
pub(crate) use search::{answer, search};
pub(crate) use spacing::{check_spacing, mean_distance};
pub use spacing::{Length, Spacing, Units};

use crate::error::Result;
use crate::metric::{Measure, Period};
use crate::points::PointsView;
use crate::query::result_set::ResultSet;
use crate::query::{Neighbor, NeighborSearch, Neighborhood, Query, QueryOptions};
use crate::scalar::Scalar;
use crate::table::{NeighborTable, TableOptions};

/// The stored points an index visits for a table of its own points, in the order that keeps
/// the cache warm (the tree order of its leaves): `at(w)` is the caller index and the
/// coordinates of the `w`-th, for `w < len`. (Plumbing of [`NeighborIndex`]'s hidden methods.)
#[doc(hidden)]
pub struct StoredPoints<'a, T> {
    /// Number of points.
    pub len: usize,
    /// The `w`-th point's caller index and coordinates.
    pub at: &'a (dyn Fn(usize) -> (u32, &'a [T]) + Sync),
}

/// An exact neighbour index over d-dimensional points with `T` coordinates: the static
/// `KdTree` (`src/tree/`) and the growing `DynamicKdTree` (`src/dynamic/`).
///
/// Every query is written once, in this trait, over the few facts each flavour provides (the
/// hidden methods below). So every query exists for both flavours and gives the same answer for
/// the same live points, under the conventions of the crate: caller indices, inclusive radii,
/// squared distances, rows ordered by `(sq_dist, index)` and identical for any thread count.
///
/// ```
/// use nbhd::{BuildOptions, DynamicKdTree, KdTree, NeighborIndex, PointsView, Query};
///
/// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
/// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
/// let mut growing = DynamicKdTree::<f32>::new(2, &BuildOptions::default())?;
/// growing.insert_flat(&pts[..4])?;
/// growing.insert_flat(&pts[4..])?;
///
/// // one function serves both flavours
/// fn two_nearest<I: NeighborIndex<f32>>(index: &I) -> Vec<u32> {
///     let mut out = Vec::new();
///     index.knn(Query::point(&[0.1, 0.1]), 2, &mut out).unwrap();
///     out.iter().map(|n| n.index).collect()
/// }
/// assert_eq!(two_nearest(&tree), [0, 1]);
/// assert_eq!(two_nearest(&growing), two_nearest(&tree));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub trait NeighborIndex<T: Scalar>: NeighborSearch<T> + Sized {
    /// Number of points held (live points; skipped and removed ones not counted).
    fn len(&self) -> usize;

    /// `true` if no point is held.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    // ---- What each flavour provides (plumbing, not part of the documented API) ----

    /// The coordinates of `query` and the caller index its answer leaves out: the query's
    /// checks (dimension, finite coordinates; a stored point that exists and is live).
    #[doc(hidden)]
    fn resolve<'q>(&'q self, query: Query<'q, T>) -> Result<(&'q [T], Option<u32>)>;

    /// The one traversal: offers to `set` every held point (except the caller index
    /// `exclude`) that may enter it, for the finite point `q` of the index's dimension.
    #[doc(hidden)]
    fn visit<C: ResultSet<T>>(&self, q: &[T], exclude: Option<u32>, set: &mut C);

    /// [`NeighborIndex::visit`] under a measure other than the exact Euclidean one: the
    /// metric's keys, its cells' bounds scaled by `measure.scale` (`src/metric.rs`).
    #[doc(hidden)]
    fn visit_with<C: ResultSet<T>>(
        &self,
        q: &[T],
        exclude: Option<u32>,
        measure: &Measure,
        set: &mut C,
    );

    /// The periodic box of the index, if it has one: its queries are then wrapped into the box
    /// and answered by [`NeighborIndex::visit_with`] (nearest images), never by the plain
    /// traversal or the grouped paths.
    #[doc(hidden)]
    fn period(&self) -> Option<&Period<T>>;

    /// Appends to `out`, in no particular order, the caller indices of the held points in the
    /// closed box `min ≤ x ≤ max` (checked); `scratch` is the traversal's to reuse.
    #[doc(hidden)]
    fn visit_box(&self, min: &[T], max: &[T], scratch: &mut Vec<T>, out: &mut Vec<u32>);

    /// Runs `f` with the held points in the order a table of them visits them.
    #[doc(hidden)]
    fn with_stored<R>(&self, f: impl FnOnce(&StoredPoints<'_, T>) -> R) -> R;

    /// A key of the region of space `q` falls into (the first tree position of its leaf), below
    /// [`NeighborIndex::region_keys`]: a batch of queries is answered in the order of these keys,
    /// so that consecutive queries touch the same cells.
    #[doc(hidden)]
    fn region_key(&self, q: &[T]) -> u32;

    /// One more than the largest [`NeighborIndex::region_key`].
    #[doc(hidden)]
    fn region_keys(&self) -> usize;

    /// The table of every held point by a faster path than one search per point, if the
    /// flavour has one for this dimension (on the current thread pool).
    #[doc(hidden)]
    fn grouped_table(
        &self,
        _nbhd: Neighborhood<T>,
        _exclude_self: bool,
    ) -> Option<Result<NeighborTable<T>>> {
        None
    }

    /// The table of the packed, finite `queries` by a faster path than one search per query,
    /// if the flavour has one for this batch (on the current thread pool): row `i` for query
    /// `i`; `order` lists the queries by [`NeighborIndex::region_key`], `keys` those keys.
    #[doc(hidden)]
    fn grouped_batch(
        &self,
        _queries: &[T],
        _order: &[u32],
        _keys: &[u32],
        _nbhd: Neighborhood<T>,
    ) -> Option<Result<NeighborTable<T>>> {
        None
    }

    /// The pairs `(i, j)`, `i < j`, of held points whose key under `measure` is at most
    /// `bound` — row `i` of the table those `j` ascending, with their keys, `source_len` rows —
    /// by a faster path than one search per point, if the flavour has one (on the current
    /// thread pool).
    #[doc(hidden)]
    fn grouped_pairs(&self, _bound: T, _measure: &Measure) -> Option<Result<NeighborTable<T>>> {
        None
    }

    // ---- The queries, written once ----

    /// The `k` nearest held points of `query`, by `(sq_dist, index)`, into `out` (cleared
    /// first).
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, Query};
    ///
    /// let pts = [0.0f64, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let mut out = Vec::new();
    /// tree.knn(Query::stored_excluding_self(0), 2, &mut out)?;
    /// assert_eq!(out.iter().map(|n| (n.index, n.sq_dist)).collect::<Vec<_>>(), [(1, 1.0), (2, 1.0)]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: [`NbhdError::ZeroK`](crate::NbhdError::ZeroK), and those of the query
    /// (dimension, non-finite coordinates, an index out of range, skipped or removed).
    fn knn(&self, query: Query<'_, T>, k: usize, out: &mut Vec<Neighbor<T>>) -> Result<()> {
        search(self, query, Neighborhood::Knn { k }, out)
    }

    /// All held points within `radius` (inclusive, `‖x − q‖ ≤ radius`) of `query`, by
    /// `(sq_dist, index)`, into `out` (cleared first).
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, Query};
    ///
    /// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let mut out = Vec::new();
    /// tree.radius(Query::point(&[0.0, 0.0]), 1.0, &mut out)?; // the radius is inclusive
    /// assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), [0, 1, 2]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: [`NbhdError::InvalidRadius`](crate::NbhdError::InvalidRadius) (negative, NaN,
    /// infinite), [`NbhdError::RadiusOutOfRange`](crate::NbhdError::RadiusOutOfRange), and
    /// those of the query.
    fn radius(&self, query: Query<'_, T>, radius: T, out: &mut Vec<Neighbor<T>>) -> Result<()> {
        let nbhd = Neighborhood::Radius {
            radius,
            sorted: true,
        };
        search(self, query, nbhd, out)
    }

    /// The ε-k-neighbourhood (thesis Section 2.1.1): the `k` nearest among the held points
    /// within `radius` of `query`, by `(sq_dist, index)`, into `out` (cleared first).
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, Query};
    ///
    /// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let mut out = Vec::new();
    /// tree.knn_radius(Query::point(&[0.0, 0.0]), 10, 1.5, &mut out)?;
    /// assert_eq!(out.len(), 3); // the point at (3, 3) lies beyond the radius
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`NeighborIndex::knn`] and [`NeighborIndex::radius`].
    fn knn_radius(
        &self,
        query: Query<'_, T>,
        k: usize,
        radius: T,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        search(self, query, Neighborhood::KnnRadius { k, radius }, out)
    }

    /// The neighbourhood `nbhd` of `query` under `options` — any Minkowski metric, an
    /// approximate search, a strict radius ([`QueryOptions`]) — by `(sq_dist, index)` unless
    /// an unsorted radius query was asked for, into `out` (cleared first). `sq_dist` holds the
    /// metric's key (squared for Euclidean, the distance for p = 1 and ∞, `Σ |x_j|^p` for any
    /// other p; [`Metric::distance_of`](crate::Metric::distance_of) converts), and the radius
    /// is a distance in the metric. With the default options this is [`NeighborSearch::search`].
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, Query, QueryOptions};
    ///
    /// let pts = [0.0f64, 0.0, 1.0, 1.0, 1.5, 0.0, 3.0, 3.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let mut out = Vec::new();
    /// let near = |p: f64, out: &mut Vec<_>| {
    ///     let opts = QueryOptions::with_p(p).unwrap();
    ///     tree.search_with(Query::point(&[0.0, 0.0]), Neighborhood::Knn { k: 2 }, &opts, out)
    /// };
    /// near(1.0, &mut out)?; // Manhattan: (1.5, 0) at 1.5 is nearer than (1, 1) at 2
    /// assert_eq!(out.iter().map(|n| (n.index, n.sq_dist)).collect::<Vec<_>>(), [(0, 0.0), (2, 1.5)]);
    /// near(f64::INFINITY, &mut out)?; // Chebyshev: (1, 1) at 1 is nearer than (1.5, 0)
    /// assert_eq!(out.iter().map(|n| (n.index, n.sq_dist)).collect::<Vec<_>>(), [(0, 0.0), (1, 1.0)]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`NeighborSearch::search`]; a Minkowski `p < 1` or NaN, a negative or
    /// non-finite `eps` ([`NbhdError::InvalidOption`](crate::NbhdError::InvalidOption)); a radius
    /// whose key overflows the scalar type
    /// ([`NbhdError::RadiusOutOfRange`](crate::NbhdError::RadiusOutOfRange), unless `strict`).
    fn search_with(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        options: &QueryOptions,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        search::search_with(self, query, nbhd, options, out)
    }

    /// The caller indices of the held points in the closed box `min ≤ x ≤ max` (every
    /// coordinate; thesis Section 3.2.3), ascending, in `out` (cleared first). Bounds may be
    /// infinite; a zero-extent box holds the points on its plane.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView};
    ///
    /// let pts = [0.0f64, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let mut out = Vec::new();
    /// tree.in_box(&[0.0, 0.0], &[1.0, f64::INFINITY], &mut out)?;
    /// assert_eq!(out, [0, 1, 2]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: a bound slice of the wrong length
    /// ([`NbhdError::DimensionMismatch`](crate::NbhdError::DimensionMismatch)), a NaN bound or
    /// `min[j] > max[j]` ([`NbhdError::InvalidBox`](crate::NbhdError::InvalidBox)).
    fn in_box(&self, min: &[T], max: &[T], out: &mut Vec<u32>) -> Result<()> {
        in_box::in_box(self, min, max, out)
    }

    /// The points in each box of a batch, computed in parallel on `threads` workers (0: the
    /// current pool), rows in the boxes' order, identical for any thread count. `boxes` holds
    /// `2 · dim` values per box: its `min` corner, then its `max` corner.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView};
    ///
    /// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let rows = tree.in_boxes(&[0.0, 0.0, 1.0, 0.5, /* second box */ 2.0, 2.0, 4.0, 4.0], 0)?;
    /// assert_eq!((rows.row(0), rows.row(1)), (&[0u32, 1][..], &[3u32][..]));
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: as [`NeighborIndex::in_box`], naming the box; a length not a multiple of
    /// `2 · dim` is [`NbhdError::BufferTooSmall`](crate::NbhdError::BufferTooSmall).
    fn in_boxes(&self, boxes: &[T], threads: usize) -> Result<IndexRows> {
        in_box::in_boxes(self, boxes, threads)
    }

    /// The neighbourhood of every held point as compressed rows in the caller's index order
    /// (row `i` for index `i`, [`NeighborSearch::source_len`] rows; points not held — skipped at
    /// build time, removed — get empty rows), computed in parallel; identical bytes for any
    /// thread count and for both flavours over the same live points.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, TableOptions};
    ///
    /// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let table = tree.neighborhoods(Neighborhood::Knn { k: 1 }, &TableOptions::default())?;
    /// assert_eq!(table.indices_of(3), [1]); // (1, 0) and (0, 1) tie at 13: the lower index
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of the neighbourhood, [`NbhdError::OutOfMemory`](crate::NbhdError::OutOfMemory)
    /// for a table that cannot fit, [`NbhdError::ThreadPool`](crate::NbhdError::ThreadPool).
    fn neighborhoods(
        &self,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        tables::neighborhoods(self, nbhd, options)
    }

    /// The neighbourhoods of the held points `indices` (a subset of the index's own points, in
    /// any order, repeats allowed): row `r` for `indices[r]`, the row
    /// [`NeighborIndex::neighborhoods`] gives that point, computed in parallel.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, TableOptions};
    ///
    /// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let nbhd = Neighborhood::Knn { k: 2 };
    /// let some = tree.neighborhoods_at(&[3, 0], nbhd, &TableOptions::default())?;
    /// let all = tree.neighborhoods(nbhd, &TableOptions::default())?;
    /// assert_eq!((some.indices_of(0), some.indices_of(1)), (all.indices_of(3), all.indices_of(0)));
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`NeighborIndex::neighborhoods`] and of a stored-point query (an index
    /// out of range, skipped or removed), naming the first such index by position.
    fn neighborhoods_at(
        &self,
        indices: &[u32],
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        tables::neighborhoods_at(self, indices, nbhd, options)
    }

    /// The neighbourhoods of a batch of query points (row `i` for query `i`), computed in
    /// parallel, in the order of the regions the queries fall into so that consecutive queries
    /// touch the same cells; identical for any thread count and to the single queries' rows.
    /// `options.exclude_self` does not apply (the queries are not stored points).
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, TableOptions};
    ///
    /// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
    /// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
    /// let queries = [2.9f32, 3.0, 0.9, 0.1];
    /// let table = tree.neighborhoods_of(
    ///     &PointsView::from_flat(&queries, 2)?,
    ///     Neighborhood::Knn { k: 1 },
    ///     &TableOptions::default(),
    /// )?;
    /// assert_eq!(table.indices(), [3, 1]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of the neighbourhood, [`NbhdError::DimensionMismatch`](crate::NbhdError::DimensionMismatch),
    /// [`NbhdError::NonFiniteQuery`](crate::NbhdError::NonFiniteQuery) naming the first query
    /// (by position) with a non-finite coordinate, [`NbhdError::OutOfMemory`](crate::NbhdError::OutOfMemory),
    /// [`NbhdError::ThreadPool`](crate::NbhdError::ThreadPool).
    fn neighborhoods_of(
        &self,
        queries: &PointsView<'_>,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        tables::neighborhoods_of(self, queries, nbhd, options)
    }

    /// The nearest-neighbour spacing of the held points ([`Spacing`]): each point's distance
    /// to its nearest other point, summarised, from an all-point 1-nearest table computed on
    /// `threads` workers (0: the current pool); the same value for any thread count.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView};
    ///
    /// // points on a line at 0, 1, 3, 7, 8: nearest distances 1, 1, 2, 1, 1
    /// let pts = [0.0f64, 1.0, 3.0, 7.0, 8.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 1)?, &BuildOptions::default())?;
    /// let s = tree.spacing(0)?;
    /// assert_eq!((s.mean, s.median, s.points), (1.2, 1.0, 5));
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: fewer than two points held
    /// ([`NbhdError::InvalidOption`](crate::NbhdError::InvalidOption)), and those of
    /// [`NeighborIndex::neighborhoods`].
    fn spacing(&self, threads: usize) -> Result<Spacing> {
        spacing::spacing(self, threads)
    }

    /// Every pair `i < j` of held points within `radius` of each other (inclusive; scipy's
    /// `query_pairs`), under `options.query` (any metric, eps, a strict radius), as a table:
    /// row `i` (caller index, [`NeighborSearch::source_len`] rows) holds the `j > i`
    /// ascending, with the pair's key in `sq_dists` (squared for Euclidean, the distance for
    /// p = 1 and ∞, `Σ |x_j|^p` otherwise). On a periodic index pairs meet at their nearest
    /// images. `options.exclude_self` does not apply (a point is never its own pair).
    /// Computed in parallel on `options.threads`, identical for any thread count.
    ///
    /// With `eps > 0` (scipy's contract for pairs: every pair within `r / (1 + eps)` is returned
    /// and none beyond `r · (1 + eps)`): every pair within `r · (1 + eps)`, whatever the tree.
    /// scipy's dual traversal prunes node rectangles that touch at each split, and so keeps
    /// pairs a search pruned at `r / (1 + eps)` by nbhd's tighter per-point cell bounds would
    /// skip — its own test counts on pairs computed an ulp beyond `r` coming back with eps.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, TableOptions};
    ///
    /// let pts = [0.0f64, 1.0, 1.5, 4.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 1)?, &BuildOptions::default())?;
    /// let pairs = tree.pairs(1.0, &TableOptions::default())?;
    /// assert_eq!((pairs.indices_of(0), pairs.indices_of(1), pairs.total()), (&[1u32][..], &[2u32][..], 2));
    /// assert_eq!(pairs.sq_dists_of(1), [0.25]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of a radius query under `options.query`
    /// ([`NeighborIndex::search_with`]), [`NbhdError::OutOfMemory`](crate::NbhdError::OutOfMemory),
    /// [`NbhdError::ThreadPool`](crate::NbhdError::ThreadPool).
    fn pairs(&self, radius: T, options: &TableOptions) -> Result<NeighborTable<T>> {
        pairs::pairs(self, radius, options)
    }

    /// The pairs `(i, j)` of a held point `i` and a point `j` of `other` within `radius` of each
    /// other (inclusive; scipy's `query_ball_tree` and, as distances, `sparse_distance_matrix`),
    /// measured by this index (its metric under `options.query`, its periodic box; `other`'s
    /// box, if any, is not used, as scipy measures by the tree whose method is called): row `i`
    /// (caller index, [`NeighborSearch::source_len`] rows) holds `other`'s caller indices `j`
    /// ascending, with the pair's key in `sq_dists` — zero distances included. Computed in
    /// parallel, identical for any thread count. With `eps > 0` the rule of
    /// [`NeighborIndex::pairs`].
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, TableOptions};
    ///
    /// let a = [0.0f64, 2.0];
    /// let b = [0.5f64, 0.0, 9.0];
    /// let opts = BuildOptions::default();
    /// let ta = KdTree::<f64>::build(&PointsView::from_flat(&a, 1)?, &opts)?;
    /// let tb = KdTree::<f64>::build(&PointsView::from_flat(&b, 1)?, &opts)?;
    /// let rows = ta.pairs_with(&tb, 1.5, &TableOptions::default())?;
    /// assert_eq!((rows.indices_of(0), rows.indices_of(1)), (&[0u32, 1][..], &[0u32][..]));
    /// assert_eq!(rows.sq_dists_of(0), [0.25, 0.0]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`NeighborIndex::pairs`];
    /// [`NbhdError::DimensionMismatch`](crate::NbhdError::DimensionMismatch) for indexes of
    /// different dimensions.
    fn pairs_with<O: NeighborIndex<T>>(
        &self,
        other: &O,
        radius: T,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        pairs::pairs_with(self, other, radius, options)
    }

    /// How many pairs `(i, j)` of a held point and a point of `other` lie within each radius of
    /// `radii` (scipy's `count_neighbors` without weights), measured by this index as in
    /// [`NeighborIndex::pairs_with`] — so counting an index against itself counts each point
    /// with itself and each pair twice, as scipy does. `cumulative`: entry `k` counts the pairs
    /// with distance `≤ radii[k]` (radii in any order); otherwise the pairs in
    /// `(radii[k − 1], radii[k]]` (`[0, radii[0]]` for the first; `radii` non-decreasing; of
    /// equal radii the first gets the count, the others 0). A negative radius counts nothing,
    /// +∞ everything; `options.query.strict` makes every radius exclusive. Exact, identical for
    /// any thread count.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PointsView, TableOptions};
    ///
    /// let pts = [0.0f64, 1.0, 3.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 1)?, &BuildOptions::default())?;
    /// let opts = TableOptions::default();
    /// // pairs by distance: 0 (3 of them), 1 (2), 2 (2), 3 (2)
    /// assert_eq!(tree.count_pairs_with(&tree, &[0.0, 1.0, 2.5, f64::INFINITY], true, &opts)?, [3, 5, 7, 9]);
    /// assert_eq!(tree.count_pairs_with(&tree, &[0.0, 1.0, 2.5, f64::INFINITY], false, &opts)?, [3, 2, 2, 2]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: a NaN radius ([`NbhdError::InvalidRadius`](crate::NbhdError::InvalidRadius));
    /// decreasing radii when not `cumulative`, `eps > 0` (counts are exact), a bad metric
    /// ([`NbhdError::InvalidOption`](crate::NbhdError::InvalidOption));
    /// [`NbhdError::DimensionMismatch`](crate::NbhdError::DimensionMismatch),
    /// [`NbhdError::ThreadPool`](crate::NbhdError::ThreadPool).
    fn count_pairs_with<O: NeighborIndex<T>>(
        &self,
        other: &O,
        radii: &[T],
        cumulative: bool,
        options: &TableOptions,
    ) -> Result<Vec<u64>> {
        pairs::count_pairs_with(self, other, radii, cumulative, options)
    }

    /// [`NeighborIndex::count_pairs_with`] with weights (scipy's `count_neighbors` with
    /// `weights`): each pair `(i, j)` adds `w_this[i] · w_other[j]` (a missing side weighs 1),
    /// and each entry is the correctly rounded sum of those products (an exact sum: the same
    /// bits for any thread count and any order).
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, NeighborIndex, PairWeights, PointsView, TableOptions};
    ///
    /// let pts = [0.0f64, 1.0, 3.0];
    /// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 1)?, &BuildOptions::default())?;
    /// let w = [1.0, 2.0, 4.0];
    /// let both = PairWeights { this: Some(&w), other: Some(&w) };
    /// // within 1: (0,0) 1, (1,1) 4, (2,2) 16, (0,1) and (1,0) 2 each
    /// assert_eq!(tree.weigh_pairs_with(&tree, &[1.0], both, true, &TableOptions::default())?, [25.0]);
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    ///
    /// Errors: those of [`NeighborIndex::count_pairs_with`]; weights not one per caller index
    /// of their side or not finite ([`NbhdError::InvalidOption`](crate::NbhdError::InvalidOption)).
    fn weigh_pairs_with<O: NeighborIndex<T>>(
        &self,
        other: &O,
        radii: &[T],
        weights: PairWeights<'_>,
        cumulative: bool,
        options: &TableOptions,
    ) -> Result<Vec<f64>> {
        pairs::weigh_pairs_with(self, other, radii, weights, cumulative, options)
    }

    /// The caller indices of the held points, ascending.
    fn indices(&self) -> Vec<u32> {
        let mut all = self.with_stored(|s| (0..s.len).map(|w| (s.at)(w).0).collect::<Vec<_>>());
        all.sort_unstable();
        all
    }
}
