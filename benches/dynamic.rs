//! The dynamic tree against its peers, side by side in one run, f32: nbhd's forest
//! (`src/dynamic/`), rebuilding nbhd's static tree every frame, and kiddo's `MutableKdTree`
//! (nanoflann's dynamic adaptor is in `cpp_examples/bench_dynamic.cpp`, which runs nbhd's
//! forest through the C ABI beside it).
//!
//! - (a) accumulate: `POINTS` points arrive in frames of `FRAME`; after each frame, the 10
//!   nearest neighbours of the frame's points among everything so far.
//! - (b) sliding window: insert a frame, remove the oldest once `WINDOW` points are live,
//!   `FRAMES_B` frames; after each frame the 10 nearest neighbours of the frame's points.
//! - queries on the grown tree against a static tree over the same points.
//!
//! The points are a terrain-like surface (a scan of the ground) in random order, so every
//! frame covers the whole area, as a full sweep of a scanner does.
//!
//! Run: `cargo bench --bench dynamic` (defaults: 1M points, frames of 10k, window 200k, 100
//! frames, threads 1 and 2). Environment: `NBHD_DYN_POINTS`, `NBHD_DYN_FRAME`,
//! `NBHD_DYN_WINDOW`, `NBHD_DYN_FRAMES_B`, `NBHD_DYN_THREADS` (comma list), `NBHD_DYN_GROWTH_B`
//! (the growth factor measured beside the default, 2). A benchmark, not a
//! test: the machine's load shows in the times, so compare the ratios of one run.

use std::num::NonZero;
use std::time::Instant;

use kiddo::{MutableKdTree, SquaredEuclidean};
use nbhd::dynamic::DynamicKdTree;
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, Neighborhood, PointsView, TableOptions};
use rayon::prelude::*;

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// `n` points of a rolling terrain over 100 × 100 units, in random order (xorshift64*).
fn terrain(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut s = seed.max(1);
    let mut unit = move || {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (x, y) = (unit() * 100.0, unit() * 100.0);
            let z = 2.0 * (x / 7.0).sin() * (y / 5.0).cos() + 0.05 * (unit() - 0.5);
            [x as f32, y as f32, z as f32]
        })
        .collect()
}

/// Time of what a method spends, split in updates and queries, and a checksum of its answers.
#[derive(Default, Clone, Copy)]
struct Cost {
    update: f64,
    query: f64,
    check: f64,
}

impl Cost {
    fn total(&self) -> f64 {
        self.update + self.query
    }
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Sum of the squared distances of a table (to check the methods agree).
fn table_sum(t: &nbhd::NeighborTable<f32>) -> f64 {
    t.sq_dists().iter().map(|&d| f64::from(d)).sum()
}

fn knn10_kiddo(tree: &MutableKdTree<f32, 3>, frame: &[[f32; 3]], threads: usize) -> f64 {
    let k = NonZero::new(10).unwrap();
    let one = |p: &[f32; 3]| -> f64 {
        tree.query(p)
            .nearest_n::<SquaredEuclidean<f32>>(k)
            .execute()
            .iter()
            .map(|n| f64::from(n.distance))
            .sum()
    };
    if threads == 1 {
        frame.iter().map(one).sum()
    } else {
        frame
            .par_chunks(1024)
            .map(|c| c.iter().map(one).sum::<f64>())
            .sum()
    }
}

fn accumulate(points: &[[f32; 3]], frame: usize, threads: usize) -> [Cost; 4] {
    let options = BuildOptions {
        threads,
        ..BuildOptions::default()
    };
    let table = TableOptions {
        exclude_self: false,
        threads,
        ..Default::default()
    };
    let knn = Neighborhood::Knn { k: 10 };
    let frames: Vec<&[[f32; 3]]> = points.chunks(frame).collect();
    // nbhd's forest, the default growth factor and another
    let mut forest = [Cost::default(); 2];
    for (g, dynamic) in [nbhd::dynamic::GROWTH, growth_b()]
        .into_iter()
        .zip(&mut forest)
    {
        let mut tree = DynamicKdTree::<f32>::new(3, &options).unwrap();
        tree.set_growth(g).unwrap();
        for f in &frames {
            let view = PointsView::from_rows(f).unwrap();
            let t = Instant::now();
            tree.insert(&view).unwrap();
            dynamic.update += secs(t);
            let t = Instant::now();
            let rows = tree.neighborhoods_of(&view, knn, &table).unwrap();
            dynamic.query += secs(t);
            dynamic.check += table_sum(&rows);
        }
    }
    // nbhd's static tree rebuilt every frame
    let mut rebuild = Cost::default();
    for (i, f) in frames.iter().enumerate() {
        let so_far = &points[..(i * frame + f.len())];
        let t = Instant::now();
        let tree = KdTree::<f32>::build(&PointsView::from_rows(so_far).unwrap(), &options).unwrap();
        rebuild.update += secs(t);
        let t = Instant::now();
        let rows = tree
            .neighborhoods_of(&PointsView::from_rows(f).unwrap(), knn, &table)
            .unwrap();
        rebuild.query += secs(t);
        rebuild.check += table_sum(&rows);
    }
    // kiddo's mutable tree
    let mut kiddo = Cost::default();
    let mut tree: MutableKdTree<f32, 3> = MutableKdTree::default();
    for (i, f) in frames.iter().enumerate() {
        let t = Instant::now();
        for (j, p) in f.iter().enumerate() {
            tree.add(p, (i * frame + j) as u32).unwrap();
        }
        kiddo.update += secs(t);
        let t = Instant::now();
        kiddo.check += knn10_kiddo(&tree, f, threads);
        kiddo.query += secs(t);
    }
    [forest[0], forest[1], rebuild, kiddo]
}

fn sliding(points: &[[f32; 3]], frame: usize, window: usize, threads: usize) -> [Cost; 4] {
    let options = BuildOptions {
        threads,
        ..BuildOptions::default()
    };
    let table = TableOptions {
        exclude_self: false,
        threads,
        ..Default::default()
    };
    let knn = Neighborhood::Knn { k: 10 };
    let frames: Vec<&[[f32; 3]]> = points.chunks(frame).collect();
    let keep = window / frame;
    let mut forest = [Cost::default(); 2];
    for (g, dynamic) in [nbhd::dynamic::GROWTH, growth_b()]
        .into_iter()
        .zip(&mut forest)
    {
        let mut tree = DynamicKdTree::<f32>::new(3, &options).unwrap();
        tree.set_growth(g).unwrap();
        for (i, f) in frames.iter().enumerate() {
            let view = PointsView::from_rows(f).unwrap();
            let t = Instant::now();
            tree.insert(&view).unwrap();
            if i >= keep {
                let old: Vec<u32> = ((i - keep) * frame..(i - keep + 1) * frame)
                    .map(|j| j as u32)
                    .collect();
                tree.remove(&old).unwrap();
            }
            dynamic.update += secs(t);
            let t = Instant::now();
            let rows = tree.neighborhoods_of(&view, knn, &table).unwrap();
            dynamic.query += secs(t);
            dynamic.check += table_sum(&rows);
        }
    }
    let mut rebuild = Cost::default();
    for i in 0..frames.len() {
        let start = (i + 1).saturating_sub(keep) * frame;
        let live = &points[start..(i * frame + frames[i].len())];
        let t = Instant::now();
        let tree = KdTree::<f32>::build(&PointsView::from_rows(live).unwrap(), &options).unwrap();
        rebuild.update += secs(t);
        let t = Instant::now();
        let rows = tree
            .neighborhoods_of(&PointsView::from_rows(frames[i]).unwrap(), knn, &table)
            .unwrap();
        rebuild.query += secs(t);
        rebuild.check += table_sum(&rows);
    }
    let mut kiddo = Cost::default();
    let mut tree: MutableKdTree<f32, 3> = MutableKdTree::default();
    for (i, f) in frames.iter().enumerate() {
        let t = Instant::now();
        for (j, p) in f.iter().enumerate() {
            tree.add(p, (i * frame + j) as u32).unwrap();
        }
        if i >= keep {
            let o = i - keep;
            for (j, p) in frames[o].iter().enumerate() {
                tree.remove(p, (o * frame + j) as u32);
            }
        }
        kiddo.update += secs(t);
        let t = Instant::now();
        kiddo.check += knn10_kiddo(&tree, f, threads);
        kiddo.query += secs(t);
    }
    [forest[0], forest[1], rebuild, kiddo]
}

/// kNN 10 of `queries` on the grown forest and on a static tree over the same points.
fn grown_vs_static(points: &[[f32; 3]], frame: usize, queries: &[[f32; 3]], threads: usize) {
    let options = BuildOptions {
        threads,
        ..BuildOptions::default()
    };
    let table = TableOptions {
        exclude_self: false,
        threads,
        ..Default::default()
    };
    let knn = Neighborhood::Knn { k: 10 };
    let stat = KdTree::<f32>::build(&PointsView::from_rows(points).unwrap(), &options).unwrap();
    for growth in [nbhd::dynamic::GROWTH, growth_b()] {
        let mut tree = DynamicKdTree::<f32>::new(3, &options).unwrap();
        tree.set_growth(growth).unwrap();
        for f in points.chunks(frame) {
            tree.insert(&PointsView::from_rows(f).unwrap()).unwrap();
        }
        let qv = PointsView::from_rows(queries).unwrap();
        let (mut best_dyn, mut best_stat) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..3 {
            let t = Instant::now();
            let a = tree.neighborhoods_of(&qv, knn, &table).unwrap();
            best_dyn = best_dyn.min(secs(t));
            let t = Instant::now();
            let b = stat.neighborhoods_of(&qv, knn, &table).unwrap();
            best_stat = best_stat.min(secs(t));
            assert_eq!(a, b, "the forest answers as the static tree");
        }
        println!(
            "  queries on the grown tree (growth {growth}, {} trees, sizes {:?}): {:.3} s, static \
         tree {:.3} s: ratio {:.2}",
            tree.stats().trees.len(),
            tree.stats().trees.iter().map(|t| t.0).collect::<Vec<_>>(),
            best_dyn,
            best_stat,
            best_dyn / best_stat
        );
    }
}

/// The second growth factor measured beside the default `nbhd::dynamic::GROWTH`
/// (`NBHD_DYN_GROWTH_B`, 2 by default: the default before it was measured).
fn growth_b() -> usize {
    env("NBHD_DYN_GROWTH_B", 2).max(2)
}

fn report(name: &str, costs: [Cost; 4]) {
    let second = format!("nbhd dynamic, growth {}", growth_b());
    let names = [
        "nbhd dynamic",
        second.as_str(),
        "nbhd static rebuilt",
        "kiddo MutableKdTree",
    ];
    println!("  {name}:");
    println!(
        "    {:<22} {:>9} {:>9} {:>9} {:>14}",
        "method", "update s", "query s", "total s", "÷ nbhd dynamic"
    );
    for (n, c) in names.iter().zip(costs) {
        println!(
            "    {:<22} {:>9.3} {:>9.3} {:>9.3} {:>14.2}",
            n,
            c.update,
            c.query,
            c.total(),
            c.total() / costs[0].total()
        );
    }
    let rel = |c: &Cost| (c.check - costs[0].check).abs() / costs[0].check.max(1e-30);
    println!(
        "    answers agree (sum of squared distances, relative difference): growth b {:.1e}, \
         rebuild {:.1e}, kiddo {:.1e}",
        rel(&costs[1]),
        rel(&costs[2]),
        rel(&costs[3])
    );
}

fn main() {
    let n = env("NBHD_DYN_POINTS", 1_000_000);
    let frame = env("NBHD_DYN_FRAME", 10_000);
    let window = env("NBHD_DYN_WINDOW", 200_000);
    let frames_b = env("NBHD_DYN_FRAMES_B", 100);
    let threads: Vec<usize> = std::env::var("NBHD_DYN_THREADS")
        .unwrap_or_else(|_| "1,2".into())
        .split(',')
        .filter_map(|t| t.trim().parse().ok())
        .collect();
    let points = terrain(n.max(frame * frames_b), 42);
    let queries = terrain(200_000, 7);
    println!(
        "dynamic trees, f32, terrain points in random order: (a) {n} points in frames of \
         {frame}, kNN 10 of each frame; (b) window {window}, {frames_b} frames of {frame}"
    );
    for &t in &threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap();
        pool.install(|| {
            println!("threads {t}:");
            report("(a) accumulate", accumulate(&points[..n], frame, t));
            report(
                "(b) sliding window",
                sliding(&points[..frame * frames_b], frame, window, t),
            );
            grown_vs_static(&points[..n], frame, &queries, t);
        });
    }
}
