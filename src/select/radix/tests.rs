use super::*;
use proptest::prelude::*;

/// Values at every corner of the order: NaNs of both signs and payloads, infinities, extremes,
/// subnormals, both zeros.
fn corners64() -> Vec<f64> {
    vec![
        -f64::NAN,
        -f64::from_bits(0x7FF0_0000_0000_0001),
        f64::NEG_INFINITY,
        -f64::MAX,
        -1.0,
        -f64::MIN_POSITIVE,
        -f64::from_bits(1),
        -0.0,
        0.0,
        f64::from_bits(1),
        f64::from_bits((1 << 52) - 1),
        f64::MIN_POSITIVE,
        1.0,
        1.0 + f64::EPSILON,
        f64::MAX,
        f64::INFINITY,
        f64::from_bits(0x7FF0_0000_0000_0001),
        f64::NAN,
    ]
}

#[test]
fn the_keys_order_as_total_cmp_and_invert() {
    let v = corners64();
    for &a in &v {
        assert_eq!(f64::from_order_key(a.order_key()).to_bits(), a.to_bits());
        let a32 = a as f32;
        assert_eq!(
            f32::from_order_key(a32.order_key()).to_bits(),
            a32.to_bits()
        );
        assert!(a32.order_key() < 1 << 32);
        for &b in &v {
            assert_eq!(
                a.order_key().cmp(&b.order_key()),
                a.total_cmp(&b),
                "{a} {b}"
            );
            let b32 = b as f32;
            assert_eq!(a32.order_key().cmp(&b32.order_key()), a32.total_cmp(&b32));
        }
    }
    // the corners above are listed in that order
    assert!(v.windows(2).all(|w| w[0].order_key() < w[1].order_key()));
}

/// The reference: the element the standard library's selection puts at `rank`.
fn reference<T: OrderKey>(parts: &[Vec<T>], rank: usize) -> u64 {
    let mut all: Vec<u64> = parts.iter().flatten().map(|v| v.order_key()).collect();
    all.select_nth_unstable(rank);
    all[rank]
}

fn check<T: OrderKey + std::fmt::Debug>(parts: &[Vec<T>]) {
    let slices: Vec<&[T]> = parts.iter().map(Vec::as_slice).collect();
    let n: usize = parts.iter().map(Vec::len).sum();
    for rank in 0..n {
        let got = select_in_parts(&slices, rank as u64).expect("rank in range");
        assert_eq!(
            got.order_key(),
            reference(parts, rank),
            "rank {rank} of {parts:?}"
        );
    }
    assert!(select_in_parts(&slices, n as u64).is_err());
}

fn value64() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>(),
        prop::sample::select(corners64()),
        (-3i32..3).prop_map(f64::from), // many ties
        (0.0f64..1.0),
    ]
}

proptest! {
    #[test]
    fn every_rank_matches_the_standard_selection_f64(
        parts in prop::collection::vec(prop::collection::vec(value64(), 0..40), 0..5)
    ) {
        check(&parts);
    }

    #[test]
    fn every_rank_matches_the_standard_selection_f32(
        parts in prop::collection::vec(prop::collection::vec(
            prop_oneof![any::<f32>(), (-2i32..2).prop_map(|x| x as f32)], 0..40), 0..5)
    ) {
        check(&parts);
    }

    #[test]
    fn large_parts_and_any_split_agree_with_total_cmp(
        seed in any::<u64>(),
        cuts in prop::collection::vec(0usize..30_000, 0..6),
        ranks in prop::collection::vec(0usize..30_000, 4),
    ) {
        // values sharing a few exponents (as residuals do), with duplicates: the table path
        let mut s = seed | 1;
        let values: Vec<f64> = (0..30_000)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let x = (s >> 11) as f64 / (1u64 << 53) as f64;
                if s % 7 == 0 { 0.25 } else { x * 3.0 - 1.0 }
            })
            .collect();
        let mut bounds = cuts.clone();
        bounds.extend([0, values.len()]);
        bounds.sort_unstable();
        let parts: Vec<Vec<f64>> = bounds.windows(2).map(|w| values[w[0]..w[1]].to_vec()).collect();
        let slices: Vec<&[f64]> = parts.iter().map(Vec::as_slice).collect();
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        for rank in ranks {
            let got = select_in_parts(&slices, rank as u64).expect("rank in range");
            prop_assert_eq!(got.to_bits(), sorted[rank].to_bits());
            // and the library's own selection under the same order
            let mut v = values.clone();
            select_nth(&mut v, rank, &mut |a: &f64, b: &f64| a.total_cmp(b).is_lt(),
                       SelectAlgorithm::MedianOfMedians);
            prop_assert_eq!(got.to_bits(), v[rank].to_bits());
        }
    }
}

#[test]
fn all_equal_values_are_found_without_gathering() {
    let part = vec![2.5f64; 50_000];
    let parts: [&[f64]; 3] = [&part, &part[..7], &part];
    let mut search = RankSearch::<f64>::new(60_000);
    let mut rounds = 0;
    while let RankStep::Counts = search.step() {
        let mut counts = search.digit_counts(parts[0]);
        for p in &parts[1..] {
            counts.merge(&search.digit_counts(p)).unwrap();
        }
        search.feed_counts(&counts).unwrap();
        rounds += 1;
    }
    assert!(matches!(search.step(), RankStep::Found(v) if v == 2.5));
    assert_eq!(rounds, 4, "all 64 bits fixed by counting, nothing gathered");
}

#[test]
fn zeros_of_both_signs_and_nan_are_ordered_as_total_cmp() {
    let parts = [
        vec![0.0, -0.0, f64::NAN],
        vec![-0.0, -f64::NAN, 1.0],
        vec![0.0],
    ];
    let want = [-f64::NAN, -0.0, -0.0, 0.0, 0.0, 1.0, f64::NAN];
    let slices: Vec<&[f64]> = parts.iter().map(Vec::as_slice).collect();
    for (rank, w) in want.iter().enumerate() {
        let got = select_in_parts(&slices, rank as u64).unwrap();
        assert_eq!(got.to_bits(), w.to_bits(), "rank {rank}");
    }
}

#[test]
fn merged_counts_do_not_depend_on_the_order() {
    let a: Vec<f64> = (0..20_000).map(|i| (i % 977) as f64 * 0.37).collect();
    let b: Vec<f64> = (0..300).map(|i| -(i as f64)).collect();
    let c: Vec<f64> = (0..5000).map(|i| 1e-300 * i as f64).collect();
    let s = RankSearch::<f64>::new(0);
    let (ca, cb, cc) = (s.digit_counts(&a), s.digit_counts(&b), s.digit_counts(&c));
    let mut x = ca.clone();
    x.merge(&cb).unwrap();
    x.merge(&cc).unwrap();
    let mut y = cc.clone();
    y.merge(&ca).unwrap();
    let mut bc = cb.clone();
    bc.merge(&y).unwrap();
    assert_eq!(x, bc);
    assert_eq!(x.total(), 25_300);
    // the sparse (sorting) and table paths count alike
    let mut whole = a.clone();
    whole.extend(&b);
    whole.extend(&c);
    assert_eq!(s.digit_counts(&whole), x);
    let small = s.digit_counts(&whole[..100]);
    let mut big = whole[..100].to_vec();
    big.extend(std::iter::repeat_n(f64::NAN, SPARSE_BELOW));
    let mut with_nan = small.clone();
    with_nan
        .merge(&s.digit_counts(&vec![f64::NAN; SPARSE_BELOW]))
        .unwrap();
    assert_eq!(s.digit_counts(&big), with_nan);
}

#[test]
fn inconsistent_rounds_are_refused() {
    // values in [1, 2) that agree in their first 32 key bits: two counting rounds before the
    // bucket is small enough to gather
    let at = |i: i32| 1.0 + f64::from(i) * (-40f64).exp2();
    let a: Vec<f64> = (0..10_000).map(|i| at(2 * i)).collect();
    let b: Vec<f64> = (0..10_000).map(|i| at(2 * i + 1)).collect();
    // no values at all, or a rank past the end
    assert!(select_in_parts::<f64>(&[], 0).is_err());
    assert!(select_in_parts(&[&a[..], &b[..]], 20_000).is_err());
    let mut s = RankSearch::<f64>::new(9_999);
    assert!(s.feed_values(&a).is_err(), "values before counts");
    let mut first = s.digit_counts(&a);
    first.merge(&s.digit_counts(&b)).unwrap();
    s.feed_counts(&first).unwrap();
    // the first round's counts again: another round's
    assert!(s.feed_counts(&first).is_err());
    let mut other = s.digit_counts(&a);
    assert!(other.merge(&first).is_err());
    // a part left out of the second round
    assert!(matches!(s.step(), RankStep::Counts));
    assert!(s.feed_counts(&s.digit_counts(&a)).is_err());
    other.merge(&s.digit_counts(&b)).unwrap();
    s.feed_counts(&other).unwrap();
    while let RankStep::Counts = s.step() {
        let mut counts = s.digit_counts(&a);
        counts.merge(&s.digit_counts(&b)).unwrap();
        s.feed_counts(&counts).unwrap();
    }
    // a value from outside the bucket, or too few values
    assert!(matches!(s.step(), RankStep::Values));
    let mut values = s.matching_values(&a);
    values.extend(s.matching_values(&b));
    let mut wrong = values.clone();
    wrong[0] = 1.5;
    assert!(s.feed_values(&wrong).is_err());
    assert!(s.feed_values(&values[1..]).is_err());
    s.feed_values(&values).unwrap();
    assert!(matches!(s.step(), RankStep::Found(v) if v == at(9_999)));
}

#[test]
fn a_search_and_its_counts_travel_as_bytes() {
    let values: Vec<f64> = (0..20_000u64)
        .map(|i| ((i * 7919) % 10_007) as f64 * 0.25 - 100.0)
        .collect();
    let parts: Vec<&[f64]> = values.chunks(3000).collect();
    let travel = |c: DigitCounts| DigitCounts::from_bytes(&c.to_bytes()).unwrap();
    for rank in [0, 1, 9_999, 19_999] {
        let mut search = RankSearch::<f64>::new(rank);
        let found = loop {
            // the driver sends its state to the parts every round
            search = RankSearch::from_bytes(&search.to_bytes()).unwrap();
            match search.step() {
                RankStep::Found(v) => break v,
                RankStep::Counts => {
                    let mut merged = travel(search.digit_counts(&[]));
                    for p in &parts {
                        merged.merge(&travel(search.digit_counts(p))).unwrap();
                    }
                    search.feed_counts(&merged).unwrap();
                }
                RankStep::Values => {
                    let v: Vec<f64> = parts
                        .iter()
                        .flat_map(|p| search.matching_values(p))
                        .collect();
                    search.feed_values(&v).unwrap();
                }
            }
        };
        let direct = select_in_parts(&parts, rank).unwrap();
        assert_eq!(found.to_bits(), direct.to_bits());
    }
    // another value type, lengths, flags and prefixes no search reaches are refused
    let bytes = RankSearch::<f64>::new(3).to_bytes();
    assert!(RankSearch::<f32>::from_bytes(&bytes).is_err());
    assert!(RankSearch::<f64>::from_bytes(&bytes[1..]).is_err());
    let mut flag = bytes.clone();
    flag[21] = 2;
    assert!(RankSearch::<f64>::from_bytes(&flag).is_err());
    let mut bits = bytes;
    bits[17] = 7;
    assert!(RankSearch::<f64>::from_bytes(&bits).is_err());
    assert!(DigitCounts::from_bytes(&[0; 11]).is_err());
    let mut counts = RankSearch::<f64>::new(0)
        .digit_counts(&[1.0, 2.0])
        .to_bytes();
    counts.extend_from_within(12..22);
    assert!(DigitCounts::from_bytes(&counts).is_err(), "digits repeated");
}
