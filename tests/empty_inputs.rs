//! No point is not an error: a tree over zero points (none given, none listed, or every one
//! skipped) and a batch of zero queries are valid, for the static tree, the growing tree and
//! brute force, in every dimension and scalar type. Queries find nothing, tables have one empty
//! row per index (no row for no index), a tree of no point saves and loads back, and the
//! functions that need points (the spacing, outlier removal by k, the PCA sweep) say so.

use nbhd::dynamic::DynamicKdTree;
use nbhd::filter::{radius_outlier_removal, RadiusOutlierOptions};
use nbhd::{
    BruteForce, BuildOptions, KdTree, NbhdError, NeighborIndex, NeighborSearch, Neighborhood,
    NonFinitePolicy, PcaSweep, Persist, PointsView, Query, Scalar, TableOptions,
};

fn nbhds<T: Scalar>() -> [Neighborhood<T>; 4] {
    [
        Neighborhood::Knn { k: 3 },
        Neighborhood::Radius {
            radius: T::from_f64(10.0),
            sorted: true,
        },
        Neighborhood::Radius {
            radius: T::from_f64(10.0),
            sorted: false,
        },
        Neighborhood::KnnRadius {
            k: 2,
            radius: T::from_f64(10.0),
        },
    ]
}

/// Every query of `s` (a search over no point, `source_len` indices) finds nothing; a stored
/// index is out of range or names a point not held.
fn finds_nothing<T: Scalar, S: NeighborSearch<T>>(s: &S, dim: usize, source_len: usize) {
    let q = vec![T::from_f64(0.5); dim];
    let mut out = vec![nbhd::Neighbor {
        index: 7,
        sq_dist: T::ZERO,
    }];
    for nb in nbhds::<T>() {
        s.search(Query::point(&q), nb, &mut out).unwrap();
        assert!(out.is_empty(), "{nb:?}");
        let e = s.search(Query::stored(0), nb, &mut out).unwrap_err();
        if source_len == 0 {
            assert_eq!(e, NbhdError::IndexOutOfRange { index: 0, count: 0 });
        } else {
            assert_eq!(e, NbhdError::SkippedPoint { index: 0 });
        }
        // A non-finite query is still refused.
        let nan = vec![T::from_f64(f64::NAN); dim];
        assert!(s.search(Query::point(&nan), nb, &mut out).is_err());
    }
}

fn static_tree<T: Scalar>(dim: usize) {
    let none: Vec<T> = Vec::new();
    let view = PointsView::from_flat(&none, dim).unwrap();
    assert!(view.is_empty());
    let opts = |threads| BuildOptions {
        threads,
        ..BuildOptions::default()
    };
    for threads in [1, 2] {
        let t = KdTree::<T>::build(&view, &opts(threads)).unwrap();
        assert!(t.is_empty());
        assert_eq!((t.len(), t.source_len()), (0, 0));
        let s = t.stats();
        assert_eq!((s.points, s.depth, s.nodes, s.leaves), (0, 0, 1, 1));
        finds_nothing(&t, dim, 0);
        for nb in nbhds::<T>() {
            for exclude_self in [false, true] {
                let o = TableOptions {
                    exclude_self,
                    threads,
                    ..Default::default()
                };
                let table = t.neighborhoods(nb, &o).unwrap();
                assert_eq!((table.len(), table.total()), (0, 0));
                // Queries against no point: a row each, empty; no query: no row.
                let qs = vec![T::from_f64(1.0); 4 * dim];
                let qv = PointsView::from_flat(&qs, dim).unwrap();
                let rows = t.neighborhoods_of(&qv, nb, &o).unwrap();
                assert_eq!((rows.len(), rows.total()), (4, 0));
                assert_eq!(t.neighborhoods_of(&view, nb, &o).unwrap().len(), 0);
            }
        }
        let mut inside = vec![9];
        let (lo, hi) = (vec![T::from_f64(-1.0); dim], vec![T::from_f64(1.0); dim]);
        t.in_box(&lo, &hi, &mut inside).unwrap();
        assert!(inside.is_empty());
        assert_eq!(t.in_boxes(&[lo, hi].concat(), threads).unwrap().total(), 0);
        assert!(matches!(
            t.spacing(threads),
            Err(NbhdError::InvalidOption { name: "points", .. })
        ));
        let kept = radius_outlier_removal(
            &t,
            &RadiusOutlierOptions {
                radius: 1.0,
                min_neighbors: 1,
                threads,
            },
        )
        .unwrap();
        assert!(kept.indices.is_empty());
        // A tree of no point saves and loads back as one.
        let back = KdTree::<T>::from_bytes(&t.to_bytes()).unwrap();
        assert!(back.same_structure(&t) && back.is_empty());
    }
    // Every point skipped: a tree of no point with a row per index.
    let nan = vec![T::from_f64(f64::NAN); 5 * dim];
    let skip = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    let t = KdTree::<T>::from_flat(&nan, dim, &skip).unwrap();
    assert!(t.is_empty() && t.source_len() == 5);
    finds_nothing(&t, dim, 5);
    let table = t
        .neighborhoods(Neighborhood::Knn { k: 2 }, &TableOptions::default())
        .unwrap();
    assert_eq!((table.len(), table.total()), (5, 0));
    let back = KdTree::<T>::from_bytes(&t.to_bytes()).unwrap();
    assert!(back.same_structure(&t) && back.source_len() == 5);
    // No index listed: a tree of no point over the view's indices.
    let pts: Vec<T> = (0..6 * dim).map(|i| T::from_f64(i as f64)).collect();
    let pv = PointsView::from_flat(&pts, dim).unwrap();
    let t = KdTree::<T>::build_subset(&pv, &[], &BuildOptions::default()).unwrap();
    assert!(t.is_empty() && t.source_len() == 6);
    finds_nothing(&t, dim, 6);
}

/// A tree of points and a batch of no query: a table of no row, for every kind and dimension.
fn zero_queries<T: Scalar>(dim: usize) {
    let pts: Vec<T> = (0..40 * dim)
        .map(|i| T::from_f64((i * 7919 % 101) as f64))
        .collect();
    let t = KdTree::<T>::from_flat(&pts, dim, &BuildOptions::default()).unwrap();
    let none: Vec<T> = Vec::new();
    let qv = PointsView::from_flat(&none, dim).unwrap();
    for nb in nbhds::<T>() {
        for threads in [1, 2] {
            let o = TableOptions {
                exclude_self: false,
                threads,
                ..Default::default()
            };
            let rows = t.neighborhoods_of(&qv, nb, &o).unwrap();
            assert_eq!((rows.len(), rows.total()), (0, 0), "{nb:?}");
        }
    }
    let mut boxes = t.in_boxes(&[], 1).unwrap();
    assert_eq!(boxes.len(), 0);
    boxes = t.in_boxes(&none, 2).unwrap();
    assert!(boxes.is_empty());
}

fn growing_tree<T: Scalar>(dim: usize) {
    let mut g = DynamicKdTree::<T>::new(dim, &BuildOptions::default()).unwrap();
    let none: Vec<T> = Vec::new();
    let nv = PointsView::from_flat(&none, dim).unwrap();
    // A batch of no point inserts nothing and gives no index.
    assert_eq!(g.insert(&nv).unwrap(), 0);
    assert_eq!((g.len(), g.next_index()), (0, 0));
    finds_nothing(&g, dim, 0);
    let o = TableOptions::default();
    for nb in nbhds::<T>() {
        assert_eq!(g.neighborhoods(nb, &o).unwrap().len(), 0);
        assert_eq!(g.neighborhoods_of(&nv, nb, &o).unwrap().len(), 0);
    }
    let pts: Vec<T> = (0..30 * dim).map(|i| T::from_f64(i as f64 * 0.5)).collect();
    g.insert(&PointsView::from_flat(&pts, dim).unwrap())
        .unwrap();
    assert_eq!(g.insert(&nv).unwrap(), 30);
    assert_eq!((g.len(), g.next_index()), (30, 30));
    for nb in nbhds::<T>() {
        let rows = g.neighborhoods_of(&nv, nb, &o).unwrap();
        assert_eq!((rows.len(), rows.total()), (0, 0), "{nb:?}");
    }
}

fn brute_force<T: Scalar>(dim: usize) {
    let none: Vec<T> = Vec::new();
    let view = PointsView::from_flat(&none, dim).unwrap();
    let b = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    finds_nothing(&b, dim, 0);
    // The PCA sweep needs principal axes: no point is refused, not answered.
    assert_eq!(
        PcaSweep::<T>::new(&view, NonFinitePolicy::Reject).unwrap_err(),
        NbhdError::EmptyInput
    );
}

#[test]
fn a_tree_over_no_point_is_valid() {
    for dim in [1, 2, 3, 5] {
        static_tree::<f32>(dim);
        static_tree::<f64>(dim);
    }
}

#[test]
fn a_batch_of_no_query_is_a_table_of_no_row() {
    for dim in [1, 2, 3, 5] {
        zero_queries::<f32>(dim);
        zero_queries::<f64>(dim);
    }
}

#[test]
fn the_growing_tree_takes_empty_batches() {
    for dim in [1, 3, 4] {
        growing_tree::<f32>(dim);
        growing_tree::<f64>(dim);
    }
}

#[test]
fn brute_force_over_no_point() {
    for dim in [1, 3] {
        brute_force::<f32>(dim);
        brute_force::<f64>(dim);
    }
}
