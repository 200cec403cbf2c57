//! Where the time of `nbhd_estimate_normals` goes on a torus (diagnostic, not a test): the
//! whole call as the C ABI makes it (`geometry::estimate_normals`), the same with the propagated
//! orientation (issue: propagation may take no more time than the normals themselves), the
//! full per-point analysis (`nbhd_estimate_curvatures`), and the stages of the old path.
//!
//! `cargo run --release --example normals_timing -- [POINTS] [--threads T] [--repeat R]`
//! `[--only normals|curvatures|table]` (one run of that stage alone, for
//! `valgrind --tool=callgrind`).
use nbhd::geometry::estimate_normals;
use nbhd::geometry::neighbors::neighbor_table;
use nbhd::geometry::normals::local_frames;
use nbhd::shapes::{sample, Torus};
use nbhd::smooth::{self, SmoothOptions};
use nbhd::Neighborhood;
use std::time::Instant;

/// CPU time of the whole process (every thread) in seconds.
fn cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec for the call.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
}

/// The least wall time and the least process CPU time of `r` runs of `f`: on a shared, loaded
/// machine the CPU time of a one-thread run is the steadier measure.
fn best(r: usize, mut f: impl FnMut()) -> (f64, f64) {
    (0..r)
        .map(|_| {
            let (t, c) = (Instant::now(), cpu_seconds());
            f();
            (t.elapsed().as_secs_f64(), cpu_seconds() - c)
        })
        .fold((f64::INFINITY, f64::INFINITY), |a, b| {
            (a.0.min(b.0), a.1.min(b.1))
        })
}

fn main() {
    let (mut n, mut threads, mut repeat) = (1_000_000usize, 1usize, 3usize);
    let mut only = String::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--only" {
            only = args.next().expect("normals, curvatures or table");
            continue;
        }
        let mut value = || args.next().expect("a value").parse().expect("a number");
        match a.as_str() {
            "--threads" => threads = value(),
            "--repeat" => repeat = value(),
            _ => n = a.parse().expect("a number of points"),
        }
    }
    let points = sample(&Torus::new(1.0, 0.4), n, 1).points;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let opts = SmoothOptions {
            steps: 0,
            lambda: smooth::Curvature::Absolute(1.0),
            threads: 0,
            ..SmoothOptions::default()
        };
        match only.as_str() {
            "normals" => return drop(estimate_normals(&points, &opts.normal_options()).unwrap()),
            "curvatures" => return drop(smooth::smooth(&points, &opts).unwrap()),
            "table" => {
                return drop(neighbor_table(&points, Neighborhood::Knn { k: 15 }, true).unwrap())
            }
            _ => {}
        }
        let normals = best(repeat, || {
            estimate_normals(&points, &opts.normal_options()).unwrap();
        });
        let propagated = SmoothOptions {
            orientation: nbhd::geometry::Orientation::Propagate,
            ..opts
        };
        let oriented = best(repeat, || {
            estimate_normals(&points, &propagated.normal_options()).unwrap();
        });
        let full = best(repeat, || {
            smooth::smooth(&points, &opts).unwrap();
        });
        let mut table = None;
        let t_table = best(repeat, || {
            table = Some(neighbor_table(&points, Neighborhood::Knn { k: 15 }, true).unwrap());
        });
        let table = table.unwrap();
        let t_frames = best(repeat, || {
            local_frames(&points, &table).unwrap();
        });
        let (w, c) = (|t: (f64, f64)| t.0, |t: (f64, f64)| t.1);
        println!(
            "torus {n}, {threads} thread(s), best of {repeat}, wall s / CPU s: estimate_normals \
             {:.3} / {:.3}, with propagation {:.3} / {:.3} (propagation / normals {:.2} / {:.2}), \
             all outputs (estimate_curvatures) {:.3} / {:.3}; table k=15 {:.3} / {:.3}, \
             local_frames {:.3} / {:.3}",
            w(normals),
            c(normals),
            w(oriented),
            c(oriented),
            (w(oriented) - w(normals)) / w(normals),
            (c(oriented) - c(normals)) / c(normals),
            w(full),
            c(full),
            w(t_table),
            c(t_table),
            w(t_frames),
            c(t_frames),
        );
    });
}
