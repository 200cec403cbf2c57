//! Single kNN queries (one `KdTree::knn` call per point, in the caller's order, f32 or f64, one
//! thread) against kiddo's `ImmutableKdTree` called the same way: a small binary for
//! `valgrind --tool=callgrind` / `cachegrind` and for side-by-side timings on a busy machine.
//! Times are the calling thread's CPU time (steadier than wall time under load), the minimum
//! over the repetitions, nbhd and kiddo alternating.
//!
//! Run: `cargo run --release --example single_timing -- torus-77k 10 [reps] [nbhd|kiddo|both]
//! [f32|f64]`

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nbhd::shapes::datasets::Dataset;
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, PointsView, Query, Scalar};

/// A coordinate type with kiddo's single query on its immutable tree.
trait Peer: Scalar {
    const NAME: &'static str;
    type Tree;
    fn peer_build(pts: &[[Self; 3]]) -> Self::Tree;
    /// The sum of the `k` nearest indices of `p`.
    fn peer_knn(tree: &Self::Tree, p: &[Self; 3], k: NonZero<usize>) -> u64;
}

macro_rules! peer {
    ($t:ty, $name:literal) => {
        impl Peer for $t {
            const NAME: &'static str = $name;
            type Tree = ImmutableKdTree<$t, 3>;
            fn peer_build(pts: &[[$t; 3]]) -> Self::Tree {
                ImmutableKdTree::new_from_slice(pts).unwrap()
            }
            fn peer_knn(tree: &Self::Tree, p: &[$t; 3], k: NonZero<usize>) -> u64 {
                let res = tree.query(p).nearest_n::<SquaredEuclidean<$t>>(k).execute();
                res.iter().map(|r| r.item as u64).sum::<u64>()
            }
        }
    };
}
peer!(f32, "f32");
peer!(f64, "f64");

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
    match args.get(5).map_or("f32", String::as_str) {
        "f64" => run::<f64>(&set, set_name, k, reps, which),
        _ => run::<f32>(&set, set_name, k, reps, which),
    }
}

/// nbhd's and kiddo's loops in `T`, alternating; prints their best times.
fn run<T: Peer>(set: &Dataset, set_name: &str, k: usize, reps: usize, which: &str) {
    let pts: Vec<[T; 3]> = set
        .points()
        .iter()
        .map(|p| p.map(<T as Scalar>::from_f64))
        .collect();
    let view = PointsView::from_rows(&pts).unwrap();
    let opts = BuildOptions {
        threads: 1,
        ..BuildOptions::default()
    };
    let tree = KdTree::<T>::build(&view, &opts).unwrap();
    let peer = (which != "nbhd").then(|| T::peer_build(&pts));
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
                sum += T::peer_knn(peer, p, n);
            }
            best_theirs = best_theirs.min(thread_cpu() - s);
            sum_theirs = sum;
        }
    }
    println!(
        "{set_name} {} k={k}: nbhd {:.1} ms, kiddo {:.1} ms, kiddo/nbhd {:.3} (index sums {sum_ours} {sum_theirs}, {} nodes)",
        T::NAME,
        best_ours * 1e3,
        best_theirs * 1e3,
        best_theirs / best_ours,
        tree.stats().nodes
    );
}
