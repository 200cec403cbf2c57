//! Parameter exploration of the robust mode on the 1h shapes (diagnostic; the defaults came
//! from it). `cargo run --release --example robust_tune [k=24] [kp=48] [iw=5] [fa=25] [tol=0.02]
//! [it=10] [tau=1] [eps=12] [amp=1] [n=20000] [seed=1]`
use nbhd::shapes::metrics::evaluate;
use nbhd::shapes::{noisy_sample, Cube, CylinderPlane, NoiseKind, Shape, Torus};
use nbhd::smooth::robust::{smooth_robust_report, RobustOptions};
use std::time::Instant;

fn main() {
    let mut o = RobustOptions::default();
    let mut amp = 1.0;
    let mut n = 20_000;
    let mut seed = 1u64;
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').unwrap();
        let f: f64 = v.parse().unwrap();
        match k {
            "k" => o.k = f as usize,
            "kp" => o.k_plane = f as usize,
            "it" => o.max_iterations = f as usize,
            "iw" => o.inlier_width = f,
            "fa" => o.feature_angle = f,
            "tau" => o.tau = f,
            "tol" => o.tolerance = f,
            "eps" => o.epsilon = nbhd::smooth::Length::Relative(f),
            "amp" => amp = f,
            "n" => n = f as usize,
            "seed" => seed = f as u64,
            _ => panic!("{k}"),
        }
    }
    let shapes: Vec<Box<dyn Shape>> = vec![
        Box::new(Cube::new(1.0)),
        Box::new(CylinderPlane::new(1.0, 2.0)),
        Box::new(Torus::new(1.0, 0.4)),
    ];
    for s in &shapes {
        let ns = noisy_sample(s.as_ref(), n, amp, NoiseKind::Gaussian, seed).unwrap();
        let t = Instant::now();
        let r = smooth_robust_report(&ns.points, &o, &mut |_, _| true).unwrap();
        let secs = t.elapsed().as_secs_f64();
        let q = evaluate(
            s.as_ref(),
            &ns.clean,
            ns.h,
            &r.result.points,
            Some(&r.normals),
        )
        .unwrap();
        println!(
            "{:15} rms {:.3} edge {:.3} shr {:+.3} nerr {:.2} max {:.2} it {} {:.2}s noise {:?} moved {:?}",
            s.name(),
            q.rms,
            q.edge_rms,
            q.shrinkage,
            q.normal_error_deg.unwrap(),
            q.max,
            r.moved.len(),
            secs,
            r.noise.iter().map(|v| (v * 100.0).round() / 100.0).collect::<Vec<_>>(),
            r.moved.iter().map(|v| (v * 1000.0).round() / 1000.0).collect::<Vec<_>>()
        );
    }
}
