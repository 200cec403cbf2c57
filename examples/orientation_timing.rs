//! The propagated orientation against the normals it orients, side by side in one run (the goal:
//! propagation may take no more time than the normals themselves).
//!
//! `cargo run --release --example orientation_timing -- [POINTS | CLOUD] [options]`
//!
//! * `POINTS` — points sampled on a torus (default 1,000,000); `CLOUD` — a point cloud file
//!   (e.g. `tests/data/pcl/office1.pcd`; non-finite points are left out).
//! * `--repeat R` — time the normals and the propagation R times each, alternating, and report
//!   the minimum of each and their ratio (default 3; the machine may be shared and noisy).
//! * `--stage table|normals|propagate` — stop after the neighbour table, the normals or the
//!   propagation (one pass, no checks): run under `valgrind --tool=callgrind` with
//!   `RAYON_NUM_THREADS=1` at each stage, the differences of the instruction counts are the
//!   normals' and the propagation's.
//! * `--save FILE` / `--compare FILE` — write which normals the propagation flipped (one byte per
//!   point), or count the points whose orientation differs from such a file.
//!
//! k = 15 nearest neighbours, as `nbhd normals` uses by default.
use glam::DVec3;
use nbhd::geometry::neighbors::neighbor_table;
use nbhd::geometry::normals::{local_frames, orient, Orientation};
use nbhd::shapes::{sample, Shape, Torus};
use nbhd::Neighborhood;
use std::time::Instant;

fn main() {
    let mut input = String::from("1000000");
    let (mut repeat, mut stage) = (3usize, String::from("all"));
    let (mut save, mut compare) = (None, None);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| panic!("{a} needs a value"));
        match a.as_str() {
            "--repeat" => repeat = value().parse().expect("a number of repeats"),
            "--stage" => stage = value(),
            "--save" => save = Some(value()),
            "--compare" => compare = Some(value()),
            _ => input = a,
        }
    }
    let torus = Torus::new(1.0, 0.4);
    let (points, name) = match input.parse::<usize>() {
        Ok(n) => (sample(&torus, n, 1).points, format!("torus of {n} points")),
        Err(_) => {
            let cloud = nbhd::io::read(&input).expect("a readable point cloud");
            let points: Vec<DVec3> = cloud
                .positions
                .iter()
                .map(|&p| DVec3::from_array(p))
                .filter(|p| p.is_finite())
                .collect();
            let name = format!("{input} ({} finite points)", points.len());
            (points, name)
        }
    };
    let now = Instant::now();
    let table = neighbor_table(&points, Neighborhood::Knn { k: 15 }, true).unwrap();
    let table_s = now.elapsed().as_secs_f64();
    if stage == "table" {
        println!("{name}: table {table_s:.3} s");
        return;
    }
    let runs = if stage == "all" { repeat.max(1) } else { 1 };
    if stage == "propagate" {
        let mut frames = local_frames(&points, &table).unwrap();
        orient(&points, &table, &mut frames, Orientation::Propagate).unwrap();
        return;
    }
    let (mut normals_s, mut propagate_s) = (f64::INFINITY, f64::INFINITY);
    let (mut frames, mut oriented) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let now = Instant::now();
        frames = local_frames(&points, &table).unwrap();
        normals_s = normals_s.min(now.elapsed().as_secs_f64());
        if stage != "all" {
            println!("{name}: table {table_s:.3} s, normals {normals_s:.3} s");
            return;
        }
        oriented = frames.clone();
        let now = Instant::now();
        orient(&points, &table, &mut oriented, Orientation::Propagate).unwrap();
        propagate_s = propagate_s.min(now.elapsed().as_secs_f64());
    }
    let flipped: Vec<u8> = frames
        .iter()
        .zip(&oriented)
        .map(|(f, o)| u8::from(f.normal.dot(o.normal) < 0.0))
        .collect();
    let outward = if input.parse::<usize>().is_ok() {
        let out = oriented
            .iter()
            .zip(&points)
            .filter(|(f, &p)| f.normal.dot(torus.closest(p).normal) > 0.0)
            .count();
        format!(", {out} of {} outward", points.len())
    } else {
        String::new()
    };
    println!(
        "{name}, k = 15, {} threads, best of {runs}: table {table_s:.3} s, normals {normals_s:.3} \
         s, propagate {propagate_s:.3} s, propagate/normals {:.2}{outward}",
        rayon::current_num_threads(),
        propagate_s / normals_s
    );
    if let Some(path) = save {
        std::fs::write(&path, &flipped).expect("a writable file");
    }
    if let Some(path) = compare {
        let before = std::fs::read(&path).expect("a file written by --save");
        assert_eq!(
            before.len(),
            flipped.len(),
            "the saved run had other points"
        );
        let differ = before.iter().zip(&flipped).filter(|(a, b)| a != b).count();
        println!(
            "{differ} of {} normals oriented otherwise than in {path}",
            flipped.len()
        );
    }
}
