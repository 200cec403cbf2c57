//! The pivot policies (thesis Algorithm 4, Section 5.4, eq. 5.1, and sliding midpoint) as one
//! decision: given the facts about a node's points, which dimension to split and how many points
//! go to the left. The selection build and the presorted build answer the facts differently
//! (a scan versus the ends of sorted lists) but decide identically, so they build the same
//! tree.

use super::options::PivotPolicy;
use crate::scalar::Scalar;

/// What the policies need to know about the points of a node.
pub(crate) trait NodeFacts<T> {
    /// Number of points (≥ 2).
    fn len(&self) -> usize;
    /// Smallest and largest coordinate in dimension `dim`.
    fn range(&self, dim: usize) -> (T, T);
    /// Number of points whose coordinate in `dim` is `< value`.
    fn count_below(&self, dim: usize, value: T) -> usize;
    /// The coordinate value in `dim` closest to `target` (the lower one on a tie).
    fn closest(&self, dim: usize, target: T) -> T;
}

/// A split: the dimension and the rank of the first point of the right child in the
/// composite (lexicographic) order of that dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Split {
    pub dim: usize,
    pub rank: usize,
}

/// Decides the split of a node at `depth` with `d` dimensions. The rank is always in
/// `1..n`, so both children are non-empty and every build terminates.
pub(crate) fn choose_split<T: Scalar>(
    policy: PivotPolicy,
    depth: usize,
    d: usize,
    facts: &impl NodeFacts<T>,
) -> Split {
    let n = facts.len();
    let median = n / 2;
    if policy == PivotPolicy::CyclicMedian {
        return Split {
            dim: depth % d,
            rank: median,
        };
    }
    // The dimension of largest spread, the lowest on a tie.
    let (mut dim, mut lo, mut hi) = (0, T::ZERO, T::ZERO);
    let mut spread = T::ZERO;
    for j in 0..d {
        let (l, h) = facts.range(j);
        if j == 0 || h - l > spread {
            (dim, lo, hi, spread) = (j, l, h, h - l);
        }
    }
    if spread <= T::ZERO {
        // All points coincide: only the index order tells them apart; halve by it.
        return Split {
            dim: depth % d,
            rank: median,
        };
    }
    let half = T::from_f64(0.5);
    let middle = lo * half + hi * half;
    let rank = match policy {
        PivotPolicy::CyclicMedian | PivotPolicy::SpreadMedian => median,
        PivotPolicy::ClosestToMiddle => {
            // eq. 5.1: the pivot is the (lexicographically first) point whose coordinate is
            // closest to the middle; it starts the right child.
            facts.count_below(dim, facts.closest(dim, middle))
        }
        PivotPolicy::SlidingMidpoint => facts.count_below(dim, middle),
    };
    Split {
        dim,
        rank: rank.clamp(1, n - 1),
    }
}

/// `true` if slot `a` precedes slot `b` in the composite coordinate order starting at
/// dimension `start` (thesis Definition 4, Algorithm 5), with the slot (which increases with
/// the caller's index) as the final tie-break instead of a hash code.
#[inline]
pub(crate) fn lex_less<T: Scalar>(coords: &[T], d: usize, a: u32, b: u32, start: usize) -> bool {
    let (pa, pb) = (a as usize * d, b as usize * d);
    let mut j = start;
    for _ in 0..d {
        let (x, y) = (coords[pa + j], coords[pb + j]);
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
    a < b
}
