//! Floyd–Rivest select (R. W. Floyd and R. L. Rivest, "Expected time bounds for selection",
//! CACM 18(3), 1975 \[FR75\]; thesis Section 6.1).
//!
//! Like randomized select (thesis Algorithm 10) it partitions around one pivot and continues on
//! the side holding rank `k`; the difference is the pivot. From a range of `n` elements it draws
//! a random sample of `s ≈ n^(2/3) / 2` elements, selects within the sample (recursively, with
//! the same algorithm) the element whose rank in the sample corresponds to rank `k` in the
//! range, shifted by about `sqrt(ln n · s)` ranks towards the middle, and uses it as the pivot.
//! With high probability the pivot then lands just beyond rank `k` on the far side of the
//! middle, so one pass removes the larger part of the range and the next pass, with rank `k`
//! now near an end, leaves only a small window: about `n + min(k, n − k) + o(n)` comparisons
//! in expectation, optimal up to lower-order terms.
//!
//! Following \[FR75\], the sample size `s = e^(2 ln n / 3) / 2`, the shift
//! `sd = sqrt(ln n · s · (n − s) / n) / 2` and the cut-off of 600 below which sampling does not
//! pay are the published constants. Unlike the published version, which takes a contiguous block
//! of the range as its sample and so assumes randomly ordered input, the sample is drawn by a
//! partial Fisher–Yates shuffle from a deterministic generator, so sorted or organ-pipe input
//! is no worse than random input. Short ranges are finished by quickselect.

use super::{median_of_medians, partition, quickselect, SplitMix64, WORK_BUDGET_FACTOR};

/// Ranges up to this length are not sampled (\[FR75\] uses 600).
const SAMPLE_ABOVE: usize = 600;

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
    budget: usize,
) {
    let mut rng = SplitMix64::seeded(v.len());
    select_rec(v, k, less, &mut rng, budget);
}

fn select_rec<E: Copy, F: FnMut(&E, &E) -> bool>(
    v: &mut [E],
    k: usize,
    less: &mut F,
    rng: &mut SplitMix64,
    mut budget: usize,
) {
    let (mut lo, mut hi) = (0, v.len());
    loop {
        let n = hi - lo;
        if n <= SAMPLE_ABOVE {
            quickselect::select_with_budget(&mut v[lo..hi], k - lo, less, budget);
            return;
        }
        if n > budget {
            median_of_medians::select(&mut v[lo..hi], k - lo, less);
            return;
        }
        budget -= n;
        let w = &mut v[lo..hi];
        let i = k - lo;
        let (from, to) = sample_window(n, i);
        draw_sample(w, from, to, rng);
        // Recursion on the sample only (≈ n^(2/3) / 2 elements): afterwards w[i] holds the
        // sample element of the matching rank.
        let m = to - from;
        select_rec(
            &mut w[from..to],
            i - from,
            less,
            rng,
            WORK_BUDGET_FACTOR.saturating_mul(m),
        );
        let j = lo + partition(w, i, less);
        match k.cmp(&j) {
            std::cmp::Ordering::Less => hi = j,
            std::cmp::Ordering::Greater => lo = j + 1,
            std::cmp::Ordering::Equal => return,
        }
    }
}

/// The positions `from..to` (containing `i`) of a range of length `n` that receive the sample,
/// so that rank `i − from` in the sample estimates rank `i` in the range, shifted towards the
/// middle by `sd` (\[FR75\]).
fn sample_window(n: usize, i: usize) -> (usize, usize) {
    let nf = n as f64;
    let fi = i as f64;
    let z = nf.ln();
    let s = 0.5 * (2.0 * z / 3.0).exp();
    let sd = 0.5 * (z * s * (nf - s) / nf).sqrt() * if 2 * i < n { -1.0 } else { 1.0 };
    let from = (fi - fi * s / nf + sd).floor().max(0.0) as usize;
    let last = ((fi + (nf - fi) * s / nf + sd).floor().max(0.0) as usize).min(n - 1);
    (from.min(i), last.max(i) + 1)
}

/// Moves a uniform random sample (without replacement) of the elements of `w` to the positions
/// `from..to`, by a partial Fisher–Yates shuffle over the order "positions `from..to`, then the
/// rest".
fn draw_sample<E: Copy>(w: &mut [E], from: usize, to: usize, rng: &mut SplitMix64) {
    let (n, m) = (w.len(), to - from);
    // Virtual position u in that order → physical position.
    let phys = |u: usize| {
        if u < m {
            from + u
        } else if u - m < from {
            u - m
        } else {
            u
        }
    };
    for t in 0..m {
        let r = t + rng.below(n - t);
        w.swap(phys(t), phys(r));
    }
}
