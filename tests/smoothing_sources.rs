//! The smoothing gives the same result whatever its neighbourhoods come from: its own k-d tree
//! search, the PCA sweep, brute force ('Use Kd-Tree for NNSearch', thesis Section 7.3), a table
//! or a tree the caller already has (`nbhd::smooth::source`).

use glam::DVec3;
use nbhd::shapes::{noisy_sample, Cube, NoiseKind};
use nbhd::smooth::robust::{smooth_robust_from, smooth_robust_report, RobustOptions};
use nbhd::smooth::source::tree_neighbors;
use nbhd::smooth::{
    analyze, analyze_from, smooth, smooth_from, Neighbors, SearchMethod, SmoothOptions,
};
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, NeighborTable, Neighborhood, PointsView, TableOptions};

fn cloud() -> Vec<DVec3> {
    noisy_sample(&Cube::new(1.0), 3000, 0.5, NoiseKind::Gaussian, 7)
        .unwrap()
        .points
}

fn knn_table(points: &[DVec3], k: usize) -> NeighborTable<f64> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    KdTree::<f64>::build(
        &PointsView::from_flat(&flat, 3).unwrap(),
        &BuildOptions::default(),
    )
    .unwrap()
    .neighborhoods(Neighborhood::Knn { k }, &TableOptions::default())
    .unwrap()
}

const SEARCHES: [SearchMethod; 3] = [
    SearchMethod::KdTree,
    SearchMethod::PcaSweep,
    SearchMethod::BruteForce,
];

#[test]
fn faithful_smoothing_is_the_same_from_every_source() {
    let p = cloud();
    for opts in [
        SmoothOptions::default(),
        SmoothOptions {
            update_neighbors: true,
            steps: 2,
            ..SmoothOptions::isotropic()
        },
    ] {
        let want = smooth(&p, &opts).unwrap();
        for method in SEARCHES {
            let got = smooth_from(&p, Neighbors::Search(method), &opts, &mut |_, _| true);
            assert_eq!(got.unwrap(), want, "{method:?}");
        }
        // a caller's k-nearest table with more neighbours than k: its first k are taken
        let table = knn_table(&p, opts.k + 5);
        let got = smooth_from(&p, Neighbors::Table(&table), &opts, &mut |_, _| true);
        assert_eq!(got.unwrap(), want);
    }
    let opts = SmoothOptions::default();
    let table = knn_table(&p, opts.k);
    assert_eq!(
        analyze_from(&p, Neighbors::Table(&table), &opts).unwrap(),
        analyze(&p, &opts).unwrap()
    );
}

#[test]
fn robust_smoothing_is_the_same_from_every_source() {
    let p = cloud();
    let opts = RobustOptions {
        max_iterations: 3,
        ..RobustOptions::default()
    };
    let want = smooth_robust_report(&p, &opts, &mut |_, _| true).unwrap();
    for method in SEARCHES {
        let got = smooth_robust_from(&p, Neighbors::Search(method), &opts, &mut |_, _| true);
        assert_eq!(got.unwrap(), want, "{method:?}");
    }
    let table = knn_table(&p, opts.k_plane);
    let got = smooth_robust_from(&p, Neighbors::Table(&table), &opts, &mut |_, _| true);
    assert_eq!(got.unwrap(), want);
}

#[test]
fn a_built_tree_is_smoothed_without_a_second_build() {
    let p = cloud();
    let opts = SmoothOptions::default();
    let flat: Vec<f64> = p.iter().flat_map(|q| q.to_array()).collect();
    let tree = KdTree::<f64>::from_flat(&flat, 3, &BuildOptions::default()).unwrap();
    let (points, table) = tree_neighbors(&tree, opts.k).unwrap();
    assert_eq!(points, p);
    let got = smooth_from(&points, Neighbors::Table(&table), &opts, &mut |_, _| true);
    assert_eq!(got.unwrap(), smooth(&p, &opts).unwrap());

    // An f32 tree: its points widened to f64, its rows re-measured in f64; the same as the
    // smoothing of the widened points (no k-th-neighbour tie within f32 rounding here).
    let flat32: Vec<f32> = flat.iter().map(|&v| v as f32).collect();
    let tree32 = KdTree::<f32>::from_flat(&flat32, 3, &BuildOptions::default()).unwrap();
    let (points32, table32) = tree_neighbors(&tree32, opts.k).unwrap();
    let widened: Vec<DVec3> = flat32
        .chunks(3)
        .map(|c| DVec3::new(c[0].into(), c[1].into(), c[2].into()))
        .collect();
    assert_eq!(points32, widened);
    let got = smooth_from(&points32, Neighbors::Table(&table32), &opts, &mut |_, _| {
        true
    });
    assert_eq!(got.unwrap(), smooth(&widened, &opts).unwrap());
}

#[test]
fn tables_that_do_not_fit_the_points_are_refused() {
    let p = cloud();
    let opts = SmoothOptions::default();
    let run = |t: &NeighborTable<f64>| {
        smooth_from(&p, Neighbors::Table(t), &opts, &mut |_, _| true)
            .unwrap_err()
            .to_string()
    };
    // one row short
    let short = knn_table(&p[1..], 4);
    assert!(run(&short).contains("rows for"), "{}", run(&short));
    // a point in its own row (self included)
    let flat: Vec<f64> = p.iter().flat_map(|q| q.to_array()).collect();
    let with_self = KdTree::<f64>::from_flat(&flat, 3, &BuildOptions::default())
        .unwrap()
        .neighborhoods(
            Neighborhood::Knn { k: 4 },
            &TableOptions {
                exclude_self: false,
                threads: 0,
                ..Default::default()
            },
        )
        .unwrap();
    assert!(run(&with_self).contains("itself"), "{}", run(&with_self));
    // rows out of order
    let t = knn_table(&p, 4);
    let (offsets, mut index, mut d2) = (
        t.offsets().to_vec(),
        t.indices().to_vec(),
        t.sq_dists().to_vec(),
    );
    index.swap(0, 1);
    d2.swap(0, 1);
    let unordered = NeighborTable::from_parts(offsets, index, d2).unwrap();
    assert!(run(&unordered).contains("ordered"), "{}", run(&unordered));
    // a tree that skipped a non-finite point has nothing to smooth there
    let mut holes = flat.clone();
    holes[4] = f64::NAN;
    let tree = KdTree::<f64>::from_flat(
        &holes,
        3,
        &BuildOptions {
            non_finite: nbhd::NonFinitePolicy::Skip,
            ..BuildOptions::default()
        },
    )
    .unwrap();
    let e = tree_neighbors(&tree, 15).unwrap_err().to_string();
    assert!(e.contains("skipped"), "{e}");
}

#[test]
fn a_table_with_skipped_points_gives_the_same_as_the_skipping_point_call() {
    let mut p = cloud();
    p[5] = DVec3::new(f64::NAN, 0.0, 0.0);
    p[40] = DVec3::new(0.0, f64::INFINITY, 0.0);
    let flat: Vec<f64> = p.iter().flat_map(|q| q.to_array()).collect();
    let tree = KdTree::<f64>::from_flat(
        &flat,
        3,
        &BuildOptions {
            non_finite: nbhd::NonFinitePolicy::Skip,
            ..BuildOptions::default()
        },
    )
    .unwrap();
    // rows for the skipped points are empty; the others name finite points only
    let table = tree
        .neighborhoods(Neighborhood::Knn { k: 48 }, &TableOptions::default())
        .unwrap();
    let opts = SmoothOptions {
        non_finite: nbhd::NonFinitePolicy::Skip,
        ..SmoothOptions::default()
    };
    let want = smooth(&p, &opts).unwrap();
    let got = smooth_from(&p, Neighbors::Table(&table), &opts, &mut |_, _| true).unwrap();
    assert_eq!(got.points.len(), p.len());
    for (a, b) in got.points.iter().zip(&want.points) {
        assert!(a == b || (a.is_nan() && b.is_nan()), "{a} {b}");
    }
    let robust = RobustOptions {
        non_finite: nbhd::NonFinitePolicy::Skip,
        max_iterations: 2,
        ..RobustOptions::default()
    };
    let want = smooth_robust_report(&p, &robust, &mut |_, _| true).unwrap();
    let got = smooth_robust_from(&p, Neighbors::Table(&table), &robust, &mut |_, _| true).unwrap();
    for (a, b) in got.result.points.iter().zip(&want.result.points) {
        assert!(a == b || (a.is_nan() && b.is_nan()), "{a} {b}");
    }
}
