//! Neighbourhood tables: the neighbourhoods of many query points (usually every point of a
//! tree) as compressed rows, `offsets` + caller `indices` + `sq_dists`, row `i` belonging to
//! query `i` (for a tree's own points: the caller's point `i`; skipped points get empty rows).

use crate::error::{NbhdError, Result};
use crate::prefetch::{prefetch_bytes, prefetch_range};
use crate::query::{Neighbor, NeighborSearch, Neighborhood, Query, QueryOptions};
use crate::scalar::Scalar;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;

/// Compressed rows of neighbours.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct NeighborTable<T> {
    offsets: Vec<usize>,
    indices: Vec<u32>,
    sq_dists: Vec<T>,
}

impl<T: Copy> NeighborTable<T> {
    /// Assembles a table from its parts. `offsets` has one more entry than there are rows,
    /// starts at 0, never decreases and ends at `indices.len() == sq_dists.len()`; returns
    /// `None` otherwise.
    pub fn from_parts(offsets: Vec<usize>, indices: Vec<u32>, sq_dists: Vec<T>) -> Option<Self> {
        let ok = offsets.first() == Some(&0)
            && offsets.windows(2).all(|w| w[0] <= w[1])
            && offsets.last() == Some(&indices.len())
            && indices.len() == sq_dists.len();
        ok.then_some(Self {
            offsets,
            indices,
            sq_dists,
        })
    }

    /// The parts `(offsets, indices, sq_dists)`, moved out without a copy (what
    /// [`Self::from_parts`] takes): for bindings that hand the rows to another owner, such as
    /// the Python package's numpy arrays.
    pub fn into_parts(self) -> (Vec<usize>, Vec<u32>, Vec<T>) {
        (self.offsets, self.indices, self.sq_dists)
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// `true` if the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Caller indices of the neighbours of row `i`.
    pub fn indices_of(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Squared distances of the neighbours of row `i` (parallel to [`Self::indices_of`]).
    pub fn sq_dists_of(&self, i: usize) -> &[T] {
        &self.sq_dists[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Row boundaries: row `i` is `offsets[i]..offsets[i + 1]`.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// All neighbour indices, row after row.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// All squared distances, row after row.
    pub fn sq_dists(&self) -> &[T] {
        &self.sq_dists
    }

    /// Total number of neighbours over all rows.
    pub fn total(&self) -> usize {
        self.indices.len()
    }

    /// Length of the shortest row (0 for an empty table).
    pub fn min_row_len(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| w[1] - w[0])
            .min()
            .unwrap_or(0)
    }

    /// Length of the longest row (0 for an empty table).
    pub fn max_row_len(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }

    /// Mean row length (0 for an empty table).
    pub fn mean_row_len(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            self.total() as f64 / self.len() as f64
        }
    }
}

/// Queries per parallel work item: large enough to amortise scheduling, small enough to
/// balance two to dozens of threads.
pub(crate) const CHUNK: usize = 1024;

/// Rows of the output written by one worker at a time when the chunks are gathered into the
/// table.
const ROW_BLOCK: usize = 4096;

/// Where one row of a chunk is in the chunk's buffers: the entries `at..at + len`, less the
/// entry at `at + skip` when `skip < len` (the rows of copies of one point share one stored row,
/// each without its own point; see [`RowsChunk::push_shared`]).
#[derive(Clone, Copy, Debug)]
struct RowSource {
    at: usize,
    len: usize,
    skip: usize,
}

impl RowSource {
    /// Entries of the row.
    fn row_len(&self) -> usize {
        self.len - usize::from(self.skip < self.len)
    }
}

/// The final table's entries, written in place by the workers of [`rows_in_chunks`] when
/// every row's length is known in advance (k-nearest tables).
struct InPlace<T> {
    ids: *mut u32,
    dists: *mut T,
    total: usize,
}

// SAFETY: the pointers are only written through [`RowsChunk::push_row`] and
// [`RowsChunk::push_shared`], each worker into the slots of its own work items, which are
// disjoint (`rows_in_chunks` checks that no two work items map to one row), and only while
// `rows_in_chunks` keeps the vectors they point into alive and otherwise untouched.
unsafe impl<T: Send> Send for InPlace<T> {}
// SAFETY: as above: no two threads ever write the same entry, and nobody reads them meanwhile.
unsafe impl<T: Send> Sync for InPlace<T> {}

/// A chunk that writes its rows in place: the table's entries, the rows' offsets, the map from
/// work item to row, and the next work item.
struct Direct<'a, T> {
    table: &'a InPlace<T>,
    offsets: &'a [usize],
    row_of: &'a (dyn Fn(usize) -> usize + Sync),
    next: usize,
    /// The end of the chunk's work items.
    end: usize,
}

impl<T: Copy> Direct<'_, T> {
    /// Requests the slots of the next `now` work items' rows (whose offsets an earlier call
    /// requested) and the offsets of the `later` items after them: rows go to the caller's
    /// order, scattered over the table, and each would otherwise wait for two cache misses.
    fn prefetch(&self, now: usize, later: usize) {
        let soon = self.next..(self.next + now).min(self.end);
        for r in soon.clone().map(self.row_of) {
            let (from, to) = (self.offsets[r], self.offsets[r + 1]);
            if from <= to && to <= self.table.total {
                let len = to - from;
                let ids = self.table.ids.wrapping_add(from);
                prefetch_bytes(ids.cast(), len * std::mem::size_of::<u32>());
                let dists = self.table.dists.wrapping_add(from);
                prefetch_bytes(dists.cast(), len * std::mem::size_of::<T>());
            }
        }
        for r in (soon.end..(soon.end + later).min(self.end)).map(self.row_of) {
            prefetch_range(&self.offsets[r..r + 2]);
        }
    }

    /// The entries of the next work item's row as two slices, if its slot has `len` entries.
    #[inline]
    fn next_slot(&mut self, len: usize) -> Option<(&mut [u32], &mut [T])> {
        let r = (self.row_of)(self.next);
        self.next += 1;
        let (from, to) = (self.offsets[r], self.offsets[r + 1]);
        if to - from != len || to > self.table.total {
            return None;
        }
        // SAFETY: `from..to` lies inside the table's two vectors (`to ≤ total`, their length);
        // the slot belongs to this work item alone (no two work items map to one row, checked
        // when the offsets were built, and each work item is taken once, by `next`), so no
        // other reference to these entries exists while the slices live.
        unsafe {
            Some((
                std::slice::from_raw_parts_mut(self.table.ids.add(from), len),
                std::slice::from_raw_parts_mut(self.table.dists.add(from), len),
            ))
        }
    }
}

/// The rows of one chunk of queries, appended in work order: into the chunk's buffers (row
/// sources, neighbour indices, squared distances), gathered into the table afterwards, or —
/// when every row's length is known in advance — straight into the final table.
///
/// Rows go in through [`RowsChunk::push_row`] and [`RowsChunk::push_shared`], which reserve
/// fallibly: the size of a table comes from the caller's input (a radius covering every point,
/// a huge `k`), and an allocation failure must become [`NbhdError::OutOfMemory`], never an
/// abort. The bytes a chunk holds count against [`IN_CHUNKS`] until it is dropped.
#[derive(Default)]
pub(crate) struct RowsChunk<'a, T> {
    rows: Vec<RowSource>,
    ids: Vec<u32>,
    dists: Vec<T>,
    /// The bytes an allocation failed to get (the chunk takes no more rows once set).
    failed: Option<u128>,
    /// Bytes of this chunk counted in [`IN_CHUNKS`].
    counted: u64,
    direct: Option<Direct<'a, T>>,
    /// A row's length differed from its slot's in the final table (the table is then built
    /// through the buffers instead).
    mismatch: bool,
}

impl<T: Copy + Default> RowsChunk<'_, T> {
    /// `true` once the chunk takes no more rows (an allocation failed, or a row did not fit
    /// its slot): the caller may stop computing them.
    #[inline]
    pub(crate) fn is_done(&self) -> bool {
        self.failed.is_some() || self.mismatch
    }

    /// Requests the memory the rows of the next `now` work items will be written to, and
    /// prepares the same for the `later` items after them (a hint: no row changes; best called
    /// once per group of `now` rows, with `later` about the next group's size).
    #[inline]
    pub(crate) fn prefetch(&self, now: usize, later: usize) {
        if let Some(direct) = &self.direct {
            direct.prefetch(now, later);
        }
    }

    /// Appends the row of the next work item: `len` pairs `(sq_dist, index)`.
    #[inline]
    pub(crate) fn push_row(&mut self, len: usize, row: impl Iterator<Item = (T, u32)>) {
        if self.is_done() {
            return;
        }
        if let Some(direct) = &mut self.direct {
            match direct.next_slot(len) {
                Some((ids, dists)) => {
                    for ((id, d), (sd, i)) in ids.iter_mut().zip(dists.iter_mut()).zip(row) {
                        (*id, *d) = (i, sd);
                    }
                }
                None => self.mismatch = true,
            }
            return;
        }
        if !self.reserve(len) {
            return;
        }
        let at = self.ids.len();
        for (sd, i) in row.take(len) {
            self.ids.push(i);
            self.dists.push(sd);
        }
        let len = self.ids.len() - at;
        self.rows.push(RowSource {
            at,
            len,
            skip: usize::MAX,
        });
    }

    /// Appends the rows of the next `own.len()` work items, copies of one point: each the
    /// shared row `ids`/`dists` less the entry of its own index (if the row holds it). The
    /// shared row is stored once; each member's row is written only into the final table.
    pub(crate) fn push_shared(&mut self, ids: &[u32], dists: &[T], own: &[u32]) {
        if self.is_done() {
            return;
        }
        let skip_of = |o: u32| ids.iter().position(|&i| i == o).unwrap_or(usize::MAX);
        if let Some(direct) = &mut self.direct {
            for &o in own {
                let skip = skip_of(o);
                let (before, after) = if skip < ids.len() {
                    (skip, skip + 1)
                } else {
                    (ids.len(), ids.len())
                };
                let len = before + ids.len() - after;
                match direct.next_slot(len) {
                    Some((out_ids, out_dists)) => {
                        out_ids[..before].copy_from_slice(&ids[..before]);
                        out_ids[before..].copy_from_slice(&ids[after..]);
                        out_dists[..before].copy_from_slice(&dists[..before]);
                        out_dists[before..].copy_from_slice(&dists[after..]);
                    }
                    None => {
                        self.mismatch = true;
                        return;
                    }
                }
            }
            return;
        }
        if !self.reserve(ids.len()) || self.rows.try_reserve(own.len()).is_err() {
            self.failed.get_or_insert(0);
            return;
        }
        let at = self.ids.len();
        self.ids.extend_from_slice(ids);
        self.dists.extend_from_slice(dists);
        for &o in own {
            self.rows.push(RowSource {
                at,
                len: ids.len(),
                skip: skip_of(o),
            });
        }
    }

    /// Makes room in the buffers for one more row of `len` neighbours; `false` (and the
    /// failure recorded) if the memory cannot be had — the allocator refuses, or the rows of
    /// all tables being computed would exceed the machine's memory ([`memory_limit`]).
    #[inline]
    fn reserve(&mut self, len: usize) -> bool {
        let needed = self.ids.len() as u128 + len as u128;
        if needed > self.ids.capacity() as u128 {
            // the buffers grow (at least doubling): count the new capacity
            let grown = (needed.max(2 * self.ids.capacity() as u128) * entry_bytes::<T>())
                .min(u128::from(u64::MAX)) as u64;
            let extra = grown.saturating_sub(self.counted);
            let before = IN_CHUNKS.fetch_add(extra, Ordering::Relaxed);
            self.counted += extra;
            let want = needed.max(2 * self.ids.capacity() as u128) as usize;
            let fits = u128::from(before) + u128::from(extra) <= memory_limit()
                && self.ids.try_reserve(want - self.ids.len()).is_ok()
                && self.dists.try_reserve(want - self.dists.len()).is_ok();
            if !fits {
                self.failed = Some(needed * entry_bytes::<T>());
                return false;
            }
        }
        if self.rows.try_reserve(1).is_err() {
            self.failed = Some(needed * entry_bytes::<T>());
            return false;
        }
        true
    }
}

impl<T> Drop for RowsChunk<'_, T> {
    fn drop(&mut self) {
        IN_CHUNKS.fetch_sub(self.counted, Ordering::Relaxed);
    }
}

/// Bytes held by the rows of tables being computed, in the whole process.
static IN_CHUNKS: AtomicU64 = AtomicU64::new(0);

/// Bytes of one table entry: an index and a squared distance.
fn entry_bytes<T>() -> u128 {
    (std::mem::size_of::<u32>() + std::mem::size_of::<T>()) as u128
}

/// The most a table may need: the machine's physical memory plus swap, as the system reports
/// it (`u128::MAX` where it does not). A table's rows are gathered per chunk on several
/// threads at once, each piece below what the allocator would refuse on its own; their sum
/// must not run the process into the system's out-of-memory killer, so it is bounded here.
fn memory_limit() -> u128 {
    static LIMIT: OnceLock<u128> = OnceLock::new();
    *LIMIT.get_or_init(|| {
        #[cfg(target_os = "linux")]
        {
            // SAFETY: an all-zero sysinfo is a valid value of the plain C struct.
            let mut info: libc::sysinfo = unsafe { std::mem::zeroed() };
            // SAFETY: `info` is a valid, writable sysinfo struct; the call only writes it.
            if unsafe { libc::sysinfo(&mut info) } == 0 {
                let unit = u128::from(info.mem_unit.max(1));
                return (info.totalram as u128 + info.totalswap as u128) * unit;
            }
        }
        u128::MAX
    })
}

/// Refuses, before any search, a k-nearest table whose size is known in advance and cannot
/// fit: every row of a `Knn { k }` table holds `min(k, points − 1)` neighbours (with the point
/// itself excluded) or `min(k, points)`, so `rows × that` entries are needed
/// ([`NbhdError::OutOfMemory`] with the bytes). `k` never usefully exceeds the number of points.
pub(crate) fn check_knn_total<T: Scalar>(
    rows: usize,
    points: usize,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
) -> Result<()> {
    if let Neighborhood::Knn { k } = nbhd {
        let per_row = k.min(points.saturating_sub(usize::from(exclude_self)));
        let bytes = rows as u128 * per_row as u128 * entry_bytes::<T>();
        if bytes > memory_limit() || bytes > isize::MAX as u128 {
            return Err(NbhdError::OutOfMemory {
                what: "the k-nearest neighbour table (rows × min(k, points) entries of an index \
                       and a squared distance)",
                bytes,
            });
        }
    }
    Ok(())
}

/// Options of the all-point neighbourhood table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableOptions {
    /// Leave each point out of its own row (the default, as smoothing and normals need).
    pub exclude_self: bool,
    /// Worker threads: 0 uses the current rayon pool. The table is identical for any value.
    pub threads: usize,
    /// How each row's query measures (metric, eps, strict radius; default exact Euclidean):
    /// the rows are then those of `NeighborIndex::search_with` (`src/index/`),
    /// and `sq_dists` hold the metric's keys.
    pub query: QueryOptions,
}

impl Default for TableOptions {
    fn default() -> Self {
        Self {
            exclude_self: true,
            threads: 0,
            query: QueryOptions::default(),
        }
    }
}

/// The neighbourhood of every stored point of `searcher` (row `i` for caller index `i`;
/// points skipped at build time get empty rows), with or without the point itself, computed
/// in parallel in the current rayon pool. The bytes are identical for any number of threads:
/// rows are computed independently and concatenated in index order.
pub fn neighborhoods_of_all<T: Scalar, S: NeighborSearch<T> + ?Sized>(
    searcher: &S,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
) -> Result<NeighborTable<T>> {
    check_knn_total(
        searcher.source_len(),
        searcher.source_len(),
        nbhd,
        exclude_self,
    )?;
    rows_in_parallel(
        searcher.source_len(),
        |i, row, _| {
            let query = Query::Stored {
                index: i as u32,
                exclude_self,
            };
            match searcher.search(query, nbhd, row) {
                Err(NbhdError::SkippedPoint { .. }) => {
                    row.clear();
                    Ok(())
                }
                other => other,
            }
        },
        nbhd,
    )
}

/// The neighbourhoods of the points of `queries` (row `i` for query `i`), in parallel.
pub fn neighborhoods_of_points<T: Scalar, S: NeighborSearch<T> + ?Sized>(
    searcher: &S,
    queries: &crate::points::PointsView<'_>,
    nbhd: Neighborhood<T>,
) -> Result<NeighborTable<T>> {
    if queries.dim() != searcher.dim() {
        return Err(NbhdError::DimensionMismatch {
            expected: searcher.dim(),
            got: queries.dim(),
        });
    }
    check_knn_total(queries.len(), searcher.source_len(), nbhd, false)?;
    let d = queries.dim();
    rows_in_parallel(
        queries.len(),
        |i, row, q| {
            q.resize(d, T::ZERO);
            queries.read_point(i, q);
            searcher
                .search(Query::point(q), nbhd, row)
                .map_err(|e| e.for_query(i))
        },
        nbhd,
    )
}

/// Runs `query(i, row, scratch)` for rows `0..n` in fixed chunks on the current rayon pool and joins
/// the rows in order, so the table does not depend on the number of threads.
fn rows_in_parallel<T: Scalar>(
    n: usize,
    query: impl Fn(usize, &mut Vec<Neighbor<T>>, &mut Vec<T>) -> Result<()> + Sync,
    nbhd: Neighborhood<T>,
) -> Result<NeighborTable<T>> {
    nbhd.validate()?;
    rows_in_work_order(n, n, |w| w, query)
}

/// Runs `query(w, row, scratch)` for the work items `w` in `0..work` in fixed chunks on the
/// current rayon pool, and places the row of item `w` at table row `row_of(w)` (rows no item
/// maps to stay empty). The work order is free — the tree answers its own points in tree order
/// for cache locality — while the table comes out in row order, identical for any number of
/// threads. Rows are gathered in per-chunk buffers that grow as needed: no allocation per row.
pub(crate) fn rows_in_work_order<T: Scalar>(
    rows: usize,
    work: usize,
    row_of: impl Fn(usize) -> usize + Sync,
    query: impl Fn(usize, &mut Vec<Neighbor<T>>, &mut Vec<T>) -> Result<()> + Sync,
) -> Result<NeighborTable<T>> {
    let bounds: Vec<usize> = (0..work.div_ceil(CHUNK))
        .map(|c| c * CHUNK)
        .chain(std::iter::once(work))
        .collect();
    rows_in_chunks(rows, &bounds, row_of, None, |c, chunk| {
        let mut row: Vec<Neighbor<T>> = Vec::new();
        let mut scratch: Vec<T> = Vec::new();
        for w in bounds[c]..bounds[c + 1] {
            query(w, &mut row, &mut scratch)?;
            chunk.push_row(row.len(), row.iter().map(|nb| (nb.sq_dist, nb.index)));
            if chunk.is_done() {
                break;
            }
        }
        Ok(())
    })
}

/// Runs `fill(c, rows)` for the chunks `c` of work items `bounds[c]..bounds[c + 1]` on the
/// current rayon pool; `fill` appends the rows of its items, in work order, to `rows`. The row
/// of item `w` goes to table row `row_of(w)` (rows no item maps to stay empty). The chunks are
/// fixed by `bounds`, not by the threads, and each row is computed on its own, so the table is
/// identical for any number of threads.
///
/// With `row_len = Some(len)` every work item's row holds `len` entries (k-nearest tables):
/// the offsets are known before any search, and the rows are written once, straight into
/// their place in the table. Otherwise (or should a row not have that length) they are
/// collected in per-chunk buffers and gathered into the table afterwards.
pub(crate) fn rows_in_chunks<T: Scalar>(
    rows: usize,
    bounds: &[usize],
    row_of: impl Fn(usize) -> usize + Sync,
    row_len: Option<usize>,
    fill: impl Fn(usize, &mut RowsChunk<'_, T>) -> Result<()> + Sync,
) -> Result<NeighborTable<T>> {
    if let Some(len) = row_len.filter(|&l| l > 0) {
        if let Some(table) = rows_in_place(rows, bounds, &row_of, len, &fill)? {
            return Ok(table);
        }
    }
    let chunks = fill_chunks(bounds, &fill)?;
    let (offsets, source) = row_sources(rows, bounds, &row_of, &chunks)?;
    let (indices, sq_dists) = gather_rows(&offsets, &source, &chunks)?;
    Ok(NeighborTable {
        offsets,
        indices,
        sq_dists,
    })
}

/// The buffered rows of each chunk of [`rows_in_chunks`], filled in parallel; once one chunk's
/// rows did not fit, the chunks not yet started skip their work and the table is refused.
fn fill_chunks<'a, T: Scalar>(
    bounds: &[usize],
    fill: &(dyn Fn(usize, &mut RowsChunk<'a, T>) -> Result<()> + Sync),
) -> Result<Vec<RowsChunk<'a, T>>> {
    let out_of_memory = AtomicBool::new(false);
    let chunks: Vec<Result<RowsChunk<'a, T>>> = (0..bounds.len().saturating_sub(1))
        .into_par_iter()
        .map(|c| {
            let mut chunk = RowsChunk::default();
            if out_of_memory.load(Ordering::Relaxed) {
                // another chunk's rows did not fit: the table is refused, skip the work
                chunk.failed = Some(0);
                return Ok(chunk);
            }
            fill(c, &mut chunk)?;
            if chunk.failed.is_some() {
                out_of_memory.store(true, Ordering::Relaxed);
            }
            Ok(chunk)
        })
        .collect();
    let chunks: Vec<RowsChunk<'a, T>> = chunks.into_iter().collect::<Result<_>>()?;
    if let Some(failed) = chunks.iter().filter_map(|c| c.failed).max() {
        // The rows of one chunk did not fit; the whole table needs about that much for every
        // chunk (an estimate from the failing chunk's share of the rows).
        let n_chunks = bounds.len().saturating_sub(1).max(1) as u128;
        return Err(NbhdError::OutOfMemory {
            what: "the neighbour table (estimated from the rows of the first chunk that did \
                   not fit, times the number of chunks)",
            bytes: failed.saturating_mul(n_chunks),
        });
    }
    Ok(chunks)
}

/// Where a row of [`rows_in_chunks`] waits: its chunk and its row in that chunk.
type ChunkRow = (u32, usize);

/// The table's row offsets and, per row, its chunk and row in that chunk (the default for rows
/// no work item maps to); refused when the table would exceed the memory limit.
fn row_sources<T: Scalar>(
    rows: usize,
    bounds: &[usize],
    row_of: &(dyn Fn(usize) -> usize + Sync),
    chunks: &[RowsChunk<'_, T>],
) -> Result<(Vec<usize>, Vec<ChunkRow>)> {
    let mut offsets = try_zeroed::<usize>(rows + 1, "the table's row offsets")?;
    let mut source = try_filled(rows, (0u32, 0usize), "the table's row sources")?;
    for (c, chunk) in chunks.iter().enumerate() {
        for (j, s) in chunk.rows.iter().enumerate() {
            let r = row_of(bounds[c] + j);
            offsets[r + 1] = s.row_len();
            source[r] = (c as u32, j);
        }
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    let total = offsets[rows];
    let table_bytes = total as u128 * entry_bytes::<T>();
    if u128::from(IN_CHUNKS.load(Ordering::Relaxed)) + table_bytes > memory_limit() {
        return Err(NbhdError::OutOfMemory {
            what: "the neighbour table",
            bytes: table_bytes,
        });
    }
    Ok((offsets, source))
}

/// The indices and squared distances of the table with row `offsets`, gathered in parallel from
/// the chunks' buffers (each row's entry `skip` dropped).
fn gather_rows<T: Scalar>(
    offsets: &[usize],
    source: &[ChunkRow],
    chunks: &[RowsChunk<'_, T>],
) -> Result<(Vec<u32>, Vec<T>)> {
    let rows = offsets.len() - 1;
    let total = offsets[rows];
    // Filled in parallel, by blocks of consecutive rows: each block is one contiguous piece of
    // the output, gathered from the chunks. (The buffers are reserved fallibly and filled by
    // the workers, so their pages are first touched in parallel, too.)
    let (mut indices, mut sq_dists) = (
        try_filled_par(total, 0u32, "the neighbour table (indices)")?,
        try_filled_par(total, T::ZERO, "the neighbour table (squared distances)")?,
    );
    let mut blocks = Vec::with_capacity(rows.div_ceil(ROW_BLOCK));
    let (mut ids_rest, mut dists_rest) = (&mut indices[..], &mut sq_dists[..]);
    for first in (0..rows).step_by(ROW_BLOCK) {
        let end = (first + ROW_BLOCK).min(rows);
        let len = offsets[end] - offsets[first];
        let (ids, ir) = std::mem::take(&mut ids_rest).split_at_mut(len);
        let (dists, dr) = std::mem::take(&mut dists_rest).split_at_mut(len);
        (ids_rest, dists_rest) = (ir, dr);
        blocks.push((first..end, ids, dists));
    }
    // A row's chunk and entry there, for the hints ahead of the copy: `None` past the table and
    // for rows no work item wrote (empty ones, whose source is the default).
    let source_of = |r: usize| {
        let &(c, j) = source.get(r)?;
        let chunk = chunks.get(c as usize)?;
        Some((chunk, chunk.rows.get(j)?))
    };
    blocks.into_par_iter().for_each(|(block, ids, dists)| {
        let base = offsets[block.start];
        let end = block.end;
        for r in block {
            // the sources are scattered over the chunks (tree order): request a row's source
            // entry two steps ahead and its entries one step ahead
            if let Some((_, s)) =
                source_of(r + 2 * GATHER_AHEAD).filter(|_| r + 2 * GATHER_AHEAD < end)
            {
                prefetch_range(std::slice::from_ref(s));
            }
            if let Some((chunk, s)) = source_of(r + GATHER_AHEAD).filter(|_| r + GATHER_AHEAD < end)
            {
                prefetch_range(&chunk.ids[s.at..s.at + s.len]);
                prefetch_range(&chunk.dists[s.at..s.at + s.len]);
            }
            let (from, to) = (offsets[r] - base, offsets[r + 1] - base);
            if from == to {
                continue;
            }
            let (c, j) = source[r];
            let chunk = &chunks[c as usize];
            let s = chunk.rows[j];
            let (src_ids, src_dists) = (
                &chunk.ids[s.at..s.at + s.len],
                &chunk.dists[s.at..s.at + s.len],
            );
            let before = s.skip.min(s.len);
            let after = (before + 1).min(s.len);
            let mid = from + before;
            ids[from..mid].copy_from_slice(&src_ids[..before]);
            ids[mid..to].copy_from_slice(&src_ids[after..]);
            dists[from..mid].copy_from_slice(&src_dists[..before]);
            dists[mid..to].copy_from_slice(&src_dists[after..]);
        }
    });
    Ok((indices, sq_dists))
}

/// Rows ahead whose source entries [`rows_in_chunks`] requests while it gathers a row.
const GATHER_AHEAD: usize = 8;

/// [`rows_in_chunks`] for rows of `len` entries each, written in place; `None` (nothing
/// written that counts) if two work items map to one row or a row turned out to have another
/// length, for the caller to build the table through the buffers instead.
fn rows_in_place<T: Scalar>(
    rows: usize,
    bounds: &[usize],
    row_of: &(dyn Fn(usize) -> usize + Sync),
    len: usize,
    fill: &(dyn Fn(usize, &mut RowsChunk<'_, T>) -> Result<()> + Sync),
) -> Result<Option<NeighborTable<T>>> {
    let work = bounds.first().copied().unwrap_or(0)..bounds.last().copied().unwrap_or(0);
    let mut offsets = try_zeroed::<usize>(rows + 1, "the table's row offsets")?;
    for w in work {
        let r = row_of(w);
        if offsets[r + 1] != 0 {
            return Ok(None);
        }
        offsets[r + 1] = len;
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    let total = offsets[rows];
    let (mut indices, mut sq_dists) = (
        try_filled_par(total, 0u32, "the neighbour table (indices)")?,
        try_filled_par(total, T::ZERO, "the neighbour table (squared distances)")?,
    );
    let table = InPlace {
        ids: indices.as_mut_ptr(),
        dists: sq_dists.as_mut_ptr(),
        total,
    };
    let mismatch = AtomicBool::new(false);
    (0..bounds.len().saturating_sub(1))
        .into_par_iter()
        .try_for_each(|c| {
            let mut chunk = RowsChunk::default();
            chunk.direct = Some(Direct {
                table: &table,
                offsets: &offsets,
                row_of,
                next: bounds[c],
                end: bounds[c + 1],
            });
            fill(c, &mut chunk)?;
            let written = chunk.direct.as_ref().map_or(0, |d| d.next);
            if chunk.mismatch || written != bounds[c + 1] {
                mismatch.store(true, Ordering::Relaxed);
            }
            Ok::<_, NbhdError>(())
        })?;
    // `table`'s pointers are not used past this point (the workers are done): the vectors
    // are whole again.
    if mismatch.load(Ordering::Relaxed) {
        return Ok(None);
    }
    Ok(Some(NeighborTable {
        offsets,
        indices,
        sq_dists,
    }))
}

/// `n` copies of `value` in a vector allocated fallibly: [`NbhdError::OutOfMemory`] naming
/// `what` and the bytes when the memory cannot be had.
pub(crate) fn try_filled<V: Clone>(n: usize, value: V, what: &'static str) -> Result<Vec<V>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| NbhdError::OutOfMemory {
        what,
        bytes: n as u128 * std::mem::size_of::<V>() as u128,
    })?;
    v.resize(n, value);
    Ok(v)
}

/// [`try_filled`] filled by the workers of the current pool, so that the pages are first
/// touched (and placed) by the threads that write the table next.
pub(crate) fn try_filled_par<V: Copy + Send + Sync>(
    n: usize,
    value: V,
    what: &'static str,
) -> Result<Vec<V>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| NbhdError::OutOfMemory {
        what,
        bytes: n as u128 * std::mem::size_of::<V>() as u128,
    })?;
    v.par_extend(rayon::iter::repeat_n(value, n));
    Ok(v)
}

/// [`try_filled`] with zeros (`Default`).
pub(crate) fn try_zeroed<V: Clone + Default>(n: usize, what: &'static str) -> Result<Vec<V>> {
    try_filled(n, V::default(), what)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_validation() {
        let t = NeighborTable::from_parts(vec![0, 2, 2, 3], vec![1, 2, 0], vec![1.0, 2.0, 3.0])
            .unwrap();
        assert_eq!(t.len(), 3);
        assert_eq!(t.indices_of(0), &[1, 2]);
        assert!(t.indices_of(1).is_empty());
        assert_eq!(t.sq_dists_of(2), &[3.0]);
        assert_eq!((t.min_row_len(), t.max_row_len()), (0, 2));
        assert!(NeighborTable::<f32>::from_parts(vec![0, 2], vec![1], vec![1.0]).is_none());
        assert!(NeighborTable::<f32>::from_parts(vec![1, 1], vec![], vec![]).is_none());
        assert_eq!(
            t.into_parts(),
            (vec![0, 2, 2, 3], vec![1, 2, 0], vec![1.0, 2.0, 3.0])
        );
    }
}

#[cfg(test)]
mod table_build_tests {
    use super::*;
    use crate::{BruteForce, NonFinitePolicy, PointsView};

    #[test]
    fn all_point_table_matches_single_queries_and_skips() {
        let pts = [0.0f64, 0.0, 1.0, 0.0, f64::NAN, 0.0, 3.0, 0.0, 1.5, 0.0];
        let view = PointsView::from_flat(&pts, 2).unwrap();
        let bf = BruteForce::<f64>::new(&view, NonFinitePolicy::Skip).unwrap();
        let t = neighborhoods_of_all(&bf, Neighborhood::Knn { k: 2 }, true).unwrap();
        assert_eq!(t.len(), 5);
        assert_eq!(t.indices_of(0), &[1, 4]);
        assert!(t.indices_of(2).is_empty());
        assert_eq!(t.indices_of(3), &[4, 1]);
        assert_eq!(t.sq_dists_of(4), &[0.25, 2.25]);
    }
}
