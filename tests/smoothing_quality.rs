//! Quality of the smoothing at 20k points against the analytic truth, in the metrics of
//! `docs/smoothing-results.md` (lengths in h = mean spacing of the clean sample; sample seed 1,
//! noise seed 2). Targets: RMS ≤ 0.14h and edge RMS ≤ 0.27h on the cube at 0.3h noise for the
//! faithful method; RMS ≤ 0.30h / edge RMS ≤ 0.41h (torus: RMS ≤ 0.29h, |shrinkage| ≤ 0.05h) at
//! 1h noise for the robust mode.
//! Every run is deterministic, so each bound sits just above the value measured (stated in the
//! doc comment; `cargo run --release --example robust_quality` prints them all). Where a target
//! is missed, the test pins what is reached and says by how much it misses.

use glam::DVec3;
use nbhd::shapes::metrics::{evaluate, unsigned_angle_deg, Quality};
use nbhd::shapes::{noisy_sample, sample, Cube, CylinderPlane, NoiseKind, Shape, Torus};
use nbhd::smooth::robust::{smooth_robust, RobustOptions};
use nbhd::smooth::{analyze, smooth, Curvature, SmoothOptions, SmoothResult};

const N: usize = 20_000;

/// Quality of the noisy input and of `method`'s result (with its reported normals).
fn run(
    shape: &dyn Shape,
    amp: f64,
    method: impl Fn(&[DVec3]) -> SmoothResult,
) -> (Quality, Quality) {
    let ns = noisy_sample(shape, N, amp, NoiseKind::Gaussian, 1).unwrap();
    let before = evaluate(shape, &ns.clean, ns.h, &ns.points, None).unwrap();
    let r = method(&ns.points);
    let normals: Vec<DVec3> = r.outputs.iter().map(|o| o.normal).collect();
    let after = evaluate(shape, &ns.clean, ns.h, &r.points, Some(&normals)).unwrap();
    eprintln!("{} {amp}h: {after:?}", shape.name());
    (before, after)
}

fn faithful(o: SmoothOptions) -> impl Fn(&[DVec3]) -> SmoothResult {
    move |p| smooth(p, &o).unwrap()
}

fn robust(p: &[DVec3]) -> SmoothResult {
    smooth_robust(p, &RobustOptions::default()).unwrap()
}

/// The notes' anisotropic setting for noise of 1h: `g_sharp`, λ = 0.5/h, 5 steps.
fn faithful_1h() -> SmoothOptions {
    SmoothOptions {
        steps: 5,
        lambda: Curvature::Relative(0.5),
        ..SmoothOptions::default()
    }
}

/// §3: isotropic on a torus with 1h Gaussian noise, RMS ≤ 0.32h, |shrinkage| < 0.15h.
/// Measured: 0.295h, −0.129h (3 steps of τ = 0.5, 15 neighbours within 6h). Met.
#[test]
fn torus_isotropic_at_1h() {
    let o = SmoothOptions {
        steps: 3,
        ..SmoothOptions::isotropic()
    };
    let (before, after) = run(&Torus::new(1.0, 0.4), 1.0, faithful(o));
    assert!((before.rms - 1.0).abs() < 0.05);
    assert!(after.rms <= 0.30, "{after:?}");
    assert!(after.shrinkage.abs() < 0.135, "{after:?}");
}

/// §3: anisotropic on a cube with 0.3h noise, RMS ≤ 0.14h and edge RMS ≤ 0.27h.
///
/// **Not met by the faithful method.** Measured with the defaults (`g_sharp`, λ = 0.2/h,
/// 3 steps): 0.159h / 0.358h — 0.019h and 0.088h over the targets; isotropic fairing gets
/// 0.207h / 0.615h, so the anisotropic flow does keep the edges far better. The sweep over
/// λ ∈ {0.1, 0.15, 0.2, 0.3, 0.5}/h, 2–8 steps, `g_sharp` and `g_cont`
/// (`examples/sweep_cube.rs`) finds no setting that reaches either target: the lowest RMS is
/// 0.150h (edge 0.35h), the lowest edge RMS 0.291h (RMS 0.22h). The feature criteria Q, K, D
/// (eq. 2.33–2.35) do not help either, and 'constrain interior' (Section 7.3) holds noisy face
/// points in place, raising the RMS to 0.22–0.27h (`examples/sweep_cube_features.rs`), so the
/// defaults stay as they are. At this noise the uniform
/// umbrella's tangential component and the curvature estimates of covariance normals blended
/// across the edge limit the method. The robust mode reaches both targets here
/// (`robust_cube_at_0_3h`).
#[test]
fn cube_anisotropic_at_0_3h() {
    let cube = Cube::new(1.0);
    let (_, iso) = run(&cube, 0.3, faithful(SmoothOptions::isotropic()));
    let (before, aniso) = run(&cube, 0.3, faithful(SmoothOptions::default()));
    assert!(aniso.rms < 0.165 && aniso.edge_rms < 0.365, "{aniso:?}");
    assert!(aniso.rms < 0.8 * iso.rms, "{aniso:?} {iso:?}");
    assert!(aniso.edge_rms < 0.6 * iso.edge_rms, "{aniso:?} {iso:?}");
    assert!(aniso.rms < 0.55 * before.rms, "{aniso:?} {before:?}");
}

/// §3: covariance normals (eq. 2.10; 15 nearest other points within 6h) of a clean torus of
/// 80,000 points are within 1° of the truth on average. Measured: 0.50°. Met.
#[test]
fn clean_torus_normals_80k() {
    let torus = Torus::new(1.0, 0.4);
    let s = sample(&torus, 80_000, 1);
    let r = analyze(&s.points, &SmoothOptions::default()).unwrap();
    let err = r
        .outputs
        .iter()
        .zip(&s.normals)
        .map(|(o, &n)| unsigned_angle_deg(o.normal, n))
        .sum::<f64>()
        / s.points.len() as f64;
    eprintln!("clean 80k torus: mean normal error {err:.3}°");
    assert!(err < 0.55, "{err}");
}

/// §4 on the cube with 1h noise: RMS ≤ 0.30h and edge RMS ≤ 0.41h at once. Measured with the
/// defaults: 0.174h / 0.335h, shrinkage +0.015h (0.178h / 0.355h before the neighbourhoods were
/// kept across iterations and the candidates cut to the farthest quarter; the faithful
/// anisotropic flow: 0.404h / 0.818h; isotropic fairing 0.365h / 0.768h; PCL MLS 0.30h / 0.56h
/// and CGAL bilateral 0.34h / 0.41h in docs/smoothing-results.md). Met.
#[test]
fn robust_cube_at_1h() {
    let cube = Cube::new(1.0);
    let (before, r) = run(&cube, 1.0, robust);
    let (_, f) = run(&cube, 1.0, faithful(faithful_1h()));
    assert!((before.rms - 1.0).abs() < 0.05);
    assert!(r.rms < 0.18 && r.edge_rms < 0.345, "{r:?}");
    assert!(r.shrinkage.abs() < 0.02, "{r:?}");
    assert!(
        r.rms < 0.5 * f.rms && r.edge_rms < 0.5 * f.edge_rms,
        "{r:?} {f:?}"
    );
}

/// §4 on the cylinder united with a plane (sharp creases) with 1h noise: RMS ≤ 0.30h and edge
/// RMS ≤ 0.41h at once. Measured: 0.199h / 0.334h (before the faster formulation 0.200h /
/// 0.349h; faithful anisotropic: 0.315h / 0.516h). Met.
#[test]
fn robust_cylinder_plane_at_1h() {
    let shape = CylinderPlane::new(1.0, 2.0);
    let (_, r) = run(&shape, 1.0, robust);
    let (_, f) = run(&shape, 1.0, faithful(faithful_1h()));
    assert!(r.rms < 0.205 && r.edge_rms < 0.345, "{r:?}");
    assert!(
        r.rms < 0.7 * f.rms && r.edge_rms < 0.7 * f.edge_rms,
        "{r:?} {f:?}"
    );
}

/// §4 on the torus with 1h noise: RMS ≤ 0.29h with |shrinkage| ≤ 0.05h. Measured: 0.209h,
/// −0.005h, normal error 2.29° (isotropic fairing: 0.295h, −0.129h; faithful anisotropic: 0.349h, −0.180h). Met.
#[test]
fn robust_torus_at_1h() {
    let torus = Torus::new(1.0, 0.4);
    let (_, r) = run(&torus, 1.0, robust);
    assert!(r.rms < 0.215, "{r:?}");
    assert!(r.shrinkage.abs() < 0.01, "{r:?}");
    assert!(r.normal_error_deg.unwrap() < 2.4, "{r:?}");
}

/// The §3 cube target (RMS ≤ 0.14h, edge RMS ≤ 0.27h at 0.3h noise), which the faithful method
/// misses, with the robust mode's one default setting: 0.054h / 0.130h (0.053h / 0.129h before
/// the candidates of smooth patches were skipped, 0.054h / 0.133h before the faster
/// formulation). Met.
#[test]
fn robust_cube_at_0_3h() {
    let (_, r) = run(&Cube::new(1.0), 0.3, robust);
    assert!(r.rms < 0.06 && r.edge_rms < 0.135, "{r:?}");
}
