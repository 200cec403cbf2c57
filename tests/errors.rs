//! Every bad input gets its typed error, never a panic.

use nbhd::{
    BruteForce, BuildOptions, KdTree, NbhdError, NeighborSearch, Neighborhood, NonFinitePolicy,
    PointsView, Query, ScalarType, MAX_POINTS,
};

fn tree(c: &[f64]) -> KdTree<f64> {
    KdTree::from_flat(c, 3, &BuildOptions::default()).unwrap()
}

#[test]
fn empty_input_and_zero_dimension() {
    let none: [f64; 0] = [];
    assert_eq!(
        KdTree::<f64>::from_flat(&none, 3, &BuildOptions::default()).unwrap_err(),
        NbhdError::EmptyInput
    );
    assert_eq!(
        KdTree::<f64>::from_flat(&[1.0, 2.0], 0, &BuildOptions::default()).unwrap_err(),
        NbhdError::ZeroDimension
    );
}

#[test]
fn stride_smaller_than_a_point() {
    let raw = [0u8; 64];
    assert_eq!(
        PointsView::new(&raw, 2, 3, 8, ScalarType::F32).unwrap_err(),
        NbhdError::StrideTooSmall {
            stride: 8,
            point_bytes: 12
        }
    );
}

#[test]
fn more_points_than_the_index_type_holds() {
    let raw = [0u8; 16];
    let err = PointsView::new(&raw, MAX_POINTS + 1, 1, 4, ScalarType::F32).unwrap_err();
    assert!(matches!(err, NbhdError::TooManyPoints { .. }), "{err}");
}

#[test]
fn non_finite_points_are_named_or_skipped() {
    let c = [
        0.0,
        0.0,
        0.0,
        1.0,
        f64::INFINITY,
        0.0,
        2.0,
        0.0,
        f64::NAN,
        3.0,
        0.0,
        0.0,
    ];
    let err = KdTree::<f64>::from_flat(&c, 3, &BuildOptions::default()).unwrap_err();
    assert_eq!(
        err,
        NbhdError::NonFinite {
            index: 1,
            coordinate: 1
        }
    );
    assert!(err.to_string().contains("point 1"));
    let opts = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    let t = KdTree::<f64>::from_flat(&c, 3, &opts).unwrap();
    assert_eq!(t.len(), 2);
    let mut out = Vec::new();
    t.knn(Query::point(&[2.9, 0.0, 0.0]), 2, &mut out).unwrap();
    assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), vec![3, 0]);
    assert_eq!(
        t.knn(Query::stored(2), 1, &mut out).unwrap_err(),
        NbhdError::SkippedPoint { index: 2 }
    );
    // f64 values beyond the f32 range are non-finite for an f32 tree.
    let big = [0.0, 0.0, 0.0, 1e300, 0.0, 0.0];
    assert!(matches!(
        KdTree::<f32>::from_flat(&big.map(|x| x as f32), 3, &BuildOptions::default()),
        Err(NbhdError::NonFinite { index: 1, .. })
    ));
    let all_bad = [f64::NAN; 3];
    assert_eq!(
        KdTree::<f64>::from_flat(&all_bad, 3, &opts).unwrap_err(),
        NbhdError::EmptyInput
    );
}

#[test]
fn bad_queries() {
    let t = tree(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    let bf = BruteForce::<f64>::new(
        &PointsView::from_flat(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], 3).unwrap(),
        NonFinitePolicy::Reject,
    )
    .unwrap();
    let searchers: [&dyn NeighborSearch<f64>; 2] = [&t, &bf];
    let mut out = Vec::new();
    for s in searchers {
        let q = Query::point(&[0.0, 0.0, 0.0]);
        assert_eq!(
            s.search(q, Neighborhood::Knn { k: 0 }, &mut out)
                .unwrap_err(),
            NbhdError::ZeroK
        );
        assert_eq!(
            s.search(q, Neighborhood::KnnRadius { k: 0, radius: 1.0 }, &mut out)
                .unwrap_err(),
            NbhdError::ZeroK
        );
        for radius in [-1.0, f64::NAN, f64::INFINITY] {
            let nb = Neighborhood::Radius {
                radius,
                sorted: true,
            };
            assert!(matches!(
                s.search(q, nb, &mut out).unwrap_err(),
                NbhdError::InvalidRadius(_)
            ));
        }
        assert_eq!(
            s.search(
                Query::point(&[0.0, 0.0]),
                Neighborhood::Knn { k: 1 },
                &mut out
            )
            .unwrap_err(),
            NbhdError::DimensionMismatch {
                expected: 3,
                got: 2
            }
        );
        assert_eq!(
            s.search(
                Query::point(&[0.0, f64::NAN, 0.0]),
                Neighborhood::Knn { k: 1 },
                &mut out
            )
            .unwrap_err(),
            NbhdError::NonFiniteQuery {
                query: None,
                coordinate: 1
            }
        );
        assert_eq!(
            s.search(Query::stored(2), Neighborhood::Knn { k: 1 }, &mut out)
                .unwrap_err(),
            NbhdError::IndexOutOfRange { index: 2, count: 2 }
        );
        // k larger than n is not an error: all points come back.
        s.search(q, Neighborhood::Knn { k: 10 }, &mut out).unwrap();
        assert_eq!(out.len(), 2);
        // Excluding self from a one-point neighbourhood leaves it empty, not an error.
        s.search(
            Query::stored_excluding_self(0),
            Neighborhood::KnnRadius { k: 3, radius: 0.5 },
            &mut out,
        )
        .unwrap();
        assert!(out.is_empty());
    }
}

#[test]
fn zero_leaf_size_is_refused() {
    let opts = BuildOptions {
        leaf_size: 0,
        ..BuildOptions::default()
    };
    assert!(matches!(
        KdTree::<f64>::from_flat(&[0.0; 3], 3, &opts),
        Err(NbhdError::InvalidOption {
            name: "leaf_size",
            ..
        })
    ));
}

#[test]
fn radius_is_inclusive_and_plain() {
    // Exact integer distances: points at distance exactly 2 are inside a radius of 2.
    let c = [0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 2.0, 2.0, 0.0];
    let t = tree(&c);
    let mut out = Vec::new();
    t.radius(Query::stored(0), 2.0, &mut out).unwrap();
    let got: Vec<_> = out.iter().map(|n| (n.index, n.sq_dist)).collect();
    assert_eq!(got, vec![(0, 0.0), (1, 4.0), (2, 4.0)]);
    t.knn_radius(Query::stored_excluding_self(0), 1, 2.0, &mut out)
        .unwrap();
    assert_eq!(out.iter().map(|n| n.index).collect::<Vec<_>>(), vec![1]);
}

/// Large clouds on several threads are read in parallel: a NaN or an f64 beyond the f32 range
/// is still named by its index (the first one), or skipped with the others keeping their
/// indices, exactly as on one thread.
#[test]
fn non_finite_points_of_large_clouds_on_several_threads() {
    let n = 300_000;
    let mut c: Vec<f64> = (0..3 * n)
        .map(|i| ((i * 7919) % 10007) as f64 * 0.01)
        .collect();
    c[3 * 123_456 + 2] = f64::NAN;
    c[3 * 200_000] = 1e300; // finite in f64, not in f32
    let view = PointsView::from_flat(&c, 3).unwrap();
    for threads in [1, 2, 3] {
        let reject = BuildOptions {
            threads,
            ..BuildOptions::default()
        };
        let err = KdTree::<f32>::build(&view, &reject).unwrap_err();
        assert_eq!(
            err,
            NbhdError::NonFinite {
                index: 123_456,
                coordinate: 2
            },
            "threads={threads}"
        );
        let skip = BuildOptions {
            non_finite: NonFinitePolicy::Skip,
            ..reject
        };
        let t = KdTree::<f32>::build(&view, &skip).unwrap();
        assert_eq!(t.len(), n - 2);
        assert!(t.point(123_456).is_none() && t.point(200_000).is_none());
        assert_eq!(
            t.point(7).unwrap(),
            &c[21..24].iter().map(|&v| v as f32).collect::<Vec<_>>()[..]
        );
        let serial = KdTree::<f32>::build(&view, &BuildOptions { threads: 1, ..skip }).unwrap();
        assert!(t.same_structure(&serial), "threads={threads}");
    }
}
