//! Single kNN queries (one `KdTree::knn` call per point, in the caller's order, f32, one
//! thread) against kiddo's `ImmutableKdTree` called the same way: a small binary for
//! `valgrind --tool=callgrind` / `cachegrind` and for side-by-side timings on a busy machine.
//! Times are the calling thread's CPU time (steadier than wall time under load), the minimum
//! over the repetitions, nbhd and kiddo alternating.
//!
//! Run: `cargo run --release --example single_timing -- torus-77k 10 [reps] [nbhd|kiddo|both]`

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nbhd::shapes::datasets::Dataset;
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, PointsView, Query};

/// CPU time of the calling thread, in seconds.
fn thread_cpu() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant of the platform.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let set_name = args.get(1).map_or("torus-77k", String::as_str);
    let k: usize = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(10);
    let reps: usize = args.get(3).and_then(|r| r.parse().ok()).unwrap_or(1);
    let which = args.get(4).map_or("both", String::as_str);
    let set: Dataset = set_name.parse().unwrap_or_else(|e| panic!("{e}"));
    let pts: Vec<[f32; 3]> = set.points().iter().map(|p| p.map(|c| c as f32)).collect();
    let view = PointsView::from_rows(&pts).unwrap();
    let opts = BuildOptions {
        threads: 1,
        ..BuildOptions::default()
    };
    let tree = KdTree::<f32>::build(&view, &opts).unwrap();
    let peer = (which != "nbhd").then(|| ImmutableKdTree::<f32, 3>::new_from_slice(&pts).unwrap());
    let (mut best_ours, mut best_theirs) = (f64::INFINITY, f64::INFINITY);
    let (mut sum_ours, mut sum_theirs) = (0u64, 0u64);
    for _ in 0..reps {
        if which != "kiddo" {
            let mut out = Vec::with_capacity(k);
            let s = thread_cpu();
            let mut sum = 0u64;
            for p in &pts {
                tree.knn(Query::point(p), k, &mut out).unwrap();
                sum += out.iter().map(|n| n.index as u64).sum::<u64>();
            }
            best_ours = best_ours.min(thread_cpu() - s);
            sum_ours = sum;
        }
        if let Some(peer) = &peer {
            let s = thread_cpu();
            let mut sum = 0u64;
            let n = NonZero::new(k).unwrap();
            for p in &pts {
                let res = peer
                    .query(p)
                    .nearest_n::<SquaredEuclidean<f32>>(n)
                    .execute();
                sum += res.iter().map(|r| r.item as u64).sum::<u64>();
            }
            best_theirs = best_theirs.min(thread_cpu() - s);
            sum_theirs = sum;
        }
    }
    println!(
        "{set_name} k={k}: nbhd {:.1} ms, kiddo {:.1} ms, kiddo/nbhd {:.3} (index sums {sum_ours} {sum_theirs}, {} nodes)",
        best_ours * 1e3,
        best_theirs * 1e3,
        best_theirs / best_ours,
        tree.stats().nodes
    );
}
