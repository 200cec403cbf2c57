//! A static tree's table of a batch of query points (`neighborhoods_of`: grouped where the batch
//! is dense enough, in one to three dimensions; one search per query otherwise) equals one
//! single search per query and brute force, byte for byte: every pivot policy, leaf sizes 1, 4
//! and 12, 1 and 2 threads, f32 and f64, in 1 to 5 dimensions, on random, clustered,
//! duplicate-heavy, identical, collinear, coplanar (zero-extent axes) and grid sets, with
//! batches that mix the tree's own points (exact ties), new points, copies of one point and
//! points far outside the cloud. A non-finite query is refused as before, naming it.

mod common;

use common::{points, sorted_rows, to_f32, Kind, KINDS};
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, NbhdError, NeighborSearch, NeighborTable, Neighborhood,
    NonFinitePolicy, PivotPolicy, PointsView, Query, Scalar, TableOptions,
};
use proptest::prelude::*;

/// A batch over the cloud `coords` (dimension `d`): its points in reverse order, new points of
/// the same kind, copies of its first point, and points far outside it.
fn batch(kind: Kind, coords: &[f64], d: usize, seed: u64) -> Vec<f64> {
    let n = coords.len() / d;
    let mut q: Vec<f64> = coords.chunks_exact(d).rev().flatten().copied().collect();
    q.extend(points(kind, n.div_ceil(2), d, seed ^ 0x5eed));
    for _ in 0..5 {
        q.extend_from_slice(&coords[..d]);
    }
    for (i, p) in coords.chunks_exact(d).take(7).enumerate() {
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        q.extend(p.iter().map(|c| sign * (c * 1000.0 + 1.0e4)));
    }
    q
}

/// The table of one search per query of `searcher`.
fn single_rows<T: Scalar, S: NeighborSearch<T>>(
    searcher: &S,
    queries: &[T],
    d: usize,
    nbhd: Neighborhood<T>,
) -> Vec<(Vec<u32>, Vec<T>)> {
    let mut row = Vec::new();
    queries
        .chunks_exact(d)
        .map(|q| {
            searcher.search(Query::point(q), nbhd, &mut row).unwrap();
            (
                row.iter().map(|nb| nb.index).collect(),
                row.iter().map(|nb| nb.sq_dist).collect(),
            )
        })
        .collect()
}

fn rows_of<T: Scalar>(t: &NeighborTable<T>) -> Vec<(Vec<u32>, Vec<T>)> {
    (0..t.len())
        .map(|i| (t.indices_of(i).to_vec(), t.sq_dists_of(i).to_vec()))
        .collect()
}

fn check<T: Scalar>(coords: &[T], queries: &[T], d: usize, leaf_sizes: &[usize]) {
    let view = PointsView::from_flat(coords, d).unwrap();
    let qview = PointsView::from_flat(queries, d).unwrap();
    let n = view.len();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    // A radius through an actual neighbour distance, so points lie exactly on it.
    let mut tmp = Vec::new();
    brute
        .search(
            Query::stored(0),
            Neighborhood::Knn { k: 6.min(n) },
            &mut tmp,
        )
        .unwrap();
    let radius = T::from_f64(tmp.last().unwrap().sq_dist.to_f64().sqrt());
    let mut kinds = vec![
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 7 },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
        Neighborhood::KnnRadius { k: 5, radius },
        // long rows sorted by insertion (k up to 64), rows in heaps above
        Neighborhood::Knn { k: 31 },
        Neighborhood::Knn { k: 70 },
        Neighborhood::KnnRadius { k: 90, radius },
    ];
    if n <= 300 {
        kinds.push(Neighborhood::Knn { k: n + 2 });
    }
    let want: Vec<_> = kinds
        .iter()
        .map(|&nbhd| single_rows(&brute, queries, d, nbhd))
        .collect();
    for pivot in PivotPolicy::ALL {
        for &leaf_size in leaf_sizes {
            let opts = BuildOptions {
                pivot,
                leaf_size,
                ..BuildOptions::default()
            };
            let tree = KdTree::<T>::build(&view, &opts).unwrap();
            for (nbhd, want) in kinds.iter().zip(&want) {
                assert!(
                    single_rows(&tree, queries, d, *nbhd) == *want,
                    "single queries: {pivot:?} leaf {leaf_size} {nbhd:?}"
                );
                for threads in [1, 2] {
                    let topts = TableOptions {
                        threads,
                        ..TableOptions::default()
                    };
                    let got = tree.neighborhoods_of(&qview, *nbhd, &topts).unwrap();
                    assert!(
                        rows_of(&got) == *want,
                        "{pivot:?} leaf {leaf_size} {nbhd:?} threads={threads}"
                    );
                }
            }
            let unsorted = Neighborhood::Radius {
                radius,
                sorted: false,
            };
            let sorted = Neighborhood::Radius {
                radius,
                sorted: true,
            };
            let topts = TableOptions {
                threads: 2,
                ..TableOptions::default()
            };
            let got = tree.neighborhoods_of(&qview, unsorted, &topts).unwrap();
            let all = tree.neighborhoods_of(&qview, sorted, &topts).unwrap();
            assert!(sorted_rows(&got) == sorted_rows(&all), "{pivot:?} unsorted");
        }
    }
}

fn run(kind: Kind, n: usize, d: usize, seed: u64) {
    let coords = points(kind, n, d, seed);
    let queries = batch(kind, &coords, d, seed);
    check::<f64>(&coords, &queries, d, &[1, 4, 12]);
    check::<f32>(&to_f32(&coords), &to_f32(&queries), d, &[1, 4, 12]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    #[test]
    fn batch_equals_single_queries_3d(kind in 0..KINDS.len(), n in 1usize..300, seed in any::<u64>()) {
        run(KINDS[kind], n, 3, seed);
    }

    #[test]
    fn batch_equals_single_queries_2d(kind in 0..KINDS.len(), n in 1usize..200, seed in any::<u64>()) {
        run(KINDS[kind], n, 2, seed);
    }

    #[test]
    fn batch_equals_single_queries_1d(kind in 0..KINDS.len(), n in 1usize..100, seed in any::<u64>()) {
        run(KINDS[kind], n, 1, seed);
    }

    #[test]
    fn batch_equals_single_queries_in_more_dimensions(kind in 0..KINDS.len(), n in 1usize..120, d in 4usize..6, seed in any::<u64>()) {
        run(KINDS[kind], n, d, seed);
    }
}

/// Every kind of set at least once, and batches of several parallel chunks (over 1024
/// queries), dense (grouped) and sparse (one search per query).
#[test]
fn every_set_and_several_chunks() {
    for (i, &kind) in KINDS.iter().enumerate() {
        run(kind, 250, 3, 3 + i as u64);
    }
    for kind in [Kind::Random, Kind::DuplicateHeavy, Kind::Coplanar] {
        let coords = points(kind, 3000, 3, 17);
        let queries = batch(kind, &coords, 3, 17);
        check::<f32>(&to_f32(&coords), &to_f32(&queries), 3, &[12]);
        // a sparse batch: a few queries on a larger tree
        check::<f64>(&coords, &queries[..30], 3, &[12]);
    }
}

/// A non-finite query in a dense batch is refused, naming the first one by position, before
/// any search.
#[test]
fn a_non_finite_query_is_named() {
    let coords = points(Kind::Random, 400, 3, 5);
    let tree = KdTree::<f64>::build(
        &PointsView::from_flat(&coords, 3).unwrap(),
        &BuildOptions::default(),
    )
    .unwrap();
    for bad in [f64::NAN, f64::INFINITY] {
        let mut queries = coords.clone();
        queries[3 * 200 + 1] = bad;
        queries[3 * 300] = f64::NAN;
        let qview = PointsView::from_flat(&queries, 3).unwrap();
        let err = tree
            .neighborhoods_of(&qview, Neighborhood::Knn { k: 4 }, &TableOptions::default())
            .unwrap_err();
        assert!(
            matches!(
                err,
                NbhdError::NonFiniteQuery {
                    query: Some(200),
                    coordinate: 1
                }
            ),
            "{err:?}"
        );
    }
}
