//! The box query's convention, shared by the index (`src/index/in_box.rs`, over the tree's
//! `src/tree/boxes.rs`) and the brute-force reference: a **closed** axis-aligned box,
//! `min[j] ≤ x[j] ≤ max[j]` for every coordinate, compared in the searcher's scalar type.
//! Infinite bounds are allowed; a NaN bound or `min[j] > max[j]` is refused
//! ([`NbhdError::InvalidBox`]).

use crate::error::{NbhdError, Result};
use crate::scalar::Scalar;

/// Checks one box: `dim` bounds each, no NaN, `min[j] ≤ max[j]`. `query` names the box of a
/// batch in the error.
pub(crate) fn check_box<T: Scalar>(
    min: &[T],
    max: &[T],
    dim: usize,
    query: Option<usize>,
) -> Result<()> {
    for got in [min.len(), max.len()] {
        if got != dim {
            return Err(NbhdError::DimensionMismatch { expected: dim, got });
        }
    }
    for (j, (&lo, &hi)) in min.iter().zip(max).enumerate() {
        // refused: a NaN bound (unordered) or an inverted one
        if lo
            .partial_cmp(&hi)
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
        {
            return Err(NbhdError::InvalidBox {
                query,
                coordinate: j,
                min: lo.to_f64(),
                max: hi.to_f64(),
            });
        }
    }
    Ok(())
}

/// `true` if `p` lies in the closed box.
#[inline]
pub(crate) fn in_closed_box<T: Scalar>(p: &[T], min: &[T], max: &[T]) -> bool {
    p.iter()
        .zip(min.iter().zip(max))
        .all(|(&x, (&lo, &hi))| lo <= x && x <= hi)
}
