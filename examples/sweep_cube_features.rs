//! Feature criteria (eq. 2.33–2.35) and 'constrain interior' (Section 7.3) of the faithful
//! anisotropic flow on the cube with 0.3h noise, 20k points (diagnostic for the §3 cube target:
//! RMS ≤ 0.14h, edge RMS ≤ 0.27h). `cargo run --release --example sweep_cube_features`
use nbhd::shapes::metrics::evaluate;
use nbhd::shapes::{noisy_sample, Cube, NoiseKind};
use nbhd::smooth::{smooth, Curvature, FeatureCriterion, SmoothOptions, Weighting};

fn main() {
    let cube = Cube::new(1.0);
    let ns = noisy_sample(&cube, 20_000, 0.3, NoiseKind::Gaussian, 1).unwrap();
    let criteria = [
        FeatureCriterion::AllPoints,
        FeatureCriterion::EdgeQuotient(0.3),
        FeatureCriterion::PrincipalCurvature(Curvature::Relative(0.1)),
        FeatureCriterion::PrincipalCurvature(Curvature::Relative(0.2)),
        FeatureCriterion::DirectionalCurvature(Curvature::Relative(0.3)),
        FeatureCriterion::DirectionalCurvature(Curvature::Relative(0.5)),
    ];
    for feature in criteria {
        for interior in [None, Some(0.005), Some(0.01)] {
            for (weighting, lambda, steps) in [
                (Weighting::Sharp, 0.15, 3),
                (Weighting::Sharp, 0.15, 5),
                (Weighting::Continuous, 0.1, 5),
            ] {
                let o = SmoothOptions {
                    weighting,
                    lambda: Curvature::Relative(lambda),
                    steps,
                    feature,
                    constrain_interior: interior,
                    outputs: false,
                    ..SmoothOptions::default()
                };
                let r = smooth(&ns.points, &o).unwrap();
                let q = evaluate(&cube, &ns.clean, ns.h, &r.points, None).unwrap();
                println!(
                    "{feature:?} interior {interior:?} {weighting:?} λ={lambda} steps={steps}: rms {:.3} edge {:.3}",
                    q.rms, q.edge_rms
                );
            }
        }
    }
}
