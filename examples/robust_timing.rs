//! Time of the robust smoothing (`smooth_robust`, default options without the per-point outputs, as
//! `cpp_examples/bench_smoothing` times it) on a noisy torus, repeated
//! and summarised by the median and the minimum (the machine may be shared), with the number of
//! iterations the stopping rule ran and the quality reached.
//!
//! `cargo run --release --example robust_timing [points] [threads] [repeats] [noise]`, or with a
//! point file (PCD, PLY, ...) in place of the point count to time a scan (its non-finite points
//! dropped, as `cpp_examples/bench_smoothing` drops them; no quality figures). Each run also
//! prints a digest of the bits of the smoothed points and normals, to compare two builds (or
//! thread counts) bit for bit.
use glam::DVec3;
use nbhd::geometry::neighbors::mean_spacing;
use nbhd::shapes::metrics::evaluate;
use nbhd::shapes::{add_noise, sample, NoiseKind, Torus};
use nbhd::smooth::robust::{smooth_robust_report, RobustOptions, RobustReport};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(d);
    let file = args.get(1).filter(|a| a.parse::<f64>().is_err());
    let n = if file.is_some() {
        0
    } else {
        arg(1, 80_000.0) as usize
    };
    let threads = arg(2, 1.0) as usize;
    let repeats = (arg(3, 3.0) as usize).max(1);
    let noise = arg(4, 1.0);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("the global pool is built once");
    if let Some(path) = file {
        let cloud = nbhd::io::read(path).expect("a readable point file");
        let p: Vec<DVec3> = cloud
            .positions
            .iter()
            .map(|&c| DVec3::from_array(c))
            .filter(|p| p.is_finite())
            .collect();
        let (t, r) = time(&p, repeats);
        println!(
            "{path}: {} points, {threads} thread(s), median (min) of {repeats}: {:.3} ({:.3}) s; {} iterations, noise estimates {:?}; digest {:08x}",
            p.len(),
            t[t.len() / 2],
            t[0],
            r.moved.len(),
            rounded(&r.noise),
            digest(&r)
        );
        return;
    }
    let torus = Torus::new(1.0, 0.35);
    let s = sample(&torus, n, 1);
    let h = mean_spacing(&s.points).expect("a torus sample has a spacing");
    let p = add_noise(&s, noise, h, NoiseKind::Gaussian, 2).expect("finite noise");
    let (times, r) = time(&p, repeats);
    let q = evaluate(&torus, &s, h, &r.result.points, Some(&r.normals)).expect("evaluated");
    println!(
        "{n} points, noise {noise}h, {threads} thread(s), median (min) of {repeats}: {:.3} ({:.3}) s; \
         {} iterations, noise estimates {:?}; RMS {:.3}h, shrinkage {:+.3}h, normal error {:.2}°; \
         digest {:08x}",
        times[times.len() / 2],
        times[0],
        r.moved.len(),
        rounded(&r.noise),
        q.rms,
        q.shrinkage,
        q.normal_error_deg.unwrap_or(f64::NAN),
        digest(&r)
    );
}

/// The smoothing alone, as `cpp_examples/bench_smoothing` times it (no per-point outputs):
/// the sorted times of `repeats` runs and the last report.
fn time(p: &[DVec3], repeats: usize) -> (Vec<f64>, RobustReport) {
    let options = RobustOptions {
        outputs: false,
        ..RobustOptions::default()
    };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let r = smooth_robust_report(p, &options, &mut |_, _| true).expect("smoothing succeeds");
        times.push(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    times.sort_by(f64::total_cmp);
    (times, last.expect("at least one repeat"))
}

/// CRC-32 of the bits of the smoothed points and the normals, in the caller's order.
fn digest(r: &RobustReport) -> u32 {
    let bytes: Vec<u8> = (r.result.points.iter().chain(&r.normals))
        .flat_map(|p| p.to_array())
        .flat_map(f64::to_le_bytes)
        .collect();
    crc32fast::hash(&bytes)
}

/// Values to three decimals, for printing.
fn rounded(v: &[f64]) -> Vec<f64> {
    v.iter().map(|x| (x * 1000.0).round() / 1000.0).collect()
}
