//! The `nbhd` binary as a person runs it.

use std::path::PathBuf;
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

fn data(rel: &str) -> Option<String> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data");
    if !d.is_dir() {
        println!("NOTE: {} is missing; real-file test skipped", d.display());
        return None;
    }
    Some(d.join(rel).display().to_string())
}

fn tmp(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("nbhd-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name).display().to_string()
}

#[test]
fn info_on_bunny_prints_the_count() {
    let Some(f) = data("pcl/bunny.pcd") else {
        return;
    };
    let o = nbhd(&["info", &f]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    assert!(s.contains("points     397"), "{s}");
    assert!(s.contains("non-finite 0"), "{s}");
    assert!(s.contains("format     PCD"), "{s}");
    assert!(s.contains("fields     x y z"), "{s}");
}

#[test]
fn info_json_on_the_organized_mug_scan() {
    let Some(f) = data("pcl/table_scene_mug_stereo_textured.pcd") else {
        return;
    };
    let o = nbhd(&["info", "--json", &f]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON document");
    assert_eq!(v["points"], 307_200);
    assert_eq!(v["non_finite"], 97_920);
    assert_eq!(v["organized"]["width"], 640);
    assert_eq!(v["organized"]["height"], 480);
    assert_eq!(v["fields"], serde_json::json!(["x", "y", "z", "rgba"]));
    assert!(v["bbox"]["diagonal"].as_f64().unwrap() > 0.0);
}

#[test]
fn quiet_prints_nothing() {
    let Some(f) = data("meshes/fandisk.obj") else {
        return;
    };
    let o = nbhd(&["--quiet", "info", &f]);
    assert!(o.status.success());
    assert_eq!(stdout(&o), "");
}

#[test]
fn convert_keeps_points_and_fields() {
    let Some(f) = data("pcl/cturtle.pcd") else {
        return;
    };
    let ply = tmp("cturtle.ply");
    let o = nbhd(&[
        "convert",
        &f,
        &ply,
        "--encoding",
        "ascii",
        "--precision",
        "single",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("167198 points (PCD -> PLY)"),
        "{}",
        stdout(&o)
    );
    let head = std::fs::read_to_string(&ply).unwrap();
    assert!(head.contains("property float intensity"));
    let o = nbhd(&["info", "--json", &ply]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["points"], 167_198);
    assert_eq!(v["format"], "PLY");
    assert_eq!(v["fields"], serde_json::json!(["x", "y", "z", "intensity"]));

    // Back to compressed PCD and again: the same cloud.
    let pcd = tmp("cturtle.pcd");
    let o = nbhd(&["--json", "convert", &ply, &pcd, "-e", "compressed"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["to"], "PCD");
    let o = nbhd(&["info", &pcd]);
    assert!(stdout(&o).contains("points     167198"));
}

#[test]
fn render_writes_a_png() {
    let Some(f) = data("pcl/bunny.pcd") else {
        return;
    };
    let png = tmp("bunny.png");
    let o = nbhd(&[
        "render", &f, &png, "--width", "120", "--height", "90", "--color", "y", "--view", "0,0,-1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"));
    let o = nbhd(&["render", &f, &png, "--color", "curvature"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("no scalar field 'curvature'"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn errors_name_the_file_and_place() {
    let bad = tmp("bad.xyz");
    std::fs::write(&bad, "1 2 3\n4 5 six\n").unwrap();
    let o = nbhd(&["info", &bad]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("bad.xyz: line 2: 'six' is not a number"), "{e}");

    let o = nbhd(&["info", &tmp("missing.ply")]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.ply"));

    let o = nbhd(&["convert", &bad, &tmp("out.stl")]);
    assert!(!o.status.success());
}

#[test]
fn help_explains_the_terms() {
    let o = nbhd(&["--help"]);
    assert!(o.status.success());
    let s = stdout(&o);
    for term in [
        "influence radius",
        "maximum valence",
        "info",
        "convert",
        "--json",
        "--quiet",
    ] {
        assert!(s.contains(term), "--help lacks '{term}':\n{s}");
    }
    let o = nbhd(&["convert", "--help"]);
    assert!(stdout(&o).contains("binary-compressed") || stdout(&o).contains("compressed"));
}
