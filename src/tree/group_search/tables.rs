//! The two drivers of the grouped search, both over [`super::Search`] and the same row
//! collectors: the table of a tree's own points ([`Plan`], groups of consecutive tree
//! positions, with the gathered fast path first), and the table of a batch of query points over
//! a forest of trees ([`batch_table`], groups of queries that fall into nearby leaves).

use std::ops::Range;

use super::cells::{CellView, Cells};
use super::{groups, run_rows, GroupAnswer, Search, SingleSearch, GROUP};
use crate::error::Result;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::table::{rows_in_chunks, NeighborTable, CHUNK};
use crate::tree::search::TreeView;

/// The all-point table of `tree` (dimension `D`), rows in the caller's index order.
pub(crate) fn table<T: Scalar, const D: usize>(
    tree: &TreeView<'_, T>,
    source_len: usize,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
) -> Result<NeighborTable<T>> {
    let plan = Plan::<T, D>::new(tree, nbhd, exclude_self);
    plan.rows(0..plan.chunks(), source_len, |pos| tree.ids[pos] as usize)
}

/// The grouped search of one tree's own points for one neighbourhood, prepared once (cells,
/// groups) and run over any run of its chunks: the whole table, or a block of tree positions at
/// a time when the table of every point would not fit in memory.
pub(crate) struct Plan<'a, T, const D: usize> {
    tree: &'a TreeView<'a, T>,
    cells: Cells<T, D>,
    groups: Vec<Range<usize>>,
    /// Chunk `c` holds the groups `chunk_groups[c]..chunk_groups[c + 1]`.
    chunk_groups: Vec<usize>,
    /// Chunk `c` holds the tree positions `work_bounds[c]..work_bounds[c + 1]`.
    work_bounds: Vec<usize>,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
}

impl<'a, T: Scalar, const D: usize> Plan<'a, T, D> {
    pub(crate) fn new(
        tree: &'a TreeView<'a, T>,
        nbhd: Neighborhood<T>,
        exclude_self: bool,
    ) -> Self {
        // Made in this order (boxes, groups, coordinates by dimension): with the coordinates
        // allocated before the groups, glibc trimmed the worker's heap when a table's cells
        // were freed, and the next table of 77k points, k = 30, paid 25 % more in page faults.
        let boxes = Cells::<T, D>::boxes_of(tree, 0);
        let groups = groups(tree.nodes);
        // Chunks of whole groups, about CHUNK points each: fixed by the tree, not the threads.
        let mut chunk_groups = vec![0usize];
        let mut work_bounds = vec![0usize];
        let mut acc = 0;
        for (g, r) in groups.iter().enumerate() {
            acc += r.len();
            if acc >= CHUNK || g + 1 == groups.len() {
                chunk_groups.push(g + 1);
                work_bounds.push(r.end);
                acc = 0;
            }
        }
        Self {
            tree,
            cells: boxes.with_coords(tree),
            groups,
            chunk_groups,
            work_bounds,
            nbhd,
            exclude_self,
        }
    }

    /// How many chunks the tree's positions are cut into.
    pub(crate) fn chunks(&self) -> usize {
        self.work_bounds.len() - 1
    }

    /// The tree positions of the chunks `chunks`.
    pub(crate) fn positions(&self, chunks: Range<usize>) -> Range<usize> {
        self.work_bounds[chunks.start]..self.work_bounds[chunks.end]
    }

    /// The rows of the points at the tree positions of `chunks`, computed in parallel, as a
    /// table of `rows` rows in which the row of position `pos` is `row_of(pos)`.
    pub(crate) fn rows(
        &self,
        chunks: Range<usize>,
        rows: usize,
        row_of: impl Fn(usize) -> usize + Sync,
    ) -> Result<NeighborTable<T>> {
        let (_, sq_radius) = self.nbhd.limits();
        let parts = [self.cells.view(self.tree, None)];
        let search = Search {
            parts: &parts,
            sq_radius,
            exclude_self: self.exclude_self,
            single: None,
        };
        let first = chunks.start;
        // Every row of a k-nearest table (no radius) holds k of the tree's other points, or
        // all of them: its place in the table is known before the search.
        let row_len = match self.nbhd {
            Neighborhood::Knn { k } => Some(k.min(
                self.tree.ids.len() - usize::from(self.exclude_self).min(self.tree.ids.len()),
            )),
            _ => None,
        };
        rows_in_chunks(
            rows,
            &self.work_bounds[chunks.start..=chunks.end],
            row_of,
            row_len,
            |c, out| {
                let c = first + c;
                let groups = |each: &mut GroupAnswer<'_, T, D>| {
                    for g in &self.groups[self.chunk_groups[c]..self.chunk_groups[c + 1]] {
                        each(&search, search.members_at(g.clone()), g.len());
                    }
                };
                run_rows(&groups, self.nbhd, true, out);
                Ok(())
            },
        )
    }
}

/// How a batch's queries are grouped: consecutive queries (in the order of their leaves)
/// whose leaves lie within `span` tree positions of the group's first form a group of at most
/// `max_group` members; `gather`: each group is first answered from one gathered block
/// (`gather.rs`; a single tree only).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BatchGroups {
    pub span: u32,
    pub max_group: usize,
    pub gather: bool,
}

/// The rows of the packed, finite `queries` (dimension `D`), row `i` for query `i`, over the
/// trees `parts` (largest first: its bounds prune the smaller trees most), answered in groups
/// along `order` (a permutation of the queries); in parallel over fixed chunks of `order`, so
/// identical for any thread count.
///
/// `keys[w]` is the first tree position, in the largest tree, of the leaf the query `order[w]`
/// falls into (increasing): queries are grouped by `grouping` ([`BatchGroups`]), and a query
/// with no neighbour within its span is answered alone by `single` (a group of far-apart
/// queries would search the space between them) unless the group is gathered. The members'
/// rows are kept from tree to tree, so the trees' answers merge in `(sq_dist, index)` order
/// and every later tree is searched with the bounds the earlier ones left.
pub(crate) fn batch_table<T: Scalar, const D: usize>(
    parts: &[CellView<'_, T, D>],
    queries: &[T],
    (order, keys): (&[u32], &[u32]),
    grouping: BatchGroups,
    nbhd: Neighborhood<T>,
    single: &SingleSearch<'_, T>,
) -> Result<NeighborTable<T>> {
    // the gathered block is collected from the first tree alone, every point of it live
    let gather = grouping.gather && parts.len() == 1 && parts[0].not_live.is_none();
    let (span, max_group) = (grouping.span, grouping.max_group.clamp(1, GROUP));
    let n = order.len();
    let bounds: Vec<usize> = (0..n.div_ceil(CHUNK))
        .map(|c| c * CHUNK)
        .chain(std::iter::once(n))
        .collect();
    let (_, sq_radius) = nbhd.limits();
    let search = Search {
        parts,
        sq_radius,
        exclude_self: false,
        single: Some(single),
    };
    // Every row of k nearest holds k points, or all of them, when every point of the trees is
    // live: its place in the table is known before the search.
    let all_live = parts.iter().all(|p| p.not_live.is_none());
    let row_len = match nbhd {
        Neighborhood::Knn { k } if all_live => Some(k.min(parts.iter().map(|p| p.ids.len()).sum())),
        _ => None,
    };
    rows_in_chunks(
        n,
        &bounds,
        |w| order[w] as usize,
        row_len,
        |c, out| {
            let work = &order[bounds[c]..bounds[c + 1]];
            let keys = &keys[bounds[c]..bounds[c + 1]];
            let groups = |each: &mut GroupAnswer<'_, T, D>| {
                let mut s = 0;
                while s < work.len() {
                    let mut e = s + 1;
                    while e < work.len() && e - s < max_group && keys[e] - keys[s] <= span {
                        e += 1;
                    }
                    each(&search, search.members_of(queries, &work[s..e]), e - s);
                    s = e;
                }
            };
            run_rows(&groups, nbhd, gather, out);
            Ok(())
        },
    )
}
