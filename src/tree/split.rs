//! The pivot policies (thesis Algorithm 4, Section 5.4, eq. 5.1, and sliding midpoint) as one
//! decision: given the facts about a node's points, which dimension to split and how many points
//! go to the left. The selection build and the presorted build answer the facts differently
//! (a scan versus the ends of sorted lists) but decide identically, so they build the same
//! tree.

use super::options::PivotPolicy;
use crate::scalar::Scalar;

/// What the policies need to know about the points of a node.
pub(crate) trait NodeFacts<T: Scalar> {
    /// Number of points (≥ 2).
    fn len(&self) -> usize;
    /// Smallest and largest coordinate in dimension `dim`.
    fn range(&self, dim: usize) -> (T, T);
    /// The coordinate value in `dim` closest to `target` (the lower one on a tie).
    fn closest(&self, dim: usize, target: T) -> T;
    /// The dimension of largest spread (the lowest on a tie) and its range.
    fn widest(&self, d: usize) -> (usize, T, T) {
        let (mut best, mut lo, mut hi) = (0, T::ZERO, T::ZERO);
        for j in 0..d {
            let (l, h) = self.range(j);
            if j == 0 || h - l > hi - lo {
                (best, lo, hi) = (j, l, h);
            }
        }
        (best, lo, hi)
    }
}

/// What a policy decided, before the points are moved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Plan<T> {
    /// Split at this rank of the composite order of `dim` (the median policies, and the
    /// fallback when all points coincide).
    Rank(Split),
    /// As [`Plan::Rank`], for a node whose points all coincide: the composite order is the
    /// index order, so a node sorted by index splits at the rank with no selection (and its
    /// children stay sorted).
    Coincident(Split),
    /// Points with coordinate `< value` in `dim` go left, the rest right, and the split
    /// value is `value` (sliding midpoint, closest to middle). If no point is below `value` (it
    /// is the node's smallest coordinate in `dim`), the threshold slides up to the next
    /// coordinate: the copies of the smallest go left ([`Below::SlideUp`]).
    Below {
        /// Dimension.
        dim: usize,
        /// Threshold.
        value: T,
    },
}

/// A split: the dimension and the rank of the first point of the right child in the
/// composite (lexicographic) order of that dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Split {
    pub dim: usize,
    pub rank: usize,
}

/// Decides the split of a node at `depth` with `d` dimensions. Ranks are in `1..n`, so both
/// children are non-empty and every build terminates. From depth `guard` on (see
/// [`super::options::max_unbalanced_depth`]) every policy splits at the median of the most
/// spread dimension, so that no input makes a tree deeper than `guard` plus a balanced tree.
pub(crate) fn choose_split<T: Scalar>(
    policy: PivotPolicy,
    depth: usize,
    guard: usize,
    d: usize,
    facts: &impl NodeFacts<T>,
) -> Plan<T> {
    let n = facts.len();
    let median = n / 2;
    let policy = if depth >= guard && !policy.is_balanced() {
        PivotPolicy::SpreadMedian
    } else {
        policy
    };
    if policy == PivotPolicy::CyclicMedian {
        return Plan::Rank(Split {
            dim: depth % d,
            rank: median,
        });
    }
    let (dim, lo, hi) = facts.widest(d);
    if hi - lo <= T::ZERO {
        // All points coincide: only the index order tells them apart; halve by it.
        return Plan::Coincident(Split {
            dim: depth % d,
            rank: median,
        });
    }
    let half = T::from_f64(0.5);
    let middle = lo * half + hi * half;
    match policy {
        PivotPolicy::CyclicMedian | PivotPolicy::SpreadMedian => {
            Plan::Rank(Split { dim, rank: median })
        }
        // eq. 5.1: the pivot is the (lexicographically first) point whose coordinate is
        // closest to the middle; it starts the right child.
        PivotPolicy::ClosestToMiddle => Plan::Below {
            dim,
            value: facts.closest(dim, middle),
        },
        PivotPolicy::SlidingMidpoint => Plan::Below { dim, value: middle },
    }
}

/// How a [`Plan::Below`] splits a node of `n` points when `below` are under its threshold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Below {
    /// Both sides hold points: the first `below` are the left child.
    Rank(usize),
    /// No point is below: the threshold is the node's smallest coordinate in the dimension.
    /// This is a tie, not a choice of the policy — the closest-to-middle pivot equally far
    /// from both ends of a node that holds two distinct values (thesis eq. 5.1 names no
    /// order among equals), or a midpoint rounded down onto the smaller of two neighbouring
    /// floats. The points at the smallest coordinate form the left child and the split value
    /// is the next coordinate above it, where the pivot's side then starts: one point per
    /// level split off instead made such nodes n/2 levels deep in O(n²) time.
    SlideUp,
    /// Every point is below (a threshold above the largest coordinate, which no policy
    /// gives): split at this rank of the composite order instead.
    Clamp(usize),
}

/// The [`Below`] case of `below` points under a threshold in a node of `n` points.
pub(crate) fn resolve_below(below: usize, n: usize) -> Below {
    match below {
        0 => Below::SlideUp,
        b if b < n => Below::Rank(b),
        _ => Below::Clamp(n - 1),
    }
}
