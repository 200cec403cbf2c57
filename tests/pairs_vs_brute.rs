//! Pair queries (`NeighborIndex::pairs`, `pairs_with`, `count_pairs_with`, `weigh_pairs_with`;
//! scipy's `query_pairs`, `query_ball_tree`, `sparse_distance_matrix`, `count_neighbors`)
//! against a brute force over every pair, written here from the definitions
//! (`tests/common/keys.rs`): for p ∈ {1, 1.5, 2, 3, ∞}, f32 and f64, d ∈ {1, 2, 3, 5}, plain
//! trees and periodic boxes (every axis, and some axes with open ones beside them), every pivot
//! policy, on a grid of step L/4 (exact ties, pairs exactly on the radius, pairs across the
//! box's edge at exactly L/2), random points and copies of a few points (zero distances):
//! the static and the growing tree give the brute force's pairs and keys bit for bit, on 1 and
//! 2 threads; counts are exact, cumulative and not, with and without weights, for radii
//! negative, 0, on the grid, repeated and infinite. With eps > 0 the pairs keep scipy's
//! contract (all within r / (1 + eps), none beyond r · (1 + eps)) and are exactly those within
//! r · (1 + eps), on any tree (scipy's test_query_pairs_eps counts on it). Empty trees, bad radii,
//! weights and options are refused or answered as documented.

mod common;

use common::keys::key;
use common::trees::static_and_growing;
use common::Rng;
use nbhd::{
    BuildOptions, KdTree, Metric, NbhdError, NeighborIndex, NeighborTable, PairWeights,
    PivotPolicy, PointsView, QueryOptions, Scalar, TableOptions,
};

const PS: [f64; 5] = [1.0, 1.5, 2.0, 3.0, f64::INFINITY];
const DIMS: [usize; 4] = [1, 2, 3, 5];
/// The box size on periodic axes.
const L: f64 = 2.0;

/// `n` points of dimension `d` in `[0, L)` on every axis: a grid of step L/4, random, or
/// copies of three points.
fn cloud(kind: usize, n: usize, d: usize, rng: &mut Rng) -> Vec<f64> {
    let base: Vec<f64> = (0..3 * d).map(|_| rng.unit() * L).collect();
    (0..n)
        .flat_map(|_| {
            let c = rng.below(3);
            let v: Vec<f64> = (0..d)
                .map(|j| match kind {
                    0 => rng.below(4) as f64 * L / 4.0,
                    1 => rng.unit() * L,
                    _ => base[c * d + j],
                })
                .collect();
            v
        })
        .collect()
}

/// The boxes of a test: none, `L` on every axis, `L` on the even axes (odd ones open); as
/// given to the tree and as the brute force uses them (+∞ on open axes).
fn boxes(d: usize, which: usize) -> (Option<Vec<f64>>, Vec<f64>) {
    let given: Vec<f64> = (0..d)
        .map(|j| if which == 2 && j % 2 == 1 { 0.0 } else { L })
        .collect();
    let sizes = given
        .iter()
        .map(|&s| {
            if which == 0 || s == 0.0 {
                f64::INFINITY
            } else {
                s
            }
        })
        .collect();
    ((which > 0).then_some(given), sizes)
}

/// Row `i` of `a`: `(j, key)` for every point `j` of `b` (`j > i` if `upper`) whose key from
/// `b[j]` to `a[i]` is at most `bound`, `j` ascending.
fn brute<T: Scalar>(
    a: &[T],
    b: &[T],
    d: usize,
    sizes: &[T],
    metric: Metric,
    bound: T,
    upper: bool,
) -> Vec<Vec<(u32, T)>> {
    a.chunks_exact(d)
        .enumerate()
        .map(|(i, p)| {
            b.chunks_exact(d)
                .enumerate()
                .filter(|&(j, _)| !upper || j > i)
                .map(|(j, q)| (j as u32, key(metric, q, p, sizes)))
                .filter(|&(_, k)| k <= bound)
                .collect()
        })
        .collect()
}

fn rows_of<T: Scalar>(t: &NeighborTable<T>) -> Vec<Vec<(u32, T)>> {
    (0..t.len())
        .map(|i| {
            let ks = t.sq_dists_of(i).iter().copied();
            t.indices_of(i).iter().copied().zip(ks).collect()
        })
        .collect()
}

fn table(query: QueryOptions, threads: usize) -> TableOptions {
    TableOptions {
        threads,
        query,
        ..TableOptions::default()
    }
}

/// Pairs within one index and between two, both flavours, 1 and 2 threads, against the brute
/// force.
fn check_pairs<T: Scalar>(a: &[T], b: &[T], d: usize, given: Option<&[f64]>, sizes: &[T]) {
    for (c, &p) in PS.iter().enumerate() {
        let pivot = PivotPolicy::ALL[(c + d) % PivotPolicy::ALL.len()];
        let (ta, ga) = static_and_growing(a, d, given, pivot);
        let (tb, _) = static_and_growing(b, d, given, pivot);
        let metric = Metric::from_p(p).unwrap();
        let exact = QueryOptions::with_p(p).unwrap();
        for r in [0.0, L / 4.0, L / 2.0, 0.8 * L] {
            let r = T::from_f64(r);
            let bound = metric.key_of(r);
            let what = format!("p {p} d {d} r {r} box {given:?}");
            let want = brute(a, a, d, sizes, metric, bound, true);
            let one = ta.pairs(r, &table(exact, 1)).unwrap();
            assert_eq!(rows_of(&one), want, "pairs: {what}");
            assert_eq!(ta.pairs(r, &table(exact, 2)).unwrap(), one, "{what}");
            assert_eq!(ga.pairs(r, &table(exact, 2)).unwrap(), one, "{what}");
            let want = brute(a, b, d, sizes, metric, bound, false);
            let with = ta.pairs_with(&tb, r, &table(exact, 1)).unwrap();
            assert_eq!(rows_of(&with), want, "pairs_with: {what}");
            assert_eq!(ga.pairs_with(&tb, r, &table(exact, 2)).unwrap(), with);
        }
        check_counts(&ta, &tb, a, b, d, sizes, metric);
        check_eps(&ta, a, d, sizes, metric);
    }
}

/// Counts in bins of radii (negative, 0, on the grid, repeated, infinite) against the brute
/// force's keys, cumulative and not, unweighted and with weights whose sums are exact.
fn check_counts<T: Scalar>(
    ta: &KdTree<T>,
    tb: &KdTree<T>,
    a: &[T],
    b: &[T],
    d: usize,
    sizes: &[T],
    metric: Metric,
) {
    let radii: Vec<T> = [-1.0, 0.0, L / 4.0, L / 4.0, L / 2.0, f64::INFINITY]
        .iter()
        .map(|&r| T::from_f64(r))
        .collect();
    let keys = brute(a, b, d, sizes, metric, T::INFINITY, false);
    let wa: Vec<f64> = (0..a.len() / d).map(|i| (i % 4) as f64 * 0.5).collect();
    let wb: Vec<f64> = (0..b.len() / d).map(|j| (j % 3 + 1) as f64).collect();
    let upto = |r: T, lo: Option<T>| -> (u64, f64) {
        let mut n = (0, 0.0);
        for (i, row) in keys.iter().enumerate() {
            for &(j, k) in row {
                let inside = r >= T::ZERO && k <= metric.key_of(r);
                let above = lo.is_none_or(|lo| lo < T::ZERO || k > metric.key_of(lo));
                if inside && above {
                    n = (n.0 + 1, n.1 + wa[i] * wb[j as usize]);
                }
            }
        }
        n
    };
    let opts = table(QueryOptions::with_p(metric.p()).unwrap(), 2);
    let w = PairWeights {
        this: Some(&wa),
        other: Some(&wb),
    };
    let cum = ta.count_pairs_with(tb, &radii, true, &opts).unwrap();
    let wcum = ta.weigh_pairs_with(tb, &radii, w, true, &opts).unwrap();
    let non = ta.count_pairs_with(tb, &radii, false, &opts).unwrap();
    let wnon = ta.weigh_pairs_with(tb, &radii, w, false, &opts).unwrap();
    for (k, &r) in radii.iter().enumerate() {
        let (n, s) = upto(r, None);
        assert_eq!((cum[k], wcum[k]), (n, s), "cumulative, radius {r}");
        let repeated = k > 0 && radii[k - 1] == r;
        let want = if repeated {
            (0, 0.0)
        } else {
            upto(r, (k > 0).then(|| radii[k - 1]))
        };
        assert_eq!((non[k], wnon[k]), want, "non-cumulative, radius {r}");
    }
    // radii in any order when cumulative; one side weighted
    let mixed = [radii[4], radii[1], radii[5]];
    let got = ta.count_pairs_with(tb, &mixed, true, &opts).unwrap();
    assert_eq!(got, [cum[4], cum[1], cum[5]]);
    let one_side = PairWeights {
        this: None,
        other: Some(&wb),
    };
    let got = ta
        .weigh_pairs_with(tb, &mixed, one_side, true, &opts)
        .unwrap();
    let ones: f64 = keys.iter().flatten().map(|&(j, _)| wb[j as usize]).sum();
    assert_eq!(got[2], ones);
}

/// eps > 0: every pair within r / (1 + eps) is found, none beyond r · (1 + eps) (keys with a
/// little slack for the rounding of the factors) — scipy's contract — and in fact exactly the
/// pairs within r · (1 + eps), the key the pairs are accepted up to (`NeighborIndex::pairs`).
fn check_eps<T: Scalar>(ta: &KdTree<T>, a: &[T], d: usize, sizes: &[T], metric: Metric) {
    let eps = 0.5;
    let opts = QueryOptions {
        eps,
        ..QueryOptions::with_p(metric.p()).unwrap()
    };
    let r = T::from_f64(L / 4.0);
    let f = metric.eps_factor(eps);
    let inner = T::from_f64(metric.key_of(r).to_f64() * f * (1.0 - 1e-6));
    let outer = metric.key_of(r).to_f64() / f * (1.0 + 1e-6);
    let got = rows_of(&ta.pairs(r, &table(opts, 2)).unwrap());
    let must = brute(a, a, d, sizes, metric, inner, true);
    for (row, need) in got.iter().zip(&must) {
        assert!(
            need.iter().all(|e| row.contains(e)),
            "eps: a near pair lost"
        );
        assert!(
            row.iter().all(|&(_, k)| k.to_f64() <= outer),
            "eps: a far pair"
        );
    }
    let accepted = metric.key_of(r) * T::from_f64(1.0 / f);
    let mut all = brute(a, a, d, sizes, metric, accepted, true);
    all.iter_mut().for_each(|row| row.sort_by_key(|&(j, _)| j));
    assert_eq!(got, all, "eps: the pairs within r · (1 + eps)");
}

fn run<T: Scalar>(seed: u64) {
    let mut rng = Rng::new(seed);
    for d in DIMS {
        for kind in 0..3 {
            for which in 0..3 {
                let (given, sizes) = boxes(d, which);
                let a: Vec<T> = cloud(kind, 50, d, &mut rng)
                    .iter()
                    .map(|&x| T::from_f64(x))
                    .collect();
                let b: Vec<T> = cloud(kind, 30, d, &mut rng)
                    .iter()
                    .map(|&x| T::from_f64(x))
                    .collect();
                let sizes: Vec<T> = sizes.iter().map(|&s| T::from_f64(s)).collect();
                check_pairs(&a, &b, d, given.as_deref(), &sizes);
            }
        }
    }
}

#[test]
fn pairs_equal_the_brute_force_f64() {
    run::<f64>(11);
}

#[test]
fn pairs_equal_the_brute_force_f32() {
    run::<f32>(12);
}

/// scipy's `test_query_pairs_eps`: a 4 × 4 grid of step √2 (irrational: some neighbours'
/// distances round just above √2). With r = √2 only the pairs computed ≤ √2 come back; with
/// eps = 0.1 all 24 grid neighbours do, whichever cells the tree splits the grid into.
#[test]
fn pairs_with_eps_keep_the_neighbours_an_ulp_beyond_the_radius() {
    let s = 2f64.sqrt();
    let line: Vec<f64> = (0..4).map(|i| i as f64 * (3.0 * s / 3.0)).collect();
    let grid: Vec<f64> = line
        .iter()
        .flat_map(|&x| line.iter().flat_map(move |&y| [x, y]))
        .collect();
    let view = PointsView::from_flat(&grid, 2).unwrap();
    for pivot in PivotPolicy::ALL {
        for leaf_size in [1, 4, 10, 16] {
            let opts = BuildOptions {
                pivot,
                leaf_size,
                ..BuildOptions::default()
            };
            let tree = KdTree::build(&view, &opts).unwrap();
            let count = |eps: f64, r: f64| {
                let query = QueryOptions {
                    eps,
                    ..QueryOptions::default()
                };
                tree.pairs(r, &table(query, 1)).unwrap().total()
            };
            let exact = count(0.0, s);
            assert!(
                exact < 24,
                "{pivot:?} {leaf_size}: rounding keeps {exact} of 24"
            );
            assert_eq!(count(0.1, s), 24, "{pivot:?} {leaf_size}");
            assert_eq!(count(0.0, s * 1.01), 24, "{pivot:?} {leaf_size}");
        }
    }
}

/// Euclidean pairs in 3-D clouds of a few hundred points, where `pairs_with` answers by the
/// grouped searches (a growing index: the other index's points as its grouped batch; a static
/// tree against itself: its own table): the brute force's pairs and keys bit for bit for every
/// pivot policy, leaves of 3 and 16, 1 and 2 threads, f32 and f64 — also with a growing tree
/// with removed points (empty rows, caller indices with gaps) as the other side.
fn check_grouped_pairs<T: Scalar>(seed: u64) {
    let mut rng = Rng::new(seed);
    let sizes = [T::INFINITY; 3];
    let metric = Metric::Euclidean;
    for kind in 0..3 {
        let a: Vec<T> = cloud(kind, 400, 3, &mut rng)
            .iter()
            .map(|&x| T::from_f64(x))
            .collect();
        let b: Vec<T> = cloud(kind, 300, 3, &mut rng)
            .iter()
            .map(|&x| T::from_f64(x))
            .collect();
        let removed: Vec<u32> = (0..300).filter(|j| j % 7 == 3).collect();
        let ga = static_and_growing(&a, 3, None, PivotPolicy::ALL[1]).1;
        let mut gb = static_and_growing(&b, 3, None, PivotPolicy::ALL[0]).1;
        gb.remove(&removed).unwrap();
        for pivot in PivotPolicy::ALL {
            for leaf_size in [3, 16] {
                let opts = BuildOptions {
                    pivot,
                    leaf_size,
                    ..BuildOptions::default()
                };
                let ta = KdTree::from_flat(&a, 3, &opts).unwrap();
                let tb = KdTree::from_flat(&b, 3, &opts).unwrap();
                for r in [0.0, L / 8.0, L / 4.0, L / 2.0] {
                    let r = T::from_f64(r);
                    let bound = metric.key_of(r);
                    let what = format!("kind {kind} {pivot:?} leaf {leaf_size} r {r}");
                    let exact = QueryOptions::default();
                    let one = ta.pairs(r, &table(exact, 1)).unwrap();
                    assert_eq!(
                        rows_of(&one),
                        brute(&a, &a, 3, &sizes, metric, bound, true),
                        "{what}"
                    );
                    assert_eq!(ta.pairs(r, &table(exact, 2)).unwrap(), one, "{what}");
                    let with = ta.pairs_with(&tb, r, &table(exact, 2)).unwrap();
                    let want = brute(&a, &b, 3, &sizes, metric, bound, false);
                    assert_eq!(rows_of(&with), want, "pairs_with: {what}");
                    let grown = ga.pairs_with(&tb, r, &table(exact, 2)).unwrap();
                    assert_eq!(grown, with, "growing pairs_with: {what}");
                    let own = ta.pairs_with(&ta, r, &table(exact, 2)).unwrap();
                    let all = brute(&a, &a, 3, &sizes, metric, bound, false);
                    assert_eq!(rows_of(&own), all, "pairs_with itself: {what}");
                    let gapped = ta.pairs_with(&gb, r, &table(exact, 1)).unwrap();
                    let want: Vec<Vec<(u32, T)>> = want
                        .into_iter()
                        .map(|row| row.into_iter().filter(|(j, _)| j % 7 != 3).collect())
                        .collect();
                    assert_eq!(rows_of(&gapped), want, "pairs_with removed: {what}");
                }
            }
        }
    }
}

#[test]
fn euclidean_pairs_on_the_grouped_paths_equal_the_brute_force() {
    check_grouped_pairs::<f64>(21);
    check_grouped_pairs::<f32>(22);
}

#[test]
fn empty_indexes_have_no_pairs() {
    let opts = BuildOptions::default();
    let empty =
        KdTree::<f64>::build(&PointsView::from_flat::<f64>(&[], 2).unwrap(), &opts).unwrap();
    let some = KdTree::<f64>::from_flat(&[0.0, 0.0, 1.0, 1.0], 2, &opts).unwrap();
    let t = TableOptions::default();
    assert_eq!(empty.pairs(1.0, &t).unwrap().len(), 0);
    let rows = some.pairs_with(&empty, 1.0, &t).unwrap();
    assert_eq!((rows.len(), rows.total()), (2, 0));
    assert_eq!(empty.pairs_with(&some, 1.0, &t).unwrap().len(), 0);
    let radii = [1.0, f64::INFINITY];
    assert_eq!(
        empty.count_pairs_with(&some, &radii, true, &t).unwrap(),
        [0, 0]
    );
    assert_eq!(
        some.count_pairs_with(&empty, &radii, false, &t).unwrap(),
        [0, 0]
    );
    let none = some.weigh_pairs_with(&empty, &radii, PairWeights::default(), true, &t);
    assert_eq!(none.unwrap(), [0.0, 0.0]);
    assert_eq!(some.count_pairs_with(&some, &[], true, &t).unwrap(), []);
}

#[test]
fn bad_radii_weights_and_options_are_refused() {
    let opts = BuildOptions::default();
    let tree = KdTree::<f64>::from_flat(&[0.0, 0.0, 1.0, 1.0, 1.0, 2.0], 2, &opts).unwrap();
    let line = KdTree::<f64>::from_flat(&[0.0, 1.0], 1, &opts).unwrap();
    let t = TableOptions::default();
    for r in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            tree.pairs(r, &t),
            Err(NbhdError::InvalidRadius(_))
        ));
        assert!(tree.pairs_with(&tree, r, &t).is_err());
    }
    assert!(matches!(
        tree.pairs_with(&line, 1.0, &t),
        Err(NbhdError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        tree.count_pairs_with(&line, &[1.0], true, &t),
        Err(NbhdError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        tree.count_pairs_with(&tree, &[1.0, f64::NAN], true, &t),
        Err(NbhdError::InvalidRadius(_))
    ));
    assert!(matches!(
        tree.count_pairs_with(&tree, &[2.0, 1.0], false, &t),
        Err(NbhdError::InvalidOption { name: "radii", .. })
    ));
    let eps = TableOptions {
        query: QueryOptions {
            eps: 0.1,
            ..QueryOptions::default()
        },
        ..t
    };
    assert!(matches!(
        tree.count_pairs_with(&tree, &[1.0], true, &eps),
        Err(NbhdError::InvalidOption { name: "eps", .. })
    ));
    let short = [1.0, 2.0];
    let nan = [1.0, f64::NAN, 1.0];
    for w in [&short[..], &nan[..]] {
        let weights = PairWeights {
            this: Some(w),
            other: None,
        };
        let got = tree.weigh_pairs_with(&tree, &[1.0], weights, true, &t);
        assert!(matches!(got, Err(NbhdError::InvalidOption { .. })), "{w:?}");
    }
    // (1, 1) and (1, 2) are 1 apart, (0, 0) and (1, 1) √2: a strict radius leaves out the
    // pairs exactly on it
    let strict = TableOptions {
        query: QueryOptions {
            strict: true,
            ..QueryOptions::default()
        },
        ..t
    };
    assert_eq!(tree.pairs(1.2, &t).unwrap().total(), 1);
    assert_eq!(tree.pairs(1.0, &t).unwrap().total(), 1);
    assert_eq!(tree.pairs(1.0, &strict).unwrap().total(), 0);
    assert_eq!(tree.count_pairs_with(&tree, &[1.0], true, &t).unwrap(), [5]);
    assert_eq!(
        tree.count_pairs_with(&tree, &[1.0], true, &strict).unwrap(),
        [3]
    );
}

/// The static tree's pairs come from its self-join over the leaves (each pair of leaves once),
/// the growing tree's from one search per point: over the seven kinds of sets of
/// `tests/common` (duplicates, all points identical, zero-extent axes, integer grids with
/// pairs exactly on the radius), d = 1–5, every pivot policy, leaves of 1, 2 and 7 points (many
/// leaves, so the descents prune), radii at quantiles of the pair distances and on the grid's
/// steps, inclusive and strict, Euclidean, p = 1 and a periodic box: both equal the brute force
/// bit for bit, on 1 and 2 threads.
fn check_self_join_on_every_kind<T: Scalar>(seed: u64) {
    use common::{points, KINDS};
    for (c, kind) in KINDS.into_iter().enumerate() {
        for d in 1..=5 {
            let pts: Vec<T> = points(kind, 120, d, seed + c as u64 * 10 + d as u64)
                .iter()
                .map(|&x| T::from_f64(x))
                .collect();
            let open = vec![T::INFINITY; d];
            let mut dists: Vec<f64> =
                brute(&pts, &pts, d, &open, Metric::Euclidean, T::INFINITY, true)
                    .iter()
                    .flatten()
                    .map(|&(_, k)| k.to_f64().sqrt())
                    .collect();
            dists.sort_by(f64::total_cmp);
            let mut radii = vec![0.0, 1.0, 2.0];
            radii.extend([0.02, 0.1, 0.3].map(|q| dists[(q * (dists.len() - 1) as f64) as usize]));
            for (v, pivot) in PivotPolicy::ALL.into_iter().enumerate() {
                let leaf_size = [1, 2, 7][(v + d) % 3];
                check_join_case(&pts, d, pivot, leaf_size, &radii, kind);
            }
        }
    }
}

/// [`check_self_join_on_every_kind`] for one set, pivot policy and leaf size.
fn check_join_case<T: Scalar>(
    pts: &[T],
    d: usize,
    pivot: PivotPolicy,
    leaf_size: usize,
    radii: &[f64],
    kind: common::Kind,
) {
    let opts = BuildOptions {
        pivot,
        leaf_size,
        ..BuildOptions::default()
    };
    // a periodic box around the set: the points shifted into [0, 12) on every axis
    let shifted: Vec<T> = pts.iter().map(|&x| x + T::from_f64(6.0)).collect();
    let (lo, hi) = shifted
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x.to_f64()), h.max(x.to_f64()))
        });
    let fits = lo >= 0.0 && hi < 12.0;
    let tree = KdTree::from_flat(pts, d, &opts).unwrap();
    let periodic = fits.then(|| {
        let view = PointsView::from_flat(&shifted, d).unwrap();
        KdTree::build_periodic(&view, &opts, &[12.0]).unwrap()
    });
    let (_, growing) = static_and_growing(pts, d, None, pivot);
    let open = vec![T::INFINITY; d];
    let sizes = vec![T::from_f64(12.0); d];
    for &r in radii {
        let r = T::from_f64(r);
        for (p, strict) in [(2.0, false), (2.0, true), (1.0, false)] {
            let metric = Metric::from_p(p).unwrap();
            let query = QueryOptions {
                strict,
                ..QueryOptions::with_p(p).unwrap()
            };
            let key = metric.key_of(r);
            let bound = if strict { key.next_down() } else { key };
            let what =
                format!("{kind:?} d {d} {pivot:?} leaf {leaf_size} r {r} p {p} strict {strict}");
            let one = tree.pairs(r, &table(query, 1)).unwrap();
            assert_eq!(
                rows_of(&one),
                brute(pts, pts, d, &open, metric, bound, true),
                "{what}"
            );
            assert_eq!(
                tree.pairs(r, &table(query, 2)).unwrap(),
                one,
                "2 threads: {what}"
            );
            assert_eq!(
                growing.pairs(r, &table(query, 2)).unwrap(),
                one,
                "growing: {what}"
            );
            if let Some(t) = &periodic {
                let want = brute(&shifted, &shifted, d, &sizes, metric, bound, true);
                let got = t.pairs(r, &table(query, 2)).unwrap();
                assert_eq!(rows_of(&got), want, "periodic: {what}");
            }
        }
    }
}

#[test]
fn self_join_pairs_equal_the_brute_force_on_every_kind_of_set() {
    check_self_join_on_every_kind::<f64>(31);
    check_self_join_on_every_kind::<f32>(32);
}
