//! `nbhd bench speed` as a person runs it: the quick run's table has every requested row and
//! its neighbour counts agree with kiddo's; bad options fail with a clear message.

use std::process::{Command, Output};

fn nbhd(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nbhd"))
        .args(args)
        .output()
        .expect("run nbhd")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small scan-like XYZ file (a wavy 60 × 50 grid, one NaN point) in a fresh folder.
fn small_xyz() -> String {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-bench-speed-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let mut s = String::from("nan nan nan\n");
    for i in 0..60 {
        for j in 0..50 {
            let (x, y) = (i as f64 * 0.01, j as f64 * 0.013);
            s += &format!("{x} {y} {}\n", 0.02 * (7.0 * x).sin() * (5.0 * y).cos());
        }
    }
    let f = d.join("grid.xyz");
    std::fs::write(&f, s).unwrap();
    f.display().to_string()
}

#[test]
fn quick_run_has_every_row_and_counts_agree() {
    let file = small_xyz();
    let sets = format!("torus-77k,{file}");
    let o = nbhd(&[
        "bench", "speed", "--quick", "--sets", &sets, "--scalar", "both",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    for set in ["torus-77k", "grid.xyz"] {
        for scalar in ["f32", "f64"] {
            for op in [
                "build", "knn10", "knn30", "radius", "epsk", "single10", "single30",
            ] {
                for threads in [1, 2] {
                    let row = format!("| {set} | {scalar} | {op} | {threads} |");
                    assert_eq!(s.matches(&row).count(), 1, "no single row {row} in\n{s}");
                }
            }
        }
    }
    // The file's NaN point is skipped; brute force runs on it (3,000 points) and not on the
    // torus (over the quick limit).
    assert!(s.contains("| grid.xyz | 3000 | f32 |"), "{s}");
    let brute = |set: &str| {
        s.lines()
            .find(|l| l.starts_with(&format!("| {set} | f32 | knn10 | 1 |")))
            .unwrap()
            .split('|')
            .nth(8)
            .unwrap()
            .trim()
            .to_string()
    };
    assert_ne!(brute("grid.xyz"), "–", "{s}");
    assert_eq!(brute("torus-77k"), "–", "{s}");
    // The tables carry the floor, the single queries the C ABI's time.
    let column = |set: &str, op: &str, at: usize| {
        s.lines()
            .find(|l| l.starts_with(&format!("| {set} | f32 | {op} | 1 |")))
            .unwrap()
            .split('|')
            .nth(at)
            .unwrap()
            .trim()
            .to_string()
    };
    for (op, c_abi, floor) in [
        ("knn10", false, true),
        ("single10", true, false),
        ("radius", false, true),
        ("build", false, false),
    ] {
        assert_eq!(column("torus-77k", op, 11) != "–", c_abi, "{op}: {s}");
        assert_eq!(column("torus-77k", op, 13) != "–", floor, "{op}: {s}");
    }
    assert!(!s.contains("differs"), "{s}");
    assert!(s.contains("Count check: all agree with kiddo."), "{s}");
}

#[test]
fn quick_json_reports_the_check() {
    let o = nbhd(&[
        "bench",
        "speed",
        "--quick",
        "--json",
        "--sets",
        "torus-77k",
        "--ops",
        "knn10,epsk",
        "--thread-counts",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON document");
    assert_eq!(v["counts_agree"], true);
    assert_eq!(v["reps"], 1);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        assert_eq!(r["nbhd_total"], r["kiddo_total"]);
        assert!(r["kiddo_ratio"].as_f64().unwrap() > 0.0);
    }
    assert_eq!(v["sets"][0]["points"], 77_616);
    assert!(v["sets"][0]["tree_bytes_per_point"].as_f64().unwrap() > 12.0);
}

#[test]
fn bad_options_give_a_clear_error() {
    let cases: [(&[&str], &str); 5] = [
        (&["--sets", "no-such-set"], "neither a generated set"),
        (&["--ops", "knn11"], "invalid value 'knn11'"),
        (
            &["--thread-counts", "0"],
            "--thread-counts must be at least 1",
        ),
        (&["--reps", "0"], "--reps must be at least 1"),
        (
            &["--quick", "--sets", "cube-1M"],
            "--quick runs small sets only",
        ),
    ];
    for (args, msg) in cases {
        let o = nbhd(&[&["bench", "speed"], args].concat());
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr(&o).contains(msg), "{args:?}: {}", stderr(&o));
    }
}
