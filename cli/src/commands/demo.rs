//! `nbhd demo` (also `nbhd` with no arguments): the whole pipeline on built-in data.
//!
//! For each of the thesis' test shapes — cube, torus, cylinder ∪ plane segment — a seeded
//! sample with seeded Gaussian noise in units of the mean spacing h; a k-d tree with every pivot
//! policy (statistics and build times); the ε-k neighbourhood table from each tree (checked to
//! be identical); isotropic, anisotropic and robust smoothing; before/after PLY files with normals and
//! curvatures and PNG pictures coloured by curvature; and the quality against the analytic
//! surface (RMS distance, edge RMS, normal error) in a summary table.

use crate::error::{Context, Result};
use crate::output::{ms, num, Output};
use crate::progress::Progress;
use crate::render::{Image, RenderOptions};
use crate::write;
use glam::DVec3;
use nbhd::geometry::Orientation;
use nbhd::io::{PointCloud, Precision, WriteOptions};
use nbhd::shapes::metrics::{evaluate, Quality};
use nbhd::shapes::{noisy_sample, Cube, CylinderPlane, NoiseKind, NoisySample, Shape, Torus};
use nbhd::smooth::robust::{smooth_robust_with_progress, RobustOptions};
use nbhd::smooth::{smooth_with_progress, SmoothOptions, SmoothResult};
use nbhd::NeighborIndex;
use nbhd::{
    BuildOptions, KdTree, NeighborTable, Neighborhood, PivotPolicy, PointsView, TableOptions,
};
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Run the demo on built-in shapes (what `nbhd` without a command does)
///
/// Generates noisy samples of a cube, a torus and a cylinder united with a plane segment, builds
/// the k-d tree with every pivot policy, computes the ε-k neighbourhoods, smooths isotropically
/// and anisotropically, writes PLY files (normals and curvatures as properties) and PNG
/// pictures coloured by the surface variation λ0/(λ0+λ1+λ2) into the output folder, and prints
/// tree statistics, neighbourhood sizes, times and the RMS distance to the true surface before
/// and after.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Output folder (created if missing)
    #[arg(long, short, default_value = "nbhd-demo")]
    pub out: PathBuf,

    /// Points per shape
    #[arg(long, short = 'n', default_value_t = 40_000)]
    pub points: usize,

    /// Gaussian noise amplitude, in units of the mean spacing h (along the normal and both
    /// tangents)
    #[arg(long, default_value_t = 0.5)]
    pub noise: f64,

    /// Seed of the samples and the noise
    #[arg(long, default_value_t = 1)]
    pub seed: u64,

    /// Maximum valence k of the neighbourhoods
    #[arg(short, long, default_value_t = 15)]
    pub k: usize,

    /// Influence radius ε in units of h
    #[arg(long, default_value_t = 6.0)]
    pub radius_h: f64,

    /// Leaf bucket size of the trees
    #[arg(long, default_value_t = nbhd::tree::DEFAULT_LEAF_SIZE)]
    pub leaf_size: usize,
}

/// A demo shape with the camera that shows it best.
struct DemoShape {
    shape: Box<dyn Shape>,
    file: &'static str,
    view: [f64; 3],
    up: [f64; 3],
}

fn shapes() -> Vec<DemoShape> {
    vec![
        DemoShape {
            shape: Box::new(Cube::new(1.0)),
            file: "cube",
            view: [-0.9, -0.75, -1.0],
            up: [0.0, 1.0, 0.0],
        },
        DemoShape {
            shape: Box::new(Torus::new(1.0, 0.4)),
            file: "torus",
            view: [-0.35, -0.55, -1.0],
            up: [0.0, 1.0, 0.0],
        },
        DemoShape {
            shape: Box::new(CylinderPlane::new(1.0, 2.0)),
            file: "cylinder-plane",
            view: [0.55, 1.0, -0.75],
            up: [0.0, 0.0, 1.0],
        },
    ]
}

/// One pivot policy's tree on one shape.
struct TreeRow {
    policy: PivotPolicy,
    stats: nbhd::TreeStats,
    build_ms: f64,
    table_ms: f64,
}

/// One smoothing result.
struct Run {
    label: &'static str,
    quality: Quality,
    seconds: f64,
    file: String,
    png: String,
}

/// Everything measured on one shape.
struct ShapeReport {
    name: &'static str,
    points: usize,
    h: f64,
    trees: Vec<TreeRow>,
    tables_identical: bool,
    rows: (usize, f64, usize),
    runs: Vec<Run>,
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    if a.points < 100 {
        return Err(format!("--points {} is too few; use at least 100", a.points).into());
    }
    if !(a.noise.is_finite() && a.noise >= 0.0) {
        return Err(format!("--noise {} must be a finite number >= 0", a.noise).into());
    }
    if !(a.radius_h.is_finite() && a.radius_h > 0.0) {
        return Err(format!("--radius-h {} must be a finite number > 0", a.radius_h).into());
    }
    std::fs::create_dir_all(&a.out).context(a.out.display())?;
    let folder = a.out.canonicalize().unwrap_or_else(|_| a.out.clone());
    let started = Instant::now();
    out.text(format!(
        "nbhd demo: {} points per shape, Gaussian noise {}h, ε-k neighbourhoods k = {}, ε = {}h\n\
         writing to {}\n",
        a.points,
        a.noise,
        a.k,
        a.radius_h,
        folder.display()
    ));
    let mut reports = Vec::new();
    let mut tiles = Vec::new();
    for s in shapes() {
        let (report, images) = run_shape(&a, &s, out)?;
        out.text(shape_text(&report));
        reports.push(report);
        tiles.push(images);
    }
    let overview = a.out.join("overview.png");
    write::png(&overview, &mosaic(&tiles))?;
    let summary = summary_table(&reports);
    let total = started.elapsed().as_secs_f64();
    let md = a.out.join("summary.md");
    std::fs::write(
        &md,
        format!(
            "# nbhd demo\n\n{} points per shape, Gaussian noise {}h, k = {}, ε = {}h.\n\n{}\n{}",
            a.points,
            a.noise,
            a.k,
            a.radius_h,
            reports
                .iter()
                .map(shape_text)
                .collect::<Vec<_>>()
                .join("\n"),
            summary
        ),
    )
    .context(md.display())?;
    out.json(&json!({
        "folder": folder.display().to_string(),
        "points_per_shape": a.points,
        "noise_h": num(a.noise),
        "k": a.k,
        "radius_h": num(a.radius_h),
        "overview": overview.display().to_string(),
        "seconds": num(total),
        "shapes": reports.iter().map(shape_json).collect::<Vec<_>>(),
    }));
    out.text(format!(
        "{summary}\nRMS: distance to the true surface; edge RMS: over the points within 2h of an \
         edge or crease; both in units of h; normal°: mean angle to the true normal.\n\
         Build times are the median of three builds (leaf size {}, median policies with \
         Floyd-Rivest); the ε-k table is every point's k nearest other points within ε.\n\
         Pictures: {}/*.png, all of them in overview.png (rows: {}; columns: noisy, \
         isotropic, anisotropic, robust); colour = curvature as the surface variation \
         λ0/(λ0+λ1+λ2) of the neighbourhood (the thesis' CovQuotient), pale where flat, red at \
         edges and noise; light from the estimated normals.\n\
         Point files with normals and curvature properties: {}/*.ply\n\
         done in {total:.1} s",
        a.leaf_size,
        folder.display(),
        reports
            .iter()
            .map(|r| r.name)
            .collect::<Vec<_>>()
            .join(", "),
        folder.display(),
    ));
    Ok(())
}

/// Runs everything on one shape; returns the report and the pictures (noisy, isotropic,
/// anisotropic, robust).
fn run_shape(a: &Args, s: &DemoShape, out: &Output) -> Result<(ShapeReport, Vec<Image>)> {
    let name = s.shape.name();
    // Stages: sample, 4 trees, normals of the input, two smoothings (10 each), files.
    let bar = Progress::bar(out, 30, format!("{name}: sampling"));
    let ns = noisy_sample(
        s.shape.as_ref(),
        a.points,
        a.noise,
        NoiseKind::Gaussian,
        a.seed,
    )
    .context(name)?;
    let h = ns.h;
    bar.inc(1);
    let trees = time_trees(a, name, &ns.points, h, &bar)?;
    let results = smooth_all(a, name, &ns.points, &bar)?;
    bar.message(format!("{name}: files and pictures"));
    let (runs, images) = write_runs(a, s, &ns, &results)?;
    bar.set(30);
    Ok((
        ShapeReport {
            name,
            points: ns.points.len(),
            h,
            trees: trees.rows,
            tables_identical: trees.identical,
            rows: trees.row_lens,
            runs,
        },
        images,
    ))
}

/// The trees of every pivot policy on one shape and their ε-k tables.
struct Trees {
    rows: Vec<TreeRow>,
    /// Whether every policy's table is the first one's.
    identical: bool,
    /// Smallest, mean and largest row length of the table.
    row_lens: (usize, f64, usize),
}

/// Builds the tree with every pivot policy (median of three builds) and times the ε-k table
/// of each; advances the bar by one per policy.
fn time_trees(a: &Args, name: &str, points: &[DVec3], h: f64, bar: &Progress) -> Result<Trees> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    let view = PointsView::from_flat(&flat, 3).context(name)?;
    let nbhd = Neighborhood::KnnRadius {
        k: a.k,
        radius: a.radius_h * h,
    };
    // One untimed tree and table first, so that the first timed policy does not pay for
    // page faults and thread start-up.
    KdTree::<f64>::build(&view, &BuildOptions::default())
        .and_then(|t| t.neighborhoods(nbhd, &TableOptions::default()))
        .context(name)?;
    let mut rows = Vec::new();
    let mut first: Option<NeighborTable<f64>> = None;
    let mut identical = true;
    for policy in PivotPolicy::ALL {
        bar.message(format!("{name}: tree {}", policy.name()));
        let opts = BuildOptions {
            leaf_size: a.leaf_size,
            ..BuildOptions::with(policy, nbhd::MedianAlgorithm::default())
        };
        // The median of three builds.
        let mut times = Vec::new();
        let mut tree = None;
        for _ in 0..3 {
            let t = Instant::now();
            tree = Some(KdTree::<f64>::build(&view, &opts).context(name)?);
            times.push(ms(t));
        }
        times.sort_by(f64::total_cmp);
        let (tree, build_ms) = (tree.expect("built"), times[1]);
        let t = Instant::now();
        let table = tree
            .neighborhoods(nbhd, &TableOptions::default())
            .context(name)?;
        let table_ms = ms(t);
        match &first {
            None => first = Some(table),
            Some(f) => identical &= *f == table,
        }
        rows.push(TreeRow {
            policy,
            stats: tree.stats(),
            build_ms,
            table_ms,
        });
        bar.inc(1);
    }
    let table = first.expect("at least one policy");
    Ok(Trees {
        rows,
        identical,
        row_lens: (
            table.min_row_len(),
            table.mean_row_len(),
            table.max_row_len(),
        ),
    })
}

/// Normals and curvatures of the noisy input (`noisy`, no step), then the isotropic, the
/// anisotropic and the robust smoothing; each with its time in seconds.
fn smooth_all(
    a: &Args,
    name: &str,
    points: &[DVec3],
    bar: &Progress,
) -> Result<Vec<(&'static str, SmoothResult, f64)>> {
    let base = SmoothOptions {
        k: a.k,
        epsilon: nbhd::smooth::Length::Relative(a.radius_h),
        orientation: Orientation::Propagate,
        ..SmoothOptions::default()
    };
    let runs_opts = [
        ("noisy", SmoothOptions { steps: 0, ..base }),
        (
            "isotropic",
            SmoothOptions {
                weighting: nbhd::smooth::Weighting::Isotropic,
                steps: SmoothOptions::isotropic().steps,
                ..base
            },
        ),
        ("anisotropic", base),
    ];
    let mut results: Vec<(&'static str, SmoothResult, f64)> = Vec::new();
    let progress_of = |i: usize, label: &'static str| {
        let (start, len) = (bar_pos(i), bar_pos(i + 1) - bar_pos(i));
        move |f: f64, _| {
            bar.message(format!("{name}: {label}"));
            bar.set(start + (f * len as f64) as u64);
            true
        }
    };
    for (i, (label, o)) in runs_opts.iter().enumerate() {
        let t = Instant::now();
        let r = smooth_with_progress(points, o, &mut progress_of(i, label)).context(name)?;
        results.push((label, r, t.elapsed().as_secs_f64()));
    }
    // The robust smoothing with its defaults (its neighbourhoods are its own: the 24 nearest
    // within 12h, planes over the 48 nearest).
    let t = Instant::now();
    let robust = RobustOptions {
        orientation: Orientation::Propagate,
        ..RobustOptions::default()
    };
    let r =
        smooth_robust_with_progress(points, &robust, &mut progress_of(runs_opts.len(), "robust"))
            .context(name)?;
    results.push(("robust", r, t.elapsed().as_secs_f64()));
    Ok(results)
}

/// Writes each result as a PLY file with normals and curvatures and as a PNG picture, and
/// measures its quality against the analytic surface.
fn write_runs(
    a: &Args,
    s: &DemoShape,
    ns: &NoisySample,
    results: &[(&'static str, SmoothResult, f64)],
) -> Result<(Vec<Run>, Vec<Image>)> {
    let name = s.shape.name();
    let mut runs = Vec::new();
    let mut images = Vec::new();
    for (label, r, secs) in results {
        let normals: Vec<DVec3> = r.outputs.iter().map(|o| o.normal).collect();
        let quality =
            evaluate(s.shape.as_ref(), &ns.clean, ns.h, &r.points, Some(&normals)).context(name)?;
        let mut cloud = PointCloud::from_positions(r.points.iter().map(|p| p.to_array()).collect());
        let index: Vec<usize> = (0..cloud.len()).collect();
        write::add_fields(&mut cloud, &index, &r.outputs, true)?;
        let file = format!("{}-{label}.ply", s.file);
        let single = WriteOptions {
            precision: Precision::Single,
            ..WriteOptions::default()
        };
        write::cloud(&a.out.join(&file), &cloud, &single)?;
        let img = write::surface_variation_picture(
            &cloud,
            RenderOptions {
                width: 640,
                height: 480,
                view: s.view,
                up: s.up,
                ..RenderOptions::default()
            },
        )?;
        let png = format!("{}-{label}.png", s.file);
        write::png(&a.out.join(&png), &img)?;
        images.push(img);
        runs.push(Run {
            label,
            quality,
            seconds: if *label == "noisy" { 0.0 } else { *secs },
            file,
            png,
        });
    }
    Ok((runs, images))
}

/// Bar position where smoothing run `i` starts (0: input's normals, 1: isotropic, 2:
/// anisotropic, 3: robust, 4: the end of the last).
fn bar_pos(i: usize) -> u64 {
    [5, 8, 13, 18, 29][i]
}

/// The pictures of all shapes in one: a row per shape, a column per stage.
fn mosaic(rows: &[Vec<Image>]) -> Image {
    let (tw, th) = rows
        .first()
        .and_then(|r| r.first())
        .map_or((1, 1), |i| (i.width, i.height));
    let cols = rows.iter().map(Vec::len).max().unwrap_or(1) as u32;
    let (w, h) = (tw * cols, th * rows.len() as u32);
    let mut img = Image {
        width: w,
        height: h,
        pixels: vec![[255, 255, 255]; (w * h) as usize],
    };
    for (r, row) in rows.iter().enumerate() {
        for (c, tile) in row.iter().enumerate() {
            for y in 0..tile.height {
                for x in 0..tile.width {
                    let (gx, gy) = (c as u32 * tw + x, r as u32 * th + y);
                    // A thin grey frame between tiles.
                    let frame = x == 0 || y == 0;
                    img.pixels[(gy * w + gx) as usize] = if frame {
                        [200, 200, 200]
                    } else {
                        tile.pixel(x, y)
                    };
                }
            }
        }
    }
    img
}

fn shape_text(r: &ShapeReport) -> String {
    let mut t = format!(
        "{}: {} points, mean spacing h = {:.5}\n",
        r.name, r.points, r.h
    );
    t.push_str("  pivot policy        depth   nodes  leaves     KiB  build ms  ε-k table ms\n");
    for tr in &r.trees {
        let _ = writeln!(
            t,
            "  {:<18} {:>6} {:>7} {:>7} {:>7} {:>9.2} {:>13.2}",
            tr.policy.name(),
            tr.stats.depth,
            tr.stats.nodes,
            tr.stats.leaves,
            tr.stats.bytes / 1024,
            tr.build_ms,
            tr.table_ms
        );
    }
    let _ = writeln!(
        t,
        "  ε-k neighbourhoods: min {} / mean {:.2} / max {} points per row; {} for all four trees",
        r.rows.0,
        r.rows.1,
        r.rows.2,
        if r.tables_identical {
            "identical"
        } else {
            "DIFFERENT"
        }
    );
    t
}

fn edge(q: &Quality) -> String {
    if q.edge_count > 0 {
        format!("{:.3}", q.edge_rms)
    } else {
        "-".into()
    }
}

fn summary_table(reports: &[ShapeReport]) -> String {
    let mut t = String::from(
        "| shape          | method      | RMS   | edge RMS | normal° | seconds |\n\
         |----------------|-------------|-------|----------|---------|---------|\n",
    );
    for r in reports {
        for run in &r.runs {
            let q = &run.quality;
            let _ = writeln!(
                t,
                "| {:<14} | {:<11} | {:.3} | {:>8} | {:>7.1} | {:>7} |",
                r.name,
                run.label,
                q.rms,
                edge(q),
                q.normal_error_deg.unwrap_or(f64::NAN),
                if run.label == "noisy" {
                    "-".to_string()
                } else {
                    format!("{:.2}", run.seconds)
                }
            );
        }
    }
    t
}

fn quality_json(q: &Quality) -> serde_json::Value {
    json!({
        "rms_h": num(q.rms),
        "max_h": num(q.max),
        "edge_rms_h": if q.edge_count > 0 { num(q.edge_rms) } else { serde_json::Value::Null },
        "edge_points": q.edge_count,
        "shrinkage_h": num(q.shrinkage),
        "normal_error_deg": q.normal_error_deg.map(num),
    })
}

fn shape_json(r: &ShapeReport) -> serde_json::Value {
    json!({
        "shape": r.name,
        "points": r.points,
        "h": num(r.h),
        "trees": r.trees.iter().map(|t| json!({
            "pivot": t.policy.name(),
            "depth": t.stats.depth,
            "nodes": t.stats.nodes,
            "leaves": t.stats.leaves,
            "bytes": t.stats.bytes,
            "build_ms": num(t.build_ms),
            "table_ms": num(t.table_ms),
        })).collect::<Vec<_>>(),
        "tables_identical": r.tables_identical,
        "neighbors": {"min": r.rows.0, "mean": num(r.rows.1), "max": r.rows.2},
        "runs": r.runs.iter().map(|x| json!({
            "stage": x.label,
            "quality": quality_json(&x.quality),
            "seconds": num(x.seconds),
            "ply": x.file,
            "png": x.png,
        })).collect::<Vec<_>>(),
    })
}
