//! The one order of every neighbour result (see the conventions in `src/query/mod.rs`): by
//! squared distance, ties by index. Everything that compares, sorts or packs neighbours — the
//! bounded heap, the result sets of the searches, the row sorts of the tables and of the
//! smoothing — goes through this file.
//!
//! Squared distances are never NaN and never −0 (a sum of squares starting from +0), and the
//! bits of non-negative IEEE floats order as their values. So a pair packs into one integer key
//! `(bits(sq_dist) << 32) | index` — a `u64` for `f32`, a `u128` for `f64` — that orders as the
//! pair; every key of distinct pairs is distinct, so an unstable sort of keys gives the one order.
//! The tests below check the keys against [`precedes`] and [`cmp`].

use std::cmp::Ordering;

use crate::scalar::Scalar;

/// Whether `a = (sq_dist, index)` comes strictly before `b`: the nearer first, the smaller
/// index first at equal distances.
#[inline(always)]
pub(crate) fn precedes<T: PartialOrd>(a: (T, u32), b: (T, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// The total order of [`precedes`] (distances are never NaN).
#[inline]
pub(crate) fn cmp<T: PartialOrd>(a: (T, u32), b: (T, u32)) -> Ordering {
    a.0.partial_cmp(&b.0)
        .unwrap_or(Ordering::Equal)
        .then(a.1.cmp(&b.1))
}

/// The packed key of an `f32` pair (`T` must be `f32`: an `f32` survives the round trip through
/// `f64` exactly): orders as [`cmp`].
#[inline(always)]
pub(crate) fn key32<T: Scalar>(sq_dist: T, index: u32) -> u64 {
    (u64::from((sq_dist.to_f64() as f32).to_bits()) << 32) | u64::from(index)
}

/// The pair of a [`key32`] key.
#[inline(always)]
pub(crate) fn unkey32<T: Scalar>(key: u64) -> (T, u32) {
    (
        T::from_f64(f64::from(f32::from_bits((key >> 32) as u32))),
        key as u32,
    )
}

/// The packed key of any pair, through `f64` (exact for both scalar types): orders as [`cmp`].
#[inline(always)]
pub(crate) fn key64<T: Scalar>(sq_dist: T, index: u32) -> u128 {
    (u128::from(sq_dist.to_f64().to_bits()) << 32) | u128::from(index)
}

/// The pair of a [`key64`] key.
#[inline(always)]
pub(crate) fn unkey64<T: Scalar>(key: u128) -> (T, u32) {
    (T::from_f64(f64::from_bits((key >> 32) as u64)), key as u32)
}

/// A neighbour packed into one integer key that orders as `(sq_dist, index)` ([`cmp`]): a `u64`
/// for `f32` ([`key32`]), a `u128` for any scalar ([`key64`]). The single queries' result sets
/// (`src/query/result_set.rs`) and the grouped search's rows (`src/tree/group_search/`) hold
/// these, so that an insertion, a sort or a heap compares integers.
pub(crate) trait PackedKey<T>: Copy + Ord + Default {
    /// The key of a candidate.
    fn of(index: u32, sq_dist: T) -> Self;
    /// Its `(sq_dist, index)`.
    fn pair(self) -> (T, u32);
}

impl<T: Scalar> PackedKey<T> for u64 {
    #[inline(always)]
    fn of(index: u32, sq_dist: T) -> Self {
        key32(sq_dist, index)
    }
    #[inline(always)]
    fn pair(self) -> (T, u32) {
        unkey32(self)
    }
}

impl<T: Scalar> PackedKey<T> for u128 {
    #[inline(always)]
    fn of(index: u32, sq_dist: T) -> Self {
        key64(sq_dist, index)
    }
    #[inline(always)]
    fn pair(self) -> (T, u32) {
        unkey64(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pairs with ties in distance, equal indices at different distances, zero, subnormal,
    /// large and infinite distances and the extreme indices.
    fn pairs() -> Vec<(f64, u32)> {
        let dists = [
            0.0,
            f64::from(f32::from_bits(1)), // smallest f32 subnormal
            1e-30,
            0.25,
            0.5,
            1.0,
            1.0 + f64::from(f32::EPSILON),
            3.0,
            1e30,
            f64::from(f32::MAX),
            f64::INFINITY,
        ];
        let indices = [0u32, 1, 2, 7, 1 << 31, u32::MAX - 1];
        let mut v = Vec::new();
        for &d in &dists {
            for &i in &indices {
                v.push((d, i));
            }
        }
        v
    }

    #[test]
    fn precedes_is_the_strict_part_of_cmp() {
        let p = pairs();
        for &a in &p {
            for &b in &p {
                assert_eq!(precedes(a, b), cmp(a, b) == Ordering::Less, "{a:?} {b:?}");
                assert_eq!(cmp(a, b), cmp(b, a).reverse());
            }
        }
        assert!(precedes((1.0, 9), (2.0, 0)));
        assert!(precedes((1.0, 3), (1.0, 4)));
        assert!(!precedes((1.0, 4), (1.0, 4)));
    }

    #[test]
    fn packed_keys_order_as_the_pairs() {
        let p = pairs();
        for &a in &p {
            for &b in &p {
                let want = cmp(a, b);
                let (a32, b32) = ((a.0 as f32, a.1), (b.0 as f32, b.1));
                assert_eq!(key32(a32.0, a32.1).cmp(&key32(b32.0, b32.1)), cmp(a32, b32));
                assert_eq!(key64(a.0, a.1).cmp(&key64(b.0, b.1)), want, "{a:?} {b:?}");
                assert_eq!(key64(a32.0, a32.1).cmp(&key64(b32.0, b32.1)), cmp(a32, b32));
            }
            let a32 = (a.0 as f32, a.1);
            assert_eq!(unkey32::<f32>(key32(a32.0, a32.1)), a32);
            assert_eq!(unkey64::<f64>(key64(a.0, a.1)), a);
            assert_eq!(unkey64::<f32>(key64(a32.0, a32.1)), a32);
        }
    }
}
