//! Deterministic select (thesis Algorithm 11, Blum, Floyd, Pratt, Rivest and Tarjan \[Blu+73\]).
//!
//! The range is cut into groups of five; the median of each group is moved to the front of the
//! range (in place, no buffer), the median of these `⌈n/5⌉` medians is selected recursively and
//! used as the pivot of a three-way partition. At least about `3n/10` elements lie on each side
//! of that pivot, so the side holding rank `k` has at most about `7n/10` elements, and the
//! running time satisfies `T(n) ≤ T(n/5) + T(7n/10) + O(n) = O(n)` (thesis eq. (6.1)).
//! Short ranges are sorted. The recursion is only on the medians (depth `log₅ n`); the side
//! holding rank `k` is handled by a loop.

use super::{insertion_sort, partition3};

/// Ranges shorter than this are sorted (the thesis uses 140 to simplify its proof; any bound
/// above the point where `7n/10 + 6 < n` keeps the guarantee).
const SORT_BELOW: usize = 48;

/// Puts the element of rank `k` at `v[k]` (`k < v.len()`).
pub(super) fn select<E: Copy, F: FnMut(&E, &E) -> bool>(v: &mut [E], k: usize, less: &mut F) {
    let (mut lo, mut hi) = (0, v.len());
    loop {
        let n = hi - lo;
        if n < SORT_BELOW {
            insertion_sort(&mut v[lo..hi], less);
            return;
        }
        let w = &mut v[lo..hi];
        let m = medians_to_front(w, less);
        // Recursion on the medians only: m = ⌈n/5⌉.
        select(&mut w[..m], m / 2, less);
        let (a, b) = partition3(w, m / 2, less);
        let r = k - lo;
        if r < a {
            hi = lo + a;
        } else if r >= b {
            lo += b;
        } else {
            return;
        }
    }
}

/// Moves the median of every group of five consecutive elements (the last group may be
/// shorter; its lower median is taken) to the front of `v`, in group order; returns the number
/// of groups `⌈n/5⌉`.
fn medians_to_front<E: Copy, F: FnMut(&E, &E) -> bool>(v: &mut [E], less: &mut F) -> usize {
    let n = v.len();
    let groups = n.div_ceil(5);
    for g in 0..groups {
        let start = 5 * g;
        let end = (start + 5).min(n);
        let group = &mut v[start..end];
        let mid = if group.len() == 5 {
            median_of_five(group, less)
        } else {
            insertion_sort(group, less);
            (group.len() - 1) / 2
        };
        // g ≤ start: the slot receiving the median belongs to a group already done.
        v.swap(g, start + mid);
    }
    groups
}

/// Position (0..5) of the median of the five elements of `g` (which it permutes), with six
/// comparisons: twice, the smaller of two pair minima has three elements above it and so
/// cannot be the median; it is set aside and the search continues on the rest.
#[inline]
fn median_of_five<E: Copy, F: FnMut(&E, &E) -> bool>(g: &mut [E], less: &mut F) -> usize {
    // Order the pairs (0,1) and (2,3) so that g[0] ≤ g[1], g[2] ≤ g[3].
    if less(&g[1], &g[0]) {
        g.swap(0, 1);
    }
    if less(&g[3], &g[2]) {
        g.swap(2, 3);
    }
    // The smaller of the two pair minima is below three elements: not the median; replace it
    // by g[4] and repeat on the remaining four.
    if less(&g[2], &g[0]) {
        g.swap(0, 2);
        g.swap(1, 3);
    }
    // Now g[0] ≤ g[1], g[0] ≤ g[2] ≤ g[3]: g[0] is out (rank 0 or 1 of five), so the median
    // is the second smallest of the other four. Park it at position 4.
    g.swap(0, 4);
    if less(&g[1], &g[0]) {
        g.swap(0, 1);
    }
    // g[0] ≤ g[1], g[2] ≤ g[3]; the smaller pair minimum is out again, and the median is the
    // smaller of the other pair's minimum and this pair's maximum.
    if less(&g[2], &g[0]) {
        // g[2] is out; median = min(g[0], g[3])
        if less(&g[3], &g[0]) {
            3
        } else {
            0
        }
    } else {
        // g[0] is out; median = min(g[1], g[2])
        if less(&g[2], &g[1]) {
            2
        } else {
            1
        }
    }
}

/// [`median_of_five`] for the unit tests.
#[cfg(test)]
pub(super) fn median_of_five_for_tests<E: Copy, F: FnMut(&E, &E) -> bool>(
    g: &mut [E],
    less: &mut F,
) -> usize {
    median_of_five(g, less)
}
