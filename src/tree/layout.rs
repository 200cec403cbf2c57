//! How a build reads the points it partitions: by slot into packed coordinates (any
//! dimension), or as compact records that carry their coordinates (small fixed dimensions,
//! the 3-D hot path), so that selections move contiguous records instead of chasing slots
//! across memory.

use crate::scalar::Scalar;

/// Access to the coordinates and the slot of a build item.
pub(crate) trait Layout<T: Scalar>: Sync {
    /// What the partitions move.
    type Item: Copy + Send + Sync;
    /// Dimension.
    fn dim(&self) -> usize;
    /// Coordinate `j` of `item`.
    fn coord(&self, item: &Self::Item, j: usize) -> T;
    /// Slot (position in the caller-ordered cloud; increases with the caller's index).
    fn slot(&self, item: &Self::Item) -> u32;

    /// `true` if `a` precedes `b` in the composite coordinate order starting at dimension
    /// `start` (thesis Definition 4, Algorithm 5), with the slot as the final tie-break
    /// instead of a hash code.
    #[inline]
    fn lex_less(&self, a: &Self::Item, b: &Self::Item, start: usize) -> bool {
        let d = self.dim();
        let mut j = start;
        for _ in 0..d {
            let (x, y) = (self.coord(a, j), self.coord(b, j));
            if x < y {
                return true;
            }
            if x > y {
                return false;
            }
            j += 1;
            if j == d {
                j = 0;
            }
        }
        self.slot(a) < self.slot(b)
    }
}

/// Items are slots into packed coordinates.
pub(crate) struct BySlot<'a, T> {
    pub coords: &'a [T],
    pub dim: usize,
}

impl<T: Scalar> Layout<T> for BySlot<'_, T> {
    type Item = u32;
    #[inline]
    fn dim(&self) -> usize {
        self.dim
    }
    #[inline]
    fn coord(&self, item: &u32, j: usize) -> T {
        self.coords[*item as usize * self.dim + j]
    }
    #[inline]
    fn slot(&self, item: &u32) -> u32 {
        *item
    }
}

/// A point's coordinates and slot, moved as one.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Record<T, const D: usize> {
    pub p: [T; D],
    pub slot: u32,
}

/// Items are [`Record`]s of dimension `D`.
pub(crate) struct Inline<const D: usize>;

impl<T: Scalar, const D: usize> Layout<T> for Inline<D> {
    type Item = Record<T, D>;
    #[inline]
    fn dim(&self) -> usize {
        D
    }
    #[inline]
    fn coord(&self, item: &Record<T, D>, j: usize) -> T {
        item.p[j]
    }
    #[inline]
    fn slot(&self, item: &Record<T, D>) -> u32 {
        item.slot
    }
}
