//! Orthogonal range (box) queries on the k-d tree: the region query of thesis Section 3.2.3
//! (Algorithms 2 and 3). The descent keeps the cell of each node (the box its splits bound,
//! starting from all of space); a subtree whose cell lies inside the query box is reported
//! whole (its points are one contiguous range in tree order), a subtree whose cell misses the
//! box is skipped, and the points of the leaves in between are tested one by one.
//!
//! Convention: the box is **closed**, a point `x` is inside when `min[j] ≤ x[j] ≤ max[j]` for
//! every coordinate `j`, compared in the tree's scalar type. Bounds may be infinite (a slab or
//! a half-space); a NaN bound or `min[j] > max[j]` is refused with [`NbhdError::InvalidBox`]
//! (an inverted box is nearly always swapped corners, so it is not silently empty). A
//! zero-extent box (`min[j] = max[j]`) is valid and holds the points on that plane. Results
//! are the caller's indices, sorted ascending, identical for any thread count.

use rayon::prelude::*;

use super::KdTree;
use crate::error::{NbhdError, Result};
use crate::parallel::with_threads;
use crate::query::region::{check_box, in_closed_box};
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

impl<T: Scalar> KdTree<T> {
    /// The caller's indices of all points in the closed box `min ≤ x ≤ max` (every
    /// coordinate), ascending, in `out` (cleared first). Errors: a bound slice of the wrong
    /// length ([`NbhdError::DimensionMismatch`]), a NaN bound or `min[j] > max[j]`
    /// ([`NbhdError::InvalidBox`]).
    pub fn in_box(&self, min: &[T], max: &[T], out: &mut Vec<u32>) -> Result<()> {
        check_box(min, max, self.dim, None)?;
        out.clear();
        self.collect_in_box(min, max, &mut Vec::new(), out);
        out.sort_unstable();
        Ok(())
    }

    /// The points in each box of a batch, in parallel on `threads` workers (0: the current
    /// pool), rows in the boxes' order, identical for any thread count. `boxes` holds
    /// `2 · dim` values per box: its `min` corner, then its `max` corner. Errors as
    /// [`KdTree::in_box`], naming the box; a length not a multiple of `2 · dim` is
    /// [`NbhdError::BufferTooSmall`].
    pub fn in_boxes(&self, boxes: &[T], threads: usize) -> Result<IndexRows> {
        let per = 2 * self.dim;
        if boxes.len() % per != 0 {
            return Err(NbhdError::BufferTooSmall {
                what: "boxes (values; 2 * dim per box)",
                len: boxes.len(),
                needed: boxes.len().div_ceil(per) * per,
            });
        }
        let n = boxes.len() / per;
        let corners = |i: usize| {
            let b = &boxes[i * per..(i + 1) * per];
            b.split_at(self.dim)
        };
        for i in 0..n {
            let (min, max) = corners(i);
            check_box(min, max, self.dim, Some(i))?;
        }
        let rows: Vec<Result<Vec<u32>>> = with_threads(threads, || {
            (0..n)
                .into_par_iter()
                .with_min_len(16)
                .map_init(Vec::new, |cells, i| {
                    let (min, max) = corners(i);
                    let mut row = Vec::new();
                    self.collect_in_box(min, max, cells, &mut row);
                    row.sort_unstable();
                    Ok(row)
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
            total += r.as_ref().map_or(0, |r| r.len());
            offsets.push(total);
        }
        let mut indices = Vec::new();
        indices
            .try_reserve_exact(total)
            .map_err(|_| oom("the box rows' indices", total as u128 * 4))?;
        for r in rows {
            indices.extend_from_slice(&r?);
        }
        Ok(IndexRows { offsets, indices })
    }

    /// Appends the caller's indices of the points in the box to `out`, unsorted. `cells` is
    /// scratch space: the pending subtrees' cells, `2 · dim` values each.
    fn collect_in_box(&self, min: &[T], max: &[T], cells: &mut Vec<T>, out: &mut Vec<u32>) {
        let d = self.dim;
        // pending subtrees: (node, first tree position); their cells on `cells`, lo then hi
        let mut stack: Vec<(u32, u32)> = vec![(0, 0)];
        cells.clear();
        cells.extend(std::iter::repeat_n(T::from_f64(f64::NEG_INFINITY), d));
        cells.extend(std::iter::repeat_n(T::INFINITY, d));
        while let Some((node, start)) = stack.pop() {
            let at = cells.len() - 2 * d;
            let n = self.nodes[node as usize];
            let (lo, hi) = cells[at..].split_at(d);
            if in_closed_box(lo, min, max) && in_closed_box(hi, min, max) {
                // the whole cell is inside: every point of the subtree (Algorithm 3's report)
                out.extend_from_slice(&self.ids[start as usize..n.b as usize]);
                cells.truncate(at);
                continue;
            }
            if n.is_leaf() {
                for i in n.a as usize..n.b as usize {
                    if in_closed_box(self.point_at(i), min, max) {
                        out.push(self.ids[i]);
                    }
                }
                cells.truncate(at);
                continue;
            }
            // left subtree: coordinates ≤ split; right subtree: coordinates ≥ split
            let (j, s) = (n.dim as usize, n.split);
            let (go_left, go_right) = (min[j] <= s, max[j] >= s);
            // the right child reuses the slot at `at`, the left one a copy above it (popped
            // first)
            match (go_left, go_right) {
                (true, true) => {
                    cells.extend_from_within(at..at + 2 * d);
                    cells[at + j] = cells[at + j].max_of(s);
                    stack.push((n.a, self.nodes[node as usize + 1].b));
                    let left = at + 2 * d;
                    cells[left + d + j] = cells[left + d + j].min_of(s);
                    stack.push((node + 1, start));
                }
                (false, true) => {
                    cells[at + j] = cells[at + j].max_of(s);
                    stack.push((n.a, self.nodes[node as usize + 1].b));
                }
                (true, false) => {
                    cells[at + d + j] = cells[at + d + j].min_of(s);
                    stack.push((node + 1, start));
                }
                (false, false) => cells.truncate(at),
            }
        }
    }
}

fn oom(what: &'static str, bytes: u128) -> NbhdError {
    NbhdError::OutOfMemory { what, bytes }
}
