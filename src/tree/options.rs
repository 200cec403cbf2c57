//! Build options of the k-d tree: pivot policy (thesis Sections 3.2, 5.4), median algorithm
//! (Section 3.3 and Chapter 6), leaf bucket size, non-finite policy and threads.

use crate::error::{NbhdError, Result};
use crate::named_option;
use crate::names::OptionName;
use crate::packed::NonFinitePolicy;

/// How a node chooses its splitting dimension and pivot.
///
/// Every policy splits a node's points by the composite-coordinate (lexicographic) order of
/// thesis 3.2.3 / 3.3.1 along the chosen dimension, with the caller's index as the last
/// tie-break, so duplicates and shared coordinates always split and the tree never degenerates
/// on them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum PivotPolicy {
    /// The thesis' default (Algorithm 4): dimensions in turn (depth mod d), split at the median.
    CyclicMedian,
    /// Median of the dimension of largest spread (Omohundro, thesis 5.4).
    SpreadMedian,
    /// The point closest to the middle of the most spread dimension (Moore, thesis eq. 5.1).
    /// Not balanced: depths grow large on surface samples (thesis Fig. 8.7).
    ClosestToMiddle,
    /// Sliding midpoint (ANN, nanoflann, FLANN): split the most spread dimension at the middle
    /// of the points' range; if one side would be empty, slide to the nearest point.
    #[default]
    SlidingMidpoint,
}

impl PivotPolicy {
    /// All policies, for tests and benchmarks.
    pub const ALL: [PivotPolicy; 4] = [
        PivotPolicy::CyclicMedian,
        PivotPolicy::SpreadMedian,
        PivotPolicy::ClosestToMiddle,
        PivotPolicy::SlidingMidpoint,
    ];

    /// `true` for the policies that split at the median, whose trees are balanced.
    pub fn is_balanced(self) -> bool {
        matches!(self, PivotPolicy::CyclicMedian | PivotPolicy::SpreadMedian)
    }
}

/// The depth from which the unbalanced policies ([`PivotPolicy::ClosestToMiddle`],
/// [`PivotPolicy::SlidingMidpoint`]) split at the median of the most spread dimension instead,
/// in a tree over `points` points: 4 ⌈log2 n⌉ + 64. As introsort turns to heapsort, this bounds
/// every build: no tree is deeper than this plus a balanced tree below it (⌈log2 n⌉ + 1), and
/// a build does O(n) work per level, O(n log n) in all. Surfaces, grids and duplicates never
/// come near it (closest to middle: 17-25 levels on the thesis' 77k-123k sets; the sets of
/// `tests/tree_degenerate.rs`); coordinates spread over hundreds of binary orders of magnitude,
/// on which each of these splits cuts off a few points, reach it.
pub fn max_unbalanced_depth(points: usize) -> usize {
    4 * points.max(1).next_power_of_two().trailing_zeros() as usize + 64
}

/// How the pivot of a node is found among its points. For a given pivot policy every
/// algorithm gives the identical tree (thesis 8.1); they differ in speed only.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum MedianAlgorithm {
    /// d lists presorted once by the composite order of each dimension and kept sorted through
    /// a stable partition at every node (Algorithm 6, "Sorting" in thesis Chapter 8).
    Presorted,
    /// Sort the node's points, then pick ("Median (Sorting)").
    Sort,
    /// Randomised quickselect with a median-of-three pivot (Algorithm 10).
    Quickselect,
    /// Floyd–Rivest selection ("Median (Floyd–Rivest)", thesis 6.1).
    #[default]
    FloydRivest,
    /// Deterministic median of medians (Algorithm 11, "Median (Linear Det.)").
    MedianOfMedians,
}

impl MedianAlgorithm {
    /// All algorithms, for tests and benchmarks.
    pub const ALL: [MedianAlgorithm; 5] = [
        MedianAlgorithm::Presorted,
        MedianAlgorithm::Sort,
        MedianAlgorithm::Quickselect,
        MedianAlgorithm::FloydRivest,
        MedianAlgorithm::MedianOfMedians,
    ];
}

impl OptionName for PivotPolicy {
    const OPTION: &'static str = "pivot";
    const WHAT: &'static str = "pivot";
    const NAMES: &'static [(Self, &'static str)] = &[
        (PivotPolicy::CyclicMedian, "cyclic-median"),
        (PivotPolicy::SpreadMedian, "spread-median"),
        (PivotPolicy::ClosestToMiddle, "closest-to-middle"),
        (PivotPolicy::SlidingMidpoint, "sliding-midpoint"),
    ];
}
named_option!(PivotPolicy);

impl OptionName for MedianAlgorithm {
    const OPTION: &'static str = "median";
    const WHAT: &'static str = "median";
    const NAMES: &'static [(Self, &'static str)] = &[
        (MedianAlgorithm::Presorted, "presorted"),
        (MedianAlgorithm::Sort, "sort"),
        (MedianAlgorithm::Quickselect, "quickselect"),
        (MedianAlgorithm::FloydRivest, "floyd-rivest"),
        (MedianAlgorithm::MedianOfMedians, "median-of-medians"),
    ];
}
named_option!(MedianAlgorithm);

/// Everything that shapes a tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BuildOptions {
    /// Pivot policy.
    pub pivot: PivotPolicy,
    /// Median algorithm.
    pub median: MedianAlgorithm,
    /// Most points in a leaf (≥ 1). 1 gives one point per leaf, the thesis' tree shape.
    pub leaf_size: usize,
    /// Reject or skip points with NaN or infinite coordinates.
    pub non_finite: NonFinitePolicy,
    /// Worker threads: 0 uses the current rayon pool, 1 builds serially, n > 1 uses a pool of
    /// n threads; at most [`crate::parallel::MAX_THREADS`]. The tree is identical for every
    /// value.
    pub threads: usize,
}

/// The default leaf bucket size.
pub const DEFAULT_LEAF_SIZE: usize = 12;

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            pivot: PivotPolicy::default(),
            median: MedianAlgorithm::default(),
            leaf_size: DEFAULT_LEAF_SIZE,
            non_finite: NonFinitePolicy::default(),
            threads: 0,
        }
    }
}

impl BuildOptions {
    /// Options with the given pivot policy and median algorithm, defaults otherwise.
    pub fn with(pivot: PivotPolicy, median: MedianAlgorithm) -> Self {
        Self {
            pivot,
            median,
            ..Self::default()
        }
    }

    /// Checks the leaf size and the thread count (at most [`crate::parallel::MAX_THREADS`]).
    pub fn validate(&self) -> Result<()> {
        crate::parallel::check_threads(self.threads)?;
        if self.leaf_size == 0 {
            return Err(NbhdError::InvalidOption {
                name: "leaf_size",
                reason: "must be at least 1".into(),
            });
        }
        if self.leaf_size > u32::MAX as usize {
            return Err(NbhdError::InvalidOption {
                name: "leaf_size",
                reason: "must fit in 32 bits".into(),
            });
        }
        Ok(())
    }
}
