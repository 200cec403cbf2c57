//! Every bad input gets its typed error, never a panic.

use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, NbhdError, NeighborSearch, Neighborhood, NonFinitePolicy,
    PointsView, Query, ScalarType, MAX_POINTS,
};

fn tree(c: &[f64]) -> KdTree<f64> {
    KdTree::from_flat(c, 3, &BuildOptions::default()).unwrap()
}

#[test]
fn zero_dimension() {
    // (No point is not an error: tests/empty_inputs.rs.)
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
    // Every point skipped: a tree of no point (tests/empty_inputs.rs).
    let all_bad = [f64::NAN; 3];
    let t = KdTree::<f64>::from_flat(&all_bad, 3, &opts).unwrap();
    assert!(t.is_empty() && t.source_len() == 1);
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

/// Sizes that overflow the address space name the argument and the values passed.
#[test]
fn size_overflows_name_the_values() {
    let e = PointsView::required_bytes(4, usize::MAX / 4, 0, ScalarType::F64).unwrap_err();
    assert!(matches!(e, NbhdError::SizeOverflow { .. }));
    assert_eq!(
        e.to_string(),
        format!(
            "dim {} times 8 bytes per coordinate (F64) overflows the address space",
            usize::MAX / 4
        )
    );
    let e = PointsView::required_bytes(3, 3, usize::MAX / 2, ScalarType::F32).unwrap_err();
    assert!(
        e.to_string().starts_with(&format!(
            "the point buffer of count 3 and stride {}",
            usize::MAX / 2
        )),
        "{e}"
    );
}

/// A non-finite query of a batch is named by its index; a radius whose square overflows the
/// tree's type is refused with the value passed.
#[test]
fn batch_queries_and_radii_out_of_range_are_named() {
    let c: Vec<f32> = (0..30).map(|i| i as f32 * 0.1).collect();
    let t = KdTree::<f32>::from_flat(&c, 3, &BuildOptions::default()).unwrap();
    let q = [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, f32::NAN, 0.0];
    let qv = PointsView::from_flat(&q, 3).unwrap();
    let e = t
        .neighborhoods_of(
            &qv,
            Neighborhood::Knn { k: 2 },
            &nbhd::TableOptions::default(),
        )
        .unwrap_err();
    assert_eq!(
        e,
        NbhdError::NonFiniteQuery {
            query: Some(2),
            coordinate: 1
        }
    );
    assert_eq!(
        e.to_string(),
        "query point 2 has a NaN or infinite coordinate (coordinate 1)"
    );
    let e = Neighborhood::<f32>::Radius {
        radius: 1e20,
        sorted: true,
    }
    .validate()
    .unwrap_err();
    assert!(
        matches!(e, NbhdError::RadiusOutOfRange { scalar: "f32", .. }),
        "{e}"
    );
    // 1e20 as an f32 is 1.0000000200408773e20
    assert!(
        e.to_string()
            .starts_with("radius 1.0000000200408773e20 is too large for a tree of f32"),
        "{e}"
    );
    assert!(Neighborhood::<f32>::Radius {
        radius: 1e19,
        sorted: true
    }
    .validate()
    .is_ok());
    assert!(Neighborhood::<f64>::Radius {
        radius: 1e20,
        sorted: true
    }
    .validate()
    .is_ok());
}

/// Tables and smoothing whose output cannot fit in memory return
/// [`NbhdError::OutOfMemory`] with the bytes needed, never abort: checked in a child process
/// (this test binary run again) whose address space is limited with `RLIMIT_AS`.
#[cfg(target_os = "linux")]
#[test]
fn output_that_does_not_fit_is_an_error_not_an_abort() {
    const CHILD: &str = "NBHD_OOM_CHILD";
    if std::env::var_os(CHILD).is_some() {
        oom_child();
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let out = std::process::Command::new(exe)
        .args([
            "--exact",
            "output_that_does_not_fit_is_an_error_not_an_abort",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD, "1")
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "child failed: {:?}\n{text}",
        out.status
    );
    assert!(text.contains("oom child: all checks passed"), "{text}");
}

#[cfg(target_os = "linux")]
fn oom_child() {
    use nbhd::smooth::{smooth, Length, SmoothOptions};
    use nbhd::TableOptions;
    // 300,000 points in the unit cube
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let c: Vec<f32> = (0..900_000).map(|_| next() as f32).collect();
    let t = KdTree::<f32>::from_flat(&c, 3, &BuildOptions::default()).unwrap();
    let pts: Vec<glam::DVec3> = c
        .chunks(3)
        .map(|p| glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect();
    // the address space now plus 768 MB
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap();
    let pages: u64 = statm.split_whitespace().next().unwrap().parse().unwrap();
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) } as u64;
    let limit = pages * page + (768 << 20);
    let lim = libc::rlimit {
        rlim_cur: limit,
        rlim_max: limit,
    };
    // SAFETY: a valid rlimit struct for the calling process.
    assert_eq!(unsafe { libc::setrlimit(libc::RLIMIT_AS, &lim) }, 0);
    let opts = TableOptions::default();
    let oom = |r: nbhd::Result<nbhd::NeighborTable<f32>>| match r {
        Err(e @ NbhdError::OutOfMemory { .. }) => {
            assert!(e.to_string().contains(" bytes ("), "{e}");
        }
        other => panic!("expected OutOfMemory, got {:?}", other.map(|t| t.total())),
    };
    let all = Neighborhood::Radius {
        radius: 10.0f32,
        sorted: true,
    };
    oom(t.neighborhoods(all, &opts));
    oom(t.neighborhoods(
        Neighborhood::KnnRadius {
            k: 1_000_000_000,
            radius: 10.0,
        },
        &opts,
    ));
    oom(t.neighborhoods(
        Neighborhood::KnnRadius {
            k: usize::MAX,
            radius: 10.0,
        },
        &opts,
    ));
    match t.neighborhoods(Neighborhood::Knn { k: usize::MAX }, &opts) {
        Err(NbhdError::OutOfMemory { bytes, .. }) => {
            assert_eq!(bytes, 300_000u128 * 299_999 * 8)
        }
        other => panic!("{:?}", other.map(|t| t.total())),
    }
    let qv = PointsView::from_flat(&c, 3).unwrap();
    oom(t.neighborhoods_of(&qv, all, &opts));
    let so = SmoothOptions {
        k: usize::MAX,
        epsilon: Length::Absolute(1e300),
        ..SmoothOptions::default()
    };
    assert!(matches!(
        smooth(&pts, &so),
        Err(NbhdError::OutOfMemory { .. })
    ));
    // the process is unharmed
    let ok = t.neighborhoods(Neighborhood::Knn { k: 8 }, &opts).unwrap();
    assert_eq!(ok.total(), 300_000 * 8);
    println!("oom child: all checks passed");
}
