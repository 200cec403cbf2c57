//! Property tests: every pivot policy × median algorithm × leaf size gives exactly the brute
//! force answer (same indices, same squared distances, same (sq_dist, index) order) for all
//! three neighbourhood kinds, with and without the query point itself, on every kind of point
//! set, in 1, 2, 3 and 7 dimensions, f32 and f64.

mod common;

use common::{points, to_f32, Kind, Rng, KINDS};
use nbhd::{
    BruteForce, BuildOptions, KdTree, MedianAlgorithm, NeighborSearch, Neighborhood,
    NonFinitePolicy, PivotPolicy, PointsView, Query, Scalar,
};
use proptest::prelude::*;

const LEAF_SIZES: [usize; 3] = [1, 3, 12];

fn neighborhoods<T: Scalar>(n: usize, radius: T) -> Vec<Neighborhood<T>> {
    vec![
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 7 },
        // f32 single queries with 16 < k <= 32 collect into a buffer of 2k selected when full.
        Neighborhood::Knn { k: 20 },
        Neighborhood::KnnRadius { k: 24, radius },
        Neighborhood::Knn { k: n + 2 },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
        Neighborhood::KnnRadius { k: 5, radius },
        Neighborhood::KnnRadius { k: n, radius },
    ]
}

fn check_set<T: Scalar>(coords: &[T], d: usize, seed: u64) {
    let view = PointsView::from_flat(coords, d).unwrap();
    let n = view.len();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let mut rng = Rng::new(seed ^ 0xABCD);
    // Queries: some stored points (with and without self) and some arbitrary points.
    let stored: Vec<u32> = (0..6).map(|_| rng.below(n) as u32).collect();
    let free: Vec<Vec<T>> = (0..3)
        .map(|i| {
            let base = &coords[(stored[i] as usize) * d..(stored[i] as usize + 1) * d];
            base.iter()
                .map(|&c| c + T::from_f64((rng.unit() - 0.5) * 0.3))
                .collect()
        })
        .collect();
    // A radius through an actual neighbour distance, so boundary points exist.
    let mut tmp = Vec::new();
    brute
        .search(
            Query::stored(stored[0]),
            Neighborhood::Knn { k: 6.min(n) },
            &mut tmp,
        )
        .unwrap();
    let radius = T::from_f64(tmp.last().unwrap().sq_dist.to_f64().sqrt());
    let kinds = neighborhoods(n, radius);
    let mut want = Vec::new();
    let mut got = Vec::new();
    for pivot in PivotPolicy::ALL {
        for median in MedianAlgorithm::ALL {
            for leaf_size in LEAF_SIZES {
                let opts = BuildOptions {
                    pivot,
                    median,
                    leaf_size,
                    ..BuildOptions::default()
                };
                let tree = KdTree::<T>::build(&view, &opts).unwrap();
                let mut queries: Vec<Query<'_, T>> = Vec::new();
                for &s in &stored {
                    queries.push(Query::stored(s));
                    queries.push(Query::stored_excluding_self(s));
                }
                for (i, p) in free.iter().enumerate() {
                    queries.push(Query::point(p));
                    queries.push(Query::Point {
                        coords: p,
                        exclude: Some(stored[i]),
                    });
                }
                for q in &queries {
                    for nb in &kinds {
                        brute.search(*q, *nb, &mut want).unwrap();
                        tree.search(*q, *nb, &mut got).unwrap();
                        assert_eq!(
                            got, want,
                            "{pivot:?} {median:?} leaf {leaf_size} {nb:?} {q:?}"
                        );
                    }
                    // The unsorted radius variant returns the same set.
                    let unsorted = Neighborhood::Radius {
                        radius,
                        sorted: false,
                    };
                    tree.search(*q, unsorted, &mut got).unwrap();
                    got.sort_by(|a, b| a.cmp_by_distance(b));
                    brute
                        .search(
                            *q,
                            Neighborhood::Radius {
                                radius,
                                sorted: true,
                            },
                            &mut want,
                        )
                        .unwrap();
                    assert_eq!(got, want, "unsorted radius {pivot:?} {median:?}");
                }
            }
        }
    }
}

fn run(kind_index: usize, n: usize, d: usize, seed: u64) {
    let kind: Kind = KINDS[kind_index];
    let coords = points(kind, n, d, seed);
    check_set::<f64>(&coords, d, seed);
    check_set::<f32>(&to_f32(&coords), d, seed);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn matches_brute_force_1d(kind in 0..KINDS.len(), n in 1usize..120, seed in any::<u64>()) {
        run(kind, n, 1, seed);
    }

    #[test]
    fn matches_brute_force_2d(kind in 0..KINDS.len(), n in 1usize..120, seed in any::<u64>()) {
        run(kind, n, 2, seed);
    }

    #[test]
    fn matches_brute_force_3d(kind in 0..KINDS.len(), n in 1usize..200, seed in any::<u64>()) {
        run(kind, n, 3, seed);
    }

    #[test]
    fn matches_brute_force_7d(kind in 0..KINDS.len(), n in 1usize..120, seed in any::<u64>()) {
        run(kind, n, 7, seed);
    }
}

/// Every kind of set at least once, deterministically (proptest picks kinds at random).
#[test]
fn every_kind_in_3d() {
    for kind in 0..KINDS.len() {
        run(kind, 150, 3, 42 + kind as u64);
    }
}
