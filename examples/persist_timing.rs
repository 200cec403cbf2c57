//! Loading a saved tree next to building it (docs/tree-file-format.md), as the minimum and the
//! median of several runs: build on 1 thread and on all threads, save (to bytes and to a file),
//! load from bytes and from a file, and the parts of a load (reading the file, CRC-32 of the
//! payload). `cargo run --release --example persist_timing [set] [reps] [f32|f64]`, set as in
//! `nbhd::shapes::datasets::Dataset` (default torus-1M).
use std::time::Instant;

use nbhd::shapes::datasets::Dataset;
use nbhd::Persist;
use nbhd::{BuildOptions, KdTree, PointsView, Scalar};

fn stats(v: &mut [f64]) -> String {
    v.sort_by(f64::total_cmp);
    format!("min {:7.2} ms  median {:7.2} ms", v[0], v[v.len() / 2])
}

fn time<R>(v: &mut Vec<f64>, f: impl FnOnce() -> R) -> R {
    let t = Instant::now();
    let r = f();
    v.push(t.elapsed().as_secs_f64() * 1e3);
    r
}

fn run<T: Scalar>(view: &PointsView<'_>, reps: usize) {
    let path = std::env::temp_dir().join(format!("nbhd-persist-timing-{}", std::process::id()));
    let names = [
        "build, 1 thread",
        "build, all threads",
        "to_bytes",
        "save_file",
        "from_bytes",
        "load_file",
        "  fs::read of the file",
        "  CRC-32 of the bytes",
    ];
    let mut t: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let mut size = 0;
    for _ in 0..reps {
        let one = BuildOptions {
            threads: 1,
            ..Default::default()
        };
        drop(time(&mut t[0], || KdTree::<T>::build(view, &one).unwrap()));
        let tree = time(&mut t[1], || {
            KdTree::<T>::build(view, &BuildOptions::default()).unwrap()
        });
        let bytes = time(&mut t[2], || tree.to_bytes());
        size = bytes.len();
        time(&mut t[3], || tree.save_file(&path).unwrap());
        let loaded = time(&mut t[4], || KdTree::<T>::from_bytes(&bytes).unwrap());
        assert!(loaded.same_structure(&tree));
        drop(time(&mut t[5], || KdTree::<T>::load_file(&path).unwrap()));
        drop(time(&mut t[6], || std::fs::read(&path).unwrap()));
        std::hint::black_box(time(&mut t[7], || crc32fast::hash(&bytes)));
    }
    let _ = std::fs::remove_file(&path);
    println!(
        "{:?}, {} points, {:.1} MB saved, {} threads:",
        T::TYPE,
        view.len(),
        size as f64 / 1e6,
        rayon::current_num_threads()
    );
    for (name, v) in names.iter().zip(&mut t) {
        println!("  {name:<24} {}", stats(v));
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("torus-1M", String::as_str);
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(7);
    let set: Dataset = name.parse().unwrap_or_else(|e| panic!("{e}"));
    let pts: Vec<[f64; 3]> = set.points();
    let view = PointsView::from_rows(&pts).unwrap();
    match args.get(3).map(String::as_str) {
        Some("f64") => run::<f64>(&view, reps),
        _ => run::<f32>(&view, reps),
    }
}
