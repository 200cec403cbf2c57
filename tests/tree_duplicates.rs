//! The early stop on copies of a point (src/tree/search.rs): a cell is skipped once its lower
//! bound ties the result's worst distance and its smallest caller index cannot beat the worst
//! index. These sets make that path decide the answer — every point one position; a few
//! positions with many copies among other points, with k below and above the copy count; copies
//! exactly on the radius — and every answer must equal brute force exactly (indices, squared
//! distances, (sq_dist, index) order), single queries and all-point tables alike, for every
//! pivot policy and leaf size.

mod common;

use common::Rng;
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, NeighborSearch, Neighborhood, NonFinitePolicy, PivotPolicy,
    PointsView, Query, Scalar, TableOptions,
};

/// Every neighbourhood of `queries` (free points) and of some stored points (with and without
/// themselves) from every tree equals brute force; so does the all-point table.
fn check<T: Scalar>(coords: &[T], queries: &[[T; 3]], nbhds: &[Neighborhood<T>]) {
    let view = PointsView::from_flat(coords, 3).unwrap();
    let n = view.len();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let stored = [0, 1, n / 2, n - 1].map(|i| i as u32);
    let (mut want, mut got) = (Vec::new(), Vec::new());
    for pivot in PivotPolicy::ALL {
        for leaf_size in [1, 3, 12] {
            let options = BuildOptions {
                pivot,
                leaf_size,
                ..BuildOptions::default()
            };
            let tree = KdTree::<T>::build(&view, &options).unwrap();
            for &nbhd in nbhds {
                let mut all: Vec<Query<'_, T>> = queries.iter().map(|q| Query::point(q)).collect();
                for &s in &stored {
                    all.push(Query::stored(s));
                    all.push(Query::stored_excluding_self(s));
                }
                for q in all {
                    brute.search(q, nbhd, &mut want).unwrap();
                    tree.search(q, nbhd, &mut got).unwrap();
                    assert_eq!(got, want, "{pivot:?} leaf {leaf_size} {nbhd:?} {q:?}");
                }
                for exclude_self in [false, true] {
                    let opts = TableOptions {
                        exclude_self,
                        threads: 1,
                        ..Default::default()
                    };
                    let table = tree.neighborhoods(nbhd, &opts).unwrap();
                    for i in 0..n {
                        let q = if exclude_self {
                            Query::stored_excluding_self(i as u32)
                        } else {
                            Query::stored(i as u32)
                        };
                        brute.search(q, nbhd, &mut want).unwrap();
                        let idx: Vec<u32> = want.iter().map(|w| w.index).collect();
                        let d2: Vec<T> = want.iter().map(|w| w.sq_dist).collect();
                        assert_eq!(table.indices_of(i), &idx[..], "{pivot:?} {nbhd:?} row {i}");
                        assert_eq!(table.sq_dists_of(i), &d2[..], "{pivot:?} {nbhd:?} row {i}");
                    }
                }
            }
        }
    }
}

fn knn<T>(k: usize) -> Neighborhood<T> {
    Neighborhood::Knn { k }
}

/// Every point at one position: any k (below, at and above the point count) and a radius of 0
/// return the lowest indices at distance 0; a query off the position gets them at one
/// distance, and a radius exactly through them keeps them all.
fn all_identical<T: Scalar>() {
    let n = 300;
    let p = [0.5, 1.25, -2.0].map(T::from_f64);
    let coords: Vec<T> = (0..n).flat_map(|_| p).collect();
    let off = [p[0] + T::from_f64(0.5), p[1], p[2]];
    let nbhds = [
        knn(1),
        knn(7),
        knn(n - 1),
        knn(n),
        knn(n + 5),
        Neighborhood::Radius {
            radius: T::ZERO,
            sorted: true,
        },
        Neighborhood::Radius {
            radius: T::from_f64(0.5),
            sorted: true,
        },
        Neighborhood::KnnRadius {
            k: 4,
            radius: T::from_f64(0.5),
        },
        Neighborhood::KnnRadius {
            k: 4,
            radius: T::from_f64(0.25),
        },
    ];
    check(&coords, &[p, off], &nbhds);
}

#[test]
fn all_identical_points_f32() {
    all_identical::<f32>();
}

#[test]
fn all_identical_points_f64() {
    all_identical::<f64>();
}

/// Five positions with 40 copies each, spread among 200 other points in a shuffled caller order
/// (so a position's copies have scattered indices); k below (3) and above (60) the copy count;
/// queries at a position, off it by an exact 0.5 (the copies then lie exactly on a radius of
/// 0.5), and between two positions.
fn many_copies<T: Scalar>() {
    let mut rng = Rng::new(15);
    let positions: Vec<[f64; 3]> = (0..5).map(|i| [i as f64, 0.5 * i as f64, 0.25]).collect();
    let mut pts: Vec<[f64; 3]> = Vec::new();
    for p in &positions {
        pts.extend(std::iter::repeat_n(*p, 40));
    }
    for _ in 0..200 {
        pts.push([rng.unit() * 5.0, rng.unit() * 3.0, rng.unit()]);
    }
    for i in (1..pts.len()).rev() {
        pts.swap(i, rng.below(i + 1));
    }
    let coords: Vec<T> = pts.iter().flatten().map(|&c| T::from_f64(c)).collect();
    let at = |p: [f64; 3]| p.map(T::from_f64);
    let queries = [
        at(positions[2]),
        at([positions[2][0] + 0.5, positions[2][1], positions[2][2]]),
        at([positions[0][0], positions[0][1], positions[0][2] - 0.5]),
        at([1.5, 0.75, 0.25]),
    ];
    let r = T::from_f64(0.5);
    let nbhds = [
        knn(1),
        knn(3),
        knn(40),
        knn(60),
        Neighborhood::Radius {
            radius: r,
            sorted: true,
        },
        Neighborhood::KnnRadius { k: 3, radius: r },
        Neighborhood::KnnRadius { k: 60, radius: r },
    ];
    check(&coords, &queries, &nbhds);
}

#[test]
fn many_copies_among_other_points_f32() {
    many_copies::<f32>();
}

#[test]
fn many_copies_among_other_points_f64() {
    many_copies::<f64>();
}
