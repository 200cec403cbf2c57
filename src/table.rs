//! Neighbourhood tables: the neighbourhoods of many query points (usually every point of a
//! tree) as compressed rows, `offsets` + caller `indices` + `sq_dists`, row `i` belonging to
//! query `i` (for a tree's own points: the caller's point `i`; skipped points get empty rows).

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

use crate::error::Result;
use crate::query::{Neighbor, NeighborSearch, Neighborhood, Query};
use crate::scalar::Scalar;
use rayon::prelude::*;

/// Queries per parallel work item: large enough to amortise scheduling, small enough to
/// balance two to dozens of threads.
const CHUNK: usize = 1024;

/// Row lengths, neighbour indices and squared distances of one chunk of queries.
type RowsChunk<T> = (Vec<usize>, Vec<u32>, Vec<T>);

/// The neighbourhood of every stored point of `searcher` (row `i` for caller index `i`;
/// points skipped at build time get empty rows), with or without the point itself, computed
/// in parallel in the current rayon pool. The bytes are identical for any number of threads:
/// rows are computed independently and concatenated in index order.
pub fn neighborhoods_of_all<T: Scalar, S: NeighborSearch<T> + ?Sized>(
    searcher: &S,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
) -> Result<NeighborTable<T>> {
    nbhd.validate()?;
    let n = searcher.source_len();
    let chunks: Vec<Result<RowsChunk<T>>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut row: Vec<Neighbor<T>> = Vec::new();
            let (mut lens, mut ids, mut dists) = (Vec::new(), Vec::new(), Vec::new());
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let query = Query::Stored {
                    index: i as u32,
                    exclude_self,
                };
                match searcher.search(query, nbhd, &mut row) {
                    Ok(()) => {}
                    Err(crate::NbhdError::SkippedPoint { .. }) => row.clear(),
                    Err(e) => return Err(e),
                }
                lens.push(row.len());
                ids.extend(row.iter().map(|nb| nb.index));
                dists.extend(row.iter().map(|nb| nb.sq_dist));
            }
            Ok((lens, ids, dists))
        })
        .collect();
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0);
    let (mut indices, mut sq_dists) = (Vec::new(), Vec::new());
    for chunk in chunks {
        let (lens, ids, dists) = chunk?;
        for len in lens {
            offsets.push(offsets.last().copied().unwrap_or(0) + len);
        }
        indices.extend_from_slice(&ids);
        sq_dists.extend_from_slice(&dists);
    }
    Ok(NeighborTable {
        offsets,
        indices,
        sq_dists,
    })
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
