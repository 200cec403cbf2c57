//! CloudCompare reads what `nbhd` writes (issue 39 item 4): Debian's CloudCompare on its command
//! line (`-SILENT`, under `xvfb-run`: it needs a display) opens nbhd's files and exports, as
//! text with a header, the points, normals and scalar fields it found; they are compared with
//! nbhd's own values.
//!
//! What CloudCompare 2.11 (Debian 12) finds on its command line, as this test checks it:
//! - PLY: coordinates, normals (`nx ny nz`) and, as scalar fields, only properties whose name
//!   has `scal` or `intensity` in it (its reader's rule without the dialog; its own writer
//!   names fields `scalar_NAME`), so of nbhd's fields `intensity`;
//! - text (`.xyz`, nbhd's `//x y z ...` header): coordinates, normals and every other column
//!   as a scalar field, in order (unnamed);
//! - LAS/LAZ: only if it was built with a LAS reader (Debian's is not: "unhandled file
//!   extension 'las'"); then the normals (`NormalX NormalY NormalZ`) and scalar fields.
//!
//! Skipped with a note if CloudCompare or xvfb-run is missing, unless NBHD_REQUIRE_CLOUDCOMPARE
//! is set (scripts/test.sh installs both and sets it).

use std::path::{Path, PathBuf};
use std::process::Command;

fn data(rel: &str) -> String {
    let f = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(rel);
    assert!(f.is_file(), "{} is missing", f.display());
    f.display().to_string()
}

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-cloudcompare-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn on_path(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Whether CloudCompare can be run; fails if NBHD_REQUIRE_CLOUDCOMPARE is set and it cannot.
fn have_cloudcompare() -> bool {
    if on_path("CloudCompare") && on_path("xvfb-run") {
        return true;
    }
    assert!(
        std::env::var_os("NBHD_REQUIRE_CLOUDCOMPARE").is_none(),
        "NBHD_REQUIRE_CLOUDCOMPARE is set but CloudCompare or xvfb-run is not on PATH"
    );
    println!("NOTE: CloudCompare or xvfb-run is not installed; the CloudCompare test is skipped");
    false
}

/// What CloudCompare exported of `file`: the column names of its header and the rows, or its
/// log if it did not open the file.
fn cloudcompare_export(file: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let o = Command::new("xvfb-run")
        .args([
            "-a",
            "CloudCompare",
            "-SILENT",
            "-NO_TIMESTAMP",
            "-O",
            "-GLOBAL_SHIFT",
            "AUTO",
        ])
        .arg(file.file_name().unwrap())
        .args(["-C_EXPORT_FMT", "ASC", "-ADD_HEADER", "-SAVE_CLOUDS"])
        .current_dir(file.parent().unwrap())
        .output()
        .expect("run xvfb-run CloudCompare");
    let log = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    let asc = file.with_extension("asc");
    let Ok(text) = std::fs::read_to_string(&asc) else {
        return Err(log);
    };
    std::fs::remove_file(&asc).unwrap();
    let mut lines = text.lines();
    let head = lines.next().unwrap_or("");
    let names = head
        .trim_start_matches("//")
        .split_whitespace()
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
        .collect();
    Ok((names, rows))
}

fn nbhd(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_nbhd"))
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Checks CloudCompare's export of `file` against nbhd's cloud `c`: the coordinates, the
/// normals (it stores them compressed, to about 1e-3), and each other column it exported (a
/// scalar field, or a colour channel it chose to make of a column) against nbhd's fields,
/// by value as the `f32` (or 8-bit channel) CloudCompare holds. Returns, per column found,
/// CloudCompare's name and the nbhd fields with those values; a column no field matches fails.
fn check(file: &Path, c: &nbhd::io::PointCloud) -> Vec<(String, Vec<String>)> {
    let (names, rows) = cloudcompare_export(file).unwrap_or_else(|log| panic!("{log}"));
    let what = file.display();
    assert_eq!(rows.len(), c.len(), "{what}: {names:?}");
    let col = |n: &str| names.iter().position(|m| m == n);
    let x = col("X").unwrap();
    for (i, r) in rows.iter().enumerate() {
        for j in 0..3 {
            assert!(
                (r[x + j] - c.positions[i][j]).abs() <= 1e-4,
                "{what}: point {i}"
            );
        }
    }
    if let Some(nx) = col("Nx") {
        let normals = c.normals.as_ref().unwrap();
        for (i, r) in rows.iter().enumerate() {
            for j in 0..3 {
                let n = normals[i][j];
                let got = r[nx + j];
                assert!((got - n).abs() <= 1e-2, "{what}: normal {i}: {got} vs {n}");
            }
        }
    }
    let same = |a: f64, b: f64, channel: bool| {
        let b = if channel {
            b.clamp(0.0, 255.0).floor()
        } else {
            b
        };
        a as f32 == b as f32 || a.is_nan() && b.is_nan()
    };
    let mut found = Vec::new();
    for (j, name) in names.iter().enumerate() {
        if ["X", "Y", "Z", "Nx", "Ny", "Nz"].contains(&name.as_str()) {
            continue;
        }
        let channel = ["R", "G", "B"].contains(&name.as_str());
        let fields: Vec<String> = c
            .scalars
            .iter()
            .filter(|f| {
                rows.iter()
                    .zip(&f.values)
                    .all(|(r, &v)| same(r[j], v, channel))
            })
            .map(|f| f.name.clone())
            .collect();
        assert!(
            !fields.is_empty(),
            "{what}: CloudCompare's {name} is none of nbhd's fields"
        );
        found.push((name.clone(), fields));
    }
    found
}

#[test]
fn cloudcompare_reads_nbhds_files() {
    if !have_cloudcompare() {
        return;
    }
    let d = dir();
    let input = data("las/full_fmt6.las");
    for ext in ["ply", "xyz", "las", "laz"] {
        let out = d.join(format!("curvature.{ext}"));
        let out_s = out.display().to_string();
        nbhd(&[
            "curvature",
            &input,
            &out_s,
            "-k",
            "10",
            "--precision",
            "double",
        ]);
        let c = nbhd::io::read(&out).unwrap();
        if ext.starts_with("la") {
            if let Err(log) = cloudcompare_export(&out) {
                assert!(log.contains("unhandled file extension"), "{log}");
                println!("NOTE: this CloudCompare has no LAS reader; nbhd's {ext} not checked");
                continue;
            }
        }
        let found = check(&out, &c);
        println!("CloudCompare found in nbhd's {ext}: normals and {found:?}");
        let matched = |f: &str| found.iter().any(|(_, m)| m.iter().any(|n| n == f));
        let want: &[&str] = match ext {
            // Without its dialog, its PLY reader takes only `*scal*` and `intensity`
            // properties, and its text reader guesses columns by position (three become a
            // colour, one is skipped).
            "ply" => &["intensity"],
            _ => &[
                "curvature",
                "k1",
                "k2",
                "mean_curvature",
                "gps_time",
                "Amplitude",
                "PulseId",
            ],
        };
        for f in want {
            assert!(
                matched(f),
                "{ext}: CloudCompare did not find {f}: {found:?}"
            );
        }
    }
}
