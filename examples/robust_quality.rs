//! The robust mode against the faithful method on the analytic shapes, in the metrics of
//! `docs/smoothing-results.md` (lengths in h = mean spacing of the clean sample; noise Gaussian, seed
//! 1 for the sample and 2 for the noise, as `tests/smoothing_quality.rs` uses). Prints the
//! markdown table of `docs/smoothing-results.md`.
//!
//! `cargo run --release --example robust_quality [points] [threads]`

use glam::DVec3;
use nbhd::shapes::metrics::{evaluate, Quality};
use nbhd::shapes::{noisy_sample, Cube, CylinderPlane, NoiseKind, Shape, Torus};
use nbhd::smooth::robust::{smooth_robust_report, RobustOptions};
use nbhd::smooth::{analyze, smooth, Curvature, SmoothOptions, SmoothResult};
use std::time::Instant;

fn normals(r: &SmoothResult) -> Vec<DVec3> {
    r.outputs.iter().map(|o| o.normal).collect()
}

fn row(shape: &str, noise: f64, method: &str, q: &Quality, secs: Option<f64>) {
    let edge = if q.edge_count > 0 {
        format!("{:.3}", q.edge_rms)
    } else {
        "–".into()
    };
    println!(
        "| {shape} | {noise}h | {method} | {:.3} | {edge} | {:+.3} | {:.2} | {} |",
        q.rms,
        q.shrinkage,
        q.normal_error_deg.unwrap_or(f64::NAN),
        secs.map_or("–".into(), |s| format!("{s:.2}"))
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .unwrap();
    let shapes: Vec<Box<dyn Shape>> = vec![
        Box::new(Cube::new(1.0)),
        Box::new(CylinderPlane::new(1.0, 2.0)),
        Box::new(Torus::new(1.0, 0.4)),
    ];
    println!("{n} points, {threads} thread(s); lengths in h, normal error in degrees, time in s");
    println!();
    println!("| shape | noise | method | RMS | edge RMS | shrinkage | normal err | time |");
    println!("|---|---|---|---|---|---|---|---|");
    for shape in &shapes {
        let shape = shape.as_ref();
        for (amp, iso_steps, lambda, aniso_steps) in [(0.3, 2, 0.2, 3), (1.0, 3, 0.5, 5)] {
            let ns = noisy_sample(shape, n, amp, NoiseKind::Gaussian, 1).unwrap();
            let eval =
                |p: &[DVec3], nv: &[DVec3]| evaluate(shape, &ns.clean, ns.h, p, Some(nv)).unwrap();
            let est = analyze(&ns.points, &SmoothOptions::isotropic()).unwrap();
            row(
                shape.name(),
                amp,
                "noisy input (covariance normals)",
                &eval(&ns.points, &normals(&est)),
                None,
            );
            for (label, o) in [
                (
                    format!("isotropic, {iso_steps} steps"),
                    SmoothOptions {
                        steps: iso_steps,
                        ..SmoothOptions::isotropic()
                    },
                ),
                (
                    format!("faithful anisotropic g_sharp λ = {lambda}/h, {aniso_steps} steps"),
                    SmoothOptions {
                        steps: aniso_steps,
                        lambda: Curvature::Relative(lambda),
                        ..SmoothOptions::default()
                    },
                ),
            ] {
                let t = Instant::now();
                let r = smooth(&ns.points, &o).unwrap();
                let secs = t.elapsed().as_secs_f64();
                row(
                    shape.name(),
                    amp,
                    &label,
                    &eval(&r.points, &normals(&r)),
                    Some(secs),
                );
            }
            let t = Instant::now();
            let r = smooth_robust_report(&ns.points, &RobustOptions::default(), &mut |_, _| true)
                .unwrap();
            let secs = t.elapsed().as_secs_f64();
            row(
                shape.name(),
                amp,
                &format!("robust (defaults; {} iterations)", r.moved.len()),
                &eval(&r.result.points, &r.normals),
                Some(secs),
            );
        }
    }
}
