//! Parameter sweep of the anisotropic flow on the noisy cube (diagnostic).
//! `cargo run --release --example sweep_cube [points] [noise]`
use nbhd::geometry::neighbors::mean_spacing;
use nbhd::shapes::metrics::evaluate;
use nbhd::shapes::{add_noise, sample, Cube, NoiseKind};
use nbhd::smooth::{smooth, Curvature, FeatureCriterion, SmoothOptions, Weighting};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let amp: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.3);
    let cube = Cube::new(1.0);
    let s = sample(&cube, n, 1);
    let h = mean_spacing(&s.points).unwrap();
    let p = add_noise(&s, amp, h, NoiseKind::Gaussian, 2).unwrap();
    for weighting in [Weighting::Sharp, Weighting::Continuous] {
        for lambda in [0.1, 0.15, 0.2, 0.3, 0.5] {
            for steps in [2, 3, 5, 8] {
                let o = SmoothOptions {
                    weighting,
                    lambda: Curvature::Relative(lambda),
                    steps,
                    feature: FeatureCriterion::AllPoints,
                    outputs: false,
                    ..SmoothOptions::default()
                };
                let r = smooth(&p, &o).unwrap();
                let q = evaluate(&cube, &s, h, &r.points, None).unwrap();
                println!(
                    "{weighting:?} λ={lambda} steps={steps}: rms {:.3} edge {:.3} max {:.2}",
                    q.rms, q.edge_rms, q.max
                );
            }
        }
    }
}
