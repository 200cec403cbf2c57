//! Box queries (thesis Section 3.2.3, the region query of Algorithms 2 and 3): the points of a
//! closed axis-aligned box, one box or a batch, over the flavour's box traversal
//! ([`NeighborIndex::visit_box`]).
//!
//! Convention (`src/query/in_box.rs`): the box is **closed**, a point `x` is inside when
//! `min[j] ≤ x[j] ≤ max[j]` for every coordinate `j`, compared in the index's scalar type.
//! Bounds may be infinite (a slab or a half-space); a NaN bound or `min[j] > max[j]` is refused
//! with [`NbhdError::InvalidBox`] (an inverted box is nearly always swapped corners, so it is
//! not silently empty). A zero-extent box (`min[j] = max[j]`) is valid and holds the points on
//! that plane. Results are the caller's indices, sorted ascending, identical for any thread
//! count.

use rayon::prelude::*;

use super::NeighborIndex;
use crate::error::{NbhdError, Result};
use crate::parallel::with_threads;
use crate::query::in_box::check_box;
use crate::scalar::Scalar;

/// Index rows, one per box of a batch: row `i` is `indices[offsets[i]..offsets[i + 1]]`,
/// the caller's indices of the points inside box `i`, ascending.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct IndexRows {
    offsets: Vec<usize>,
    indices: Vec<u32>,
}

impl IndexRows {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// `true` if there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i`: the caller's indices, ascending.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Row boundaries (`len() + 1` values, from 0 to `total()`).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// All indices, row after row.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Total number of indices over all rows.
    pub fn total(&self) -> usize {
        self.indices.len()
    }
}

/// [`NeighborIndex::in_box`].
pub(super) fn in_box<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    min: &[T],
    max: &[T],
    out: &mut Vec<u32>,
) -> Result<()> {
    check_box(min, max, index.dim(), None)?;
    out.clear();
    index.visit_box(min, max, &mut Vec::new(), out);
    out.sort_unstable();
    Ok(())
}

/// [`NeighborIndex::in_boxes`].
pub(super) fn in_boxes<T: Scalar, I: NeighborIndex<T>>(
    index: &I,
    boxes: &[T],
    threads: usize,
) -> Result<IndexRows> {
    let dim = index.dim();
    let per = 2 * dim;
    if boxes.len() % per != 0 {
        return Err(NbhdError::BufferTooSmall {
            what: "boxes (values; 2 * dim per box)",
            len: boxes.len(),
            needed: boxes.len().div_ceil(per) * per,
        });
    }
    let n = boxes.len() / per;
    let corners = |i: usize| boxes[i * per..(i + 1) * per].split_at(dim);
    for i in 0..n {
        let (min, max) = corners(i);
        check_box(min, max, dim, Some(i))?;
    }
    let rows: Vec<Vec<u32>> = with_threads(threads, || {
        (0..n)
            .into_par_iter()
            .with_min_len(16)
            .map_init(Vec::new, |scratch, i| {
                let (min, max) = corners(i);
                let mut row = Vec::new();
                index.visit_box(min, max, scratch, &mut row);
                row.sort_unstable();
                row
            })
            .collect()
    })?;
    let mut offsets = Vec::new();
    offsets
        .try_reserve_exact(n + 1)
        .map_err(|_| oom("the box rows' offsets", (n as u128 + 1) * 8))?;
    offsets.push(0);
    let mut total = 0usize;
    for r in &rows {
        total += r.len();
        offsets.push(total);
    }
    let mut indices = Vec::new();
    indices
        .try_reserve_exact(total)
        .map_err(|_| oom("the box rows' indices", total as u128 * 4))?;
    for r in rows {
        indices.extend_from_slice(&r);
    }
    Ok(IndexRows { offsets, indices })
}

fn oom(what: &'static str, bytes: u128) -> NbhdError {
    NbhdError::OutOfMemory { what, bytes }
}
