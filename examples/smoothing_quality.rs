//! Quality of the faithful smoothing on the analytic test shapes, in the metrics of
//! `docs/smoothing-results.md` (lengths in h = mean spacing of the clean sample).
//!
//! `cargo run --release --example smoothing_quality [points] [threads]`

use glam::DVec3;
use nbhd::geometry::neighbors::mean_spacing;
use nbhd::shapes::metrics::{evaluate, tangential_clustering, Quality};
use nbhd::shapes::{add_noise, sample, Catenoid, Cube, CylinderPlane, NoiseKind, Shape, Torus};
use nbhd::smooth::{smooth, Curvature, SmoothOptions};
use std::time::Instant;

fn row(label: &str, q: &Quality, clustering: f64, secs: f64) {
    println!(
        "| {label} | {:.3} | {:.2} | {:.3} | {:.2} | {:+.3} | {:.2} | {:.2} |",
        q.rms,
        q.max,
        q.edge_rms,
        q.normal_error_deg.unwrap_or(f64::NAN),
        q.shrinkage,
        clustering,
        secs
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
        Box::new(Catenoid::new(1.0, 1.2)),
    ];
    println!("{n} points, {threads} thread(s)");
    println!("| shape / noise / method | RMS [h] | max [h] | edge RMS [h] | normal err [°] | shrinkage [h] | clustering | s |");
    println!("|---|---|---|---|---|---|---|---|");
    for shape in &shapes {
        let s = sample(shape.as_ref(), n, 1);
        let h = mean_spacing(&s.points).unwrap();
        for (amp, iso_steps, lambda, aniso_steps) in [(0.3, 2, 0.2, 3), (1.0, 3, 0.5, 5)] {
            let p = add_noise(&s, amp, h, NoiseKind::Gaussian, 2).unwrap();
            let est = smooth(
                &p,
                &SmoothOptions {
                    steps: 0,
                    ..SmoothOptions::isotropic()
                },
            )
            .unwrap();
            let normals: Vec<DVec3> = est.outputs.iter().map(|o| o.normal).collect();
            let q = evaluate(shape.as_ref(), &s, h, &p, Some(&normals)).unwrap();
            let name = format!("{} {amp}h", shape.name());
            row(
                &format!("{name} noisy"),
                &q,
                tangential_clustering(&p).unwrap(),
                0.0,
            );
            for (label, o) in [
                (
                    format!("isotropic {iso_steps} steps"),
                    SmoothOptions {
                        steps: iso_steps,
                        ..SmoothOptions::isotropic()
                    },
                ),
                (
                    format!("g_sharp λ={lambda}/h {aniso_steps} steps"),
                    SmoothOptions {
                        steps: aniso_steps,
                        lambda: Curvature::Relative(lambda),
                        ..SmoothOptions::default()
                    },
                ),
            ] {
                let t = Instant::now();
                let r = smooth(&p, &o).unwrap();
                let secs = t.elapsed().as_secs_f64();
                let normals: Vec<DVec3> = r.outputs.iter().map(|o| o.normal).collect();
                let q = evaluate(shape.as_ref(), &s, h, &r.points, Some(&normals)).unwrap();
                row(
                    &format!("{name} {label}"),
                    &q,
                    tangential_clustering(&r.points).unwrap(),
                    secs,
                );
            }
        }
    }
}
