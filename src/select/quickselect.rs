//! Randomized select (thesis Algorithm 10) with the median-of-three pivot of Section 6.1.
//!
//! The three candidates are drawn at pseudo-random positions from a generator seeded by the
//! slice length (reproducible builds, and no quadratic behaviour on sorted, reverse-sorted or
//! organ-pipe inputs). The side holding rank `k` is handled by a loop, not by recursion.

use super::{
    insertion_sort, median_of_medians, median_of_three, partition, SplitMix64, INSERTION_MAX,
    WORK_BUDGET_FACTOR,
};

/// Puts the element of rank `k` at `v[k]` (`k < v.len()`).
pub(super) fn select<E: Copy, F: FnMut(&E, &E) -> bool>(v: &mut [E], k: usize, less: &mut F) {
    let budget = WORK_BUDGET_FACTOR.saturating_mul(v.len());
    select_with_budget(v, k, less, budget);
}

/// [`select`] that hands over to the median of medians once the lengths of the ranges it has
/// partitioned would exceed `budget`.
pub(super) fn select_with_budget<E: Copy, F: FnMut(&E, &E) -> bool>(
    v: &mut [E],
    k: usize,
    less: &mut F,
    mut budget: usize,
) {
    let mut rng = SplitMix64::seeded(v.len());
    let (mut lo, mut hi) = (0, v.len());
    loop {
        let n = hi - lo;
        if n <= INSERTION_MAX {
            insertion_sort(&mut v[lo..hi], less);
            return;
        }
        if n > budget {
            median_of_medians::select(&mut v[lo..hi], k - lo, less);
            return;
        }
        budget -= n;
        let w = &mut v[lo..hi];
        let p = median_of_three(w, rng.below(n), rng.below(n), rng.below(n), less);
        let j = lo + partition(w, p, less);
        match k.cmp(&j) {
            std::cmp::Ordering::Less => hi = j,
            std::cmp::Ordering::Greater => lo = j + 1,
            std::cmp::Ordering::Equal => return,
        }
    }
}
