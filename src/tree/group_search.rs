//! The grouped search: the neighbourhood table of a tree's own points, or of a batch of query
//! points over a single tree or a forest of trees (`src/dynamic/`), answered one small group of
//! nearby queries at a time. One traversal ([`Search::group_of`]) and one row-collector trait
//! (`rows.rs`) serve every case; `tables.rs` holds the two drivers (a tree's own points in
//! groups of consecutive tree positions, a batch in groups of queries falling into nearby
//! leaves), `cells.rs` what the search reads of each tree.
//!
//! Points of one leaf have nearly the same neighbourhood (the "leaf-to-leaf" sharing of
//! dual-tree search, Gray & Moore, *'N-Body' Problems in Statistical Learning*, NIPS 2000, and
//! of bucketed all-kNN, Vaidya 1989). So instead of one
//! descent per query (thesis Algorithm 9), the tree is descended once per group: a cell is
//! visited if its tight bounding box may hold a point of some member's answer, i.e. if its
//! squared distance to the group's bounding box does not exceed the largest current bound of
//! the members. Each visited leaf is then scanned for every member whose own point-to-box
//! distance admits it, with a bounded heap per member. Over a forest, the members' rows are kept
//! from tree to tree (largest first), indices shifted to the forest's and removed points
//! skipped, so later trees are searched with the bounds earlier ones left. Every member therefore sees every
//! point that could enter its answer, with the exact squared distance the single-query search
//! computes, so the rows are the single-query rows byte for byte.
//!
//! Ties in `(sq_dist, index)` order also prune: once a member holds `k` candidates whose worst
//! is `(b, w)`, a cell at distance exactly `b` whose smallest caller index is ≥ `w` cannot
//! improve it. This stops duplicate-heavy sets from scanning every copy of a point.
//!
//! k-nearest rows of a tree's own points up to `rows::SORTED_MAX_K`, and `f32` rows of any `k`
//! up to `rows::KEY_HEAP_MAX_K`, take a faster path first (`group_search/gather.rs`):
//! the group gathers every point within a guessed radius once, and each member orders its
//! candidates within it once instead of inserting them one by one; where the guess does not
//! settle a row, the group is searched as above. The rows are the same either way.
//!
//! Lower bounds are exact in floating point: the gaps, squares and sums are evaluated in the
//! order of the point distance, and rounding is monotone, so a cell's bound never exceeds the
//! computed squared distance of any of its points to any member.

#[cfg(all(target_arch = "x86_64", rustc_1_89))]
#[clippy::msrv = "1.89"]
mod avx512;
mod cells;
mod gather;
mod rows;
mod tables;

use std::ops::Range;

use gather::Gather;
use rows::{GroupKey, HeapRows, KeyHeapRows, RadiusRows, RowSets, SortedRows};
use rows::{KEY_HEAP_MAX_K, SORTED_MAX_K};

pub(crate) use cells::{CellView, Cells};
pub(crate) use tables::{batch_table, table, BatchGroups, Plan};

use super::node::Node;
use crate::query::result_set::Key32;
use crate::query::{order, Neighbor, Neighborhood};
use crate::scalar::{Scalar, ScalarType};
use crate::table::RowsChunk;

/// Most queries in one group.
const GROUP: usize = 16;

/// Points scanned at once: a leaf's squared distances to one query are computed a block at a
/// time, in straight-line code the compiler vectorises.
const BLOCK: usize = 16;

/// The groups of a tree's own points: subtrees of at most [`GROUP`] points, and pieces of
/// larger leaves, as ranges of tree positions in increasing order.
fn groups<T: Scalar>(nodes: &[Node<T>]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, start)) = stack.pop() {
        let nd = &nodes[i];
        let end = nd.b as usize;
        if nd.is_leaf() || end - start <= GROUP {
            let mut s = start;
            while s < end {
                let e = (s + GROUP).min(end);
                out.push(s..e);
                s = e;
            }
        } else {
            let left_end = nodes[i + 1].b as usize;
            stack.push((nd.a as usize, left_end));
            stack.push((i + 1, start));
        }
    }
    out
}

/// Squared distance between the boxes `[alo, ahi]` and `[blo, bhi]` (0 where they overlap):
/// per dimension the gap `max(blo − ahi, alo − bhi, 0)`, without branches.
#[inline(always)]
fn box_dist<T: Scalar, const D: usize>(
    alo: &[T; D],
    ahi: &[T; D],
    blo: &[T; D],
    bhi: &[T; D],
) -> T {
    let mut s = T::ZERO;
    for j in 0..D {
        let g = (blo[j] - ahi[j]).max_of(alo[j] - bhi[j]).max_of(T::ZERO);
        s = s + g * g;
    }
    s
}

/// Whether a group descends into the left child before the right one, given each child's
/// `(lower bound, smallest index)`: the nearer first; between equally near ones the side of the
/// split the first member is on (`on_left`) — unless only ties at the bound can still enter
/// (`ties_only`), then the one holding the smallest index.
#[inline(always)]
fn left_first<T: Scalar>(left: (T, u32), right: (T, u32), ties_only: bool, on_left: bool) -> bool {
    if left.0 == right.0 {
        if ties_only {
            left.1 < right.1
        } else {
            on_left
        }
    } else {
        left.0 < right.0
    }
}

/// `true` if a cell at squared distance `lb` whose smallest caller index is `min_id` may
/// improve a row whose worst admissible key is `(b, w)` (`w == u32::MAX` while the row is not
/// full: caller indices are below it).
#[inline(always)]
fn admits<T: Scalar>(lb: T, min_id: u32, b: T, w: u32) -> bool {
    order::precedes((lb, min_id), (b, w))
}

/// What answers one group: given the search, the group's members and their number.
type GroupAnswer<'f, T, const D: usize> = dyn FnMut(&Search<'_, T, D>, Members<T, D>, usize) + 'f;

/// Answers every group that `groups` hands out with the row collectors `nbhd` needs, each
/// group of a tree's own points first from a gathered block where `gather` allows it
/// (`group_search/gather.rs`), and appends the rows to `out`.
fn run_rows<T: Scalar, const D: usize>(
    groups: &dyn Fn(&mut GroupAnswer<'_, T, D>),
    nbhd: Neighborhood<T>,
    gather: bool,
    out: &mut RowsChunk<'_, T>,
) {
    let (k, sq_radius) = nbhd.limits();
    let sorted = nbhd.is_sorted();
    let f32 = T::TYPE == ScalarType::F32;
    let radius = || RadiusRows::new(sq_radius, sorted);
    if k == usize::MAX && f32 {
        let g = gather.then(|| Gather::<T, u64, D>::within(sorted));
        answer_groups(groups, radius(), g, out);
    } else if k == usize::MAX {
        let g = gather.then(|| Gather::<T, u128, D>::within(sorted));
        answer_groups(groups, radius(), g, out);
    } else if k <= SORTED_MAX_K && f32 {
        let rows = SortedRows::<T, Key32>::new(k, sq_radius);
        answer_groups(
            groups,
            rows,
            gather.then(|| Gather::<T, u64, D>::nearest(k)),
            out,
        );
    } else if k <= SORTED_MAX_K {
        let rows = SortedRows::<T, Neighbor<T>>::new(k, sq_radius);
        answer_groups(
            groups,
            rows,
            gather.then(|| Gather::<T, u128, D>::nearest(k)),
            out,
        );
    } else if k <= KEY_HEAP_MAX_K && f32 {
        // gathered first as the shorter rows are: the robust smoothing's wide rows (k = 148,
        // `f32`, `src/tree/exact_knn.rs`) on a 50K-point cloud with noise of three spacings
        // take 2.3G instructions instead of 3.6G (callgrind), and the whole run 0.74 of its
        // time
        let rows = KeyHeapRows::<T, u64>::new(k, sq_radius);
        answer_groups(
            groups,
            rows,
            gather.then(|| Gather::<T, u64, D>::nearest(k)),
            out,
        );
    } else if k <= KEY_HEAP_MAX_K {
        let rows = KeyHeapRows::<T, u128>::new(k, sq_radius);
        answer_groups(groups, rows, None::<Gather<T, u128, D>>, out);
    } else {
        let rows = HeapRows::new(k, sq_radius);
        answer_groups(groups, rows, None::<Gather<T, u64, D>>, out);
    }
}

/// Answers every group that `groups` hands out with the rows `rows`, each group first from a
/// gathered block where `gather` is given (`group_search/gather.rs`), and appends the rows to
/// `out`; once a chunk's rows did not fit, it takes no more (see `RowsChunk`).
fn answer_groups<T: Scalar, const D: usize, R: RowSets<T>, K: GroupKey<T>>(
    groups: &dyn Fn(&mut GroupAnswer<'_, T, D>),
    mut rows: R,
    mut gather: Option<Gather<T, K, D>>,
    out: &mut RowsChunk<'_, T>,
) {
    let mut stack = Vec::new();
    groups(&mut |s, mb, m| {
        if out.is_done() {
            return;
        }
        // the group's rows go to slots scattered over the table: request them (and the next
        // group's offsets) before the search
        out.prefetch(m, GROUP);
        match &mut gather {
            Some(gather) => s.gathered_group(mb, m, gather, &mut rows, &mut stack, out),
            None => s.group(mb, m, &mut rows, &mut stack, out),
        }
    });
}

/// The single search of one query into a row (a forest's, for a group of one query).
pub(crate) type SingleSearch<'a, T> = dyn Fn(&[T], &mut Vec<Neighbor<T>>) + Sync + 'a;

/// What every group's search reads.
struct Search<'a, T, const D: usize> {
    /// The trees, largest first: one for a tree's own table, every tree of a forest.
    parts: &'a [CellView<'a, T, D>],
    sq_radius: T,
    /// Members are a tree's own points, each left out of its row.
    exclude_self: bool,
    /// Answers a group of one query on its own (batches over a forest).
    single: Option<&'a SingleSearch<'a, T>>,
}

/// The members of a group: their coordinates, the ids their rows leave out (`u32::MAX` for
/// none) and their bounding box.
struct Members<T, const D: usize> {
    q: [[T; D]; GROUP],
    self_id: [u32; GROUP],
    lo: [T; D],
    hi: [T; D],
}

impl<T: Scalar, const D: usize> Members<T, D> {
    fn new() -> Self {
        Self {
            q: [[T::ZERO; D]; GROUP],
            self_id: [u32::MAX; GROUP],
            lo: [T::INFINITY; D],
            hi: [T::ZERO - T::INFINITY; D],
        }
    }

    /// Sets member `i` to the point `p`, leaving out `self_id`.
    #[inline(always)]
    fn set(&mut self, i: usize, p: &[T], self_id: u32) {
        for (j, &c) in p.iter().enumerate().take(D) {
            self.q[i][j] = c;
            self.lo[j] = self.lo[j].min_of(c);
            self.hi[j] = self.hi[j].max_of(c);
        }
        self.self_id[i] = self_id;
    }
}

/// The bounds of a group's rows as the search goes: each row's worst admissible key, and the
/// group's, the largest of them.
struct Bounds<T> {
    bound: [T; GROUP],
    worst: [u32; GROUP],
    gb: T,
    gw: u32,
}

/// Which caller indices a tree's search takes: all of them, or those not marked in a bitmap of
/// removed points.
trait Live: Copy {
    fn is_live(self, id: u32) -> bool;
}

/// Every point is live (a tree on its own, or a tree of a forest holding no removed point).
#[derive(Clone, Copy)]
struct AllLive;

impl Live for AllLive {
    #[inline(always)]
    fn is_live(self, _id: u32) -> bool {
        true
    }
}

/// The points whose bit is not set in a bitmap of removed points.
#[derive(Clone, Copy)]
struct Tombstones<'a>(&'a [u64]);

impl Live for Tombstones<'_> {
    #[inline(always)]
    fn is_live(self, id: u32) -> bool {
        self.0[(id >> 6) as usize] >> (id & 63) & 1 == 0
    }
}

impl<T: Scalar, const D: usize> Search<'_, T, D> {
    /// The members of the group of tree positions `g` of the (only) tree.
    fn members_at(&self, g: Range<usize>) -> Members<T, D> {
        let tree = &self.parts[0];
        let mut m = Members::new();
        for (i, p) in g.enumerate() {
            let own = if self.exclude_self {
                tree.ids[p]
            } else {
                u32::MAX
            };
            m.set(i, &tree.coords[p * D..p * D + D], own);
        }
        m
    }

    /// The members of the group of the packed `queries` numbered `members`.
    fn members_of(&self, queries: &[T], members: &[u32]) -> Members<T, D> {
        let mut m = Members::new();
        for (i, &w) in members.iter().enumerate() {
            let at = w as usize * D;
            m.set(i, &queries[at..at + D], u32::MAX);
        }
        m
    }

    /// Answers the group `mb` of `m` members from one gathered block (`gather`), or by
    /// [`Search::group_of`] with the rows `rows` where the gather does not settle it; appends
    /// its rows, in member order, to `out`.
    fn gathered_group<R: RowSets<T>, K: GroupKey<T>>(
        &self,
        mb: Members<T, D>,
        m: usize,
        gather: &mut Gather<T, K, D>,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<'_, T>,
    ) {
        if !gather.group(self, &mb, m, out) {
            let bound = self.group_of(mb, m, rows, stack, out);
            if R::TIGHTENS {
                gather.learn(bound, self.sq_radius);
            }
        }
    }

    /// Answers the group `mb` of `m` members (a single query on its own where the search has a
    /// single search) and appends its rows, in member order, to `out`.
    fn group<R: RowSets<T>>(
        &self,
        mb: Members<T, D>,
        m: usize,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<'_, T>,
    ) {
        match self.single {
            Some(single) if m == 1 => {
                let mut row = Vec::new();
                single(&mb.q[0], &mut row);
                out.push_row(row.len(), row.iter().map(|nb| (nb.sq_dist, nb.index)));
            }
            _ => {
                self.group_of(mb, m, rows, stack, out);
            }
        }
    }

    /// Searches every tree for the group `mb` of `m` members and appends its rows, in member
    /// order, to `out`; returns the group's bound, the largest worst distance of its rows (the
    /// search's limit where a row is not full).
    fn group_of<R: RowSets<T>>(
        &self,
        mut mb: Members<T, D>,
        m: usize,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
        out: &mut RowsChunk<'_, T>,
    ) -> T {
        // Radius rows of a group of copies of one point (duplicate-heavy sets) are one row,
        // less each member itself: searched and sorted once. (`u32::MAX` excludes nothing.)
        let copies = !R::TIGHTENS && m > 1 && mb.lo == mb.hi;
        let self_ids = mb.self_id;
        let searched = if copies {
            mb.self_id[0] = u32::MAX;
            1
        } else {
            m
        };
        rows.clear(searched);
        let mut st = Bounds {
            bound: [self.sq_radius; GROUP],
            worst: [u32::MAX; GROUP],
            gb: self.sq_radius,
            gw: u32::MAX,
        };
        for part in self.parts {
            match part.not_live {
                None => self.descend(part, AllLive, &mb, searched, &mut st, rows, stack),
                Some(bits) => {
                    let live = Tombstones(bits);
                    self.descend(part, live, &mb, searched, &mut st, rows, stack)
                }
            }
        }
        if copies {
            rows.write_copies(&self_ids[..m], out);
        } else {
            rows.write(searched, out);
        }
        st.gb
    }

    /// Descends one tree for the group `mb` (its first `m` members), from the bounds `st` the
    /// earlier trees left, inserting into `rows` the live points that improve a row.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn descend<R: RowSets<T>, L: Live>(
        &self,
        part: &CellView<'_, T, D>,
        live: L,
        mb: &Members<T, D>,
        m: usize,
        st: &mut Bounds<T>,
        rows: &mut R,
        stack: &mut Vec<(u32, T)>,
    ) {
        let (q, glo, ghi) = (&mb.q, &mb.lo, &mb.hi);
        stack.clear();
        stack.push((0, box_dist(glo, ghi, &part.lo[0], &part.hi[0])));
        while let Some((mut node, lb)) = stack.pop() {
            if !admits(lb, part.min_id[node as usize], st.gb, st.gw) {
                continue;
            }
            loop {
                let ni = node as usize;
                // A cell of copies of one point (duplicate-heavy sets): its distance to each
                // member is exact, so test the members one by one; near a cluster of copies
                // the group's box would admit every cell of it for members that only need
                // smaller indices at a tie.
                if part.lo[ni] == part.hi[ni]
                    && !(0..m).any(|i| {
                        let lb = box_dist(&q[i], &q[i], &part.lo[ni], &part.hi[ni]);
                        admits(lb, part.min_id[ni], st.bound[i], st.worst[i])
                    })
                {
                    break;
                }
                let nd = &part.nodes[ni];
                if nd.is_leaf() {
                    Self::scan_leaf(part, live, ni, mb, m, st, rows);
                    if R::TIGHTENS {
                        (st.gb, st.gw) = (st.bound[0], st.worst[0]);
                        for i in 1..m {
                            if order::precedes((st.gb, st.gw), (st.bound[i], st.worst[i])) {
                                (st.gb, st.gw) = (st.bound[i], st.worst[i]);
                            }
                        }
                    }
                    break;
                }
                let (l, r) = (node + 1, nd.a);
                let lbl = box_dist(glo, ghi, &part.lo[l as usize], &part.hi[l as usize]);
                let lbr = box_dist(glo, ghi, &part.lo[r as usize], &part.hi[r as usize]);
                // Nearer cell first; between equally near cells, the one holding the group
                // (the side of the split its first point is on) — unless they can only offer
                // ties at the bound (e.g. copies of the members' point once every row holds k
                // of them): then only smaller indices help, so the cell holding the smallest
                // first, which soon leaves every other cell pruned by its smallest index.
                let left_first = left_first(
                    (lbl, part.min_id[l as usize]),
                    (lbr, part.min_id[r as usize]),
                    R::TIGHTENS && lbl == st.gb,
                    q[0][nd.dim as usize] < nd.split,
                );
                let (near, lbn, far, lbf) = if left_first {
                    (l, lbl, r, lbr)
                } else {
                    (r, lbr, l, lbl)
                };
                if admits(lbf, part.min_id[far as usize], st.gb, st.gw) {
                    stack.push((far, lbf));
                }
                if !admits(lbn, part.min_id[near as usize], st.gb, st.gw) {
                    break;
                }
                node = near;
            }
        }
    }

    /// Scans the leaf `ni` for every member whose own point-to-box bound admits it, a block of
    /// points at a time, inserting into its row every live point that precedes its worst key.
    #[inline(always)]
    fn scan_leaf<R: RowSets<T>, L: Live>(
        part: &CellView<'_, T, D>,
        live: L,
        ni: usize,
        mb: &Members<T, D>,
        m: usize,
        st: &mut Bounds<T>,
        rows: &mut R,
    ) {
        let nd = &part.nodes[ni];
        let (llo, lhi, lmin) = (&part.lo[ni], &part.hi[ni], part.min_id[ni]);
        let (a, b) = (nd.a as usize, nd.b as usize);
        let (bound, worst) = (&mut st.bound, &mut st.worst);
        let simd = (crate::simd::sse(), crate::simd::avx());
        for i in 0..m {
            let qi = &mb.q[i];
            if !admits(box_dist(qi, qi, llo, lhi), lmin, bound[i], worst[i]) {
                continue;
            }
            let mut start = a;
            while start < b {
                let (d, mut hits) = part.soa.block_sq_dists_below(qi, start, bound[i], simd);
                if b - start < BLOCK {
                    hits &= (1 << (b - start)) - 1;
                }
                while hits != 0 {
                    let p = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    let id = part.ids[start + p];
                    if admits(d[p], id, bound[i], worst[i])
                        && id != mb.self_id[i]
                        && live.is_live(id)
                    {
                        (bound[i], worst[i]) = rows.insert(i, id, d[p]);
                    }
                }
                start += BLOCK;
            }
        }
    }
}
