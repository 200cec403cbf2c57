use super::*;
use proptest::prelude::*;

/// The correctly rounded sum by an independent method: Shewchuk's exact expansion of
/// non-overlapping partials with the final round-half-even correction (the method of Python's
/// `math.fsum`). Valid while no partial overflows.
fn fsum(values: &[f64]) -> f64 {
    let mut partials: Vec<f64> = Vec::new();
    for &v in values {
        let mut x = v;
        let mut i = 0;
        for j in 0..partials.len() {
            let mut y = partials[j];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            let lo = y - (hi - x);
            if lo != 0.0 {
                partials[i] = lo;
                i += 1;
            }
            x = hi;
        }
        partials.truncate(i);
        partials.push(x);
    }
    let mut n = partials.len();
    if n == 0 {
        return 0.0;
    }
    n -= 1;
    let mut hi = partials[n];
    let mut lo = 0.0;
    while n > 0 {
        let x = hi;
        let y = partials[n - 1];
        n -= 1;
        hi = x + y;
        lo = y - (hi - x);
        if lo != 0.0 {
            break;
        }
    }
    if n > 0 && ((lo < 0.0 && partials[n - 1] < 0.0) || (lo > 0.0 && partials[n - 1] > 0.0)) {
        let y = lo * 2.0;
        let x = hi + y;
        if y == x - hi {
            hi = x;
        }
    }
    hi
}

/// `2^s` as an `f64` for `−1074 ≤ s ≤ 1023`.
fn pow2(s: i32) -> f64 {
    if s >= -1022 {
        f64::from_bits(((s + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (s + 1074))
    }
}

/// The correctly rounded value of `Σ kᵢ · 2^s`: the integer sum is exact in `i128`, its
/// conversion to `f64` rounds once (to nearest, ties to even) and the scaling is exact for
/// `s = −1074` or `s ≥ −1022` (the result is then normal or below 2⁵³ · 2⁻¹⁰⁷⁴).
fn scaled_reference(ks: &[i64], s: i32) -> f64 {
    assert!(s == -1074 || s >= -1022);
    let total: i128 = ks.iter().map(|&k| i128::from(k)).sum();
    (total as f64) * pow2(s)
}

fn exact(values: &[f64]) -> f64 {
    values.iter().copied().collect::<ExactSum>().value()
}

/// Sums `values` split at `cuts` into parts, each part's sum built in reverse, merged in the
/// order `merge_order` (a permutation seed), and also through bytes.
fn in_parts(values: &[f64], cuts: &[usize], seed: u64) -> f64 {
    let mut bounds: Vec<usize> = cuts.iter().map(|&c| c % (values.len() + 1)).collect();
    bounds.push(0);
    bounds.push(values.len());
    bounds.sort_unstable();
    let mut parts: Vec<ExactSum> = bounds
        .windows(2)
        .map(|w| values[w[0]..w[1]].iter().rev().copied().collect())
        .collect();
    // a pseudo-random merge tree: repeatedly merge two parts chosen by the seed
    let mut state = seed | 1;
    while parts.len() > 1 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let i = (state % parts.len() as u64) as usize;
        let a = parts.swap_remove(i);
        let j = ((state >> 32) % parts.len() as u64) as usize;
        let b = ExactSum::from_bytes(&a.to_bytes()).expect("round trip");
        parts[j].merge(&b);
    }
    parts[0].value()
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Values over the whole finite range, with many near-cancelling pairs.
fn wide_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
        (-1e300f64..1e300),
        (-1.0f64..1.0),
        (0u64..1 << 52).prop_map(f64::from_bits),
        (0u64..1 << 52).prop_map(|b| -f64::from_bits(b)),
        Just(0.0),
        Just(-0.0),
    ]
}

proptest! {
    #[test]
    fn matches_the_expansion_sum(values in prop::collection::vec(
        prop_oneof![(-1e300f64..1e300), (-1e-300f64..1e-300), (-1.0f64..1.0),
                    (0u64..1 << 52).prop_map(f64::from_bits)], 0..60)) {
        let want = fsum(&values);
        prop_assert!(same(exact(&values), want), "{values:?}: {} vs {want}", exact(&values));
    }

    #[test]
    fn matches_the_exact_integer_sum(
        ks in prop::collection::vec(-(1i64 << 53) + 1..1 << 53, 0..200),
        s in prop::sample::select(vec![-1074, -1022, -1000, -500, -60, 0, 30, 500, 900, 970]),
    ) {
        let values: Vec<f64> = ks.iter().map(|&k| (k as f64) * pow2(s)).collect();
        let want = scaled_reference(&ks, s);
        let got = exact(&values);
        prop_assert!(same(got, want), "s = {s}: {got:e} vs {want:e}");
    }

    #[test]
    fn every_order_and_partition_gives_the_same_bits(
        mut values in prop::collection::vec(wide_value(), 0..80),
        cuts in prop::collection::vec(any::<usize>(), 0..6),
        seed in any::<u64>(),
    ) {
        let whole = exact(&values);
        prop_assert!(same(in_parts(&values, &cuts, seed), whole));
        values.reverse();
        prop_assert!(same(exact(&values), whole));
        values.sort_by(f64::total_cmp);
        prop_assert!(same(exact(&values), whole));
    }

    #[test]
    fn bytes_round_trip(values in prop::collection::vec(wide_value(), 0..40)) {
        let s: ExactSum = values.iter().copied().collect();
        let back = ExactSum::from_bytes(&s.to_bytes()).expect("round trip");
        prop_assert_eq!(&back, &s);
        prop_assert!(same(back.value(), s.value()));
    }
}

#[test]
fn cancellation_keeps_the_tiny_rest() {
    let tiny = f64::from_bits(1);
    assert_eq!(exact(&[1e308, -1e308, tiny]), tiny);
    assert_eq!(exact(&[1e308, tiny, -1e308]), tiny);
    assert_eq!(exact(&[1.0, 1e100, 1.0, -1e100]), 2.0);
    // a plain sum overflows to ∞ part way; the exact sum does not
    assert_eq!(exact(&[f64::MAX, f64::MAX, -f64::MAX]), f64::MAX);
    assert_eq!(exact(&[-f64::MAX, -f64::MAX, f64::MAX]), -f64::MAX);
}

#[test]
fn rounds_to_nearest_ties_to_even() {
    let e = f64::EPSILON; // 2⁻⁵²
    assert_eq!(exact(&[1.0, e / 2.0]), 1.0); // tie, 1 is even
    assert_eq!(exact(&[1.0, e / 2.0, f64::from_bits(1)]), 1.0 + e); // just above the tie
    assert_eq!(exact(&[1.0 + e, e / 2.0]), 1.0 + 2.0 * e); // tie, 1 + e is odd
    assert_eq!(exact(&[-1.0 - e, -e / 2.0]), -1.0 - 2.0 * e);
    // the top of the range: MAX + half an ulp is a tie towards the even 2¹⁰²⁴, which is ∞
    let half_ulp = pow2(970);
    assert_eq!(exact(&[f64::MAX, half_ulp]), f64::INFINITY);
    assert_eq!(exact(&[-f64::MAX, -half_ulp]), f64::NEG_INFINITY);
    assert_eq!(exact(&[f64::MAX, half_ulp, -f64::from_bits(1)]), f64::MAX);
    assert_eq!(exact(&[f64::MAX, f64::MAX]), f64::INFINITY);
}

#[test]
fn subnormals_add_exactly() {
    let tiny = f64::from_bits(1);
    let many = vec![tiny; 10_000];
    assert_eq!(exact(&many), f64::from_bits(10_000));
    // into the normal range: 2⁵² subnormal units are the smallest normal
    let big_sub = f64::from_bits((1 << 52) - 1);
    assert_eq!(exact(&[big_sub, tiny]), f64::MIN_POSITIVE);
    assert_eq!(exact(&[f64::MIN_POSITIVE, -tiny]), big_sub);
    let mixed: Vec<f64> = (0..1000u64)
        .map(|i| f64::from_bits(i * 4_503_599_627_370))
        .collect();
    assert_eq!(exact(&mixed), fsum(&mixed));
}

#[test]
fn zeros_keep_the_sign_ieee_addition_gives() {
    assert_eq!(exact(&[]).to_bits(), 0.0f64.to_bits());
    assert_eq!(exact(&[-0.0]).to_bits(), (-0.0f64).to_bits());
    assert_eq!(exact(&[-0.0, -0.0]).to_bits(), (-0.0f64).to_bits());
    assert_eq!(exact(&[-0.0, 0.0]).to_bits(), 0.0f64.to_bits());
    assert_eq!(exact(&[1.0, -1.0]).to_bits(), 0.0f64.to_bits());
    assert_eq!(exact(&[-1.0, 1.0, -0.0]).to_bits(), 0.0f64.to_bits());
    // merging an empty sum changes nothing
    let mut a: ExactSum = [-0.0].into_iter().collect();
    a.merge(&ExactSum::new());
    assert_eq!(a.value().to_bits(), (-0.0f64).to_bits());
}

#[test]
fn nan_and_infinities_follow_the_policy() {
    let inf = f64::INFINITY;
    assert!(exact(&[1.0, f64::NAN, 2.0]).is_nan());
    assert!(exact(&[-f64::NAN]).is_nan());
    assert!(exact(&[inf, -inf]).is_nan());
    assert!(exact(&[inf, 1.0, f64::NAN]).is_nan());
    assert_eq!(exact(&[inf, -f64::MAX, -f64::MAX]), inf);
    assert_eq!(exact(&[-inf, f64::MAX, f64::MAX]), -inf);
    assert_eq!(exact(&[1.0, inf, inf]), inf);
    // merged parts see each other's specials
    let mut a: ExactSum = [inf].into_iter().collect();
    let b: ExactSum = [-inf].into_iter().collect();
    a.merge(&b);
    assert!(a.value().is_nan());
    assert_eq!(a.count(), 2);
}

#[test]
fn duplicates_and_all_equal_values() {
    let x = 0.1;
    let n = 1_000_003u64;
    let mut s = ExactSum::new();
    for _ in 0..n {
        s.add(x);
    }
    // 0.1 = k · 2⁻⁵⁶ exactly
    let k = (x * pow2(56)) as i64;
    assert_eq!(s.value(), ((n as i128 * k as i128) as f64) * pow2(-56));
    assert_eq!(s.count(), n);
}

#[test]
fn the_carry_room_is_enough() {
    // the worst state before a normalisation: CARRY_ROOM − 1 additions of the largest digit
    // pieces on top of normalised limbs, then one more addition
    for x in [
        f64::MAX,
        -f64::MAX,
        1.0 - f64::EPSILON / 2.0,
        -f64::from_bits((1 << 52) - 1),
    ] {
        let one: ExactSum = [x].into_iter().collect();
        let n = i64::from(CARRY_ROOM - 1);
        let mut s = ExactSum::new();
        for (l, &d) in s.limbs.iter_mut().zip(&one.limbs) {
            *l = d * n;
        }
        s.pending = CARRY_ROOM - 1;
        s.count = n as u64;
        s.add(x);
        assert_eq!(s.pending, 0, "normalised at the room's end");
        let bits = x.to_bits();
        let (k, p) = if (bits >> 52) & 0x7FF == 0 {
            (bits & ((1 << 52) - 1), -1074)
        } else {
            (
                (bits & ((1 << 52) - 1)) | 1 << 52,
                ((bits >> 52) & 0x7FF) as i32 - 1075,
            )
        };
        let k = if x < 0.0 { -(k as i128) } else { k as i128 };
        let total = (k * i128::from(CARRY_ROOM)) as f64;
        let want = if p >= -1022 {
            total * pow2(p)
        } else {
            total * pow2(-1074)
        };
        assert_eq!(s.value(), want.min(f64::INFINITY), "{x:e}");
    }
}

#[test]
fn refuses_bytes_that_are_not_a_sum() {
    let good = [1.5, -2.0].into_iter().collect::<ExactSum>().to_bytes();
    assert_eq!(good.len(), BYTES);
    assert!(ExactSum::from_bytes(&good[1..]).is_err());
    let mut bad = good.clone();
    bad[0] = b'Y';
    assert!(ExactSum::from_bytes(&bad).is_err());
    let mut bad = good.clone();
    bad[4] = 0x80; // an unknown flag
    assert!(ExactSum::from_bytes(&bad).is_err());
    let mut bad = good.clone();
    bad[16 + 7] = 0x80; // limb 0 negative: not normalised
    assert!(ExactSum::from_bytes(&bad).is_err());
    assert!(ExactSum::from_bytes(&good).is_ok());
}
