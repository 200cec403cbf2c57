//! Outlier removal against a brute-force reference written here from the definitions (mean
//! distance to the k nearest other points, threshold mean + α·σ with the sample σ; at least
//! m other points within an inclusive radius; the sums over the points exact), on seeded sets with planted outliers, NaN
//! points, duplicates and exact distance ties, for f32 and f64 and several thread counts.

mod common;

use common::{points, to_f32, Kind, Rng, KINDS};
use nbhd::filter::{
    radius_outlier_removal, statistical_outlier_removal, RadiusOutlierOptions,
    StatisticalOutlierOptions,
};
use nbhd::sum::ExactSum;
use nbhd::{BuildOptions, KdTree, NbhdError, NonFinitePolicy, PointsView, Scalar};

fn tree<T: Scalar>(coords: &[T], d: usize) -> KdTree<T> {
    let view = PointsView::from_flat(coords, d).unwrap();
    let opts = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        leaf_size: 3,
        ..BuildOptions::default()
    };
    KdTree::build(&view, &opts).unwrap()
}

fn finite<T: Scalar>(coords: &[T], d: usize, i: usize) -> bool {
    coords[i * d..(i + 1) * d].iter().all(|c| c.is_finite())
}

/// Sorted squared distances (in `T`, as the tree computes them) from point i to every other
/// finite point.
fn others<T: Scalar>(coords: &[T], d: usize, i: usize) -> Vec<f64> {
    let n = coords.len() / d;
    let mut v: Vec<f64> = (0..n)
        .filter(|&j| j != i && finite(coords, d, j))
        .map(|j| {
            let mut s = T::ZERO;
            for c in 0..d {
                let t = coords[i * d + c] - coords[j * d + c];
                s = s + t * t;
            }
            s.to_f64()
        })
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

fn brute_sor<T: Scalar>(coords: &[T], d: usize, k: usize, alpha: f64) -> Vec<u32> {
    let n = coords.len() / d;
    let dist: Vec<(u32, f64)> = (0..n)
        .filter(|&i| finite(coords, d, i))
        .map(|i| {
            let o = others(coords, d, i);
            let s = o[..k].iter().fold(0.0, |a, x| a + x.sqrt());
            (i as u32, s / k as f64)
        })
        .collect();
    // both sums exact, rounded once (the order-independent sums the filter documents)
    let m = dist.len() as f64;
    let mean = dist.iter().map(|x| x.1).collect::<ExactSum>().value() / m;
    let var = dist
        .iter()
        .map(|x| (x.1 - mean) * (x.1 - mean))
        .collect::<ExactSum>()
        .value()
        / (m - 1.0);
    let t = mean + alpha * var.sqrt();
    dist.iter().filter(|x| x.1 <= t).map(|x| x.0).collect()
}

fn brute_ror<T: Scalar>(coords: &[T], d: usize, r: f64, m: usize) -> Vec<u32> {
    let n = coords.len() / d;
    let r2 = T::from_f64(r) * T::from_f64(r);
    (0..n)
        .filter(|&i| finite(coords, d, i))
        .filter(|&i| {
            others(coords, d, i)
                .iter()
                .filter(|&&x| x <= r2.to_f64())
                .count()
                >= m
        })
        .map(|i| i as u32)
        .collect()
}

/// A set of kind `kind` plus a few far outliers and a NaN point.
fn with_outliers(kind: Kind, n: usize, d: usize, seed: u64) -> Vec<f64> {
    let mut c = points(kind, n, d, seed);
    let mut rng = Rng::new(seed);
    for _ in 0..4 {
        c.extend((0..d).map(|_| 50.0 + rng.unit() * 100.0));
    }
    c.extend((0..d).map(|j| if j == 0 { f64::NAN } else { 1.0 }));
    c
}

fn check<T: Scalar>(coords: &[T], d: usize) {
    let t = tree(coords, d);
    for (k, alpha) in [(1, 1.0), (4, 0.0), (8, 2.0), (6, -0.5)] {
        if k >= t.len() {
            continue;
        }
        let want = brute_sor(coords, d, k, alpha);
        for threads in [1, 3] {
            let got = statistical_outlier_removal(
                &t,
                &StatisticalOutlierOptions {
                    k,
                    std_ratio: alpha,
                    threads,
                },
            )
            .unwrap();
            assert_eq!(
                got.indices, want,
                "sor k {k} alpha {alpha} threads {threads}"
            );
            let mask = got.mask();
            assert_eq!(mask.len(), coords.len() / d);
            assert_eq!(mask.iter().filter(|&&b| b).count(), want.len());
        }
    }
    // radii through actual distances, so points lie exactly on the sphere
    let o = others(coords, d, 0);
    for (r, m) in [
        (o[0].sqrt(), 1),
        (o[o.len() / 2].sqrt(), 3),
        (0.0, 1),
        (o[2].sqrt(), 0),
    ] {
        let want = brute_ror(coords, d, r, m);
        for threads in [1, 2] {
            let got = radius_outlier_removal(
                &t,
                &RadiusOutlierOptions {
                    radius: r,
                    min_neighbors: m,
                    threads,
                },
            )
            .unwrap();
            assert_eq!(got.indices, want, "ror r {r} m {m}");
        }
    }
}

#[test]
fn outlier_removal_matches_brute_force() {
    for (i, kind) in KINDS.iter().enumerate() {
        if matches!(kind, Kind::AllIdentical) {
            continue; // every distance 0; covered below
        }
        for d in [2, 3] {
            let c = with_outliers(*kind, 150, d, 11 + i as u64);
            check::<f64>(&c, d);
            check::<f32>(&to_f32(&c), d);
        }
    }
    let c = with_outliers(Kind::AllIdentical, 40, 3, 5);
    check::<f64>(&c, 3);
}

#[test]
fn planted_outliers_are_removed() {
    let c = with_outliers(Kind::Random, 400, 3, 3);
    let t = tree(&c, 3);
    let kept = statistical_outlier_removal(&t, &StatisticalOutlierOptions::default()).unwrap();
    for o in 400..405u32 {
        assert!(!kept.indices.contains(&o), "outlier {o} kept");
    }
    let kept = radius_outlier_removal(
        &t,
        &RadiusOutlierOptions {
            radius: 2.0,
            min_neighbors: 2,
            threads: 0,
        },
    )
    .unwrap();
    // the far points and the NaN point go; of the uniform points, at most a sparse few
    assert!(kept.indices.iter().all(|&i| i < 400));
    assert!(kept.indices.len() >= 390, "{}", kept.indices.len());
}

#[test]
fn bad_options_are_refused() {
    let c = points(Kind::Random, 20, 3, 1);
    let t = tree(&c, 3);
    let sor = |k, std_ratio, threads| {
        statistical_outlier_removal(
            &t,
            &StatisticalOutlierOptions {
                k,
                std_ratio,
                threads,
            },
        )
    };
    assert_eq!(sor(0, 1.0, 0), Err(NbhdError::ZeroK));
    assert!(matches!(
        sor(20, 1.0, 0),
        Err(NbhdError::InvalidOption { name: "k", .. })
    ));
    assert!(matches!(
        sor(3, f64::NAN, 0),
        Err(NbhdError::InvalidOption {
            name: "std_ratio",
            ..
        })
    ));
    assert!(matches!(
        sor(3, 1.0, 5000),
        Err(NbhdError::InvalidOption {
            name: "threads",
            ..
        })
    ));
    let ror = |radius, threads| {
        radius_outlier_removal(
            &t,
            &RadiusOutlierOptions {
                radius,
                min_neighbors: 2,
                threads,
            },
        )
    };
    assert!(matches!(ror(-1.0, 0), Err(NbhdError::InvalidRadius(_))));
    assert!(matches!(ror(f64::NAN, 0), Err(NbhdError::InvalidRadius(_))));
    assert!(matches!(
        ror(f64::INFINITY, 0),
        Err(NbhdError::InvalidRadius(_))
    ));
    let tf = tree(&to_f32(&c), 3);
    assert!(matches!(
        radius_outlier_removal(
            &tf,
            &RadiusOutlierOptions {
                radius: 1e30,
                min_neighbors: 1,
                threads: 0
            }
        ),
        Err(NbhdError::RadiusOutOfRange { .. })
    ));
}
