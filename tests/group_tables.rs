//! The grouped all-point table (one descent per group of tree-order points) equals the table of
//! single queries byte for byte: every pivot policy, leaf sizes 1, 4 and 12, 1 and 2 threads,
//! with and without self, on random, clustered, duplicate-heavy, identical and grid sets, in
//! 1, 2 and 3 dimensions, f32 and f64.

mod common;

use common::{points, sorted_rows, to_f32, Kind};
use nbhd::table::neighborhoods_of_all;
use nbhd::NeighborIndex;
use nbhd::{
    BuildOptions, KdTree, Neighborhood, PivotPolicy, PointsView, Query, Scalar, TableOptions,
};
use proptest::prelude::*;

const SETS: [Kind; 6] = [
    Kind::Random,
    Kind::Clustered,
    Kind::DuplicateHeavy,
    Kind::AllIdentical,
    Kind::Grid,
    Kind::Coplanar,
];

fn check<T: Scalar>(coords: &[T], d: usize, leaf_sizes: &[usize]) {
    let view = PointsView::from_flat(coords, d).unwrap();
    let n = view.len();
    for pivot in PivotPolicy::ALL {
        for &leaf_size in leaf_sizes {
            let opts = BuildOptions {
                pivot,
                leaf_size,
                ..BuildOptions::default()
            };
            let tree = KdTree::<T>::build(&view, &opts).unwrap();
            // A radius through an actual neighbour distance, so boundary points exist.
            let mut tmp = Vec::new();
            tree.knn(Query::stored(0), 6.min(n), &mut tmp).unwrap();
            let radius = T::from_f64(tmp.last().unwrap().sq_dist.to_f64().sqrt());
            let mut kinds = vec![
                Neighborhood::Knn { k: 1 },
                Neighborhood::Knn { k: 7 },
                Neighborhood::Radius {
                    radius,
                    sorted: true,
                },
                Neighborhood::KnnRadius { k: 5, radius },
                // long rows sorted by insertion (k up to 64)
                Neighborhood::Knn { k: 31 },
                Neighborhood::KnnRadius { k: 40, radius },
                // rows kept in heaps of packed keys (k above 64)
                Neighborhood::Knn { k: 70 },
                Neighborhood::KnnRadius { k: 90, radius },
            ];
            // Rows of every point: quadratic, so only on small sets.
            if n <= 500 {
                kinds.push(Neighborhood::Knn { k: n + 2 });
                kinds.push(Neighborhood::KnnRadius { k: n, radius });
            }
            for exclude_self in [true, false] {
                for &nbhd in &kinds {
                    let want = neighborhoods_of_all(&tree, nbhd, exclude_self).unwrap();
                    for threads in [1, 2] {
                        let got = tree
                            .neighborhoods(
                                nbhd,
                                &TableOptions {
                                    exclude_self,
                                    threads,
                                    ..Default::default()
                                },
                            )
                            .unwrap();
                        assert!(
                            got == want,
                            "{pivot:?} leaf {leaf_size} {nbhd:?} self={exclude_self} threads={threads}"
                        );
                    }
                }
                let unsorted = Neighborhood::Radius {
                    radius,
                    sorted: false,
                };
                let want = neighborhoods_of_all(&tree, unsorted, exclude_self).unwrap();
                let got = tree
                    .neighborhoods(
                        unsorted,
                        &TableOptions {
                            exclude_self,
                            threads: 2,
                            ..Default::default()
                        },
                    )
                    .unwrap();
                assert_eq!(got.offsets(), want.offsets());
                assert!(sorted_rows(&got) == sorted_rows(&want));
            }
        }
    }
}

fn run(kind: usize, n: usize, d: usize, seed: u64) {
    let coords = points(SETS[kind], n, d, seed);
    check::<f64>(&coords, d, &[1, 4, 12]);
    check::<f32>(&to_f32(&coords), d, &[1, 4, 12]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn grouped_equals_single_queries_3d(kind in 0..SETS.len(), n in 1usize..400, seed in any::<u64>()) {
        run(kind, n, 3, seed);
    }

    #[test]
    fn grouped_equals_single_queries_2d(kind in 0..SETS.len(), n in 1usize..200, seed in any::<u64>()) {
        run(kind, n, 2, seed);
    }

    #[test]
    fn grouped_equals_single_queries_1d(kind in 0..SETS.len(), n in 1usize..100, seed in any::<u64>()) {
        run(kind, n, 1, seed);
    }
}

/// Every set at least once, and sets of several parallel chunks (over 1024 points).
#[test]
fn every_set_and_several_chunks() {
    for kind in 0..SETS.len() {
        run(kind, 300, 3, 7 + kind as u64);
    }
    for kind in [Kind::Random, Kind::DuplicateHeavy, Kind::AllIdentical] {
        let coords = to_f32(&points(kind, 5000, 3, 11));
        check::<f32>(&coords, 3, &[12]);
    }
}
