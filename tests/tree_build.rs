//! Facts about the built trees: every median algorithm (and the presorted build) gives the
//! identical tree for one pivot policy (thesis 8.1); balanced policies stay within
//! ⌈log2(n / leaf)⌉ + 1 levels; the parallel build equals the serial one; a million identical
//! points build with bounded depth.

mod common;

use common::{points, to_f32, Kind, KINDS};
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, MedianAlgorithm, PivotPolicy, PointsView, Query};

fn build<T: nbhd::Scalar>(c: &[T], d: usize, opts: BuildOptions) -> KdTree<T> {
    KdTree::build(&PointsView::from_flat(c, d).unwrap(), &opts).unwrap()
}

#[test]
fn every_median_algorithm_builds_the_identical_tree() {
    for kind in KINDS {
        for d in [1, 2, 3, 5] {
            let c = points(kind, 997, d, 7);
            for pivot in PivotPolicy::ALL {
                for leaf_size in [1, 4, 12] {
                    let opts = |median| BuildOptions {
                        pivot,
                        median,
                        leaf_size,
                        ..BuildOptions::default()
                    };
                    let reference = build(&c, d, opts(MedianAlgorithm::Presorted));
                    for median in MedianAlgorithm::ALL {
                        let t = build(&c, d, opts(median));
                        assert!(
                            t.same_structure(&reference),
                            "{kind:?} d={d} {pivot:?} {median:?} leaf {leaf_size}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn policies_build_different_trees() {
    // The identity above must not be vacuous: different policies do give different trees.
    let c = points(Kind::Random, 2000, 3, 3);
    let trees: Vec<_> = PivotPolicy::ALL
        .iter()
        .map(|&p| build(&c, 3, BuildOptions::with(p, MedianAlgorithm::Sort)))
        .collect();
    for i in 0..trees.len() {
        for j in i + 1..trees.len() {
            assert!(!trees[i].same_structure(&trees[j]));
        }
    }
}

#[test]
fn balanced_policies_have_logarithmic_depth() {
    for kind in KINDS {
        for n in [1usize, 2, 13, 1000, 4097] {
            let c = points(kind, n, 3, n as u64);
            for pivot in [PivotPolicy::CyclicMedian, PivotPolicy::SpreadMedian] {
                for leaf_size in [1usize, 5, 12] {
                    let t = build(
                        &c,
                        3,
                        BuildOptions {
                            pivot,
                            leaf_size,
                            ..Default::default()
                        },
                    );
                    let bound = (n as f64 / leaf_size as f64).log2().ceil().max(0.0) as usize + 1;
                    let s = t.stats();
                    assert!(
                        s.depth <= bound,
                        "{kind:?} n={n} {pivot:?} leaf {leaf_size}: {s:?}"
                    );
                    assert!(s.max_leaf_points <= leaf_size);
                    assert_eq!(s.points, n);
                    assert_eq!(s.nodes, 2 * s.leaves - 1);
                }
            }
        }
    }
}

#[test]
fn parallel_build_equals_serial_build() {
    let c = to_f32(&points(Kind::Clustered, 120_000, 3, 11));
    for pivot in PivotPolicy::ALL {
        for median in [MedianAlgorithm::FloydRivest, MedianAlgorithm::Quickselect] {
            let serial = build(
                &c,
                3,
                BuildOptions {
                    pivot,
                    median,
                    threads: 1,
                    ..Default::default()
                },
            );
            let parallel = build(
                &c,
                3,
                BuildOptions {
                    pivot,
                    median,
                    threads: 2,
                    ..Default::default()
                },
            );
            assert!(parallel.same_structure(&serial), "{pivot:?} {median:?}");
        }
    }
}

#[test]
fn a_million_identical_points_build_balanced() {
    let c = vec![1.5f32; 3_000_000];
    for pivot in PivotPolicy::ALL {
        let t = build(
            &c,
            3,
            BuildOptions {
                pivot,
                ..Default::default()
            },
        );
        let s = t.stats();
        assert_eq!(s.points, 1_000_000);
        assert!(s.depth <= 18, "{pivot:?}: depth {}", s.depth);
    }
    // Presorted too (serial, O(n log n)).
    let t = build(
        &c,
        3,
        BuildOptions::with(PivotPolicy::CyclicMedian, MedianAlgorithm::Presorted),
    );
    assert!(t.stats().depth <= 18);
    // The nearest other point of a duplicate is at distance 0, lowest index first.
    let mut out = Vec::new();
    t.knn(Query::stored_excluding_self(0), 3, &mut out).unwrap();
    let got: Vec<_> = out.iter().map(|n| (n.index, n.sq_dist)).collect();
    assert_eq!(got, vec![(1, 0.0), (2, 0.0), (3, 0.0)]);
}

#[test]
fn closest_to_middle_is_deep_on_surfaces_but_still_exact() {
    // Moore's policy is unbalanced on surface samples (thesis Fig. 8.7); the iterative
    // build and search handle any depth.
    let n = 20_000;
    let mut c = Vec::with_capacity(3 * n);
    for i in 0..n {
        let t = i as f64 / n as f64 * std::f64::consts::TAU * 7.0;
        let s = i as f64 / n as f64 * std::f64::consts::TAU;
        c.extend_from_slice(&[
            (2.0 + s.cos()) * t.cos(),
            (2.0 + s.cos()) * t.sin(),
            s.sin(),
        ]);
    }
    let t = build(
        &c,
        3,
        BuildOptions {
            pivot: PivotPolicy::ClosestToMiddle,
            leaf_size: 1,
            ..Default::default()
        },
    );
    let balanced = build(
        &c,
        3,
        BuildOptions {
            pivot: PivotPolicy::CyclicMedian,
            leaf_size: 1,
            ..Default::default()
        },
    );
    assert!(t.stats().depth > balanced.stats().depth);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for i in (0..n as u32).step_by(997) {
        t.knn(Query::stored(i), 10, &mut a).unwrap();
        balanced.knn(Query::stored(i), 10, &mut b).unwrap();
        assert_eq!(a, b);
    }
}

#[test]
fn stats_report_memory() {
    let c = to_f32(&points(Kind::Random, 10_000, 3, 5));
    let t = build(&c, 3, BuildOptions::default());
    let s = t.stats();
    // coordinates + index map + nodes
    assert!(s.bytes >= 10_000 * (12 + 4));
    assert!(
        s.bytes <= 10_000 * 24,
        "{} bytes per point",
        s.bytes as f64 / 1e4
    );
}
