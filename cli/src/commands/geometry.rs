//! `nbhd normals IN OUT` and `nbhd curvature IN OUT`: PCA normals (thesis eq. 2.8–2.10) and
//! Weingarten curvatures (eq. 2.20–2.29) of every point over its ε-k neighbourhood, written as
//! normals and scalar properties that MeshLab and CloudCompare colour by.

use crate::commands::{
    finite_points, length_text, parse_length, parse_vec3, precision_text, read_cloud, FormatArg,
    PrecisionArgs,
};
use crate::output::{num, Output};
use crate::progress::Progress;
use crate::render::{render_cloud, ColorMap, RenderOptions};
use glam::DVec3;
use nbhd::geometry::Orientation;
use nbhd::io::{self, PointCloud, WriteOptions};
use nbhd::smooth::{Length, PointOutput, SmoothOptions, SmoothResult};
use serde_json::json;
use std::path::{Path, PathBuf};

/// How normals are oriented (covariance normals have no sign of their own).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum OrientArg {
    /// The eigen-solver's sign: arbitrary but deterministic
    None,
    /// Consistent over the neighbour graph (minimum spanning tree, Hoppe et al.); outward on
    /// closed surfaces
    Propagate,
    /// Away from the centroid of the points (outward for star-shaped objects)
    Outward,
}

/// Options shared by `normals` and `curvature`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input file (.ply, .pcd, .obj, .xyz/.txt/.pts/.asc/.csv)
    pub input: PathBuf,

    /// Output file (.ply, .pcd, .xyz); normals and per-point scalar fields are added
    pub output: PathBuf,

    /// Read the input as this format instead of recognising it
    #[arg(long, value_enum)]
    pub from: Option<FormatArg>,

    /// Maximum valence k: at most the k nearest other points form a neighbourhood
    #[arg(short, long, default_value_t = 15)]
    pub k: usize,

    /// Influence radius ε: neighbours lie within this distance; a number in the points' units
    /// or a multiple of the mean spacing h such as 6h
    #[arg(long, short = 'r', default_value = "6h", value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Length,

    /// How to orient the normals
    #[arg(long, value_enum, default_value = "propagate")]
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

/// The orientation the arguments ask for, given the points.
pub fn orientation(
    orient: OrientArg,
    viewpoint: Option<[f64; 3]>,
    points: &[DVec3],
) -> Orientation {
    if let Some(v) = viewpoint {
        return Orientation::TowardViewpoint(DVec3::from_array(v));
    }
    match orient {
        OrientArg::None => Orientation::Unoriented,
        OrientArg::Propagate => Orientation::Propagate,
        OrientArg::Outward => {
            let c = points.iter().fold(DVec3::ZERO, |a, &p| a + p) / points.len().max(1) as f64;
            Orientation::AwayFrom(c)
        }
    }
}

/// Adds normals and per-point fields of `outputs` (computed on the finite points `index` of
/// `cloud`, in that order) to `cloud`; NaN for skipped points.
///
/// `curvature` is what PCL's `PointNormal::curvature` holds, the surface variation
/// λ0/(λ0+λ1+λ2) of the neighbourhood's covariance (thesis eq. 2.8; 0 on a plane, at most 1/3).
/// `all` adds the principal curvatures `k1`, `k2` (Weingarten estimate, eq. 2.25, signed
/// against the normal), `mean_curvature` (k1+k2)/2 and `max_abs_curvature` max(|k1|,|k2|)
/// ('Max Princ').
pub fn add_outputs(
    cloud: &mut PointCloud,
    index: &[usize],
    outputs: &[PointOutput],
    all: bool,
) -> Result<(), String> {
    let n = cloud.len();
    let mut normals = vec![[f64::NAN; 3]; n];
    for (&i, o) in index.iter().zip(outputs) {
        normals[i] = o.normal.to_array();
    }
    cloud.set_normals(normals).map_err(|e| e.to_string())?;
    let mut field = |name: &str, f: &dyn Fn(&PointOutput) -> f64| -> Result<(), String> {
        let mut v = vec![f64::NAN; n];
        for (&i, o) in index.iter().zip(outputs) {
            v[i] = f(o);
        }
        cloud.set_scalar(name, v).map_err(|e| e.to_string())
    };
    field("curvature", &|o| o.covariance_quotient)?;
    if all {
        field("k1", &|o| o.principal.k1)?;
        field("k2", &|o| o.principal.k2)?;
        field("mean_curvature", &|o| o.mean_curvature)?;
        field("max_abs_curvature", &|o| o.max_principal_curvature)?;
    }
    Ok(())
}

/// Writes `cloud` to `path` (format from the extension) at the precision asked for; errors
/// name the file. Returns `float32` or `float64`, what was written.
pub fn write_cloud(
    path: &Path,
    cloud: &PointCloud,
    precision: &PrecisionArgs,
) -> Result<&'static str, String> {
    let opts = WriteOptions {
        precision: precision.get(),
        ..WriteOptions::default()
    };
    io::write(path, cloud, &opts).map_err(|e| e.to_string())?;
    Ok(precision_text(opts.precision, cloud))
}

/// Draws `cloud` coloured by its `curvature` (surface variation) field on the demo's fixed scale (flat pale,
/// edges and noise in orange to red) into `path`.
pub fn write_png(
    path: &Path,
    cloud: &PointCloud,
    view: [f64; 3],
    up: [f64; 3],
) -> Result<(), String> {
    let opts = RenderOptions {
        view,
        up,
        colormap: ColorMap::Heat,
        range: Some((0.0, crate::commands::demo::SURFACE_VARIATION_RANGE)),
        ..RenderOptions::default()
    };
    let img = render_cloud(cloud, Some("curvature"), &opts)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    img.save_png(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

pub fn run(a: Args, what: What, out: &Output) -> Result<(), String> {
    let mut cloud = read_cloud(&a.input, a.from)?;
    let (points, index) = finite_points(&cloud);
    if points.is_empty() {
        return Err(format!(
            "{}: no point with finite coordinates",
            a.input.display()
        ));
    }
    let opts = SmoothOptions {
        k: a.k,
        epsilon: a.radius,
        orientation: orientation(a.orient, a.viewpoint, &points),
        ..SmoothOptions::default()
    };
    let t = std::time::Instant::now();
    let label = match what {
        What::Normals => "normals",
        What::Curvature => "curvatures",
    };
    let res: SmoothResult = {
        let bar = Progress::bar(out, 1000, label);
        let mut cb = bar.smoothing_callback(label);
        nbhd::smooth::smooth_with_progress(&points, &SmoothOptions { steps: 0, ..opts }, &mut cb)
            .map_err(|e| format!("{}: {e}", a.input.display()))?
    };
    let secs = t.elapsed().as_secs_f64();
    add_outputs(&mut cloud, &index, &res.outputs, what == What::Curvature)?;
    let stored = write_cloud(&a.output, &cloud, &a.precision)?;
    if let Some(png) = &a.png {
        write_png(png, &cloud, [-1.0, -1.0, -1.0], [0.0, 1.0, 0.0])?;
    }
    let curv: Vec<f64> = res
        .outputs
        .iter()
        .map(|o| o.max_principal_curvature)
        .collect();
    let mean_curv = curv.iter().sum::<f64>() / curv.len() as f64;
    let irregular = res.outputs.iter().filter(|o| o.normal_flags != 0).count();
    out.json(&json!({
        "input": a.input.display().to_string(),
        "output": a.output.display().to_string(),
        "png": a.png.as_ref().map(|p| p.display().to_string()),
        "points": cloud.len(),
        "skipped_non_finite": cloud.len() - points.len(),
        "k": a.k,
        "radius": num(res.epsilon),
        "radius_given": length_text(a.radius),
        "spacing_h": num(res.spacing),
        "min_neighbors": res.min_neighbors,
        "degenerate_normals": irregular,
        "mean_abs_max_curvature": num(mean_curv),
        "fields": cloud.field_names(),
        "precision": stored,
        "seconds": num(secs),
    }));
    out.text(format!(
        "{} -> {}: {} points ({} skipped as non-finite), {label} over the {} nearest within \
         ε = {:.6} ({}; h = {:.6}), smallest neighbourhood {}, {} degenerate normals, {:.2} s\n\
         fields {} ({stored}){}",
        a.input.display(),
        a.output.display(),
        cloud.len(),
        cloud.len() - points.len(),
        a.k,
        res.epsilon,
        length_text(a.radius),
        res.spacing,
        res.min_neighbors,
        irregular,
        secs,
        cloud.field_names().join(" "),
        a.png
            .as_ref()
            .map_or(String::new(), |p| format!("\npicture {}", p.display())),
    ));
    Ok(())
}
