//! One all-point table on one data set, one thread, f32, self included (as in
//! `benches/compare.rs`): a small binary to count instructions with
//! `valgrind --tool=callgrind` or `perf stat -e instructions`, which are repeatable where wall
//! times on a busy machine are not.
//!
//! Run: `cargo run --release --example table_timing -- torus-77k knn10 [reps]`
//! (operations: build, knn<k> for any k, radius, epsk; radius gives about 20 neighbours, epsk is
//! k = 16 within it). `batch-knn10` answers the same points as a batch of outside queries
//! (`neighborhoods_of`, the points in the data set's own order). A fourth argument `f64` builds
//! an `f64` tree, and `noself` leaves each point out of its own row (as the normals do).
//! `pairs` is scipy's `query_pairs` at that radius (`NeighborIndex::pairs`: each pair once).

use std::time::Instant;

use nbhd::scalar::Scalar;
use nbhd::shapes::datasets::Dataset;
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, Neighborhood, PointsView, Query, TableOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let set_name = args.get(1).map_or("torus-77k", String::as_str);
    let op = args.get(2).map_or("knn10", String::as_str);
    let reps: usize = args.get(3).and_then(|r| r.parse().ok()).unwrap_or(1);
    let set: Dataset = set_name.parse().unwrap_or_else(|e| panic!("{e}"));
    let flags = &args[args.len().min(4)..];
    let exclude_self = flags.iter().any(|f| f == "noself");
    if flags.iter().any(|f| f == "f64") {
        let pts: Vec<[f64; 3]> = set.points();
        run::<f64>(&pts, set_name, op, reps, exclude_self);
    } else {
        let pts: Vec<[f32; 3]> = set.points().iter().map(|p| p.map(|c| c as f32)).collect();
        run::<f32>(&pts, set_name, op, reps, exclude_self);
    }
}

fn run<T: Scalar>(pts: &[[T; 3]], set_name: &str, op: &str, reps: usize, exclude_self: bool) {
    let view = PointsView::from_rows(pts).unwrap();
    let opts = BuildOptions {
        threads: 1,
        ..BuildOptions::default()
    };
    if op == "build" {
        for _ in 0..reps {
            let s = Instant::now();
            let tree = KdTree::<T>::build(&view, &opts).unwrap();
            println!(
                "build {:.2} ms ({} points)",
                s.elapsed().as_secs_f64() * 1e3,
                tree.len()
            );
        }
        return;
    }
    let tree = KdTree::<T>::build(&view, &opts).unwrap();
    // The radius giving about 20 neighbours (self included), as in benches/compare.rs.
    let mut out = Vec::new();
    let mut d20: Vec<T> = (0..pts.len())
        .step_by((pts.len() / 2000).max(1))
        .map(|i| {
            tree.knn(Query::stored(i as u32), 21, &mut out).unwrap();
            T::from_f64(out.last().unwrap().sq_dist.to_f64().sqrt())
        })
        .collect();
    d20.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let radius = d20[d20.len() / 2];
    let topts = TableOptions {
        exclude_self,
        threads: 1,
        ..Default::default()
    };
    if op == "pairs" {
        for _ in 0..reps {
            let (s, c) = (Instant::now(), cpu_seconds());
            let t = tree.pairs(radius, &topts).unwrap();
            println!(
                "{set_name} pairs {:.2} ms (CPU {:.2} ms), {} pairs",
                s.elapsed().as_secs_f64() * 1e3,
                (cpu_seconds() - c) * 1e3,
                t.total()
            );
        }
        return;
    }
    let batch = op.starts_with("batch-");
    let nbhd = match op.trim_start_matches("batch-") {
        knn if knn.starts_with("knn") => Neighborhood::Knn {
            k: knn[3..].parse().expect("knn<k>"),
        },
        "radius" => Neighborhood::Radius {
            radius,
            sorted: true,
        },
        "epsk" => Neighborhood::KnnRadius { k: 16, radius },
        _ => panic!("unknown operation {op}"),
    };
    for _ in 0..reps {
        let (s, c) = (Instant::now(), cpu_seconds());
        let t = if batch {
            tree.neighborhoods_of(&view, nbhd, &topts).unwrap()
        } else {
            tree.neighborhoods(nbhd, &topts).unwrap()
        };
        println!(
            "{set_name} {op} {:.2} ms (CPU {:.2} ms), {} neighbours",
            s.elapsed().as_secs_f64() * 1e3,
            (cpu_seconds() - c) * 1e3,
            t.total()
        );
    }
}

/// CPU time of the whole process in seconds: on a loaded machine the steadier measure of a
/// one-thread table (it leaves out the time the thread waited for a core).
fn cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec for the call.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
}
