//! Property tests of queries under a Minkowski metric (`QueryOptions`, `src/metric.rs`): for
//! p ∈ {1, 1.5, 2, 3, 100, ∞}, f32 and f64, d ∈ {1, 2, 3, 5} and every pivot policy, the static
//! and the growing tree give exactly the brute force's neighbours and keys (same bits, same
//! `(key, index)` order) for the k nearest, radius and ε-k queries, inclusive and strict, on
//! random points, grids (ties everywhere, points exactly on the radius), copies of a few points
//! and sets with an axis of zero extent; tables are identical on 1 and 2 threads. Approximate
//! searches (`eps`) keep their guarantee: the i-th neighbour within `(1 + eps)` times the true
//! i-th, and a radius result between the balls of `r / (1 + eps)` and `r · (1 + eps)`.

mod common;

use common::trees::static_and_growing;
use common::{points, to_f32, Kind, Rng};
use nbhd::{
    BruteForce, BuildOptions, DynamicKdTree, KdTree, Metric, NbhdError, Neighbor, NeighborIndex,
    Neighborhood, NonFinitePolicy, PivotPolicy, PointsView, Query, QueryOptions, Scalar,
    TableOptions,
};
use proptest::prelude::*;

const PS: [f64; 6] = [1.0, 1.5, 2.0, 3.0, 100.0, f64::INFINITY];
const DIMS: [usize; 4] = [1, 2, 3, 5];

/// The point sets: random, a grid of step 0.5 (exact ties, distances of exactly 1 in every
/// metric), copies of a few points, random with axis 0 of zero extent.
fn cloud(kind: usize, n: usize, d: usize, seed: u64) -> Vec<f64> {
    match kind {
        0 => points(Kind::Random, n, d, seed),
        1 => {
            let mut rng = Rng::new(seed);
            (0..n * d).map(|_| rng.below(5) as f64 * 0.5).collect()
        }
        2 => points(Kind::DuplicateHeavy, n, d, seed),
        _ => {
            let mut v = points(Kind::Random, n, d, seed);
            v.iter_mut().step_by(d).for_each(|x| *x = 1.25);
            v
        }
    }
}

/// The queries of a set: stored points with and without themselves, points of the set
/// moved a little, and a point of the grid (on cell boundaries and at distance 1 of
/// neighbours).
fn queries<T: Scalar>(coords: &[T], d: usize, rng: &mut Rng) -> (Vec<u32>, Vec<Vec<T>>) {
    let n = coords.len() / d;
    let stored: Vec<u32> = (0..4).map(|_| rng.below(n) as u32).collect();
    let mut free: Vec<Vec<T>> = stored[..2]
        .iter()
        .map(|&s| {
            coords[s as usize * d..(s as usize + 1) * d]
                .iter()
                .map(|&c| c + T::from_f64((rng.unit() - 0.5) * 0.4))
                .collect()
        })
        .collect();
    free.push(vec![T::from_f64(1.0); d]);
    (stored, free)
}

fn nbhds<T: Scalar>(n: usize, radius: T) -> Vec<Neighborhood<T>> {
    vec![
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 5 },
        Neighborhood::Knn { k: n + 2 },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
        Neighborhood::KnnRadius { k: 4, radius },
    ]
}

/// Tree, growing tree and brute force agree exactly for every query under `options`.
fn check_exact<T: Scalar>(coords: &[T], d: usize, options: &QueryOptions, seed: u64) {
    let view = PointsView::from_flat(coords, d).unwrap();
    let n = view.len();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let mut rng = Rng::new(seed);
    let (stored, free) = queries(coords, d, &mut rng);
    // radii: 1 (points of the grid exactly on it in every metric) and the distance of a
    // stored point's 3rd neighbour (exactly on it for p = 1, ∞)
    let mut tmp = Vec::new();
    let knn3 = Neighborhood::Knn { k: 3.min(n) };
    brute
        .search_with(Query::stored(stored[0]), knn3, options, &mut tmp)
        .unwrap();
    let far = options.metric.distance_of(tmp.last().unwrap().sq_dist);
    // (keys of p = 100 overflow f32 beyond a distance of 2.4)
    let far = if far.is_finite() {
        far
    } else {
        T::from_f64(2.0)
    };
    for pivot in PivotPolicy::ALL {
        let (tree, growing) = static_and_growing(coords, d, None, pivot);
        let mut qs: Vec<Query<'_, T>> = stored
            .iter()
            .flat_map(|&s| [Query::stored(s), Query::stored_excluding_self(s)])
            .collect();
        qs.extend(free.iter().map(|p| Query::point(p)));
        for radius in [T::from_f64(1.0), far] {
            for nbhd in nbhds(n, radius) {
                for &q in &qs {
                    let (mut want, mut got, mut grown) = (Vec::new(), Vec::new(), Vec::new());
                    brute.search_with(q, nbhd, options, &mut want).unwrap();
                    tree.search_with(q, nbhd, options, &mut got).unwrap();
                    growing.search_with(q, nbhd, options, &mut grown).unwrap();
                    let what = format!("{options:?} {pivot:?} {nbhd:?} {q:?}");
                    assert_eq!(got, want, "tree: {what}");
                    assert_eq!(grown, want, "growing tree: {what}");
                }
            }
        }
        check_tables(&tree, &growing, &brute, n, options, far);
    }
}

/// Tables under `options`: identical on 1 and 2 threads and for both flavours, each row the
/// brute force's.
fn check_tables<T: Scalar>(
    tree: &KdTree<T>,
    growing: &DynamicKdTree<T>,
    brute: &BruteForce<T>,
    n: usize,
    options: &QueryOptions,
    radius: T,
) {
    for nbhd in [
        Neighborhood::Knn { k: 4 },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
    ] {
        let table = |threads| TableOptions {
            threads,
            query: *options,
            ..TableOptions::default()
        };
        let one = tree.neighborhoods(nbhd, &table(1)).unwrap();
        let two = tree.neighborhoods(nbhd, &table(2)).unwrap();
        let grown = growing.neighborhoods(nbhd, &table(2)).unwrap();
        assert_eq!(one, two, "threads: {options:?} {nbhd:?}");
        assert_eq!(one, grown, "growing: {options:?} {nbhd:?}");
        let mut want = Vec::new();
        for i in (0..n).step_by(7) {
            let q = Query::stored_excluding_self(i as u32);
            brute.search_with(q, nbhd, options, &mut want).unwrap();
            let row: Vec<Neighbor<T>> = one
                .indices_of(i)
                .iter()
                .zip(one.sq_dists_of(i))
                .map(|(&index, &sq_dist)| Neighbor { index, sq_dist })
                .collect();
            assert_eq!(row, want, "table row {i}: {options:?} {nbhd:?}");
        }
    }
}

/// An approximate search keeps scipy's guarantee against the exact brute force.
fn check_approximate<T: Scalar>(coords: &[T], d: usize, metric: Metric, eps: f64) {
    let view = PointsView::from_flat(coords, d).unwrap();
    let n = view.len();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let exact = QueryOptions {
        metric,
        ..QueryOptions::default()
    };
    let approx = QueryOptions { eps, ..exact };
    // a little slack for the rounding of keys and factors in `T`
    let tol = 1.0 + 1e-4;
    let dist = |nb: &Neighbor<T>| metric.distance_of(nb.sq_dist).to_f64();
    for pivot in [PivotPolicy::SlidingMidpoint, PivotPolicy::SpreadMedian] {
        let (tree, growing) = static_and_growing(coords, d, None, pivot);
        for i in (0..n).step_by(5) {
            let q = Query::stored_excluding_self(i as u32);
            let (mut want, mut got, mut grown) = (Vec::new(), Vec::new(), Vec::new());
            let knn = Neighborhood::Knn { k: 6 };
            brute.search_with(q, knn, &exact, &mut want).unwrap();
            tree.search_with(q, knn, &approx, &mut got).unwrap();
            assert_eq!(got.len(), want.len());
            for (g, w) in got.iter().zip(&want) {
                assert!(
                    dist(g) <= (1.0 + eps) * dist(w) * tol,
                    "{metric:?} eps {eps}"
                );
            }
            let r = T::from_f64(0.8);
            let ball = Neighborhood::Radius {
                radius: r,
                sorted: true,
            };
            let all = Neighborhood::Knn { k: n };
            brute.search_with(q, all, &exact, &mut want).unwrap();
            tree.search_with(q, ball, &approx, &mut got).unwrap();
            growing.search_with(q, ball, &approx, &mut grown).unwrap();
            let r = r.to_f64();
            for result in [&got, &grown] {
                for w in &want {
                    let found = result.iter().any(|g| g.index == w.index);
                    if dist(w) * tol <= r / (1.0 + eps) {
                        assert!(found, "{metric:?} eps {eps}: {} missing", w.index);
                    }
                    if found {
                        assert!(dist(w) <= r * (1.0 + eps) * tol, "{metric:?} eps {eps}");
                    }
                }
            }
        }
    }
}

fn check_all<T: Scalar>(coords: &[T], d: usize, seed: u64) {
    for p in PS {
        for strict in [false, true] {
            let options = QueryOptions {
                strict,
                ..QueryOptions::with_p(p).unwrap()
            };
            check_exact(coords, d, &options, seed);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    #[test]
    fn metric_queries_equal_brute_force(
        kind in 0usize..4,
        dim in 0usize..4,
        n in 1usize..90,
        seed in any::<u64>(),
    ) {
        let d = DIMS[dim];
        let coords = cloud(kind, n, d, seed);
        check_all(&coords, d, seed);
        check_all(&to_f32(&coords), d, seed);
    }

    #[test]
    fn approximate_queries_keep_their_guarantee(
        kind in 0usize..4,
        dim in 0usize..4,
        n in 8usize..90,
        seed in any::<u64>(),
    ) {
        let d = DIMS[dim];
        let coords = cloud(kind, n, d, seed);
        for p in PS {
            let metric = Metric::from_p(p).unwrap();
            for eps in [0.1, 1.0] {
                check_approximate(&coords, d, metric, eps);
                check_approximate(&to_f32(&coords), d, metric, eps);
            }
        }
    }
}

/// Strict radii leave out exactly the points at the radius: on a grid, the inclusive result
/// minus the points whose key equals the radius's.
#[test]
fn strict_radii_leave_out_the_points_on_the_radius() {
    let coords = cloud(1, 200, 2, 7);
    let tree = KdTree::<f64>::from_flat(&coords, 2, &BuildOptions::default()).unwrap();
    for p in PS {
        let inclusive = QueryOptions::with_p(p).unwrap();
        let strict = QueryOptions {
            strict: true,
            ..inclusive
        };
        let ball = Neighborhood::Radius {
            radius: 1.0,
            sorted: true,
        };
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let q = Query::point(&[1.0, 1.0]);
        tree.search_with(q, ball, &inclusive, &mut a).unwrap();
        tree.search_with(q, ball, &strict, &mut b).unwrap();
        let on = inclusive.metric.key_of(1.0);
        assert!(
            a.iter().any(|n| n.sq_dist == on),
            "p {p}: some point on the radius"
        );
        a.retain(|n| n.sq_dist < on);
        assert_eq!(a, b, "p {p}");
    }
}

/// The Euclidean options give the plain queries' answers, and p = 2 as a general Minkowski
/// metric is the Euclidean one.
#[test]
fn default_options_are_the_plain_queries() {
    let coords = cloud(0, 300, 3, 3);
    let tree = KdTree::<f32>::from_flat(&to_f32(&coords), 3, &BuildOptions::default()).unwrap();
    let two = QueryOptions {
        metric: Metric::Minkowski(2.0),
        ..QueryOptions::default()
    };
    for i in 0..300u32 {
        let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
        let q = Query::stored_excluding_self(i);
        tree.knn(q, 10, &mut a).unwrap();
        let knn = Neighborhood::Knn { k: 10 };
        tree.search_with(q, knn, &QueryOptions::default(), &mut b)
            .unwrap();
        tree.search_with(q, knn, &two, &mut c).unwrap();
        assert_eq!(a, b);
        assert_eq!(a, c);
    }
}

/// Bad options are refused by name, before any search.
#[test]
fn bad_metrics_and_eps_are_refused() {
    let tree = KdTree::<f64>::from_flat(&[0.0, 1.0, 2.0], 1, &BuildOptions::default()).unwrap();
    let mut out = Vec::new();
    let knn = Neighborhood::Knn { k: 1 };
    let q = Query::point(&[0.5]);
    for p in [0.5, 0.0, -2.0, f64::NAN] {
        let o = QueryOptions {
            metric: Metric::Minkowski(p),
            ..QueryOptions::default()
        };
        let e = tree.search_with(q, knn, &o, &mut out).unwrap_err();
        assert!(
            matches!(e, NbhdError::InvalidOption { name: "p", .. }),
            "{e}"
        );
        assert!(QueryOptions::with_p(p).is_err());
    }
    for eps in [-1.0, f64::NAN, f64::INFINITY] {
        let o = QueryOptions {
            eps,
            ..QueryOptions::default()
        };
        let e = tree.search_with(q, knn, &o, &mut out).unwrap_err();
        assert!(
            matches!(e, NbhdError::InvalidOption { name: "eps", .. }),
            "{e}"
        );
    }
    // a radius whose key overflows: refused inclusive, no bound when strict
    let l100 = QueryOptions::with_p(100.0).unwrap();
    let big = Neighborhood::KnnRadius { k: 3, radius: 1e10 };
    let e = tree.search_with(q, big, &l100, &mut out).unwrap_err();
    assert!(matches!(e, NbhdError::RadiusOutOfRange { .. }), "{e}");
    let strict = QueryOptions {
        strict: true,
        ..l100
    };
    tree.search_with(q, big, &strict, &mut out).unwrap();
    assert_eq!(out.len(), 3);
}
