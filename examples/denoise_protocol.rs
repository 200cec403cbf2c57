//! The denoising protocol of the point-cloud literature (ScoreDenoise, ICCV 2021, and its
//! successors) on meshes of your choosing, with the robust mode's defaults (see
//! `docs/smoothing-results.md#the-denoising-protocol`): each mesh normalised to the unit sphere,
//! Poisson-disk samples of 10K and 50K points, isotropic Gaussian noise of 1, 2 and 3 % of the
//! radius, Chamfer distance (CD) and point-to-mesh distance (P2M), both mean squared distances
//! taken both ways, ×10⁴, averaged over the meshes.
//!
//! ```sh
//! denoise_protocol [--sizes 10000,50000] [--noise 1,2,3] [--seed 1] [--per-shape] MESH...
//! denoise_protocol --prepare DIR ...   # also write every clean/noisy cloud and mesh to DIR
//! denoise_protocol --evaluate DIR ...  # and measure the clouds the peers left there
//! ```
//!
//! A MESH is an OFF file or `cube` / `torus` (the analytic shapes of `src/shapes`, the torus
//! of radii 1 and 0.4 as 720 × 240 quadrilaterals). `--prepare` writes `DIR/<shape>-<n>-<pct>.noisy.f64` (raw little-endian `f64` triples) and
//! the list `DIR/clouds.txt` for `cpp_examples/bench_denoise`, which writes one
//! `<cloud>.<method>.f64` per method and `<cloud>.times.txt`; `--evaluate` reads them back and
//! prints the table of every method. Without either, only the robust mode runs (in process),
//! which is the quick loop for development.
use glam::DVec3;
use nbhd::shapes::mesh::{chamfer, point_to_mesh, TriangleMesh};
use nbhd::shapes::Rng;
use nbhd::smooth::robust::{smooth_robust_report, RobustOptions};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

struct Args {
    sizes: Vec<usize>,
    noise: Vec<f64>,
    seed: u64,
    per_shape: bool,
    prepare: Option<PathBuf>,
    evaluate: Option<PathBuf>,
    meshes: Vec<PathBuf>,
    /// The robust mode's options (defaults, or `key=value` arguments for exploration).
    options: RobustOptions,
}

fn parse() -> Args {
    let mut a = Args {
        sizes: vec![10_000, 50_000],
        noise: vec![1.0, 2.0, 3.0],
        seed: 1,
        per_shape: false,
        prepare: None,
        evaluate: None,
        meshes: Vec::new(),
        options: RobustOptions::default(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(s) = it.next() {
        let mut value = || it.next().expect("a value after the option");
        match s.as_str() {
            "--sizes" => a.sizes = value().split(',').map(|v| v.parse().unwrap()).collect(),
            "--noise" => a.noise = value().split(',').map(|v| v.parse().unwrap()).collect(),
            "--seed" => a.seed = value().parse().unwrap(),
            "--per-shape" => a.per_shape = true,
            "--prepare" => a.prepare = Some(value().into()),
            "--evaluate" => a.evaluate = Some(value().into()),
            _ => match s.split_once('=') {
                Some((k, v)) => set(&mut a.options, k, v.parse().unwrap()),
                None => a.meshes.push(s.into()),
            },
        }
    }
    a
}

/// One option of the robust mode by its field's name.
fn set(o: &mut RobustOptions, key: &str, v: f64) {
    match key {
        "k" => o.k = v as usize,
        "k_plane" => o.k_plane = v as usize,
        "max_iterations" => o.max_iterations = v as usize,
        "tolerance" => o.tolerance = v,
        "inlier_width" => o.inlier_width = v,
        "feature_angle" => o.feature_angle = v,
        "tau" => o.tau = v,
        "noise_scale" => o.noise_scale = v != 0.0,
        "epsilon" => o.epsilon = nbhd::smooth::Length::Relative(v),
        _ => panic!("no option {key}"),
    }
}

fn write_f64(path: &Path, points: &[DVec3]) {
    let bytes: Vec<u8> = points
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f64::to_le_bytes)
        .collect();
    std::fs::write(path, bytes).unwrap();
}

fn read_f64(path: &Path) -> Option<Vec<DVec3>> {
    let b = std::fs::read(path).ok()?;
    let v: Vec<f64> = b
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    Some(v.chunks_exact(3).map(DVec3::from_slice).collect())
}

/// The clean sample and its noisy copy of one cell: noise seeded by the shape, size and level.
fn cloud(mesh: &TriangleMesh, n: usize, pct: f64, seed: u64) -> (Vec<DVec3>, Vec<DVec3>) {
    let clean = mesh.sample_poisson_disk(n, seed).unwrap();
    let mut rng = Rng::new(seed ^ (n as u64) << 8 ^ (pct * 10.0) as u64);
    let s = pct / 100.0;
    let noisy = clean
        .iter()
        .map(|&p| p + s * DVec3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()))
        .collect();
    (clean, noisy)
}

/// Sums of (CD, P2M, seconds) per (size, noise, method), with the shape count.
type Table = BTreeMap<(usize, u64, String), (f64, f64, f64, usize)>;

fn add(table: &mut Table, key: (usize, u64, &str), cd: f64, p2m: f64, secs: f64) {
    let e = table
        .entry((key.0, key.1, key.2.to_string()))
        .or_insert((0.0, 0.0, 0.0, 0));
    e.0 += cd * 1e4;
    e.1 += p2m * 1e4;
    e.2 += secs;
    e.3 += 1;
}

fn main() {
    let a = parse();
    let mut table = Table::new();
    let threads = std::env::var("RAYON_NUM_THREADS").unwrap_or_default();
    for path in &a.meshes {
        // the analytic shapes of src/shapes by name, every other argument an OFF file
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let mesh = match path.to_str() {
            Some("cube") => TriangleMesh::cube(),
            Some("torus") => TriangleMesh::torus(1.0, 0.4, 720, 240),
            _ => TriangleMesh::from_off(&std::fs::read_to_string(path).unwrap()).unwrap(),
        }
        .normalized();
        for &n in &a.sizes {
            for &pct in &a.noise {
                let (clean, noisy) = cloud(&mesh, n, pct, a.seed);
                let cell = format!("{name}-{n}-{pct}");
                let key = (n, (pct * 10.0) as u64);
                let mut measure = |method: &str, pts: &[DVec3], secs: f64, note: String| {
                    let cd = chamfer(pts, &clean).unwrap();
                    let p2m = point_to_mesh(pts, &mesh).unwrap();
                    if a.per_shape {
                        println!(
                            "{cell:28} {method:12} CD {:7.3} P2M {:7.3} {secs:7.3}s {note}",
                            cd * 1e4,
                            p2m * 1e4
                        );
                    }
                    add(&mut table, (key.0, key.1, method), cd, p2m, secs);
                };
                measure("noisy", &noisy, 0.0, String::new());
                if let Some(dir) = &a.prepare {
                    std::fs::create_dir_all(dir).unwrap();
                    write_f64(&dir.join(format!("{cell}.noisy.f64")), &noisy);
                    continue;
                }
                if let Some(dir) = &a.evaluate {
                    for method in ["robust", "mls", "jet"] {
                        let out = dir.join(format!("{cell}.{method}.f64"));
                        let secs = std::fs::read_to_string(dir.join(format!("{cell}.{method}.s")))
                            .ok()
                            .and_then(|s| s.trim().parse().ok())
                            .unwrap_or(f64::NAN);
                        if let Some(p) = read_f64(&out) {
                            measure(method, &p, secs, String::new());
                        }
                    }
                    continue;
                }
                let t = Instant::now();
                let r = smooth_robust_report(&noisy, &a.options, &mut |_, _| true).unwrap();
                let secs = t.elapsed().as_secs_f64();
                let h = r.result.spacing;
                let disp = (r
                    .result
                    .points
                    .iter()
                    .zip(&noisy)
                    .map(|(a, b)| a.distance_squared(*b))
                    .sum::<f64>()
                    / noisy.len() as f64)
                    .sqrt()
                    / h;
                let note = format!(
                    "sigma/h {:.2} disp {disp:.2} wide {} dim {:?} it {} moved {:?} noise {:?}",
                    pct / 100.0 / h,
                    r.wide_iterations,
                    r.dimension
                        .iter()
                        .map(|v| (v * 100.0).round() / 100.0)
                        .collect::<Vec<_>>(),
                    r.moved.len(),
                    r.moved
                        .iter()
                        .map(|v| (v * 100.0).round() / 100.0)
                        .collect::<Vec<_>>(),
                    r.noise
                        .iter()
                        .map(|v| (v * 100.0).round() / 100.0)
                        .collect::<Vec<_>>()
                );
                measure("robust", &r.result.points, secs, note);
            }
        }
    }
    println!("threads {threads:?}; mean over {} meshes", a.meshes.len());
    println!("| method | size | noise | CD ×10⁴ | P2M ×10⁴ | s/cloud |");
    println!("|---|---|---|---|---|---|");
    for ((n, p, m), (cd, p2m, s, c)) in &table {
        let c = *c as f64;
        println!(
            "| {m} | {n} | {}% | {:.3} | {:.3} | {:.3} |",
            *p as f64 / 10.0,
            cd / c,
            p2m / c,
            s / c
        );
    }
}
