//! Neighbourhood tables: the neighbourhoods of many query points (usually every point of a
//! tree) as compressed rows, `offsets` + caller `indices` + `sq_dists`, row `i` belonging to
//! query `i` (for a tree's own points: the caller's point `i`; skipped points get empty rows).

use crate::error::Result;
use crate::query::{Neighbor, NeighborSearch, Neighborhood, Query};
use crate::scalar::Scalar;
use rayon::prelude::*;

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

/// Row lengths, neighbour indices and squared distances of one chunk of queries.
pub(crate) type RowsChunk<T> = (Vec<usize>, Vec<u32>, Vec<T>);

/// Options of the all-point neighbourhood table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TableOptions {
    /// Leave each point out of its own row (the default, as smoothing and normals need).
    pub exclude_self: bool,
    /// Worker threads: 0 uses the current rayon pool. The table is identical for any value.
    pub threads: usize,
}

impl Default for TableOptions {
    fn default() -> Self {
        Self {
            exclude_self: true,
            threads: 0,
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
    rows_in_parallel(
        searcher.source_len(),
        |i, row, _| {
            let query = Query::Stored {
                index: i as u32,
                exclude_self,
            };
            match searcher.search(query, nbhd, row) {
                Err(crate::NbhdError::SkippedPoint { .. }) => {
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
    queries: &crate::PointsView<'_>,
    nbhd: Neighborhood<T>,
) -> Result<NeighborTable<T>> {
    if queries.dim() != searcher.dim() {
        return Err(crate::NbhdError::DimensionMismatch {
            expected: searcher.dim(),
            got: queries.dim(),
        });
    }
    let d = queries.dim();
    rows_in_parallel(
        queries.len(),
        |i, row, q| {
            q.resize(d, T::ZERO);
            queries.read_point(i, q);
            searcher.search(Query::point(q), nbhd, row)
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
    rows_in_chunks(rows, &bounds, row_of, |c, (lens, ids, dists)| {
        let mut row: Vec<Neighbor<T>> = Vec::new();
        let mut scratch: Vec<T> = Vec::new();
        for w in bounds[c]..bounds[c + 1] {
            query(w, &mut row, &mut scratch)?;
            lens.push(row.len());
            ids.extend(row.iter().map(|nb| nb.index));
            dists.extend(row.iter().map(|nb| nb.sq_dist));
        }
        Ok(())
    })
}

/// Runs `fill(c, rows)` for the chunks `c` of work items `bounds[c]..bounds[c + 1]` on the
/// current rayon pool; `fill` appends the rows of its items, in work order, to `rows`. The row
/// of item `w` goes to table row `row_of(w)` (rows no item maps to stay empty). The chunks are
/// fixed by `bounds`, not by the threads, and each row is computed on its own, so the table is
/// identical for any number of threads.
pub(crate) fn rows_in_chunks<T: Scalar>(
    rows: usize,
    bounds: &[usize],
    row_of: impl Fn(usize) -> usize + Sync,
    fill: impl Fn(usize, &mut RowsChunk<T>) -> Result<()> + Sync,
) -> Result<NeighborTable<T>> {
    let chunks: Vec<Result<RowsChunk<T>>> = (0..bounds.len().saturating_sub(1))
        .into_par_iter()
        .map(|c| {
            let mut chunk = (Vec::new(), Vec::new(), Vec::new());
            fill(c, &mut chunk)?;
            Ok(chunk)
        })
        .collect();
    let chunks: Vec<RowsChunk<T>> = chunks.into_iter().collect::<Result<_>>()?;
    // Where each row is: its length and its chunk and start in that chunk's buffers.
    let mut offsets = vec![0usize; rows + 1];
    let mut source = vec![(0u32, 0usize); rows];
    for (c, (lens, _, _)) in chunks.iter().enumerate() {
        let mut at = 0;
        for (j, &len) in lens.iter().enumerate() {
            let r = row_of(bounds[c] + j);
            offsets[r + 1] = len;
            source[r] = (c as u32, at);
            at += len;
        }
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    let total = offsets[rows];
    // Filled in parallel, by blocks of consecutive rows: each block is one contiguous piece of
    // the output, gathered from the chunks. (The zeroed buffers come from the allocator as
    // untouched pages, so they are first written here, by the workers, too.)
    let (mut indices, mut sq_dists) = (vec![0u32; total], vec![T::ZERO; total]);
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
    blocks.into_par_iter().for_each(|(block, ids, dists)| {
        let base = offsets[block.start];
        for r in block {
            let (from, to) = (offsets[r] - base, offsets[r + 1] - base);
            if from == to {
                continue;
            }
            let (c, at) = source[r];
            let (_, chunk_ids, chunk_dists) = &chunks[c as usize];
            ids[from..to].copy_from_slice(&chunk_ids[at..at + to - from]);
            dists[from..to].copy_from_slice(&chunk_dists[at..at + to - from]);
        }
    });
    Ok(NeighborTable {
        offsets,
        indices,
        sq_dists,
    })
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
