//! The `nbhd` binary as a person runs it.

use nbhd::NeighborIndex;
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

/// A file of the repository's `tests/data` (see its README). The data is part of the repository,
/// so a missing file is a broken checkout and fails the test rather than skipping it. (The
/// `Option` stays so that tests written against the old optional data keep compiling.)
fn data(rel: &str) -> Option<String> {
    let f = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(rel);
    assert!(
        f.is_file(),
        "{} is missing: the test data belongs to the repository",
        f.display()
    );
    Some(f.display().to_string())
}

fn tmp(name: &str) -> String {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-cli-test-{}", std::process::id()));
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

// ---- the demo ----------------------------------------------------------------------------

fn json_of(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

/// Decodes a PNG file and returns (width, height, RGB bytes).
fn read_png(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Share of the pixels that are not the white background.
fn covered(rgb: &[u8]) -> f64 {
    let px = rgb.chunks(3);
    let n = px.len() as f64;
    px.filter(|c| *c != [255, 255, 255]).count() as f64 / n
}

#[test]
fn demo_writes_files_pictures_and_a_summary_where_smoothing_reduces_the_error() {
    let dir = PathBuf::from(tmp("demo"));
    let _ = std::fs::remove_dir_all(&dir);
    let o = nbhd(&[
        "--json",
        "demo",
        "--points",
        "3000",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let v = json_of(&o);
    assert_eq!(v["points_per_shape"], 3000);
    let shapes = v["shapes"].as_array().unwrap();
    let names: Vec<&str> = shapes
        .iter()
        .map(|s| s["shape"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["cube", "torus", "cylinder+plane"]);
    for s in shapes {
        let name = s["shape"].as_str().unwrap();
        // Every pivot policy, with its statistics, and the same ε-k table from each.
        let trees = s["trees"].as_array().unwrap();
        assert_eq!(trees.len(), 4, "{name}");
        for t in trees {
            assert!(t["depth"].as_u64().unwrap() >= 8, "{name}: {t}");
            assert!(t["leaves"].as_u64().unwrap() * 12 >= 3000, "{name}: {t}");
            assert!(t["bytes"].as_u64().unwrap() > 3000 * 28, "{name}: {t}");
        }
        assert_eq!(s["tables_identical"], true, "{name}");
        assert_eq!(s["neighbors"]["max"], 15, "{name}");
        // RMS distance to the true surface: 0.5h of noise, less after either smoothing.
        let rms = |i: usize| s["runs"][i]["quality"]["rms_h"].as_f64().unwrap();
        assert!((rms(0) - 0.5).abs() < 0.05, "{name}: noisy RMS {}", rms(0));
        assert!(rms(1) < 0.7 * rms(0), "{name}: isotropic RMS {}", rms(1));
        assert!(rms(2) < 0.8 * rms(0), "{name}: anisotropic RMS {}", rms(2));
        assert_eq!(s["runs"][3]["stage"], "robust", "{name}");
        assert!(
            rms(3) < rms(1).min(rms(2)),
            "{name}: robust RMS {} vs {} / {}",
            rms(3),
            rms(1),
            rms(2)
        );
        if name == "cube" {
            // The anisotropic flow keeps the edges better than the isotropic one.
            let edge = |i: usize| s["runs"][i]["quality"]["edge_rms_h"].as_f64().unwrap();
            assert!(
                edge(2) < edge(1),
                "{name}: edge RMS {} vs {}",
                edge(2),
                edge(1)
            );
        }
        for run in s["runs"].as_array().unwrap() {
            let ply = dir.join(run["ply"].as_str().unwrap());
            let cloud = nbhd::io::read(&ply).unwrap();
            assert_eq!(cloud.len(), 3000, "{}", ply.display());
            assert!(cloud.normals.is_some(), "{}", ply.display());
            for f in ["curvature", "mean_curvature", "max_abs_curvature"] {
                let values = cloud.scalar(f).unwrap();
                assert!(values.iter().all(|x| x.is_finite()), "{f}");
            }
            let (w, h, rgb) = read_png(&dir.join(run["png"].as_str().unwrap()));
            assert_eq!((w, h), (640, 480));
            let c = covered(&rgb);
            assert!(c > 0.15 && c < 0.9, "{}: coverage {c}", run["png"]);
        }
    }
    let (w, h, _) = read_png(&dir.join("overview.png"));
    assert_eq!((w, h), (4 * 640, 3 * 480));
    let md = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(md.contains("| cube "), "{md}");
}

#[test]
fn nbhd_without_a_command_runs_the_demo_and_prints_the_summary() {
    let dir = tmp("demo-default");
    let o = nbhd(&["--points", "1000", "--out", &dir]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    for want in [
        "cyclic-median",
        "spread-median",
        "closest-to-middle",
        "sliding-midpoint",
        "identical for all four trees",
        "| shape ",
        "| cube ",
        "| torus ",
        "| cylinder+plane ",
        "overview.png",
        "done in",
    ] {
        assert!(s.contains(want), "no '{want}' in:\n{s}");
    }
    // The summary rows of the cube: noisy, isotropic, anisotropic, robust; the RMS (first
    // number of a row) smaller after each smoothing, smallest after the robust one.
    let rms: Vec<f64> = s
        .lines()
        .filter(|l| l.starts_with("| cube"))
        .map(|row| {
            row.split('|')
                .filter_map(|c| c.trim().parse::<f64>().ok())
                .next()
                .unwrap()
        })
        .collect();
    assert_eq!(rms.len(), 4, "{s}");
    assert!(rms[1..].iter().all(|&r| r < rms[0]), "{rms:?}");
    assert!(rms[3] < rms[1].min(rms[2]), "{rms:?}");
    assert!(std::path::Path::new(&dir)
        .join("cube-anisotropic.png")
        .is_file());
    // Demo options belong to the demo.
    let o = nbhd(&["--points", "1000", "info", "x.ply"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--points is an option of the demo"),
        "{}",
        stderr(&o)
    );
}

// ---- neighbourhoods against brute force -----------------------------------------------------

use nbhd::{
    BruteForce, BuildOptions, KdTree, NeighborSearch, Neighborhood, NonFinitePolicy, PointsView,
    Query, QueryOptions, TableOptions,
};

/// 400 points of a noisy sphere, 40 of them duplicates, one NaN point (index 17); written as
/// XYZ text with every digit.
fn sphere_file(name: &str) -> (String, Vec<[f64; 3]>) {
    let s = nbhd::shapes::sample(&nbhd::shapes::Sphere::new(1.0), 400, 5);
    let mut pts: Vec<[f64; 3]> = s.points.iter().map(|p| p.to_array()).collect();
    for i in 0..40 {
        pts[360 + i] = pts[3 * i];
    }
    pts[17] = [f64::NAN; 3];
    let path = tmp(name);
    let cloud = nbhd::io::PointCloud::from_positions(pts.clone());
    // Every digit: the brute-force answers are computed on these f64 points.
    let double = nbhd::io::WriteOptions {
        precision: nbhd::io::Precision::Double,
        ..nbhd::io::WriteOptions::ascii()
    };
    nbhd::io::write(&path, &cloud, &double).unwrap();
    (path, pts)
}

fn brute(pts: &[[f64; 3]]) -> BruteForce<f64> {
    BruteForce::new(&PointsView::from_rows(pts).unwrap(), NonFinitePolicy::Skip).unwrap()
}

/// Rows of a `--json` neighbourhood document.
fn rows(v: &serde_json::Value) -> Vec<(Vec<u32>, Vec<f64>)> {
    v["neighbors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let i = r["indices"].as_array().unwrap();
            let d = r["sq_dists"].as_array().unwrap();
            (
                i.iter().map(|x| x.as_u64().unwrap() as u32).collect(),
                d.iter().map(|x| x.as_f64().unwrap()).collect(),
            )
        })
        .collect()
}

fn expect_brute(
    bf: &BruteForce<f64>,
    got: &[(Vec<u32>, Vec<f64>)],
    nbhd: Neighborhood<f64>,
    exclude_self: bool,
    what: &str,
) {
    expect_brute_with(bf, got, nbhd, &QueryOptions::default(), exclude_self, what);
}

fn expect_brute_with(
    bf: &BruteForce<f64>,
    got: &[(Vec<u32>, Vec<f64>)],
    nbhd: Neighborhood<f64>,
    options: &QueryOptions,
    exclude_self: bool,
    what: &str,
) {
    assert_eq!(got.len(), 400, "{what}");
    let mut want = Vec::new();
    for (i, (idx, d)) in got.iter().enumerate() {
        if i == 17 {
            assert!(idx.is_empty(), "{what}: the NaN point has an empty row");
            continue;
        }
        let q = Query::Stored {
            index: i as u32,
            exclude_self,
        };
        bf.search_with(q, nbhd, options, &mut want).unwrap();
        let wi: Vec<u32> = want.iter().map(|n| n.index).collect();
        let wd: Vec<f64> = want.iter().map(|n| n.sq_dist).collect();
        assert_eq!(idx, &wi, "{what}: row {i}");
        assert_eq!(d, &wd, "{what}: row {i}");
    }
}

#[test]
fn knn_radius_and_neighbors_equal_brute_force_for_every_tree_variant() {
    let (file, pts) = sphere_file("sphere.xyz");
    let bf = brute(&pts);
    let variants: [&[&str]; 4] = [
        &[],
        &[
            "--pivot",
            "cyclic-median",
            "--median",
            "presorted",
            "--leaf-size",
            "1",
        ],
        &[
            "--pivot",
            "spread-median",
            "--median",
            "median-of-medians",
            "--leaf-size",
            "3",
        ],
        &["--pivot", "closest-to-middle", "--median", "quickselect"],
    ];
    for tree in variants {
        for exclude in [false, true] {
            let mut cases: Vec<(Vec<&str>, Neighborhood<f64>)> = vec![
                (vec!["knn", "-k", "7"], Neighborhood::Knn { k: 7 }),
                (
                    vec!["radius", "--radius", "0.2"],
                    Neighborhood::Radius {
                        radius: 0.2,
                        sorted: true,
                    },
                ),
                (
                    vec!["neighbors", "-k", "5", "-r", "0.15"],
                    Neighborhood::KnnRadius { k: 5, radius: 0.15 },
                ),
            ];
            for (args, nb) in cases.drain(..) {
                let mut a = vec!["--json"];
                a.extend(&args);
                a.push(&file);
                a.extend(tree);
                if exclude {
                    a.push("--exclude-self");
                }
                let v = json_of(&nbhd(&a));
                assert_eq!(v["skipped_non_finite"], 1);
                expect_brute(&bf, &rows(&v), nb, exclude, &a.join(" "));
            }
        }
    }
}

/// `--boxsize`: the rows of the library's periodic tree (every point at its nearest image), on
/// a grid of step 1/4 in a unit box periodic in x and y and open in z; points outside the box
/// are refused by name.
#[test]
fn periodic_boxes_give_the_periodic_trees_rows() {
    let mut pts = Vec::new();
    for i in 0..120u32 {
        let c = |s: u32| f64::from((i.wrapping_mul(2_654_435_761) >> s) % 4) * 0.25;
        pts.push([c(3), c(11), c(19) * 3.0]);
    }
    let path = tmp("periodic-grid.xyz");
    let cloud = nbhd::io::PointCloud::from_positions(pts.clone());
    nbhd::io::write(&path, &cloud, &nbhd::io::WriteOptions::ascii()).unwrap();
    let view = PointsView::from_rows(&pts).unwrap();
    let tree = KdTree::build_periodic(&view, &BuildOptions::default(), &[1.0, 1.0, 0.0]).unwrap();
    for (args, nb) in [
        (&["knn", "-k", "6"][..], Neighborhood::Knn { k: 6 }),
        (
            &["radius", "-r", "0.6"][..],
            Neighborhood::Radius {
                radius: 0.6,
                sorted: true,
            },
        ),
    ] {
        let mut a = vec!["--json"];
        a.extend(args);
        a.extend([
            path.as_str(),
            "--boxsize",
            "1,1,0",
            "--metric",
            "l1",
            "--exclude-self",
        ]);
        let v = json_of(&nbhd(&a));
        assert_eq!(v["boxsize"], serde_json::json!([1.0, 1.0, 0.0]));
        let options = TableOptions {
            exclude_self: true,
            query: QueryOptions::with_p(1.0).unwrap(),
            ..TableOptions::default()
        };
        let want = tree.neighborhoods(nb, &options).unwrap();
        let got = rows(&v);
        assert_eq!(got.len(), pts.len());
        for (i, (idx, d)) in got.iter().enumerate() {
            assert_eq!(idx.as_slice(), want.indices_of(i), "{a:?} row {i}");
            assert_eq!(d.as_slice(), want.sq_dists_of(i), "{a:?} row {i}");
        }
    }
    let o = nbhd(&["knn", "-k", "2", &path, "--boxsize", "0.5"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("outside the periodic box"),
        "{}",
        stderr(&o)
    );
}

/// `--metric`, `--strict` and `--eps`: the library's answers under those query options.
#[test]
fn metrics_and_strict_radii_equal_brute_force() {
    let (file, pts) = sphere_file("sphere-metric.xyz");
    let bf = brute(&pts);
    for (metric, strict) in [
        ("l1", false),
        ("linf", true),
        ("p=3", false),
        ("p=1.5", true),
    ] {
        let options = QueryOptions {
            metric: metric.parse().unwrap(),
            strict,
            ..QueryOptions::default()
        };
        let cases: [(&[&str], Neighborhood<f64>); 2] = [
            (&["knn", "-k", "6"], Neighborhood::Knn { k: 6 }),
            (
                &["neighbors", "-k", "5", "-r", "0.2"],
                Neighborhood::KnnRadius { k: 5, radius: 0.2 },
            ),
        ];
        for (args, nb) in cases {
            let mut a = vec!["--json"];
            a.extend(args);
            a.extend([file.as_str(), "--metric", metric, "--exclude-self"]);
            if strict {
                a.push("--strict");
            }
            let v = json_of(&nbhd(&a));
            assert_eq!(v["metric"], metric);
            expect_brute_with(&bf, &rows(&v), nb, &options, true, &a.join(" "));
        }
    }
    // an approximate search keeps its guarantee; a bad metric or eps is refused by name
    let v = json_of(&nbhd(&["--json", "knn", "-k", "4", &file, "--eps", "0.5"]));
    let mut want = Vec::new();
    for (i, (_, d2)) in rows(&v).iter().enumerate().filter(|(i, _)| *i != 17) {
        bf.search(
            Query::stored(i as u32),
            Neighborhood::Knn { k: 4 },
            &mut want,
        )
        .unwrap();
        assert_eq!(d2.len(), 4);
        for (g, w) in d2.iter().zip(&want) {
            assert!(
                g.sqrt() <= 1.5 * w.sq_dist.sqrt() * (1.0 + 1e-12),
                "row {i}"
            );
        }
    }
    for (bad, want) in [(["--metric", "p=0.5"], "p"), (["--eps", "-1"], "eps")] {
        let o = nbhd(&["knn", "-k", "4", &file, bad[0], bad[1]]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains(want), "{bad:?}: {}", stderr(&o));
    }
}

#[test]
fn neighbour_files_csv_and_json_and_query_files() {
    let (file, pts) = sphere_file("sphere2.xyz");
    let bf = brute(&pts);
    // CSV file: query,rank,index,sq_dist, the same numbers as brute force.
    let csv = tmp("nb.csv");
    let o = nbhd(&["knn", &file, "-k", "4", "--exclude-self", "-o", &csv]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("wrote"), "{}", stdout(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("query,rank,index,sq_dist"));
    let mut got = vec![(Vec::new(), Vec::new()); 400];
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        let q: usize = f[0].parse().unwrap();
        assert_eq!(f[1].parse::<usize>().unwrap(), got[q].0.len());
        got[q].0.push(f[2].parse::<u32>().unwrap());
        got[q].1.push(f[3].parse::<f64>().unwrap());
    }
    expect_brute(&bf, &got, Neighborhood::Knn { k: 4 }, true, "csv");
    // The same table on standard output, the summary on standard error.
    let o = nbhd(&["knn", &file, "-k", "4", "--exclude-self"]);
    assert_eq!(stdout(&o), text);
    assert!(stderr(&o).contains("knn of 400 queries"), "{}", stderr(&o));
    // A .json file holds the document.
    let js = tmp("nb.json");
    let o = nbhd(&["radius", &file, "-r", "0.25", "-o", &js]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&js).unwrap()).unwrap();
    let nb = Neighborhood::Radius {
        radius: 0.25,
        sorted: true,
    };
    expect_brute(&bf, &rows(&v), nb, false, "json file");
    // A radius in units of h: h is the mean nearest-neighbour distance of the finite points.
    let v = json_of(&nbhd(&[
        "--json",
        "neighbors",
        &file,
        "-k",
        "6",
        "-r",
        "2.5h",
    ]));
    let h = v["spacing_h"].as_f64().unwrap();
    let mut row = Vec::new();
    let (mut sum, mut count) = (0.0, 0);
    for i in 0..400u32 {
        if bf
            .search(
                Query::stored_excluding_self(i),
                Neighborhood::Knn { k: 1 },
                &mut row,
            )
            .is_ok()
        {
            sum += row[0].sq_dist.sqrt();
            count += 1;
        }
    }
    assert!((h - sum / count as f64).abs() < 1e-12 * h, "{h}");
    assert_eq!(v["radius"].as_f64().unwrap(), 2.5 * h);
    let nb = Neighborhood::KnnRadius {
        k: 6,
        radius: 2.5 * h,
    };
    expect_brute(&bf, &rows(&v), nb, false, "2.5h");
    // Queries from another file: arbitrary points.
    let qs: Vec<[f64; 3]> = vec![[0.0, 0.0, 0.0], [1.0, 0.2, -0.1], [0.3, -0.9, 0.5]];
    let qfile = tmp("queries.xyz");
    nbhd::io::write(
        &qfile,
        &nbhd::io::PointCloud::from_positions(qs.clone()),
        &nbhd::io::WriteOptions::ascii(),
    )
    .unwrap();
    let v = json_of(&nbhd(&[
        "--json",
        "knn",
        &file,
        "-k",
        "9",
        "--queries",
        &qfile,
    ]));
    let got = rows(&v);
    assert_eq!(got.len(), 3);
    for (q, (idx, d)) in qs.iter().zip(&got) {
        bf.search(Query::point(q), Neighborhood::Knn { k: 9 }, &mut row)
            .unwrap();
        assert_eq!(idx, &row.iter().map(|n| n.index).collect::<Vec<_>>());
        assert_eq!(d, &row.iter().map(|n| n.sq_dist).collect::<Vec<_>>());
    }
}

// ---- normals, curvature, smoothing ------------------------------------------------------

use glam::DVec3;
use nbhd::smooth::{Curvature, Length, SmoothOptions};

/// A noisy sphere of radius 1 (2000 points, 0.5h Gaussian noise), as PLY, and its points.
fn noisy_sphere_file(name: &str) -> (String, Vec<DVec3>) {
    let ns = nbhd::shapes::noisy_sample(
        &nbhd::shapes::Sphere::new(1.0),
        2000,
        0.5,
        nbhd::shapes::NoiseKind::Gaussian,
        9,
    )
    .unwrap();
    let path = tmp(name);
    let cloud =
        nbhd::io::PointCloud::from_positions(ns.points.iter().map(|p| p.to_array()).collect());
    let double = nbhd::io::WriteOptions {
        precision: nbhd::io::Precision::Double,
        ..Default::default()
    };
    nbhd::io::write(&path, &cloud, &double).unwrap();
    (path, ns.points)
}

#[test]
fn normals_and_curvature_match_the_library_and_point_outward() {
    let (file, pts) = noisy_sphere_file("nsphere.ply");
    let out = tmp("nsphere-curv.ply");
    let png = tmp("nsphere-curv.png");
    let o = nbhd(&[
        "curvature",
        &file,
        &out,
        "-k",
        "12",
        "-r",
        "5h",
        "--png",
        &png,
        "--precision",
        "keep",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("(float64)"), "{}", stdout(&o));
    let cloud = nbhd::io::read(&out).unwrap();
    assert_eq!(
        cloud.field_names(),
        [
            "x",
            "y",
            "z",
            "nx",
            "ny",
            "nz",
            "curvature",
            "k1",
            "k2",
            "mean_curvature",
            "max_abs_curvature"
        ]
    );
    let lib = nbhd::smooth::analyze(
        &pts,
        &SmoothOptions {
            k: 12,
            epsilon: Length::Relative(5.0),
            orientation: nbhd::geometry::Orientation::Propagate,
            ..SmoothOptions::default()
        },
    )
    .unwrap();
    let normals = cloud.normals.as_ref().unwrap();
    for (i, o) in lib.outputs.iter().enumerate() {
        assert_eq!(normals[i], o.normal.to_array(), "normal {i}");
        assert_eq!(cloud.scalar("k1").unwrap()[i], o.principal.k1);
        // curvature is PCL's: the surface variation.
        assert_eq!(cloud.scalar("curvature").unwrap()[i], o.covariance_quotient);
        assert_eq!(
            cloud.scalar("max_abs_curvature").unwrap()[i],
            o.max_principal_curvature
        );
        // Propagated orientation is outward on a sphere.
        assert!(o.normal.dot(pts[i]) > 0.5, "normal {i} points inward");
    }
    // Mean curvature about 1/R with outward normals on the unit sphere (curvatures are
    // signed against the normal: negative).
    let mean: f64 = cloud.scalar("mean_curvature").unwrap().iter().sum::<f64>() / 2000.0;
    assert!((mean + 1.0).abs() < 0.35, "mean curvature {mean}");
    let (w, h, _) = read_png(std::path::Path::new(&png));
    assert_eq!((w, h), (800, 600));

    // normals: normals and the surface variation as PCL's curvature, float32 by default
    // (what pcl::PointNormal loads).
    let out = tmp("nsphere-normals.pcd");
    let o = nbhd(&["--json", "normals", &file, &out, "--orient", "none"]);
    let v = json_of(&o);
    assert_eq!(v["points"], 2000);
    assert_eq!(v["precision"], "float32");
    let cloud = nbhd::io::read(&out).unwrap();
    assert_eq!(
        cloud.field_names(),
        ["x", "y", "z", "nx", "ny", "nz", "curvature"]
    );
    let head = std::fs::read(&out).unwrap();
    let fields = b"FIELDS x y z normal_x normal_y normal_z curvature\nSIZE 4 4 4 4 4 4 4\n\
TYPE F F F F F F F\n";
    assert!(head.windows(fields.len()).any(|w| w == fields));
}

#[test]
fn smooth_matches_the_library_and_brings_points_closer_to_the_surface() {
    let (file, pts) = noisy_sphere_file("nsphere-s.ply");
    let dist = |p: &[f64; 3]| (DVec3::from_array(*p).length() - 1.0).powi(2);
    let rms = |c: &[[f64; 3]]| (c.iter().map(dist).sum::<f64>() / c.len() as f64).sqrt();
    let before = rms(&pts.iter().map(|p| p.to_array()).collect::<Vec<_>>());
    for (args, opts) in [
        (
            vec!["--method", "isotropic"],
            SmoothOptions {
                orientation: nbhd::geometry::Orientation::Propagate,
                ..SmoothOptions::isotropic()
            },
        ),
        (
            vec![
                "--method",
                "anisotropic",
                "--lambda",
                "0.3/h",
                "--weighting",
                "cont",
                "--criterion",
                "directional",
                "--feature-curvature",
                "0.4/h",
                "--steps",
                "4",
                "--tau",
                "0.4",
                "-k",
                "12",
                "--radius",
                "5h",
            ],
            SmoothOptions {
                lambda: Curvature::Relative(0.3),
                weighting: nbhd::smooth::Weighting::Continuous,
                feature: nbhd::smooth::FeatureCriterion::DirectionalCurvature(Curvature::Relative(
                    0.4,
                )),
                steps: 4,
                tau: 0.4,
                k: 12,
                epsilon: Length::Relative(5.0),
                orientation: nbhd::geometry::Orientation::Propagate,
                ..SmoothOptions::default()
            },
        ),
        (
            vec![
                "-m",
                "anisotropic",
                "--criterion",
                "q",
                "--quotient",
                "0.4",
                "--update-neighbors",
            ],
            SmoothOptions {
                feature: nbhd::smooth::FeatureCriterion::EdgeQuotient(0.4),
                update_neighbors: true,
                orientation: nbhd::geometry::Orientation::Propagate,
                ..SmoothOptions::default()
            },
        ),
    ] {
        let out = tmp("nsphere-smooth.ply");
        let png = tmp("nsphere-smooth.png");
        let mut a = vec![
            "--json",
            "smooth",
            &file,
            &out,
            "--png",
            &png,
            "--precision",
            "keep",
        ];
        a.extend(&args);
        let v = json_of(&nbhd(&a));
        let lib = nbhd::smooth::smooth(&pts, &opts).unwrap();
        let cloud = nbhd::io::read(&out).unwrap();
        let want: Vec<[f64; 3]> = lib.points.iter().map(|p| p.to_array()).collect();
        assert_eq!(cloud.positions, want, "{args:?}");
        assert_eq!(v["steps"], opts.steps as u64);
        let after = rms(&cloud.positions);
        assert!(after < 0.8 * before, "{args:?}: RMS {after} vs {before}");
        assert!(read_png(std::path::Path::new(&png)).0 == 800);
    }
}

#[test]
fn robust_smoothing_is_the_default_and_matches_the_library() {
    use nbhd::smooth::robust::{smooth_robust, RobustOptions};
    let (file, pts) = noisy_sphere_file("nsphere-r.ply");
    let dist = |p: &[f64; 3]| (DVec3::from_array(*p).length() - 1.0).powi(2);
    let rms = |c: &[[f64; 3]]| (c.iter().map(dist).sum::<f64>() / c.len() as f64).sqrt();
    let before = rms(&pts.iter().map(|p| p.to_array()).collect::<Vec<_>>());
    for (args, opts) in [
        (
            vec![],
            RobustOptions {
                orientation: nbhd::geometry::Orientation::Propagate,
                ..RobustOptions::default()
            },
        ),
        (
            vec![
                "--method",
                "robust",
                "-k",
                "16",
                "--k-plane",
                "32",
                "--radius",
                "10h",
                "--iterations",
                "3",
                "--tolerance",
                "0",
                "--inlier-width",
                "4",
                "--feature-angle",
                "30",
                "--tau",
                "0.8",
                "--noise-scale",
                "false",
                "--orient",
                "none",
            ],
            RobustOptions {
                k: 16,
                k_plane: 32,
                epsilon: Length::Relative(10.0),
                max_iterations: 3,
                tolerance: 0.0,
                inlier_width: 4.0,
                feature_angle: 30.0,
                tau: 0.8,
                noise_scale: false,
                ..RobustOptions::default()
            },
        ),
    ] {
        let out = tmp("nsphere-robust.ply");
        // the input holds doubles: keep them, to compare with the library bit for bit
        let mut a = vec!["--json", "smooth", &file, &out, "--precision", "keep"];
        a.extend(&args);
        let v = json_of(&nbhd(&a));
        assert_eq!(v["method"], "robust");
        let lib = smooth_robust(&pts, &opts).unwrap();
        let cloud = nbhd::io::read(&out).unwrap();
        let want: Vec<[f64; 3]> = lib.points.iter().map(|p| p.to_array()).collect();
        assert_eq!(cloud.positions, want, "{args:?}");
        assert_eq!(v["k"], opts.k as u64);
        assert_eq!(v["k_plane"], opts.k_plane as u64);
        assert_eq!(v["noise_scale"], opts.noise_scale);
        assert!(v["iterations"].as_u64().unwrap() <= opts.max_iterations as u64);
        let after = rms(&cloud.positions);
        assert!(after < 0.5 * before, "{args:?}: RMS {after} vs {before}");
    }
    // options of the other method are refused, naming the option
    let out = tmp("nsphere-robust-bad.ply");
    for (args, name) in [
        (vec!["--lambda", "0.2/h"], "--lambda"),
        (vec!["--steps", "3"], "--steps"),
        (vec!["-m", "anisotropic", "--k-plane", "30"], "--k-plane"),
        (
            vec!["-m", "isotropic", "--noise-scale", "false"],
            "--noise-scale",
        ),
        (
            vec!["-m", "isotropic", "--weighting", "cont"],
            "--weighting",
        ),
    ] {
        let mut a = vec!["smooth", &file, &out];
        a.extend(&args);
        let o = nbhd(&a);
        assert!(!o.status.success(), "{args:?}");
        assert!(stderr(&o).contains(name), "{args:?}: {}", stderr(&o));
    }
}

/// The robust run's report: "1 iteration" in the singular, the extra noise estimate (the one
/// that stopped the iterations) said as such, and the noise scale's line.
#[test]
fn robust_report_counts_iterations_and_estimates() {
    let (file, _) = noisy_sphere_file("nsphere-report.ply");
    let out = tmp("nsphere-report-out.ply");
    let o = nbhd(&["smooth", &file, &out, "--iterations", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("1 iteration (at most 1"), "{text}");
    assert!(!text.contains("1 iterations"), "{text}");
    assert!(text.contains("noise scale: local dimension"), "{text}");
    let o = nbhd(&["smooth", &file, &out]);
    let text = stdout(&o);
    assert!(
        text.contains("(the last one, on the result, stopped the iterations)"),
        "{text}"
    );
}

#[test]
fn nan_points_keep_their_place_through_smoothing() {
    let (file, pts) = sphere_file("sphere-nan.xyz");
    let out = tmp("sphere-nan-smooth.xyz");
    let o = nbhd(&["smooth", &file, &out, "--method", "isotropic"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("(1 skipped as non-finite)"),
        "{}",
        stdout(&o)
    );
    let cloud = nbhd::io::read(&out).unwrap();
    assert_eq!(cloud.len(), pts.len());
    assert!(cloud.positions[17].iter().all(|c| c.is_nan()));
    assert!(cloud.positions[18].iter().all(|c| c.is_finite()));
}

// ---- errors ------------------------------------------------------------------------------

#[test]
fn bad_arguments_and_missing_files_are_reported() {
    let (file, _) = sphere_file("sphere-err.xyz");
    let missing = tmp("no-such-file.ply");
    let out = tmp("err-out.ply");
    for (args, want) in [
        (vec!["knn", &missing, "-k", "3"], "no-such-file.ply"),
        (vec!["radius", &missing, "-r", "1"], "no-such-file.ply"),
        (vec!["smooth", &missing, &out], "no-such-file.ply"),
        (vec!["curvature", &missing, &out], "no-such-file.ply"),
        (vec!["knn", &file, "-k", "0"], "k must be at least 1"),
        (
            vec!["neighbors", &file, "-k", "-2", "-r", "1"],
            "k must be at least 1",
        ),
        (
            vec!["radius", &file, "-r", "-1"],
            "radius -1 is not a finite number >= 0",
        ),
        (
            vec!["neighbors", &file, "-k", "3", "--radius=-0.5h"],
            "radius",
        ),
        (
            vec!["radius", &file, "-r", "wide"],
            "'wide' is not a length",
        ),
        (
            vec!["smooth", &file, &out, "--lambda", "x/h"],
            "'x/h' is not a curvature",
        ),
        (
            vec!["smooth", &file, &out, "-k", "0"],
            "k must be at least 1",
        ),
        (vec!["smooth", &file, &out, "--tau", "-1"], "tau"),
        (vec!["normals", &file, &out, "--radius", "0"], "epsilon"),
        (
            vec!["knn", &file, "-k", "2", "--leaf-size", "0"],
            "leaf_size",
        ),
        (
            vec![
                "knn",
                &file,
                "-k",
                "2",
                "--exclude-self",
                "--queries",
                &file,
            ],
            "--queries",
        ),
        (
            vec!["knn", &file, "-k", "2", "-o", "/nonexistent-dir/x.csv"],
            "/nonexistent-dir/x.csv",
        ),
        (
            vec!["smooth", &file, "/nonexistent-dir/x.ply"],
            "/nonexistent-dir/x.ply",
        ),
        (vec!["demo", "--points", "10"], "--points 10 is too few"),
    ] {
        let o = nbhd(&args);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(
            stderr(&o).contains(want),
            "{args:?}: '{}' lacks '{want}'",
            stderr(&o)
        );
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
}

// ---- the thesis benchmark ----------------------------------------------------------------

#[test]
fn bench_thesis_quick_writes_the_report_plots_and_checks() {
    let dir = PathBuf::from(tmp("bench"));
    let o = nbhd(&[
        "--json",
        "bench",
        "thesis",
        "--quick",
        "--repeats",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let v = json_of(&o);
    // Build times and depths of every variant on the three geometries.
    let build = v["build"].as_array().unwrap();
    assert_eq!(build.len(), 3);
    for g in build {
        let variants = g["variants"].as_array().unwrap();
        assert_eq!(variants.len(), 8);
        for var in variants {
            assert!(var["ms"][0].as_f64().unwrap() > 0.0, "{var}");
            let depth = var["depth"][0].as_u64().unwrap();
            // 4,851 to 5,249 points, one per leaf: balanced depth 13.
            if var["variant"].as_str().unwrap().starts_with("Median") || var["variant"] == "Sorting"
            {
                assert_eq!(depth, 13, "{var}");
            } else {
                assert!(depth >= 13, "{var}");
            }
        }
    }
    // The identical-tree property of Section 8.1 holds (it is checked, not assumed).
    let checks = v["checks"].as_array().unwrap();
    let identical: Vec<_> = checks
        .iter()
        .filter(|c| c["claim"].as_str().unwrap().contains("identical tree"))
        .collect();
    assert_eq!(identical.len(), 3);
    assert!(
        identical.iter().all(|c| c["holds"] == true),
        "{identical:?}"
    );
    // Brute force scans every point for every query: slower than the tree at k = 1.
    let knn = v["kd_vs_pca_knn"].as_array().unwrap();
    assert_eq!(knn[0]["label"], "kd-tree (Sorting)");
    assert_eq!(knn[2]["label"], "brute force");
    assert!(knn[0]["ms"][0].as_f64().unwrap() < knn[2]["ms"][0].as_f64().unwrap());
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for want in [
        "Fig. 8.8",
        "Fig. 8.9",
        "Fig. 8.13",
        "thesis ms",
        "conclusions",
    ] {
        assert!(report.contains(want), "report lacks {want}");
    }
    for svg in [
        "build-costa.svg",
        "build-cylinder.svg",
        "build-torus.svg",
        "fig8.9-knn.svg",
        "fig8.10-radius.svg",
        "fig8.11-cylinder-knn.svg",
        "fig8.12-costa-knn.svg",
        "fig8.13-torus-radius.svg",
    ] {
        let s = std::fs::read_to_string(dir.join(svg)).unwrap();
        assert!(
            s.starts_with("<svg") && s.trim_end().ends_with("</svg>"),
            "{svg}"
        );
        assert!(
            s.contains("<polyline") || s.contains("<path"),
            "{svg} has no curve"
        );
        assert!(report.contains(svg), "report does not show {svg}");
    }
    assert!(dir.join("results.json").is_file());
}

#[test]
fn an_absurd_thread_count_is_refused_at_once() {
    let start = std::time::Instant::now();
    let o = nbhd(&["--threads", "100000", "info", "x.pcd"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("--threads 100000 is above the maximum of 1024"),
        "{e}"
    );
    // Refused before any thread is made, not after spawning until failure.
    assert!(start.elapsed() < std::time::Duration::from_secs(10));
}

/// Issue 13, items 5 and 6: text columns are said, `--columns` overrides, LAS in and out.
#[test]
fn text_columns_are_reported_and_las_converts() {
    let txt = tmp("colours.txt");
    std::fs::write(&txt, "1 2 3 255 0 0\n2 2 3 0 255 0\n3 1 0 0 0 255\n").unwrap();
    let o = nbhd(&["info", &txt]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("read as    columns x y z red green blue (no header: columns 4-6"),
        "{}",
        stdout(&o)
    );
    let v = json_of(&nbhd(&[
        "--json",
        "info",
        &txt,
        "--columns",
        "x,y,z,nx,ny,nz",
    ]));
    assert_eq!(v["columns"]["from"], "the column names given");
    assert_eq!(v["normals"], true);

    // XYZ -> LAZ -> PLY: the colour survives, and what LAS cannot hold is named.
    let laz = tmp("colours.laz");
    let v = json_of(&nbhd(&["--json", "convert", &txt, &laz]));
    assert_eq!(v["to"], "LAS");
    assert!(std::fs::read(&laz).unwrap().starts_with(b"LASF"));
    let ply = tmp("colours-from-laz.ply");
    let o = nbhd(&["convert", &laz, &ply]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c = nbhd::io::read(&ply).unwrap();
    assert_eq!(
        c.colors().unwrap(),
        vec![[255, 0, 0], [0, 255, 0], [0, 0, 255]]
    );
    let head = String::from_utf8_lossy(&std::fs::read(&ply).unwrap()[..200]).to_string();
    assert!(head.contains("property uchar red\n"), "{head}");
    let (file, _) = noisy_sphere_file("nsphere-las.ply");
    let normals = tmp("nsphere-las-normals.ply");
    assert!(nbhd(&["normals", &file, &normals, "--orient", "none"])
        .status
        .success());
    // Normals and curvature go to LAS extra bytes (NormalX NormalY NormalZ, Curvature).
    let las_out = tmp("nsphere.las");
    let o = nbhd(&["convert", &normals, &las_out]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("not written"), "{}", stderr(&o));
    let (want, back) = (
        nbhd::io::read(&normals).unwrap(),
        nbhd::io::read(&las_out).unwrap(),
    );
    for (p, q) in want
        .normals
        .as_ref()
        .unwrap()
        .iter()
        .zip(back.normals.as_ref().unwrap())
    {
        assert!((0..3).all(|j| (p[j] - q[j]).abs() <= 1e-7), "{p:?} {q:?}");
    }
    assert_eq!(back.scalar("curvature"), want.scalar("curvature"));
}

/// Issue 39 item 4: `nbhd smooth in.laz out.laz` on LAS 1.4 point format 6 keeps the format,
/// the GPS times, returns, classes, intensities and the file's extra bytes, and adds normals
/// and curvatures as extra bytes; issue 41 item 5: what a format has no place for is said.
#[test]
fn smoothing_a_laz_keeps_every_record() {
    let input = data("las/full_fmt6.laz").unwrap();
    let out = tmp("smoothed-fmt6.laz");
    let o = nbhd(&["smooth", &input, &out, "-k", "8", "--iterations", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("not written"), "{}", stderr(&o));
    let (a, b) = (
        nbhd::io::read(&input).unwrap(),
        nbhd::io::read(&out).unwrap(),
    );
    let (ha, hb) = (
        a.metadata.las.clone().unwrap(),
        b.metadata.las.clone().unwrap(),
    );
    assert_eq!((hb.point_format, hb.version), (6, (1, 4)));
    assert_eq!((hb.scale, hb.offset), (ha.scale, ha.offset));
    for f in [
        "gps_time",
        "return_number",
        "number_of_returns",
        "classification",
        "intensity",
        "scan_angle",
        "point_source_id",
        "Amplitude",
        "PulseId",
    ] {
        let (x, y) = (a.scalar(f).unwrap(), b.scalar(f).unwrap());
        assert!(
            x.iter()
                .zip(y)
                .all(|(p, q)| p == q || p.is_nan() && q.is_nan()),
            "{f}"
        );
    }
    for f in [
        "curvature",
        "k1",
        "k2",
        "mean_curvature",
        "max_abs_curvature",
    ] {
        assert!(b.scalar(f).is_some(), "{f}: {:?}", b.field_names());
    }
    assert!(b.normals.is_some());
    assert_ne!(a.positions, b.positions);

    // PCD -> PLY: the viewpoint has no place in PLY, and the command says so.
    let o = nbhd(&[
        "convert",
        &data("pcl/office1.pcd").unwrap(),
        &tmp("office1.ply"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("not written (PLY has no place for them): the PCD viewpoint 0 0 0 0 1 0 0"),
        "{}",
        stderr(&o)
    );
}

/// `info` prints the spacing; `crop`, `sor` and `ror` write exactly the points the library
/// keeps (crop: against a brute-force test of the closed box), NaN points never.
#[test]
fn filters_write_the_kept_points_and_info_prints_the_spacing() {
    let Some(f) = data("pcl/milk.pcd") else {
        return;
    };
    let cloud = nbhd::io::read(&f).unwrap();
    let view = cloud.view().unwrap();
    let tree = nbhd::KdTree::<f64>::build(&view, &nbhd::BuildOptions::default()).unwrap();
    let h = tree.spacing(1).unwrap();
    let o = nbhd(&["info", "--json", &f]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["spacing"]["mean"].as_f64().unwrap(), h.mean);
    assert_eq!(v["spacing"]["median"].as_f64().unwrap(), h.median);

    let count = |path: &str| nbhd::io::read(path).unwrap().len();
    let out = tmp("crop.ply");
    // the middle third of the bounding box in x and y, all of z
    let b = cloud.bounding_box().unwrap();
    let third = |j: usize, t: f64| b.min[j] + t * (b.max[j] - b.min[j]);
    let (x0, x1, y0, y1) = (
        third(0, 1.0 / 3.0),
        third(0, 2.0 / 3.0),
        third(1, 0.4),
        third(1, 0.6),
    );
    let (min, max) = (format!("{x0},{y0},-inf"), format!("{x1},{y1},inf"));
    let o = nbhd(&["crop", &f, &out, "--min", &min, "--max", &max]);
    assert!(o.status.success(), "{}", stderr(&o));
    let inside = cloud
        .positions
        .iter()
        .filter(|p| (x0..=x1).contains(&p[0]) && (y0..=y1).contains(&p[1]))
        .count();
    assert!(inside > 0);
    assert_eq!(count(&out), inside);
    let o = nbhd(&["crop", &f, &out, "--min", "1,0,0", "--max", "0,1,1"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("min > max"), "{}", stderr(&o));

    let out = tmp("sor.pcd");
    let o = nbhd(&["sor", &f, &out, "-k", "20", "--std-ratio", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let want = nbhd::filter::statistical_outlier_removal(
        &tree,
        &nbhd::filter::StatisticalOutlierOptions {
            k: 20,
            std_ratio: 1.0,
            threads: 0,
        },
    )
    .unwrap();
    assert_eq!(count(&out), want.indices.len());
    assert!(want.indices.len() < cloud.len());

    let out = tmp("ror.xyz");
    let o = nbhd(&["ror", &f, &out, "-r", "2h", "-m", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let want = nbhd::filter::radius_outlier_removal(
        &tree,
        &nbhd::filter::RadiusOutlierOptions {
            radius: 2.0 * h.mean,
            min_neighbors: 4,
            threads: 0,
        },
    )
    .unwrap();
    assert_eq!(count(&out), want.indices.len());

    // voxel grid in f32 (a float file): the library's centroids, and with --nearest the
    // original points themselves
    let pts32: Vec<f32> = cloud
        .positions
        .iter()
        .flatten()
        .map(|&x| x as f32)
        .collect();
    let v32 = nbhd::PointsView::from_flat(&pts32, 3).unwrap();
    let g =
        nbhd::filter::voxel_grid::<f32>(&v32, &nbhd::filter::VoxelGridOptions::cube(0.01)).unwrap();
    assert!(g.len() > 10 && g.len() < cloud.len());
    let out = tmp("voxel.pcd");
    let o = nbhd(&["voxel", &f, &out, "--leaf", "0.01"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = nbhd::io::read(&out).unwrap();
    assert_eq!(got.len(), g.len());
    for (v, p) in got.positions.iter().enumerate() {
        let c = g.centroid(v);
        assert_eq!(*p, [c[0] as f64, c[1] as f64, c[2] as f64]);
    }
    let o = nbhd(&["voxel", &f, &out, "--leaf", "0.01", "--nearest"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = nbhd::io::read(&out).unwrap();
    let want: Vec<[f64; 3]> = g
        .nearest
        .iter()
        .map(|&i| cloud.positions[i as usize])
        .collect();
    assert_eq!(got.positions, want);
    let o = nbhd(&["voxel", &f, &out, "--leaf", "0"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("leaf"), "{}", stderr(&o));
}

/// `nbhd tree save` writes the input's tree; `--tree` loads it instead of building: the same
/// rows as brute force (and as a build with the saved options), and a tree of other points,
/// a corrupted file or a file that is no tree is refused with a message naming it.
#[test]
fn saved_trees_are_loaded_by_the_neighbour_commands_and_checked() {
    let (file, pts) = sphere_file("sphere-tree.xyz");
    let bf = brute(&pts);
    let saved = tmp("sphere.nbhdtree");
    let o = nbhd(&[
        "--json",
        "tree",
        "save",
        &file,
        &saved,
        "--pivot",
        "cyclic-median",
        "--leaf-size",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json_of(&o);
    assert_eq!(v["skipped_non_finite"], 1);
    assert_eq!(v["tree"]["pivot"], "cyclic-median");
    assert_eq!(
        v["file_bytes"].as_u64().unwrap(),
        std::fs::metadata(&saved).unwrap().len()
    );
    for exclude in [false, true] {
        let mut a = vec!["--json", "knn", "-k", "7", &file, "--tree", &saved];
        if exclude {
            a.push("--exclude-self");
        }
        let v = json_of(&nbhd(&a));
        assert_eq!(v["tree_file"], saved.as_str());
        assert_eq!(v["tree"]["pivot"], "cyclic-median", "the file's options");
        assert_eq!(v["tree"]["leaf_size"], 3);
        assert!(v["build_ms"].is_null() && v["load_ms"].is_number());
        expect_brute(
            &bf,
            &rows(&v),
            Neighborhood::Knn { k: 7 },
            exclude,
            "knn --tree",
        );
        // the same rows as building the tree with the saved options
        let mut b = vec!["--json", "knn", "-k", "7", &file];
        b.extend(["--pivot", "cyclic-median", "--leaf-size", "3"]);
        if exclude {
            b.push("--exclude-self");
        }
        assert_eq!(rows(&json_of(&nbhd(&b))), rows(&v));
    }
    // radius with query points from a file
    let qfile = tmp("tree-queries.xyz");
    std::fs::write(&qfile, "0 0 1\n0.5 0.5 0.5\n").unwrap();
    let v = json_of(&nbhd(&[
        "--json",
        "radius",
        "-r",
        "0.3",
        &file,
        "--tree",
        &saved,
        "--queries",
        &qfile,
    ]));
    let got = rows(&v);
    for (q, (idx, _)) in [[0.0, 0.0, 1.0], [0.5, 0.5, 0.5]].iter().zip(&got) {
        let mut want = Vec::new();
        let nb = Neighborhood::Radius {
            radius: 0.3,
            sorted: true,
        };
        bf.search(Query::point(q), nb, &mut want).unwrap();
        assert_eq!(idx, &want.iter().map(|n| n.index).collect::<Vec<_>>());
    }
    // the tree of other points: one point moved, or fewer points
    let mut other = pts.clone();
    other[5][0] += 1e-9;
    let other_file = tmp("sphere-other.xyz");
    let double = nbhd::io::WriteOptions {
        precision: nbhd::io::Precision::Double,
        ..nbhd::io::WriteOptions::ascii()
    };
    let cloud = nbhd::io::PointCloud::from_positions(other);
    nbhd::io::write(&other_file, &cloud, &double).unwrap();
    let o = nbhd(&["knn", "-k", "3", &other_file, "--tree", &saved]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("is not the tree of") && stderr(&o).contains("point 5 differs"),
        "{}",
        stderr(&o)
    );
    let cloud = nbhd::io::PointCloud::from_positions(pts[..300].to_vec());
    nbhd::io::write(&other_file, &cloud, &double).unwrap();
    let o = nbhd(&["knn", "-k", "3", &other_file, "--tree", &saved]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("built over 400 points, the input has 300"),
        "{}",
        stderr(&o)
    );
    // a corrupted file, and a point cloud given as a tree
    let mut bytes = std::fs::read(&saved).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    let broken = tmp("broken.nbhdtree");
    std::fs::write(&broken, &bytes).unwrap();
    for bad in [&broken, &file] {
        let o = nbhd(&["knn", "-k", "3", &file, "--tree", bad]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains(bad.as_str()), "{}", stderr(&o));
    }
}

/// A noisy terrain of `n` points over 60 x 40 (z a smooth relief, noise 0.05), as three tiles
/// cut along x, each in its own order, with two NaN points in the middle tile; written as PLY
/// double files, and their concatenation in tile order as one file. Returns the tiles' paths
/// and the whole file's.
fn terrain_tiles(name: &str, n: usize) -> (Vec<String>, String) {
    let mut s = 0x2545f4914f6cdd1du64;
    let mut r = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut tiles = vec![Vec::new(); 3];
    for _ in 0..n {
        let (x, y) = (60.0 * r(), 40.0 * r());
        let z = (x / 9.0).sin() * (y / 7.0).cos() + 0.05 * (r() + r() + r() - 1.5);
        tiles[((x / 20.0) as usize).min(2)].push([x, y, z]);
    }
    tiles[1].insert(7, [f64::NAN; 3]);
    tiles[1].push([f64::NAN, 0.0, 0.0]);
    let opts = nbhd::io::WriteOptions {
        precision: nbhd::io::Precision::Double,
        ..Default::default()
    };
    let mut paths = Vec::new();
    for (t, pts) in tiles.iter().enumerate() {
        let p = tmp(&format!("{name}-{t}.ply"));
        let cloud = nbhd::io::PointCloud::from_positions(pts.clone());
        nbhd::io::write(std::path::Path::new(&p), &cloud, &opts).unwrap();
        paths.push(p);
    }
    let whole = tmp(&format!("{name}-whole.ply"));
    let cloud = nbhd::io::PointCloud::from_positions(tiles.concat());
    nbhd::io::write(std::path::Path::new(&whole), &cloud, &opts).unwrap();
    (paths, whole)
}

/// Issue 39 item 3: `nbhd tiles` smooths tile by tile (one tile and the points of its
/// neighbours near it in memory) and writes, bit for bit, what `nbhd smooth` writes for the
/// tiles' points taken together: positions, normals and every curvature field, NaN points
/// kept; and on a LAS 1.4 file the same bytes as `nbhd smooth`, every record carried through.
#[test]
fn tiles_smooth_as_the_whole_cloud_does() {
    let (tiles, whole) = terrain_tiles("tiles-terrain", 6000);
    let want = tmp("tiles-terrain-smoothed.ply");
    let o = nbhd(&[
        "smooth",
        &whole,
        &want,
        "--orient",
        "unoriented",
        "-p",
        "double",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = tmp("tiles-terrain-out");
    let mut args = vec!["tiles", "--out", &dir, "-p", "double", "--json"];
    args.extend(tiles.iter().map(String::as_str));
    let o = nbhd(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["points"], 6002);
    assert_eq!(summary["skipped_non_finite"], 2);
    let want = nbhd::io::read(&want).unwrap();
    let mut got = Vec::new();
    for t in &tiles {
        let name = std::path::Path::new(t).file_name().unwrap();
        got.push(nbhd::io::read(std::path::Path::new(&dir).join(name)).unwrap());
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let flat = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<f64>>();
    let cat = |f: &dyn Fn(&nbhd::io::PointCloud) -> Vec<f64>| {
        bits(&got.iter().flat_map(f).collect::<Vec<_>>())
    };
    assert_eq!(cat(&|c| flat(&c.positions)), bits(&flat(&want.positions)));
    assert_eq!(
        cat(&|c| flat(c.normals.as_ref().unwrap())),
        bits(&flat(want.normals.as_ref().unwrap()))
    );
    for f in [
        "curvature",
        "k1",
        "k2",
        "mean_curvature",
        "max_abs_curvature",
    ] {
        assert_eq!(
            cat(&|c| c.scalar(f).unwrap().to_vec()),
            bits(want.scalar(f).unwrap()),
            "{f}"
        );
    }
    assert_ne!(flat(&got[0].positions), {
        let c = nbhd::io::read(&tiles[0]).unwrap();
        flat(&c.positions)
    });

    // one LAS 1.4 tile: the same file as `nbhd smooth`, records and all
    let input = data("las/full_fmt6.laz").unwrap();
    let want = tmp("tiles-fmt6-smoothed.laz");
    let o = nbhd(&[
        "smooth",
        &input,
        &want,
        "-k",
        "8",
        "--iterations",
        "2",
        "--orient",
        "none",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = tmp("tiles-fmt6-out");
    let o = nbhd(&[
        "tiles",
        &input,
        "--out",
        &dir,
        "-k",
        "8",
        "--iterations",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = std::path::Path::new(&dir).join("full_fmt6.laz");
    assert_eq!(std::fs::read(got).unwrap(), std::fs::read(&want).unwrap());
}

/// Plain loops over every pair (i, j) of `a` × `b` within `r` in the metric `p` (1, 2 or ∞),
/// with `keep(i, j)` choosing which count: rows of indices ascending and keys (squared for
/// p = 2, the distance otherwise).
fn loop_pairs(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    r: f64,
    p: f64,
    strict: bool,
    keep: impl Fn(usize, usize) -> bool,
) -> Vec<(Vec<u32>, Vec<f64>)> {
    a.iter()
        .enumerate()
        .map(|(i, x)| {
            let mut row = (Vec::new(), Vec::new());
            for (j, y) in b.iter().enumerate() {
                let d = x.iter().zip(y).map(|(u, v)| (u - v).abs());
                let (dist, key) = match p {
                    1.0 => (d.clone().sum::<f64>(), d.sum::<f64>()),
                    2.0 => {
                        let s = d.map(|t| t * t).sum::<f64>();
                        (s.sqrt(), s)
                    }
                    _ => (d.clone().fold(0.0, f64::max), d.fold(0.0, f64::max)),
                };
                let within = if strict { dist < r } else { dist <= r };
                if keep(i, j) && within {
                    row.0.push(j as u32);
                    row.1.push(key);
                }
            }
            row
        })
        .collect()
}

fn assert_same_pairs(got: &[(Vec<u32>, Vec<f64>)], want: &[(Vec<u32>, Vec<f64>)], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: rows");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.0, w.0, "{what}: row {i}");
        for (x, y) in g.1.iter().zip(&w.1) {
            assert!(
                (x - y).abs() <= 1e-12 * y.max(1e-300),
                "{what}: row {i}: {x} vs {y}"
            );
        }
    }
}

/// `nbhd pairs`: every pair within ε once (row i: the j > i), and with `--queries` every
/// (query, point) pair, against plain loops — duplicates at distance 0 and a NaN point
/// included, inclusive and strict, Euclidean, l1 and l∞.
#[test]
fn pairs_equal_plain_loops() {
    let (file, pts) = sphere_file("sphere-pairs.xyz");
    let finite = |i: usize| pts[i][0].is_finite();
    for (metric, p, strict, r) in [
        ("l2", 2.0, false, "0.2"),
        ("l1", 1.0, true, "0.25"),
        ("linf", f64::INFINITY, false, "0.12"),
    ] {
        let mut a = vec!["--json", "pairs", "-r", r, &file, "--metric", metric];
        let r: f64 = r.parse().unwrap();
        if strict {
            a.push("--strict");
        }
        let v = json_of(&nbhd(&a));
        assert_eq!(v["kind"], "pairs");
        let want = loop_pairs(&pts, &pts, r, p, strict, |i, j| {
            j > i && finite(i) && finite(j)
        });
        assert_same_pairs(&rows(&v), &want, &a.join(" "));
        assert!(
            want.iter().any(|w| w.1.contains(&0.0)),
            "duplicates pair at 0"
        );
    }
    // Against a second file: the queries' rows hold the input's points within ε, ascending.
    let queries: Vec<[f64; 3]> = pts
        .iter()
        .step_by(7)
        .filter(|q| q[0].is_finite())
        .map(|q| [q[0] * 1.01, q[1], q[2]])
        .collect();
    let qpath = tmp("sphere-pairs-queries.xyz");
    let double = nbhd::io::WriteOptions {
        precision: nbhd::io::Precision::Double,
        ..nbhd::io::WriteOptions::ascii()
    };
    nbhd::io::write(
        &qpath,
        &nbhd::io::PointCloud::from_positions(queries.clone()),
        &double,
    )
    .unwrap();
    let v = json_of(&nbhd(&[
        "--json",
        "pairs",
        "-r",
        "0.2",
        &file,
        "--queries",
        &qpath,
    ]));
    let want = loop_pairs(&queries, &pts, 0.2, 2.0, false, |_, j| finite(j));
    assert_same_pairs(&rows(&v), &want, "pairs --queries");
    let o = nbhd(&["pairs", "-r", "0.2", &file, "--exclude-self"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("never its own pair"), "{}", stderr(&o));
}

/// `nbhd tree save --boxsize`: the file keeps the box, and the commands that load it search
/// periodically — the same rows as the library's periodic tree, pairs included.
#[test]
fn saved_periodic_trees_keep_their_box() {
    let mut pts = Vec::new();
    for i in 0..150u32 {
        let c = |s: u32| f64::from((i.wrapping_mul(2_654_435_761) >> s) % 16) / 16.0;
        pts.push([c(3), c(11), c(19) * 2.0]);
    }
    let path = tmp("periodic-save.xyz");
    let cloud = nbhd::io::PointCloud::from_positions(pts.clone());
    nbhd::io::write(&path, &cloud, &nbhd::io::WriteOptions::ascii()).unwrap();
    let saved = tmp("periodic-save.nbhdtree");
    let v = json_of(&nbhd(&[
        "--json",
        "tree",
        "save",
        &path,
        &saved,
        "--boxsize",
        "1,1,0",
    ]));
    assert_eq!(v["boxsize"], serde_json::json!([1.0, 1.0, 0.0]));
    let view = PointsView::from_rows(&pts).unwrap();
    let tree = KdTree::build_periodic(&view, &BuildOptions::default(), &[1.0, 1.0, 0.0]).unwrap();
    let opts = TableOptions {
        exclude_self: false, // as the command without --exclude-self
        ..TableOptions::default()
    };
    let want_pairs = tree.pairs(0.15, &opts).unwrap();
    let want_knn = tree
        .neighborhoods(Neighborhood::Knn { k: 5 }, &opts)
        .unwrap();
    for (args, want) in [
        (&["pairs", "-r", "0.15"][..], &want_pairs),
        (&["knn", "-k", "5"][..], &want_knn),
    ] {
        let mut a = vec!["--json"];
        a.extend(args);
        a.extend([path.as_str(), "--tree", saved.as_str()]);
        let v = json_of(&nbhd(&a));
        assert_eq!(v["boxsize"], serde_json::json!([1.0, 1.0, 0.0]), "{a:?}");
        let got = rows(&v);
        assert_eq!(got.len(), pts.len());
        for (i, (idx, d)) in got.iter().enumerate() {
            assert_eq!(idx.as_slice(), want.indices_of(i), "{a:?} row {i}");
            assert_eq!(d.as_slice(), want.sq_dists_of(i), "{a:?} row {i}");
        }
    }
    assert!(want_pairs.total() > 0);
    let o = nbhd(&["knn", "-k", "2", &path, "--tree", &saved, "--boxsize", "1"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("keeps the box"), "{}", stderr(&o));
}
