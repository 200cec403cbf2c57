//! Side-by-side speed of nbhd and kiddo's immutable tree (the fastest Rust peer) in one
//! process: build, all-point kNN (k = 10, 30), all-point radius (the radius that gives about
//! 20 neighbours), ε-k (k = 16 within that radius), on 1 and 2 threads, f32, every point
//! querying the tree built on the same set, itself included (as the peers do). Each figure is
//! the median of `NBHD_BENCH_REPS` runs (default 5); ratios are peer / nbhd, so > 1 means
//! nbhd is faster. Writing the table (indices and squared distances) is included for both.
//!
//! Run: `cargo bench --bench compare` (all sets and operations) or, e.g.,
//! `NBHD_BENCH_SETS=torus-77k,cube-1M NBHD_BENCH_OPS=build,knn10 cargo bench --bench compare`
//! (radius: ~20 neighbours; epsk: k = 16 within that radius).

use std::num::NonZero;
use std::time::Instant;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nbhd::shapes::datasets::Dataset;
use nbhd::{BuildOptions, KdTree, Neighborhood, PointsView, Query, TableOptions};
use rayon::prelude::*;

type Kiddo = ImmutableKdTree<f32, 3>;

fn median_secs(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// kiddo's all-point table: rows in caller order, written like ours (offsets, indices,
/// squared distances), queries in chunks on the pool.
fn kiddo_table(tree: &Kiddo, pts: &[[f32; 3]], op: Op, r2: f32) -> usize {
    let rows: Vec<(Vec<u32>, Vec<f32>)> = pts
        .par_chunks(1024)
        .map(|chunk| {
            let (mut ids, mut dists) = (Vec::new(), Vec::new());
            for p in chunk {
                let q = tree.query(p);
                let res = match op {
                    Op::Knn(k) => q
                        .nearest_n::<SquaredEuclidean<f32>>(NonZero::new(k).unwrap())
                        .execute(),
                    Op::Radius => q.within::<SquaredEuclidean<f32>>(r2).execute(),
                    Op::EpsK(k) => q
                        .nearest_n::<SquaredEuclidean<f32>>(NonZero::new(k).unwrap())
                        .within(r2)
                        .execute(),
                };
                for item in res {
                    ids.push(item.item);
                    dists.push(item.distance);
                }
            }
            (ids, dists)
        })
        .collect();
    rows.iter().map(|r| r.0.len()).sum()
}

#[derive(Clone, Copy)]
enum Op {
    Knn(usize),
    Radius,
    EpsK(usize),
}

fn main() {
    let reps: usize = std::env::var("NBHD_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let wanted = std::env::var("NBHD_BENCH_SETS").ok();
    // Operations to run: a comma list of build, knn10, knn30, radius, epsk (default all).
    let ops_wanted = std::env::var("NBHD_BENCH_OPS").ok();
    let run = |op: &str| {
        ops_wanted
            .as_ref()
            .is_none_or(|w| w.split(',').any(|o| o == op))
    };
    println!("| set | operation | threads | nbhd [ms] | kiddo [ms] | kiddo / nbhd |");
    println!("|---|---|---|---:|---:|---:|");
    for set in Dataset::ALL {
        if let Some(w) = &wanted {
            if !w.split(',').any(|n| n == set.name()) {
                continue;
            }
        }
        let pts: Vec<[f32; 3]> = set.points().iter().map(|p| p.map(|c| c as f32)).collect();
        let view = PointsView::from_rows(&pts).unwrap();
        let row = |op: &str, threads: usize, ours: f64, peer: f64| {
            println!(
                "| {} | {op} | {threads} | {:.1} | {:.1} | {:.2} |",
                set.name(),
                ours * 1e3,
                peer * 1e3,
                peer / ours
            );
        };
        for threads in [1, 2].into_iter().filter(|_| run("build")) {
            let opts = BuildOptions {
                threads,
                ..BuildOptions::default()
            };
            let ours = median_secs(reps, || {
                KdTree::<f32>::build(&view, &opts).unwrap();
            });
            let peer = median_secs(reps, || {
                Kiddo::new_from_slice(&pts).unwrap();
            });
            row("build", threads, ours, peer);
        }
        let tree = KdTree::<f32>::build(&view, &BuildOptions::default()).unwrap();
        let kiddo = Kiddo::new_from_slice(&pts).unwrap();
        // The radius giving about 20 neighbours (self included) on average.
        let mut out = Vec::new();
        let mut d20: Vec<f32> = (0..pts.len())
            .step_by((pts.len() / 2000).max(1))
            .map(|i| {
                tree.knn(Query::stored(i as u32), 21, &mut out).unwrap();
                out.last().unwrap().sq_dist.sqrt()
            })
            .collect();
        d20.sort_by(f32::total_cmp);
        let radius = d20[d20.len() / 2];
        let ops = [
            ("knn10", Op::Knn(10), Neighborhood::Knn { k: 10 }),
            ("knn30", Op::Knn(30), Neighborhood::Knn { k: 30 }),
            (
                "radius",
                Op::Radius,
                Neighborhood::Radius {
                    radius,
                    sorted: true,
                },
            ),
            (
                "epsk",
                Op::EpsK(16),
                Neighborhood::KnnRadius { k: 16, radius },
            ),
        ];
        for (name, op, nbhd) in ops {
            if !run(name) {
                continue;
            }
            for threads in [1, 2] {
                let opts = TableOptions {
                    exclude_self: false,
                    threads,
                };
                let mut total = 0;
                let ours = median_secs(reps, || {
                    total = tree.neighborhoods(nbhd, &opts).unwrap().total();
                });
                let p = pool(threads);
                let mut peer_total = 0;
                let peer = median_secs(reps, || {
                    peer_total = p.install(|| kiddo_table(&kiddo, &pts, op, radius * radius));
                });
                assert_eq!(
                    total,
                    peer_total,
                    "{} {name}: neighbour counts differ",
                    set.name()
                );
                row(name, threads, ours, peer);
            }
        }
        let s = tree.stats();
        println!(
            "| {} | memory | – | {:.1} bytes/point | – | – |",
            set.name(),
            s.bytes as f64 / s.points as f64
        );
    }
}
