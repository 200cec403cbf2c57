use super::*;
use proptest::prelude::*;

/// Checks the postcondition of `select_nth` on `after` (a permutation of `before`) under the
/// strict weak order "key less than".
fn check_keys(before: &[(i64, u32)], after: &[(i64, u32)], k: usize) {
    let mut a = before.to_vec();
    let mut b = after.to_vec();
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b, "not a permutation of the input");
    let pivot = after[k].0;
    assert_eq!(pivot, a[k].0, "wrong element at rank {k}");
    assert!(after[..k].iter().all(|e| e.0 <= pivot), "greater before k");
    assert!(after[k + 1..].iter().all(|e| e.0 >= pivot), "less after k");
}

fn tagged(keys: &[i64]) -> Vec<(i64, u32)> {
    keys.iter()
        .enumerate()
        .map(|(i, &x)| (x, i as u32))
        .collect()
}

/// Runs every algorithm on `keys` for rank `k`, both with the key-only comparator (many
/// equivalent elements) and with the strict total order (key, tag).
fn check_all(keys: &[i64], k: usize) {
    let input = tagged(keys);
    for algo in SelectAlgorithm::ALL {
        let mut v = input.clone();
        select_nth(
            &mut v,
            k,
            &mut |a: &(i64, u32), b: &(i64, u32)| a.0 < b.0,
            algo,
        );
        check_keys(&input, &v, k);

        let mut v = input.clone();
        select_nth(&mut v, k, &mut |a: &(i64, u32), b: &(i64, u32)| a < b, algo);
        check_keys(&input, &v, k);
        let mut sorted = input.clone();
        sorted.sort_unstable();
        assert_eq!(v[k], sorted[k], "{algo:?}: strict order, rank {k}");
    }
}

fn ranks(n: usize) -> Vec<usize> {
    let mut ks = vec![
        0,
        n / 2,
        n - 1,
        n / 4,
        (3 * n) / 4,
        n.saturating_sub(2),
        1.min(n - 1),
    ];
    ks.sort_unstable();
    ks.dedup();
    ks
}

fn shapes(n: usize) -> Vec<(&'static str, Vec<i64>)> {
    let n64 = n as i64;
    vec![
        ("sorted", (0..n64).collect()),
        ("reverse", (0..n64).rev().collect()),
        (
            "organ pipe",
            (0..n64).map(|i| i.min(n64 - 1 - i)).collect::<Vec<_>>(),
        ),
        ("all equal", vec![7; n]),
        ("two values", (0..n64).map(|i| i % 2).collect()),
        ("few values", (0..n64).map(|i| (i * 7919) % 5).collect()),
        (
            "sawtooth",
            (0..n64).map(|i| i % (n64 / 10).max(1)).collect(),
        ),
        (
            "pseudo random",
            (0..n64)
                .map(|i| (i.wrapping_mul(2_654_435_761) ^ (i >> 3)) % 1_000_003)
                .collect(),
        ),
    ]
}

#[test]
fn tiny_inputs() {
    check_all(&[42], 0);
    for k in 0..2 {
        check_all(&[2, 1], k);
        check_all(&[1, 1], k);
    }
    for k in 0..3 {
        check_all(&[3, 1, 2], k);
        check_all(&[1, 3, 2], k);
        check_all(&[2, 2, 1], k);
    }
}

#[test]
fn structured_inputs_of_many_lengths() {
    for n in [1, 2, 3, 5, 16, 17, 47, 48, 49, 100, 601, 1000, 5003] {
        for (_, keys) in shapes(n) {
            for k in ranks(n) {
                check_all(&keys, k);
            }
        }
    }
}

#[test]
fn large_inputs_take_the_sampling_and_recursive_paths() {
    let n = 200_000;
    for (_, keys) in shapes(n) {
        let input = tagged(&keys);
        for algo in [
            SelectAlgorithm::Quickselect,
            SelectAlgorithm::FloydRivest,
            SelectAlgorithm::MedianOfMedians,
        ] {
            for k in [0, n / 2, n - 1, n / 3] {
                let mut v = input.clone();
                select_nth(
                    &mut v,
                    k,
                    &mut |a: &(i64, u32), b: &(i64, u32)| a.0 < b.0,
                    algo,
                );
                check_keys(&input, &v, k);
            }
        }
    }
}

/// Counts comparisons of one selection.
fn comparisons(keys: &[i64], k: usize, algo: SelectAlgorithm) -> usize {
    let mut v = keys.to_vec();
    let mut count = 0usize;
    select_nth(
        &mut v,
        k,
        &mut |a: &i64, b: &i64| {
            count += 1;
            a < b
        },
        algo,
    );
    count
}

#[test]
fn linear_number_of_comparisons() {
    let n = 100_000;
    for (name, keys) in shapes(n) {
        let k = n / 2;
        let fr = comparisons(&keys, k, SelectAlgorithm::FloydRivest);
        let qs = comparisons(&keys, k, SelectAlgorithm::Quickselect);
        let mom = comparisons(&keys, k, SelectAlgorithm::MedianOfMedians);
        assert!(fr < 3 * n, "{name}: Floyd–Rivest used {fr} comparisons");
        assert!(qs < 5 * n, "{name}: quickselect used {qs} comparisons");
        assert!(
            mom < 30 * n,
            "{name}: median of medians used {mom} comparisons"
        );
    }
}

#[test]
fn exhausted_budget_falls_back_to_median_of_medians() {
    let n = 5000;
    for (_, keys) in shapes(n) {
        let input = tagged(&keys);
        for budget in [0, n, 2 * n] {
            for k in ranks(n) {
                let less = &mut |a: &(i64, u32), b: &(i64, u32)| a.0 < b.0;
                let mut v = input.clone();
                quickselect::select_with_budget(&mut v, k, less, budget);
                check_keys(&input, &v, k);
                let mut v = input.clone();
                floyd_rivest::select_with_budget(&mut v, k, less, budget);
                check_keys(&input, &v, k);
            }
        }
    }
}

#[test]
fn deterministic() {
    let keys: Vec<i64> = (0..10_000).map(|i| (i * 7919) % 10_007).collect();
    for algo in SelectAlgorithm::ALL {
        let mut a = keys.clone();
        let mut b = keys.clone();
        select_nth(&mut a, 4321, &mut |x: &i64, y: &i64| x < y, algo);
        select_nth(&mut b, 4321, &mut |x: &i64, y: &i64| x < y, algo);
        assert_eq!(a, b);
    }
}

#[test]
fn median_of_five_is_correct_for_every_order() {
    // All 5^5 words over five values: covers every permutation and every tie pattern.
    for code in 0..5usize.pow(5) {
        let mut g: Vec<u8> = (0..5).map(|i| ((code / 5usize.pow(i)) % 5) as u8).collect();
        let mut sorted = g.clone();
        sorted.sort_unstable();
        let mut perm = g.clone();
        let m = median_of_medians::median_of_five_for_tests(&mut g, &mut |a: &u8, b: &u8| a < b);
        assert_eq!(g[m], sorted[2], "{perm:?}");
        perm.sort_unstable();
        let mut after = g.clone();
        after.sort_unstable();
        assert_eq!(perm, after, "median of five lost an element");
    }
}

#[test]
#[should_panic(expected = "out of range")]
fn rank_out_of_range_panics() {
    let mut v = [1, 2, 3];
    select_nth(
        &mut v,
        3,
        &mut |a: &i32, b: &i32| a < b,
        SelectAlgorithm::Quickselect,
    );
}

#[test]
#[should_panic(expected = "out of range")]
fn empty_slice_panics() {
    let mut v: [i32; 0] = [];
    select_nth(
        &mut v,
        0,
        &mut |a: &i32, b: &i32| a < b,
        SelectAlgorithm::Sort,
    );
}

#[test]
fn inconsistent_comparator_does_not_panic_or_hang() {
    // Not a strict weak order: no guarantee on the result, but it must terminate in bounds and
    // keep the elements.
    let keys: Vec<i64> = (0..3000).map(|i| (i * 37) % 101).collect();
    for algo in [
        SelectAlgorithm::Quickselect,
        SelectAlgorithm::FloydRivest,
        SelectAlgorithm::MedianOfMedians,
    ] {
        let mut v = keys.clone();
        let mut flip = false;
        select_nth(
            &mut v,
            1500,
            &mut |a: &i64, b: &i64| {
                flip = !flip;
                if flip {
                    a < b
                } else {
                    a <= b
                }
            },
            algo,
        );
        let mut a = keys.clone();
        a.sort_unstable();
        v.sort_unstable();
        assert_eq!(a, v);
    }
}

proptest! {
    #[test]
    fn postcondition_random_keys(
        keys in prop::collection::vec(any::<i64>(), 1..2000),
        k_frac in 0.0f64..1.0,
    ) {
        let k = ((keys.len() as f64 * k_frac) as usize).min(keys.len() - 1);
        check_all(&keys, k);
    }

    #[test]
    fn postcondition_many_duplicates(
        keys in prop::collection::vec(0i64..8, 1..2000),
        k_frac in 0.0f64..1.0,
    ) {
        let k = ((keys.len() as f64 * k_frac) as usize).min(keys.len() - 1);
        check_all(&keys, k);
    }

    #[test]
    fn postcondition_float_keys_via_total_order(
        keys in prop::collection::vec(-1e3f64..1e3, 1..2000),
        k_frac in 0.0f64..1.0,
    ) {
        let k = ((keys.len() as f64 * k_frac) as usize).min(keys.len() - 1);
        let mut sorted = keys.clone();
        sorted.sort_unstable_by(f64::total_cmp);
        for algo in SelectAlgorithm::ALL {
            let mut v = keys.clone();
            select_nth(&mut v, k, &mut |a: &f64, b: &f64| a < b, algo);
            prop_assert_eq!(v[k], sorted[k]);
            prop_assert!(v[..k].iter().all(|&x| x <= v[k]));
            prop_assert!(v[k + 1..].iter().all(|&x| x >= v[k]));
        }
    }
}

#[test]
fn selects_the_median_index_by_coordinate() {
    // indices of points, ordered by their x coordinate (ties by index: a strict total order)
    let xs = [0.5, -1.0, 2.0, 0.5, 3.0];
    for algo in SelectAlgorithm::ALL {
        let mut idx: Vec<u32> = (0..5).collect();
        let mut less = |a: &u32, b: &u32| {
            let (p, q) = (xs[*a as usize], xs[*b as usize]);
            p < q || (p == q && a < b)
        };
        select_nth(&mut idx, 2, &mut less, algo);
        assert_eq!(idx[2], 3, "{algo:?}"); // the median: x = 0.5, second of the two by index
        assert!(idx[..2].iter().all(|&i| less(&i, &3)), "{algo:?}");
        assert!(idx[3..].iter().all(|&i| less(&3, &i)), "{algo:?}");
    }
}
