//! Selection: putting the element of rank `k` at position `k` with smaller elements before it
//! and larger ones after it (thesis Chapter 6, used by the k-d tree build of Section 3.3.4 to
//! find the median without sorting).
//!
//! Four algorithms behind one entry point, [`select_nth`]:
//! - [`SelectAlgorithm::Sort`]: sort the whole slice, `O(n log n)`; the reference.
//! - [`SelectAlgorithm::Quickselect`]: randomized select (thesis Algorithm 10) with a
//!   median-of-three pivot, expected `O(n)`.
//! - [`SelectAlgorithm::FloydRivest`]: the pivot is chosen from a sample so that it lands close
//!   to rank `k` (Floyd and Rivest \[FR75\], thesis Section 6.1), about `n + min(k, n − k)`
//!   comparisons in expectation.
//! - [`SelectAlgorithm::MedianOfMedians`]: deterministic select (thesis Algorithm 11, \[Blu+73\]),
//!   `O(n)` in the worst case.
//!
//! All randomness is a fixed pseudo-random sequence seeded from the slice length, so a build is
//! reproducible. The two randomized algorithms keep a work budget (a multiple of the input
//! length); an input that exhausts it, which random pivots make vanishingly unlikely, is
//! finished by the median of medians, so every algorithm is `O(n)` in the worst case except
//! `Sort`.
//!
//! Nothing allocates (the median of medians gathers its medians in place, and `Sort` uses the
//! standard library's in-place unstable sort), and nothing recurses except on samples that
//! shrink geometrically; the side of a partition that holds rank `k` is handled by a loop.
//!
//! Across parts that are never gathered (tiles of a distributed run), [`radix`] selects exactly
//! by counting digits of the values' order keys instead of moving the values.
//!
//! The order is given as a strict "less than" predicate. The algorithms are written for a
//! strict total order, but stay correct (and fast) for a strict weak order, i.e. a comparator
//! that declares many elements equivalent: then `v[k]` is equivalent to the element of rank `k`
//! of a sorted copy, nothing before it is greater and nothing after it is less.

mod floyd_rivest;
mod median_of_medians;
pub(crate) mod network;
mod quickselect;
pub mod radix;

/// Which selection algorithm (thesis Chapter 6 / Section 3.3.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SelectAlgorithm {
    /// Sort the whole slice (unstable sort), `O(n log n)`: the baseline of Section 3.3.3.
    Sort,
    /// Randomized select (thesis Algorithm 10), median-of-three pivot from deterministic
    /// pseudo-random positions, Hoare partition; expected `O(n)`.
    Quickselect,
    /// Floyd–Rivest select \[FR75\] (thesis Section 6.1): the pivot is the element of the right
    /// rank in a random sample of about `n^(2/3)` elements, selected recursively; expected
    /// `n + min(k, n − k) + o(n)` comparisons.
    FloydRivest,
    /// Deterministic select by the median of medians of groups of five (thesis Algorithm 11,
    /// \[Blu+73\]); `O(n)` in the worst case.
    MedianOfMedians,
}

impl SelectAlgorithm {
    /// Every algorithm, for the tests that compare them.
    #[cfg(test)]
    pub const ALL: [SelectAlgorithm; 4] = [
        SelectAlgorithm::Sort,
        SelectAlgorithm::Quickselect,
        SelectAlgorithm::FloydRivest,
        SelectAlgorithm::MedianOfMedians,
    ];
}

/// Rearranges `v` so that `v[k]` is the element of rank k under the strict total order `less`,
/// every element before it is less and every element after it is greater.
///
/// `less(a, b)` must mean "a comes strictly before b". For a comparator that declares elements
/// equivalent (a strict weak order) the guarantee is the weak one: `v[k]` is equivalent to the
/// element of rank `k` of a sorted copy, no element before it is greater and none after it is
/// less. The order of the elements within each side is unspecified.
///
/// The result depends only on the input and `algo` (no run-time randomness).
///
/// Example: `tests.rs`, `selects_the_median_index_by_coordinate`.
///
/// # Panics
///
/// If `k >= v.len()` (in particular for an empty slice).
pub fn select_nth<E: Copy, F: FnMut(&E, &E) -> bool>(
    v: &mut [E],
    k: usize,
    less: &mut F,
    algo: SelectAlgorithm,
) {
    assert!(
        k < v.len(),
        "select_nth: rank {k} out of range for a slice of length {}",
        v.len()
    );
    match algo {
        SelectAlgorithm::Sort => sort(v, less),
        SelectAlgorithm::Quickselect => quickselect::select(v, k, less),
        SelectAlgorithm::FloydRivest => floyd_rivest::select(v, k, less),
        SelectAlgorithm::MedianOfMedians => median_of_medians::select(v, k, less),
    }
}

/// Ranges at most this long are finished by insertion sort.
const INSERTION_MAX: usize = 16;

/// The randomized algorithms may partition at most this many times the input length in
/// total before the median of medians takes over (expected work is about 2–3 times the length).
const WORK_BUDGET_FACTOR: usize = 8;

/// Sorts `v` by `less` with the standard library's unstable sort.
fn sort<E: Copy, F: FnMut(&E, &E) -> bool>(v: &mut [E], less: &mut F) {
    if v.len() <= INSERTION_MAX {
        insertion_sort(v, less);
    } else {
        v.sort_unstable_by(|a, b| {
            if less(a, b) {
                std::cmp::Ordering::Less
            } else if less(b, a) {
                std::cmp::Ordering::Greater
            } else {
                std::cmp::Ordering::Equal
            }
        });
    }
}

/// Sorts a short slice by insertion.
#[inline]
fn insertion_sort<E: Copy, F: FnMut(&E, &E) -> bool>(v: &mut [E], less: &mut F) {
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && less(&x, &v[j - 1]) {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

/// Position of the median of `v[a]`, `v[b]`, `v[c]` (two or three comparisons).
#[inline]
fn median_of_three<E, F: FnMut(&E, &E) -> bool>(
    v: &[E],
    a: usize,
    b: usize,
    c: usize,
    less: &mut F,
) -> usize {
    let ab = less(&v[a], &v[b]);
    let bc = less(&v[b], &v[c]);
    if ab == bc {
        // a < b < c or c ≤ b ≤ a
        return b;
    }
    let ac = less(&v[a], &v[c]);
    if ab == ac {
        // b is the extreme on a's side: a < b, a < c, c ≤ b  or  b ≤ a, c ≤ a, b < c
        c
    } else {
        a
    }
}

/// Hoare partition around the value at `pivot`; returns the pivot's final position `j`, with
/// `v[..j]` not greater and `v[j + 1..]` not less than it. Both scans stop on elements
/// equivalent to the pivot, so runs of equivalent elements are split evenly (no quadratic
/// behaviour on many equal keys). Every index is bounds-checked against the other scan, so even
/// an inconsistent comparator cannot make it run off the slice. `v` must not be empty.
#[inline]
fn partition<E: Copy, F: FnMut(&E, &E) -> bool>(v: &mut [E], pivot: usize, less: &mut F) -> usize {
    v.swap(0, pivot);
    let p = v[0];
    let mut i = 1;
    let mut j = v.len() - 1;
    loop {
        // Invariant: v[1..i] ≤ p, v[j + 1..] ≥ p.
        while i <= j && less(&v[i], &p) {
            i += 1;
        }
        while i <= j && less(&p, &v[j]) {
            j -= 1;
        }
        if i >= j {
            break;
        }
        v.swap(i, j);
        i += 1;
        j -= 1;
    }
    // Either j = i − 1 (v[j] ≤ p) or j = i with v[j] equivalent to p.
    v.swap(0, j);
    j
}

/// Three-way partition (Dijkstra) around the value at `pivot`: returns `(a, b)` with `v[..a]`
/// less than, `v[a..b]` equivalent to and `v[b..]` greater than the pivot; `a < b`.
fn partition3<E: Copy, F: FnMut(&E, &E) -> bool>(
    v: &mut [E],
    pivot: usize,
    less: &mut F,
) -> (usize, usize) {
    let p = v[pivot];
    let (mut lt, mut i, mut gt) = (0, 0, v.len());
    while i < gt {
        if less(&v[i], &p) {
            v.swap(lt, i);
            lt += 1;
            i += 1;
        } else if less(&p, &v[i]) {
            gt -= 1;
            v.swap(i, gt);
        } else {
            i += 1;
        }
    }
    if lt == gt {
        // Only for a comparator under which the pivot is not equivalent to itself; keep the
        // promise a < b so that callers always make progress.
        gt = (lt + 1).min(v.len());
        lt = gt - 1;
    }
    (lt, gt)
}

/// SplitMix64: a tiny, fast pseudo-random generator; seeded from the slice length so that
/// every selection is reproducible.
struct SplitMix64(u64);

impl SplitMix64 {
    fn seeded(len: usize) -> Self {
        Self(0x6A09_E667_F3BC_C909 ^ (len as u64).wrapping_mul(0xD1B5_4A32_D192_ED03))
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Nearly uniform in `0..n` (`n ≥ 1`), by a multiply-shift.
    #[inline]
    fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }
}

#[cfg(test)]
mod tests;
