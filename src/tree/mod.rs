//! The k-d tree (thesis Chapter 3): built with a selectable pivot policy and median
//! algorithm, holding its own compact copy of the points in tree order plus the map to the
//! caller's indices; the static flavour of the neighbour index, answering the exact queries of
//! Chapter 5 through [`NeighborIndex`] (`src/index/`).
//!
//! This file holds the tree type, its accessors and its part of the index: the descents a
//! query runs. Around it:
//! - `construct.rs`: [`KdTree::build`], from the caller's points to the tree's arrays (the
//!   driver: which layout, which build, how many threads);
//! - `build.rs`, `presorted.rs`, `split.rs`, `layout.rs`, `node.rs`: the recursive build
//!   itself (Algorithm 3.1) and what it works on;
//! - `search.rs`: the descent that answers one query (Algorithm 9), and `kernel.rs`, the leaf
//!   arithmetic it shares with the grouped search;
//! - `group_search.rs`: the grouped search, one descent per group of nearby queries, for the
//!   tree's own points and for a forest of trees (`src/dynamic/`); `neighborhoods.rs` runs it
//!   as the fast path of the tree's tables, `blocks.rs` a block of tree positions at a time;
//! - `boxes.rs`: the descent of a box query (Algorithms 2 and 3);
//! - `exact_knn.rs`: the fast exact k-nearest table of 3-D `f64` points, searched in `f32`
//!   and proven exact in `f64` ([`exact_knn_table`]);
//! - `periodic.rs`: periodic trees (a torus) and their descent;
//! - `nodes.rs`: the nodes as a caller sees them (scipy's node objects) and per-node weights;
//! - `part.rs`: what a forest reads of one of its trees;
//! - `persist.rs`: saving a built tree and loading it back (docs/tree-file-format.md).

mod blocks;
mod boxes;
mod build;
mod construct;
mod envelope;
pub(crate) mod exact_knn;
pub(crate) mod group_search;
mod kernel;
mod layout;
mod neighborhoods;
mod node;
mod nodes;
pub mod options;
mod part;
mod periodic;
mod persist;
mod presorted;
mod search;
mod split;

use std::sync::OnceLock;

use crate::error::Result;
use crate::index::{self, NeighborIndex, StoredPoints};
use crate::metric::{Measure, Period};
use crate::parallel::with_threads;
use crate::query::resolve_query;
use crate::query::result_set::ResultSet;
use crate::query::{Neighbor, NeighborSearch, Neighborhood, Query};
use crate::scalar::Scalar;
use crate::table::NeighborTable;
pub(crate) use blocks::Blocks;
pub(crate) use envelope::saved_header;
pub(crate) use envelope::{
    check_start, header, invalid, pad8, period_section_len, periodic_flag, read_codes, read_period,
    scalar_bytes, scalar_name, size, u32_at, u64_at, write_period, write_saved, written_by, Kind,
    DYNAMIC_KIND, FOREST_MAGIC, STATIC_KIND,
};
pub use envelope::{LoadOptions, Persist, FORMAT_VERSION, HEADER_LEN, MAGIC};
#[doc(hidden)]
pub use envelope::{SavedFormat, SavedHeader};
pub use exact_knn::exact_knn_table;
use node::{Descent, Node};
pub use nodes::NodeInfo;
pub use options::{
    max_unbalanced_depth, BuildOptions, MedianAlgorithm, PivotPolicy, DEFAULT_LEAF_SIZE,
};
pub use persist::SavedTreeInfo;
use search::TreeView;

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
    /// Bytes of coordinates, index map and nodes with their smallest indices (and the reverse index map once a stored-point
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
    /// Smallest caller index of every node's subtree (derived from `nodes` and `ids`, not
    /// saved): lets a search skip cells whose points cannot win on index (`search.rs`).
    min_id: Vec<u32>,
    /// The compact descent array of single queries (dimension ≤ 3; derived, not saved).
    descent: Option<Descent<T>>,
    depth: usize,
    source_len: usize,
    options: BuildOptions,
    /// Tree position of every caller index (`u32::MAX` for skipped points), made on first use.
    position_of: OnceLock<Vec<u32>>,
    /// The periodic box and the points' bounding box, for a periodic tree (`periodic.rs`).
    periodic: Option<Box<periodic::Periodic<T>>>,
}

impl<T: Scalar> KdTree<T> {
    /// The options the tree was built with.
    pub fn options(&self) -> &BuildOptions {
        &self.options
    }

    /// Number of points held.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// `true` for a tree over no point (none given, or every one skipped): one empty leaf,
    /// queries find nothing and table rows are empty.
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
                + self.min_id.len() * 4
                + self.descent.as_ref().map_or(0, Descent::bytes)
                + reverse,
        }
    }

    fn view(&self) -> TreeView<'_, T> {
        TreeView {
            nodes: &self.nodes,
            coords: &self.coords,
            ids: &self.ids,
            min_id: &self.min_id,
            dim: self.dim,
        }
    }

    /// Makes what is derived from the nodes and not saved: the smallest indices (on the
    /// `threads` of a build, serially for 1) and the compact descent.
    fn derive(&mut self, threads: usize) -> Result<()> {
        let (nodes, ids) = (&self.nodes, &self.ids);
        self.min_id = if threads == 1 {
            search::min_ids(nodes, ids, false)
        } else {
            with_threads(threads, || search::min_ids(nodes, ids, true))?
        };
        let bucket = descent_bucket(self.len());
        self.descent = Descent::new(&self.nodes, &self.min_id, self.dim, bucket);
        Ok(())
    }

    /// Runs a single search into `out`: over the compact descent where the tree has one.
    #[inline(always)]
    fn run<C: ResultSet<T>>(&self, q: &[T], exclude: Option<u32>, out: &mut C) {
        match &self.descent {
            Some(descent) => search::search_compact(
                &search::DescentView {
                    descent,
                    coords: &self.coords,
                    ids: &self.ids,
                    depth: self.depth,
                },
                q,
                exclude,
                out,
            ),
            None => search::search(&self.view(), q, exclude, out),
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
        index::search(self, query, nbhd, out)
    }
}

/// The static tree's part of the one query family (`src/index/`): its descents, and its
/// grouped all-point search (`group_search.rs`) as the fast path of its tables.
impl<T: Scalar> NeighborIndex<T> for KdTree<T> {
    fn len(&self) -> usize {
        self.ids.len()
    }

    fn resolve<'q>(&'q self, query: Query<'q, T>) -> Result<(&'q [T], Option<u32>)> {
        // The reverse index map is only made for stored-point queries.
        let positions: &[u32] = match query {
            Query::Stored { .. } => self.positions(),
            Query::Point { .. } => &[],
        };
        resolve_query(query, self.dim, self.source_len, positions, |p| {
            self.point_at(p)
        })
    }

    #[inline(always)]
    fn visit<C: ResultSet<T>>(&self, q: &[T], exclude: Option<u32>, set: &mut C) {
        // a tree of no point is one empty leaf: nothing to find
        if !self.ids.is_empty() {
            self.run(q, exclude, set);
        }
    }

    fn visit_with<C: ResultSet<T>>(
        &self,
        q: &[T],
        exclude: Option<u32>,
        measure: &Measure,
        set: &mut C,
    ) {
        if !self.ids.is_empty() {
            self.search_measured(q, exclude, measure, set);
        }
    }

    fn period(&self) -> Option<&Period<T>> {
        KdTree::period(self)
    }

    fn visit_box(&self, min: &[T], max: &[T], scratch: &mut Vec<T>, out: &mut Vec<u32>) {
        self.collect_in_box(min, max, scratch, out);
    }

    fn with_stored<R>(&self, f: impl FnOnce(&StoredPoints<'_, T>) -> R) -> R {
        f(&StoredPoints {
            len: self.len(),
            at: &|pos| (self.ids[pos], self.point_at(pos)),
        })
    }

    fn region_key(&self, q: &[T]) -> u32 {
        self.leaf_position(q)
    }

    fn region_keys(&self) -> usize {
        self.len()
    }

    fn grouped_table(
        &self,
        nbhd: Neighborhood<T>,
        exclude_self: bool,
    ) -> Option<Result<NeighborTable<T>>> {
        self.grouped_all(nbhd, exclude_self)
    }

    fn grouped_batch(
        &self,
        queries: &[T],
        order: &[u32],
        keys: &[u32],
        nbhd: Neighborhood<T>,
    ) -> Option<Result<NeighborTable<T>>> {
        self.grouped_batch_of(queries, order, keys, nbhd)
    }
}

/// Subtrees of at most this many points are one leaf of the compact descent (`node.rs`): 32
/// up to [`LARGE_TREE`] points, 64 above. Where the points fit the core's cache, leaves of 32
/// are best (77k torus: 24, 32 and 40 the same within the noise, 64 10-20 % slower at k = 10,
/// README "Single queries, the floor, and copies of a point"); where every leaf is a cache
/// miss, fewer, larger leaves are (1M cube and torus: 64 took 0.80-0.93x the time of 32 at
/// k = 10 and 30, 96 and 128 no better than 64; docs/speed-log.md, round 8).
fn descent_bucket(points: usize) -> usize {
    if points > LARGE_TREE {
        64
    } else {
        32
    }
}

/// Trees of more points than this take the larger leaves of [`descent_bucket`]: 3 MB of `f32`
/// coordinates, beyond the 1-2 MB of a core's own cache (the 123k set, 1.5 MB, kept 32's speed).
const LARGE_TREE: usize = 1 << 18;
