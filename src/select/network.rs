//! A sorting network: a fixed sequence of compare-exchanges that sorts any input, with no
//! branch on the data (Batcher, *Sorting networks and their applications*, 1968). A single
//! query sorts the candidates of its first leaf this way (`src/query/result_set.rs`): a
//! comparison sort of 32 keys mispredicted about ten branches a query (cachegrind, 1M cube,
//! k = 10), each costing more than several compare-exchanges.

/// Puts the smaller of `x[a]`, `x[b]` at `a` and the larger at `b` (`a < b`), without a
/// branch.
#[inline(always)]
fn compare_exchange<K: Copy + Ord>(x: &mut [K; 32], a: usize, b: usize) {
    let (p, q) = (x[a], x[b]);
    x[a] = p.min(q);
    x[b] = p.max(q);
}

/// Writes out a network as straight-line compare-exchanges (the compiler unrolls no loop of
/// 191 steps, and a loop over a table of pairs cost twice the instructions), and keeps its
/// pairs for the test that derives them again.
macro_rules! network {
    ($($a:literal $b:literal),* $(,)?) => {
        /// Sorts `x` ascending: Batcher's odd-even merge sort of 32 entries, 191
        /// compare-exchanges (of packed keys: `u64` for `f32` neighbours, `u128` for `f64`).
        #[inline(always)]
        pub(crate) fn sort32<K: Copy + Ord>(x: &mut [K; 32]) {
            $(compare_exchange(x, $a, $b);)*
        }

        /// The compare-exchanges of [`sort32`], in order.
        #[cfg(test)]
        const PAIRS: &[(usize, usize)] = &[$(($a, $b)),*];
    };
}

network!(
    0 1, 2 3, 4 5, 6 7, 8 9, 10 11, 12 13, 14 15, 16 17, 18 19, 20 21, 22 23, 24 25, 26 27,
    28 29, 30 31, 0 2, 1 3, 4 6, 5 7, 8 10, 9 11, 12 14, 13 15, 16 18, 17 19, 20 22, 21 23,
    24 26, 25 27, 28 30, 29 31, 1 2, 5 6, 9 10, 13 14, 17 18, 21 22, 25 26, 29 30, 0 4, 1 5,
    2 6, 3 7, 8 12, 9 13, 10 14, 11 15, 16 20, 17 21, 18 22, 19 23, 24 28, 25 29, 26 30, 27 31,
    2 4, 3 5, 10 12, 11 13, 18 20, 19 21, 26 28, 27 29, 1 2, 3 4, 5 6, 9 10, 11 12, 13 14,
    17 18, 19 20, 21 22, 25 26, 27 28, 29 30, 0 8, 1 9, 2 10, 3 11, 4 12, 5 13, 6 14, 7 15,
    16 24, 17 25, 18 26, 19 27, 20 28, 21 29, 22 30, 23 31, 4 8, 5 9, 6 10, 7 11, 20 24, 21 25,
    22 26, 23 27, 2 4, 3 5, 6 8, 7 9, 10 12, 11 13, 18 20, 19 21, 22 24, 23 25, 26 28, 27 29,
    1 2, 3 4, 5 6, 7 8, 9 10, 11 12, 13 14, 17 18, 19 20, 21 22, 23 24, 25 26, 27 28, 29 30,
    0 16, 1 17, 2 18, 3 19, 4 20, 5 21, 6 22, 7 23, 8 24, 9 25, 10 26, 11 27, 12 28, 13 29,
    14 30, 15 31, 8 16, 9 17, 10 18, 11 19, 12 20, 13 21, 14 22, 15 23, 4 8, 5 9, 6 10, 7 11,
    12 16, 13 17, 14 18, 15 19, 20 24, 21 25, 22 26, 23 27, 2 4, 3 5, 6 8, 7 9, 10 12, 11 13,
    14 16, 15 17, 18 20, 19 21, 22 24, 23 25, 26 28, 27 29, 1 2, 3 4, 5 6, 7 8, 9 10, 11 12,
    13 14, 15 16, 17 18, 19 20, 21 22, 23 24, 25 26, 27 28, 29 30,
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Batcher's odd-even merge sort of `n` (a power of two) entries, by its rule: merges of
    /// runs of `p` = 1, 2, 4, … entries, each comparing entries `k` apart for `k` = p, p/2, …, 1
    /// that lie in one run of `2p`.
    fn batcher(n: usize) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut p = 1;
        while p < n {
            let mut k = p;
            while k >= 1 {
                let mut j = k % p;
                while j + k < n {
                    for i in 0..k.min(n - j - k) {
                        if (i + j) / (2 * p) == (i + j + k) / (2 * p) {
                            out.push((i + j, i + j + k));
                        }
                    }
                    j += 2 * k;
                }
                k /= 2;
            }
            p *= 2;
        }
        out
    }

    #[test]
    fn the_network_is_batchers() {
        assert_eq!(PAIRS, &batcher(32)[..]);
    }

    /// By the 0-1 principle a network sorts every input if it sorts every input of zeros and
    /// ones; all 2^32 are too many, so every input with one run of ones, and pseudo-random keys
    /// with many ties.
    #[test]
    fn it_sorts() {
        for start in 0..32 {
            for len in 0..=32 - start {
                let mut x = [0u64; 32];
                x[start..start + len].fill(1);
                let mut want = x;
                want.sort_unstable();
                sort32(&mut x);
                assert_eq!(x, want, "ones at {start}..{}", start + len);
            }
        }
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        for round in 0..2000 {
            let mut x = [0u64; 32];
            for v in &mut x {
                s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                *v = (s >> 33) % if round % 2 == 0 { 7 } else { u64::MAX };
            }
            // `u128` keys (`f64` neighbours) whose high and low halves both decide
            let mut y = x.map(|v| u128::from(v % 5) << 64 | u128::from(v >> 3));
            let mut want = x;
            want.sort_unstable();
            sort32(&mut x);
            assert_eq!(x, want);
            let mut want = y;
            want.sort_unstable();
            sort32(&mut y);
            assert_eq!(y, want);
        }
    }
}
