//! Normals and smoothing on PCL's organized scans (office1.pcd, table_scene_mug_stereo_textured.pcd),
//! whose NaN holes the non-finite policy SKIP leaves out: every hole keeps its index, stays NaN
//! and gets NaN geometry flagged `FLAG_SKIPPED`, and every other point gets exactly what the
//! finite points alone give.
#![cfg(feature = "io")]

use glam::DVec3;
use nbhd::geometry::normals::FLAG_SKIPPED;
use nbhd::smooth::{analyze, smooth, Length, SmoothOptions};
use nbhd::{io, NbhdError, NonFinitePolicy};
use std::path::PathBuf;

/// A PCL test scan of the repository's `tests/data/pcl` (see its README); a missing file fails
/// the test rather than skipping it.
fn scan(name: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/pcl")
        .join(name);
    assert!(path.is_file(), "{} is missing", path.display());
    path
}

fn check_scan(name: &str, expect_points: usize) {
    let path = scan(name);
    let cloud = io::read(&path).unwrap();
    assert_eq!(cloud.len(), expect_points);
    let pts: Vec<DVec3> = cloud.positions.iter().map(|&p| DVec3::from(p)).collect();
    let holes: Vec<bool> = pts.iter().map(|p| !p.is_finite()).collect();
    let n_holes = holes.iter().filter(|&&h| h).count();
    assert!(n_holes > 0, "{name} has NaN holes");
    let finite: Vec<DVec3> = pts.iter().copied().filter(|p| p.is_finite()).collect();

    // refused by default, with the first hole named
    let first = holes.iter().position(|&h| h).unwrap();
    match analyze(&pts, &SmoothOptions::default()) {
        Err(NbhdError::NonFinite { index, .. }) => assert_eq!(index, first),
        other => panic!("{other:?}"),
    }
    let skip = SmoothOptions {
        non_finite: NonFinitePolicy::Skip,
        ..SmoothOptions::default()
    };
    let a = analyze(&pts, &skip).unwrap();
    let f = analyze(&finite, &SmoothOptions::default()).unwrap();
    assert_eq!(a.outputs.len(), pts.len());
    let mut j = 0;
    for (i, o) in a.outputs.iter().enumerate() {
        if holes[i] {
            assert!(o.normal.is_nan() && o.covariance_quotient.is_nan());
            assert_eq!(o.normal_flags, FLAG_SKIPPED);
        } else {
            assert_eq!(*o, f.outputs[j]);
            assert!((o.normal.length() - 1.0).abs() < 1e-9);
            j += 1;
        }
    }
    // one smoothing step: holes unmoved, the others as for the finite points alone
    let one = SmoothOptions {
        steps: 1,
        outputs: false,
        ..skip
    };
    let s = smooth(&pts, &one).unwrap();
    let sf = smooth(
        &finite,
        &SmoothOptions {
            non_finite: NonFinitePolicy::Reject,
            ..one
        },
    )
    .unwrap();
    let mut j = 0;
    for (i, p) in s.points.iter().enumerate() {
        if holes[i] {
            assert!(p.is_nan());
        } else {
            assert_eq!(*p, sf.points[j]);
            j += 1;
        }
    }
    // ε meant as a length in metres but left relative: refused, with ε in the points' units
    let cm = SmoothOptions {
        epsilon: Length::Relative(0.01),
        ..skip
    };
    let e = analyze(&pts, &cm).unwrap_err();
    assert!(matches!(e, NbhdError::Degenerate { .. }), "{e}");
    assert!(e.to_string().contains("in the points' units"), "{e}");
}

#[test]
fn office1_normals_and_smoothing_skip_the_holes() {
    check_scan("office1.pcd", 307_200);
}

#[test]
fn table_scene_mug_normals_and_smoothing_skip_the_holes() {
    check_scan("table_scene_mug_stereo_textured.pcd", 307_200);
}
