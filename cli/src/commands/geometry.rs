//! `nbhd normals IN OUT` and `nbhd curvature IN OUT`: PCA normals (thesis eq. 2.8–2.10) and
//! Weingarten curvatures (eq. 2.20–2.29) of every point over its ε-k neighbourhood, written as
//! normals and scalar properties that MeshLab and CloudCompare colour by.

use crate::args::{
    length_text, orientation, parse_length, parse_orient, parse_vec3, InputArgs, OrientArg,
    PrecisionArgs,
};
use crate::error::{Context, Result};
use crate::output::{num, Output};
use crate::progress::Progress;
use crate::read::finite_points;
use crate::write;
use glam::DVec3;
use nbhd::geometry::{estimate_normals_from, Neighbors, NormalOptions};
use nbhd::io::PointCloud;
use nbhd::smooth::{Length, SmoothOptions, SmoothResult};
use serde_json::json;
use std::path::PathBuf;

/// Options shared by `normals` and `curvature`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    /// Output file (.ply, .pcd, .las/.laz, .xyz); normals and per-point scalar fields are added
    pub output: PathBuf,

    /// Maximum valence k: at most the k nearest other points form a neighbourhood
    #[arg(short, long, default_value_t = 15)]
    pub k: usize,

    /// Influence radius ε: neighbours lie within this distance; a number in the points' units
    /// or a multiple of the mean spacing h such as 6h
    #[arg(long, short = 'r', default_value = "6h", value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Length,

    /// How to orient the normals
    #[arg(long, value_parser = parse_orient, default_value = "propagate")]
    pub orient: OrientArg,

    /// Orient the normals toward this viewpoint x,y,z instead (e.g. the scanner position)
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub viewpoint: Option<[f64; 3]>,

    /// Also draw the result into this PNG picture, coloured by the surface variation
    /// λ0/(λ0+λ1+λ2) (pale where flat, red at edges and noise), lit by the normals
    #[arg(long)]
    pub png: Option<PathBuf>,

    #[command(flatten)]
    pub precision: PrecisionArgs,
}

/// Which command runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum What {
    /// Normals and the surface variation.
    Normals,
    /// Normals and every curvature.
    Curvature,
}

pub fn run(a: Args, what: What, out: &Output) -> Result<()> {
    let input = &a.input.input;
    let mut cloud = a.input.read()?;
    let (points, index) = finite_points(&cloud);
    if points.is_empty() {
        return Err(format!("{}: no point with finite coordinates", input.display()).into());
    }
    let opts = SmoothOptions {
        k: a.k,
        epsilon: a.radius,
        orientation: orientation(a.orient, a.viewpoint, &points),
        ..SmoothOptions::default()
    };
    if what == What::Normals {
        return normals(&a, &points, &index, cloud, &opts.normal_options(), out);
    }
    let t = std::time::Instant::now();
    let label = "curvatures";
    let res: SmoothResult = {
        let bar = Progress::bar(out, 1000, label);
        let mut cb = bar.smoothing_callback(label);
        nbhd::smooth::analyze_with_progress(&points, Neighbors::default(), &opts, &mut cb)
            .context(input.display())?
    };
    let secs = t.elapsed().as_secs_f64();
    write::add_fields(&mut cloud, &index, &res.outputs, true)?;
    let curv: Vec<f64> = res
        .outputs
        .iter()
        .map(|o| o.max_principal_curvature)
        .collect();
    let mean_curv = curv.iter().sum::<f64>() / curv.len() as f64;
    let summary = Summary {
        label,
        skipped: cloud.len() - points.len(),
        epsilon: res.epsilon,
        spacing: res.spacing,
        min_neighbors: Some(res.min_neighbors),
        degenerate: res.outputs.iter().filter(|o| o.normal_flags != 0).count(),
        secs,
    };
    let extra = json!({
        "min_neighbors": res.min_neighbors,
        "mean_abs_max_curvature": num(mean_curv),
    });
    finish(&a, &cloud, &summary, extra, out)
}

/// What a run of `nbhd normals` or `nbhd curvature` computed, for its report.
struct Summary<'a> {
    /// What was computed: "normals" or "curvatures".
    label: &'a str,
    /// Points left out as non-finite.
    skipped: usize,
    /// The radius used, in the points' units.
    epsilon: f64,
    /// The mean spacing h.
    spacing: f64,
    /// The smallest neighbourhood, where the run reports it (in the text; `extra` has it in
    /// the JSON).
    min_neighbors: Option<usize>,
    /// Normals flagged as degenerate.
    degenerate: usize,
    /// Seconds the computation took.
    secs: f64,
}

/// Writes `cloud` (and the picture asked for) and reports the run: the JSON fields both
/// commands give plus the fields of `extra` (an object), and a line of text.
fn finish(
    a: &Args,
    cloud: &PointCloud,
    s: &Summary<'_>,
    extra: serde_json::Value,
    out: &Output,
) -> Result<()> {
    let input = &a.input.input;
    let stored = write::cloud(&a.output, cloud, &a.precision.write_options())?;
    if let Some(png) = &a.png {
        write::surface_variation_png(png, cloud, [-1.0, -1.0, -1.0], [0.0, 1.0, 0.0])?;
    }
    let mut report = json!({
        "input": input.display().to_string(),
        "output": a.output.display().to_string(),
        "png": a.png.as_ref().map(|p| p.display().to_string()),
        "points": cloud.len(),
        "skipped_non_finite": s.skipped,
        "k": a.k,
        "radius": num(s.epsilon),
        "radius_given": length_text(a.radius),
        "spacing_h": num(s.spacing),
        "degenerate_normals": s.degenerate,
        "fields": cloud.field_names(),
        "precision": stored,
        "seconds": num(s.secs),
    });
    if let (Some(r), serde_json::Value::Object(e)) = (report.as_object_mut(), extra) {
        r.extend(e);
    }
    out.json(&report);
    out.text(format!(
        "{} -> {}: {} points ({} skipped as non-finite), {} over the {} nearest within \
         ε = {:.6} ({}; h = {:.6}){}, {} degenerate normals, {:.2} s\n\
         fields {} ({stored}){}",
        input.display(),
        a.output.display(),
        cloud.len(),
        s.skipped,
        s.label,
        a.k,
        s.epsilon,
        length_text(a.radius),
        s.spacing,
        s.min_neighbors
            .map_or(String::new(), |m| format!(", smallest neighbourhood {m}")),
        s.degenerate,
        s.secs,
        cloud.field_names().join(" "),
        a.png
            .as_ref()
            .map_or(String::new(), |p| format!("\npicture {}", p.display())),
    ));
    Ok(())
}

/// `nbhd normals`: the library's normals ([`estimate_normals_from`], the function the C ABI and
/// Python call too) and the surface variation as the `curvature` field.
fn normals(
    a: &Args,
    points: &[DVec3],
    index: &[usize],
    mut cloud: PointCloud,
    opts: &NormalOptions,
    out: &Output,
) -> Result<()> {
    let input = &a.input.input;
    let t = std::time::Instant::now();
    let res = {
        let bar = Progress::bar(out, 1000, "normals");
        let mut cb = bar.smoothing_callback("normals");
        estimate_normals_from(points, Neighbors::default(), opts, &mut cb)
            .context(input.display())?
    };
    let secs = t.elapsed().as_secs_f64();
    write::add_normals(&mut cloud, index, &res.normals)?;
    let summary = Summary {
        label: "normals",
        skipped: cloud.len() - points.len(),
        epsilon: res.epsilon,
        spacing: res.spacing,
        min_neighbors: None,
        degenerate: res.normals.iter().filter(|e| e.flags != 0).count(),
        secs,
    };
    finish(a, &cloud, &summary, json!({}), out)
}
