//! Neighbourhood tables: equal to brute force row by row, and the same bytes for any thread
//! count.

mod common;

use common::{points, to_f32, Kind};
use nbhd::table::neighborhoods_of_all;
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, Neighborhood, NonFinitePolicy, PointsView, TableOptions,
};

#[test]
fn tree_tables_equal_brute_force_tables_for_any_thread_count() {
    for kind in [Kind::Random, Kind::DuplicateHeavy, Kind::Grid] {
        let c = to_f32(&points(kind, 3000, 3, 9));
        let view = PointsView::from_flat(&c, 3).unwrap();
        let tree = KdTree::<f32>::build(&view, &BuildOptions::default()).unwrap();
        let brute = BruteForce::<f32>::new(&view, NonFinitePolicy::Reject).unwrap();
        for nbhd in [
            Neighborhood::Knn { k: 10 },
            Neighborhood::Radius {
                radius: 0.3,
                sorted: true,
            },
            Neighborhood::KnnRadius { k: 16, radius: 0.3 },
        ] {
            for exclude_self in [true, false] {
                let want = neighborhoods_of_all(&brute, nbhd, exclude_self).unwrap();
                for threads in [1, 2, 3] {
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
                    assert_eq!(
                        got, want,
                        "{kind:?} {nbhd:?} self={exclude_self} threads={threads}"
                    );
                }
            }
        }
    }
}

#[test]
fn batch_queries_equal_single_queries() {
    let c = points(Kind::Clustered, 2000, 3, 4);
    let q = points(Kind::Random, 500, 3, 5);
    let tree = KdTree::<f64>::from_flat(&c, 3, &BuildOptions::default()).unwrap();
    let qv = PointsView::from_flat(&q, 3).unwrap();
    let nbhd = Neighborhood::Knn { k: 7 };
    let table = tree
        .neighborhoods_of(&qv, nbhd, &TableOptions::default())
        .unwrap();
    let mut row = Vec::new();
    for i in 0..500 {
        tree.knn(nbhd::Query::point(&q[3 * i..3 * i + 3]), 7, &mut row)
            .unwrap();
        let ids: Vec<u32> = row.iter().map(|n| n.index).collect();
        assert_eq!(table.indices_of(i), &ids[..]);
    }
    let bad = PointsView::from_flat(&q[..4], 2).unwrap();
    assert!(tree
        .neighborhoods_of(&bad, nbhd, &TableOptions::default())
        .is_err());
}

/// Batch queries are answered in leaf order and written back in query order: the rows equal
/// brute force's for every neighbourhood kind, in 1, 2, 3 and 7 dimensions, with queries on
/// stored points (exact ties) and elsewhere, on 1, 2 and 3 threads.
#[test]
fn batch_tables_equal_brute_force_in_any_dimension_and_thread_count() {
    for d in [1, 2, 3, 7] {
        for kind in [Kind::Grid, Kind::DuplicateHeavy, Kind::Random] {
            let c = points(kind, 1500, d, 11);
            // Queries: every third stored point, then random points.
            let mut q: Vec<f64> = c.chunks(d).step_by(3).flatten().copied().collect();
            q.extend(points(Kind::Random, 400, d, 12));
            let view = PointsView::from_flat(&c, d).unwrap();
            let qv = PointsView::from_flat(&q, d).unwrap();
            let tree = KdTree::<f64>::build(&view, &BuildOptions::default()).unwrap();
            let brute = BruteForce::<f64>::new(&view, NonFinitePolicy::Reject).unwrap();
            for nbhd in [
                Neighborhood::Knn { k: 9 },
                Neighborhood::Radius {
                    radius: 1.5,
                    sorted: true,
                },
                Neighborhood::KnnRadius { k: 12, radius: 1.5 },
            ] {
                let want = nbhd::table::neighborhoods_of_points(&brute, &qv, nbhd).unwrap();
                for threads in [1, 2, 3] {
                    let opts = TableOptions {
                        threads,
                        ..TableOptions::default()
                    };
                    let got = tree.neighborhoods_of(&qv, nbhd, &opts).unwrap();
                    assert_eq!(got, want, "d={d} {kind:?} {nbhd:?} threads={threads}");
                }
            }
        }
    }
}

#[test]
fn batch_with_a_non_finite_query_is_refused() {
    let c = points(Kind::Random, 200, 3, 1);
    let tree = KdTree::<f64>::from_flat(&c, 3, &BuildOptions::default()).unwrap();
    let mut q = points(Kind::Random, 50, 3, 2);
    q[3 * 17 + 1] = f64::NAN;
    let qv = PointsView::from_flat(&q, 3).unwrap();
    let err = tree
        .neighborhoods_of(&qv, Neighborhood::Knn { k: 3 }, &TableOptions::default())
        .unwrap_err();
    assert!(
        matches!(err, nbhd::NbhdError::NonFiniteQuery { .. }),
        "{err}"
    );
}
