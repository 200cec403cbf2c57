//! The k-d tree (thesis Chapter 3): built with a selectable pivot policy and median
//! algorithm, holding its own compact copy of the points in tree order plus the map to the
//! caller's indices, answering the exact queries of Chapter 5.

mod build;
mod group_search;
mod layout;
mod node;
pub mod options;
mod presorted;
mod search;
mod split;

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::cloud::{resolve_query, Cloud, NonFinitePolicy};
use crate::error::{NbhdError, Result};
use crate::parallel::with_threads;
use crate::points::PointsView;
use crate::query::{Neighbor, NeighborHeap, NeighborSearch, Neighborhood, Query};
use crate::scalar::{Scalar, ScalarType};
use crate::table::{check_knn_total, rows_in_work_order, NeighborTable, TableOptions};
use build::{build_parallel, build_serial, BuildInput, Subtree};
use layout::{BySlot, Inline, Layout, Record};
use node::Node;
pub use options::{BuildOptions, MedianAlgorithm, PivotPolicy, DEFAULT_LEAF_SIZE};
use search::{TreeView, WithinRadius};

/// Shape and memory of a built tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TreeStats {
    /// Points held (skipped non-finite points not counted).
    pub points: usize,
    /// Dimension.
    pub dim: usize,
    /// Edges on the longest root-to-leaf path (a single leaf has depth 0).
    pub depth: usize,
    /// Internal nodes plus leaves.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Most points in one leaf.
    pub max_leaf_points: usize,
    /// Bytes of coordinates, index map and nodes (and the reverse index map once a stored-point
    /// query has created it).
    pub bytes: usize,
}

/// A k-d tree over d-dimensional points with `T` coordinates. Immutable once built: it may
/// be queried from many threads at once.
#[derive(Debug)]
pub struct KdTree<T> {
    dim: usize,
    /// Coordinates in tree order.
    coords: Vec<T>,
    /// Caller index of each point, in tree order.
    ids: Vec<u32>,
    nodes: Vec<Node<T>>,
    depth: usize,
    source_len: usize,
    options: BuildOptions,
    /// Tree position of every caller index (`u32::MAX` for skipped points), made on first use.
    position_of: OnceLock<Vec<u32>>,
}

impl<T: Scalar> KdTree<T> {
    /// Builds a tree over the points of `view` (converted to `T`).
    ///
    /// Errors: [`NbhdError::NonFinite`] naming the first point with a NaN or infinite
    /// coordinate (unless `options.non_finite` skips them), [`NbhdError::EmptyInput`] if no
    /// point remains, [`NbhdError::InvalidOption`] for a leaf size of 0,
    /// [`NbhdError::ThreadPool`] if a requested pool cannot be created.
    pub fn build(view: &PointsView<'_>, options: &BuildOptions) -> Result<Self> {
        options.validate()?;
        let dim = view.dim();
        let (subtree, coords, ids) = match dim {
            1 => build_inline::<T, 1>(view, options)?,
            2 => build_inline::<T, 2>(view, options)?,
            3 => build_inline::<T, 3>(view, options)?,
            _ => {
                let cloud = Cloud::<T>::from_view(view, options.non_finite)?;
                let n = cloud.len();
                let layout = BySlot {
                    coords: &cloud.coords,
                    dim,
                };
                let mut slots: Vec<u32> = (0..n as u32).collect();
                let subtree = run_build(layout, options, &mut slots)?;
                let coords = slots
                    .iter()
                    .flat_map(|&s| cloud.point(s as usize).iter().copied())
                    .collect();
                let ids = slots.iter().map(|&s| cloud.ids[s as usize]).collect();
                (subtree, coords, ids)
            }
        };
        Ok(Self {
            dim,
            coords,
            ids,
            nodes: subtree.nodes,
            depth: subtree.depth,
            source_len: view.len(),
            options: *options,
            position_of: OnceLock::new(),
        })
    }

    /// Builds from packed coordinates `[x0, y0, z0, x1, ...]` of dimension `dim`.
    pub fn from_flat(coords: &[T], dim: usize, options: &BuildOptions) -> Result<Self> {
        Self::build(&PointsView::from_flat(coords, dim)?, options)
    }

    /// The options the tree was built with.
    pub fn options(&self) -> &BuildOptions {
        &self.options
    }

    /// Number of points held.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Always `false`: a tree holds at least one point.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Caller indices in tree order (points of one leaf are adjacent).
    pub fn tree_order(&self) -> &[u32] {
        &self.ids
    }

    /// Coordinates of the point at tree position `pos`.
    pub fn point_at(&self, pos: usize) -> &[T] {
        &self.coords[pos * self.dim..(pos + 1) * self.dim]
    }

    /// Coordinates of the point with caller index `index`, if the tree holds it.
    pub fn point(&self, index: u32) -> Option<&[T]> {
        let pos = *self.positions().get(index as usize)?;
        (pos != u32::MAX).then(|| self.point_at(pos as usize))
    }

    fn positions(&self) -> &[u32] {
        self.position_of.get_or_init(|| {
            let mut pos = vec![u32::MAX; self.source_len];
            for (p, &id) in self.ids.iter().enumerate() {
                pos[id as usize] = p as u32;
            }
            pos
        })
    }

    /// `true` if both trees have the same nodes, splits, leaves and point order: the
    /// identity the thesis states for the median algorithms of one pivot policy (8.1).
    pub fn same_structure(&self, other: &Self) -> bool {
        self.dim == other.dim
            && self.nodes == other.nodes
            && self.ids == other.ids
            && self.coords == other.coords
            && self.depth == other.depth
    }

    /// Depth, node counts and memory.
    pub fn stats(&self) -> TreeStats {
        let leaves = self.nodes.iter().filter(|n| n.is_leaf());
        let max_leaf_points = leaves
            .clone()
            .map(|n| (n.b - n.a) as usize)
            .max()
            .unwrap_or(0);
        let reverse = self.position_of.get().map_or(0, |v| v.len() * 4);
        TreeStats {
            points: self.len(),
            dim: self.dim,
            depth: self.depth,
            nodes: self.nodes.len(),
            leaves: leaves.count(),
            max_leaf_points,
            bytes: self.coords.len() * std::mem::size_of::<T>()
                + self.ids.len() * 4
                + self.nodes.len() * std::mem::size_of::<Node<T>>()
                + reverse,
        }
    }

    fn view(&self) -> TreeView<'_, T> {
        TreeView {
            nodes: &self.nodes,
            coords: &self.coords,
            ids: &self.ids,
            dim: self.dim,
        }
    }

    /// The `k` nearest neighbours of `query`, by `(sq_dist, index)`.
    pub fn knn(&self, query: Query<'_, T>, k: usize, out: &mut Vec<Neighbor<T>>) -> Result<()> {
        self.search(query, Neighborhood::Knn { k }, out)
    }

    /// All points within `radius` (inclusive) of `query`, by `(sq_dist, index)`.
    pub fn radius(&self, query: Query<'_, T>, radius: T, out: &mut Vec<Neighbor<T>>) -> Result<()> {
        self.search(
            query,
            Neighborhood::Radius {
                radius,
                sorted: true,
            },
            out,
        )
    }

    /// The ε-k-neighbourhood: the `k` nearest among the points within `radius` of `query`.
    pub fn knn_radius(
        &self,
        query: Query<'_, T>,
        k: usize,
        radius: T,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        self.search(query, Neighborhood::KnnRadius { k, radius }, out)
    }
}

/// Builds with compact records of dimension `D`, read straight from the caller's buffer;
/// returns the nodes, the coordinates and the caller indices in tree order. A record's slot is
/// the caller's index itself: it orders ties exactly as the packed slots of a [`Cloud`] would
/// (both increase with the caller's index), and needs no map back.
fn build_inline<T: Scalar, const D: usize>(
    view: &PointsView<'_>,
    options: &BuildOptions,
) -> Result<(Subtree<T>, Vec<T>, Vec<u32>)> {
    // Reading the points and copying the result out are a fifth of a fast build: on more than
    // one thread they would cap its speed-up, so for large clouds they run in parallel too.
    let parallel = options.threads != 1 && view.len() >= PARALLEL_COPY_MIN;
    let work = || {
        let policy = options.non_finite;
        let mut records = match (view.scalar_type(), parallel) {
            (ScalarType::F32, false) => read_records::<T, f32, D>(view, policy)?,
            (ScalarType::F64, false) => read_records::<T, f64, D>(view, policy)?,
            (ScalarType::F32, true) => read_records_parallel::<T, f32, D>(view, policy)?,
            (ScalarType::F64, true) => read_records_parallel::<T, f64, D>(view, policy)?,
        };
        let subtree = run_build(Inline::<D>, options, &mut records)?;
        let mut coords = vec![T::ZERO; records.len() * D];
        let mut ids = Vec::new();
        if parallel {
            coords
                .par_chunks_mut(D)
                .zip(records.par_iter())
                .with_min_len(4096)
                .for_each(|(c, r)| c.copy_from_slice(&r.p));
            records
                .par_iter()
                .with_min_len(4096)
                .map(|r| r.slot)
                .collect_into_vec(&mut ids);
        } else {
            for (c, r) in coords.chunks_exact_mut(D).zip(&records) {
                c.copy_from_slice(&r.p);
            }
            ids.extend(records.iter().map(|r| r.slot));
        }
        Ok((subtree, coords, ids))
    };
    if parallel {
        with_threads(options.threads, work)?
    } else {
        work()
    }
}

/// Points from which a build on more than one thread reads and writes its copies in parallel.
const PARALLEL_COPY_MIN: usize = 256 * 1024;

/// [`read_records`] on the current rayon pool: every point converted in parallel, in order;
/// if any is not finite, the serial reader decides (the error names the first such point, or
/// the skipped points are left out).
fn read_records_parallel<T: Scalar, S: Scalar, const D: usize>(
    view: &PointsView<'_>,
    policy: NonFinitePolicy,
) -> Result<Vec<Record<T, D>>> {
    let mut records = Vec::new();
    (0..view.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| Record {
            p: view.row::<S, D>(i).map(|c| T::from_f64(c.to_f64())),
            slot: i as u32,
        })
        .collect_into_vec(&mut records);
    if records
        .par_iter()
        .any(|r| r.p.iter().any(|c| !c.is_finite()))
    {
        return read_records::<T, S, D>(view, policy);
    }
    Ok(records)
}

/// The finite points of `view` (stored as `S`) as records of `T` coordinates, applying
/// `policy` to the others (a value finite in `S` that overflows `T` counts as non-finite, as
/// in [`Cloud::from_view`]).
fn read_records<T: Scalar, S: Scalar, const D: usize>(
    view: &PointsView<'_>,
    policy: NonFinitePolicy,
) -> Result<Vec<Record<T, D>>> {
    let n = view.len();
    let mut records = Vec::with_capacity(n);
    for i in 0..n {
        let p = view.row::<S, D>(i).map(|c| T::from_f64(c.to_f64()));
        if p.iter().all(|c| c.is_finite()) {
            records.push(Record { p, slot: i as u32 });
        } else if policy == NonFinitePolicy::Reject {
            let coordinate = p.iter().position(|c| !c.is_finite()).unwrap_or(0);
            return Err(NbhdError::NonFinite {
                index: i,
                coordinate,
            });
        }
    }
    if records.is_empty() {
        return Err(NbhdError::EmptyInput);
    }
    Ok(records)
}

/// Runs the build the options ask for over `items` (given in slot order, left in tree order).
fn run_build<T: Scalar, L: Layout<T>>(
    layout: L,
    options: &BuildOptions,
    items: &mut [L::Item],
) -> Result<Subtree<T>> {
    let input = BuildInput {
        layout,
        options: *options,
    };
    if options.median == MedianAlgorithm::Presorted {
        return Ok(presorted::build_presorted(&input, items));
    }
    match options.threads {
        1 => Ok(build_serial(&input, items, 0, 0)),
        t => with_threads(t, || build_parallel(&input, items, 0, 0)),
    }
}

impl<T: Scalar> KdTree<T> {
    /// The neighbourhood of every point of the tree, as compressed rows in the caller's
    /// index order (row `i` for point `i`; points skipped at build time get empty rows),
    /// computed in parallel; identical bytes for any thread count.
    pub fn neighborhoods(
        &self,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        nbhd.validate()?;
        check_knn_total(self.len(), self.len(), nbhd, options.exclude_self)?;
        // Low dimensions: one descent per group of consecutive tree-order points, shared by
        // the group (see `group_search`); the same rows as the single-query search.
        let grouped = |f: fn(&TreeView<'_, T>, usize, Neighborhood<T>, bool) -> _| {
            with_threads(options.threads, || {
                f(&self.view(), self.source_len, nbhd, options.exclude_self)
            })?
        };
        match self.dim {
            3 => return grouped(group_search::table::<T, 3>),
            2 => return grouped(group_search::table::<T, 2>),
            1 => return grouped(group_search::table::<T, 1>),
            _ => {}
        }
        // Any dimension: answered in tree order (neighbouring queries touch the same nodes and
        // leaves, so they hit the cache), written back in the caller's order.
        with_threads(options.threads, || {
            rows_in_work_order(
                self.source_len,
                self.len(),
                |pos| self.ids[pos] as usize,
                |pos, row, _| {
                    let exclude = options.exclude_self.then_some(self.ids[pos]);
                    self.search_resolved(self.point_at(pos), exclude, nbhd, row);
                    Ok(())
                },
            )
        })?
    }

    /// The neighbourhoods of a batch of query points (row `i` for query `i`), computed in
    /// parallel. `options.exclude_self` does not apply (the queries are not stored points).
    ///
    /// The queries are answered in the order of the leaves they fall into, so that consecutive
    /// queries walk the same nodes and leaves (a scan's points arrive in no useful order, and a
    /// query in random order misses the cache at almost every leaf); the rows come back in the
    /// queries' order, identical for any number of threads.
    pub fn neighborhoods_of(
        &self,
        queries: &PointsView<'_>,
        nbhd: Neighborhood<T>,
        options: &TableOptions,
    ) -> Result<NeighborTable<T>> {
        nbhd.validate()?;
        if queries.dim() != self.dim {
            return Err(NbhdError::DimensionMismatch {
                expected: self.dim,
                got: queries.dim(),
            });
        }
        check_knn_total(queries.len(), self.len(), nbhd, false)?;
        with_threads(options.threads, || {
            let order = self.leaf_order(queries);
            rows_in_work_order(
                queries.len(),
                queries.len(),
                |w| order[w] as usize,
                |w, row, q| {
                    q.resize(self.dim, T::ZERO);
                    queries.read_point(order[w] as usize, q);
                    self.search(Query::point(q), nbhd, row)
                        .map_err(|e| e.for_query(order[w] as usize))
                },
            )
        })?
    }

    /// The query indices of `queries` ordered by the first tree position of the leaf each falls
    /// into, ties by index (a counting sort: two passes over the queries).
    fn leaf_order(&self, queries: &PointsView<'_>) -> Vec<u32> {
        let leaf_of: Vec<u32> = (0..queries.len())
            .into_par_iter()
            .map_init(Vec::new, |q, i| {
                q.resize(self.dim, T::ZERO);
                queries.read_point(i, q);
                self.leaf_start(q)
            })
            .collect();
        let mut starts = vec![0u32; self.len() + 1];
        for &l in &leaf_of {
            starts[l as usize + 1] += 1;
        }
        for p in 0..self.len() {
            starts[p + 1] += starts[p];
        }
        let mut order = vec![0u32; queries.len()];
        for (i, &l) in leaf_of.iter().enumerate() {
            order[starts[l as usize] as usize] = i as u32;
            starts[l as usize] += 1;
        }
        order
    }

    /// The first tree position of the leaf `q` descends to (a non-finite coordinate takes
    /// some path; such a query is refused when it is answered).
    fn leaf_start(&self, q: &[T]) -> u32 {
        let mut node = 0;
        loop {
            let n = &self.nodes[node];
            if n.is_leaf() {
                return n.a;
            }
            node = if q[n.dim as usize] < n.split {
                node + 1
            } else {
                n.a as usize
            };
        }
    }
}

impl<T: Scalar> NeighborSearch<T> for KdTree<T> {
    fn dim(&self) -> usize {
        self.dim
    }

    fn source_len(&self) -> usize {
        self.source_len
    }

    fn search(
        &self,
        query: Query<'_, T>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) -> Result<()> {
        nbhd.validate()?;
        // The reverse index map is only made for stored-point queries.
        let positions: &[u32] = match query {
            Query::Stored { .. } => self.positions(),
            Query::Point { .. } => &[],
        };
        let (q, exclude) = resolve_query(query, self.dim, self.source_len, positions, |p| {
            self.point_at(p)
        })?;
        self.search_resolved(q, exclude, nbhd, out);
        Ok(())
    }
}

impl<T: Scalar> KdTree<T> {
    /// The search proper, on validated input.
    fn search_resolved(
        &self,
        q: &[T],
        exclude: Option<u32>,
        nbhd: Neighborhood<T>,
        out: &mut Vec<Neighbor<T>>,
    ) {
        let (k, sq_radius) = nbhd.limits();
        let tree = self.view();
        if k == usize::MAX {
            out.clear();
            search::search(&tree, q, exclude, &mut WithinRadius { out, sq_radius });
            if nbhd.is_sorted() {
                out.sort_unstable_by(|a, b| a.cmp_by_distance(b));
            }
        } else {
            let mut heap = NeighborHeap::new(out, k, sq_radius);
            search::search(&tree, q, exclude, &mut heap);
            heap.finish();
        }
    }
}
