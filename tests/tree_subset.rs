//! Trees over an index subset (`KdTree::build_subset`, PCL's `setInputCloud(cloud, indices)`):
//! every query and every all-point table equals brute force over the listed points, in the
//! caller's indices, for every dimension path (records for 1–3, packed copy above), both
//! scalar types, non-finite points rejected or skipped as by the normal build, and any order of
//! the indices; the errors name the bad index.

mod common;

use common::{points, to_f32, Kind, Rng, KINDS};
use nbhd::table::neighborhoods_of_all;
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, NbhdError, NeighborSearch, Neighborhood, NonFinitePolicy,
    PointsView, Query, Scalar, TableOptions,
};

/// A random subset of `0..n` (about `fraction` of it), shuffled.
fn subset(n: usize, fraction: f64, rng: &mut Rng) -> Vec<u32> {
    let mut s: Vec<u32> = (0..n as u32).filter(|_| rng.unit() < fraction).collect();
    if s.is_empty() {
        s.push(rng.below(n) as u32);
    }
    for i in (1..s.len()).rev() {
        s.swap(i, rng.below(i + 1));
    }
    s
}

/// The reference: brute force over the same buffer with every unlisted point made NaN and
/// skipped, so its answers are in the caller's indices among the listed points.
fn reference<T: Scalar>(c: &[T], d: usize, listed: &[u32]) -> BruteForce<T> {
    let mut masked = vec![T::from_f64(f64::NAN); c.len()];
    for &i in listed {
        let i = i as usize;
        masked[i * d..(i + 1) * d].copy_from_slice(&c[i * d..(i + 1) * d]);
    }
    let view = PointsView::from_flat(&masked, d).unwrap();
    BruteForce::new(&view, NonFinitePolicy::Skip).unwrap()
}

fn check_against_brute<T: Scalar>(c: &[T], d: usize, listed: &[u32], what: &str) {
    let view = PointsView::from_flat(c, d).unwrap();
    let n = view.len();
    let opts = BuildOptions {
        leaf_size: 4,
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    let tree = KdTree::<T>::build_subset(&view, listed, &opts).unwrap();
    let brute = reference(c, d, listed);
    let finite_listed = listed
        .iter()
        .filter(|&&i| (0..d).all(|j| c[i as usize * d + j].is_finite()))
        .count();
    assert_eq!(tree.len(), finite_listed, "{what}");
    assert_eq!(tree.source_len(), n, "{what}");

    // The same tree whatever the order of the indices.
    let mut sorted = listed.to_vec();
    sorted.sort_unstable();
    let again = KdTree::<T>::build_subset(&view, &sorted, &opts).unwrap();
    assert!(tree.same_structure(&again), "{what}: order of indices");

    let r = T::from_f64(0.8);
    let nbhds = [
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 7 },
        Neighborhood::Radius {
            radius: r,
            sorted: true,
        },
        Neighborhood::KnnRadius { k: 5, radius: r },
    ];
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for nb in nbhds {
        // Queries at every point of the buffer, listed or not.
        for i in 0..n {
            let q = &c[i * d..(i + 1) * d];
            if !q.iter().all(|x| x.is_finite()) {
                continue;
            }
            tree.search(Query::point(q), nb, &mut got).unwrap();
            brute.search(Query::point(q), nb, &mut want).unwrap();
            assert_eq!(got, want, "{what} {nb:?} at point {i}");
        }
        // Queries by stored point: the listed finite ones answer, the others are refused.
        for i in 0..n as u32 {
            let q = Query::Stored {
                index: i,
                exclude_self: true,
            };
            match brute.search(q, nb, &mut want) {
                Ok(()) => {
                    tree.search(q, nb, &mut got).unwrap();
                    assert_eq!(got, want, "{what} {nb:?} stored {i}");
                }
                Err(e) => {
                    assert_eq!(e, NbhdError::SkippedPoint { index: i as usize });
                    assert_eq!(tree.search(q, nb, &mut got), Err(e), "{what} stored {i}");
                }
            }
        }
        // All-point tables: a row per point of the buffer, empty for the unlisted ones.
        for exclude_self in [true, false] {
            for threads in [1, 2] {
                let o = TableOptions {
                    exclude_self,
                    threads,
                    ..Default::default()
                };
                let t = tree.neighborhoods(nb, &o).unwrap();
                let b = neighborhoods_of_all(&brute, nb, exclude_self).unwrap();
                assert_eq!(t.len(), n, "{what}");
                assert_eq!(t.offsets(), b.offsets(), "{what} {nb:?} {o:?}");
                assert_eq!(t.indices(), b.indices(), "{what} {nb:?} {o:?}");
                assert_eq!(t.sq_dists(), b.sq_dists(), "{what} {nb:?} {o:?}");
            }
        }
    }
}

#[test]
fn subset_trees_answer_as_brute_force_over_the_listed_points() {
    let mut rng = Rng::new(11);
    for kind in KINDS {
        for d in [1, 2, 3, 5] {
            let c = points(kind, 400, d, 3);
            for fraction in [0.05, 0.5, 1.0] {
                let listed = subset(400, fraction, &mut rng);
                let what = format!("{kind:?} d={d} {} listed", listed.len());
                check_against_brute(&c, d, &listed, &format!("f64 {what}"));
                check_against_brute(&to_f32(&c), d, &listed, &format!("f32 {what}"));
            }
        }
    }
}

#[test]
fn non_finite_listed_points_are_skipped_or_rejected_as_by_the_normal_build() {
    let mut c = to_f32(&points(Kind::Random, 500, 3, 5));
    for i in (0..500).step_by(7) {
        c[i * 3 + 1] = f32::NAN;
    }
    c[3 * 10] = f32::INFINITY; // point 10
    let mut rng = Rng::new(2);
    let listed = subset(500, 0.6, &mut rng);
    check_against_brute(&c, 3, &listed, "NaN holes skipped");

    let view = PointsView::from_flat(&c, 3).unwrap();
    let reject = BuildOptions::default();
    // Rejected: the error names the first non-finite point in index order among the listed.
    let first_bad = {
        let mut s = listed.clone();
        s.sort_unstable();
        s.into_iter()
            .find(|&i| (0..3).any(|j| !c[i as usize * 3 + j].is_finite()))
            .unwrap() as usize
    };
    match KdTree::<f32>::build_subset(&view, &listed, &reject) {
        Err(NbhdError::NonFinite { index, .. }) => assert_eq!(index, first_bad),
        other => panic!("expected NonFinite, got {other:?}"),
    }
    // Only finite points listed: the default (rejecting) build accepts them.
    let finite: Vec<u32> = (0..500u32).filter(|i| i % 7 != 0 && *i != 10).collect();
    let t = KdTree::<f32>::build_subset(&view, &finite, &reject).unwrap();
    assert_eq!(t.len(), finite.len());
    // Only non-finite points listed, skipped: a tree of no point, with a row per index.
    let skip = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    let t = KdTree::<f32>::build_subset(&view, &[0, 7, 10], &skip).unwrap();
    assert!(t.is_empty() && t.source_len() == view.len());
}

#[test]
fn bad_index_lists_are_refused_with_the_index_named() {
    let c = points(Kind::Random, 100, 3, 1);
    let view = PointsView::from_flat(&c, 3).unwrap();
    let o = BuildOptions::default();
    // An empty list is a tree of no point (tests/empty_inputs.rs).
    assert!(KdTree::<f64>::build_subset(&view, &[], &o)
        .unwrap()
        .is_empty());
    let e = KdTree::<f64>::build_subset(&view, &[3, 100, 200], &o).unwrap_err();
    assert_eq!(
        e,
        NbhdError::IndexOutOfRange {
            index: 100,
            count: 100
        }
    );
    assert!(e.to_string().contains("100"), "{e}");
    let e = KdTree::<f64>::build_subset(&view, &[5, 9, 2, 9, 5], &o).unwrap_err();
    assert_eq!(e, NbhdError::DuplicateIndex { index: 5 });
    assert!(e.to_string().contains("listed more than once"), "{e}");
    assert_eq!(
        KdTree::<f64>::build_subset(&view, &[4, 4], &o).unwrap_err(),
        NbhdError::DuplicateIndex { index: 4 }
    );
    // Options are checked as by the normal build.
    let bad = BuildOptions {
        leaf_size: 0,
        ..BuildOptions::default()
    };
    assert!(matches!(
        KdTree::<f64>::build_subset(&view, &[1, 2], &bad),
        Err(NbhdError::InvalidOption { .. })
    ));
}

#[test]
fn a_full_subset_is_the_normal_tree_and_threads_do_not_matter() {
    let c = to_f32(&points(Kind::Clustered, 5000, 3, 9));
    let view = PointsView::from_flat(&c, 3).unwrap();
    let all: Vec<u32> = (0..5000).collect();
    for threads in [1, 2] {
        let o = BuildOptions {
            threads,
            ..BuildOptions::default()
        };
        let full = KdTree::<f32>::build(&view, &o).unwrap();
        let sub = KdTree::<f32>::build_subset(&view, &all, &o).unwrap();
        assert!(full.same_structure(&sub), "threads {threads}");
        let every_other: Vec<u32> = (0..5000).step_by(2).collect();
        let a = KdTree::<f32>::build_subset(&view, &every_other, &o).unwrap();
        let b = KdTree::<f32>::build_subset(
            &view,
            &every_other,
            &BuildOptions {
                threads: 1,
                ..BuildOptions::default()
            },
        )
        .unwrap();
        assert!(a.same_structure(&b), "threads {threads}");
    }
}
