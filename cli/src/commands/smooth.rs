//! `nbhd smooth IN OUT`: isotropic Gaussian fairing (thesis Section 2.1.3) or anisotropic mean
//! curvature flow (Section 2.3) with the thesis' settings (Section 7.3).

use crate::commands::geometry::{add_outputs, orientation, write_cloud, write_png, OrientArg};
use crate::commands::{
    curvature_text, finite_points, length_text, parse_curvature, parse_length, parse_vec3,
    read_cloud, FormatArg,
};
use crate::output::{num, Output};
use crate::progress::Progress;
use nbhd::smooth::{
    smooth_with_progress, Curvature, FeatureCriterion, Length, SmoothOptions, Weighting,
};
use serde_json::json;
use std::path::PathBuf;

/// Smoothing method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Isotropic Gaussian fairing: every neighbour pulls alike (eq. 2.16); rounds edges
    Isotropic,
    /// Anisotropic mean curvature flow: neighbours across a feature pull less (eq. 2.30)
    Anisotropic,
}

/// Weights g_ij of the anisotropic Laplacian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum WeightingArg {
    /// g_sharp (eq. 2.31, 'Sharp Cutoff'): 1 below the curvature threshold λ, 0 above
    Sharp,
    /// g_cont (eq. 2.32): 1 below λ, falling off continuously above
    Cont,
}

/// Which points are smoothed anisotropically (the others isotropically).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CriterionArg {
    /// Every point
    All,
    /// Edge quotient Q (eq. 2.33): min(|k1|,|k2|)/max(|k1|,|k2|) < Q
    #[value(alias = "q")]
    Quotient,
    /// Principal curvature K (eq. 2.34): max(|k1|,|k2|) > K
    #[value(alias = "k")]
    Principal,
    /// Directional curvature D (eq. 2.35): some neighbour has |κ_ij| > D
    #[value(alias = "d")]
    Directional,
}

/// Smooth a point cloud and write the result with normals and curvatures
///
/// Each step moves every point by τ times the mean of (x_j − p_i) over its neighbourhood N_i,
/// the k nearest other points within ε (computed once on the input unless
/// --update-neighbors); anisotropically each neighbour is weighted by g(|κ_ij|), its
/// directional curvature against the threshold λ. Lengths may be given in units of the mean
/// spacing h of the input (6h), curvatures in units of 1/h (0.2/h).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input file (.ply, .pcd, .obj, .xyz/.txt/.pts/.asc/.csv); NaN points are kept as they are
    pub input: PathBuf,

    /// Output file (.ply, .pcd, .xyz) with normals and curvature fields of the result
    pub output: PathBuf,

    /// Read the input as this format instead of recognising it
    #[arg(long, value_enum)]
    pub from: Option<FormatArg>,

    /// Smoothing method
    #[arg(long, short, value_enum, default_value = "anisotropic")]
    pub method: MethodArg,

    /// Maximum valence k: at most the k nearest other points form a neighbourhood
    #[arg(short, long, default_value_t = 15)]
    pub k: usize,

    /// Influence radius ε: neighbours lie within this distance (points' units, or 6h)
    #[arg(long, short = 'r', default_value = "6h", value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Length,

    /// Number of steps [default: 2 isotropic, 3 anisotropic]
    #[arg(long, short)]
    pub steps: Option<usize>,

    /// Step size τ = λ·∂t of the explicit Euler step (eq. 2.18)
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub tau: f64,

    /// Curvature threshold λ of g_sharp / g_cont (inverse units, or 0.2/h)
    #[arg(long, short, default_value = "0.2/h", value_parser = parse_curvature, allow_hyphen_values = true)]
    pub lambda: Curvature,

    /// Anisotropic weights g_ij
    #[arg(long, short, value_enum, default_value = "sharp")]
    pub weighting: WeightingArg,

    /// Feature criterion: which points are smoothed anisotropically
    #[arg(long, short, value_enum, default_value = "all")]
    pub criterion: CriterionArg,

    /// Edge quotient Q of --criterion quotient
    #[arg(long, short = 'Q', default_value_t = 0.3, allow_hyphen_values = true)]
    pub quotient: f64,

    /// Threshold K or D of --criterion principal / directional (inverse units, or 0.5/h)
    #[arg(long, default_value = "0.5/h", value_parser = parse_curvature, allow_hyphen_values = true)]
    pub feature_curvature: Curvature,

    /// 'Constrain Interior': points whose covariance quotient λ0/(λ0+λ1+λ2) is below this
    /// interior threshold stay where they are
    #[arg(long)]
    pub constrain_interior: Option<f64>,

    /// 'Update Neighbors': recompute the neighbourhoods before every step
    #[arg(long)]
    pub update_neighbors: bool,

    /// How to orient the normals written out
    #[arg(long, value_enum, default_value = "propagate")]
    pub orient: OrientArg,

    /// Also draw the result into this PNG picture, coloured by the surface variation
    /// λ0/(λ0+λ1+λ2) (pale where flat, red at edges and noise), lit by the normals
    #[arg(long)]
    pub png: Option<PathBuf>,

    /// Viewing direction x,y,z of the picture
    #[arg(long, default_value = "-1,-1,-1", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub view: [f64; 3],

    /// World direction x,y,z shown upwards in the picture
    #[arg(long, default_value = "0,1,0", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: [f64; 3],

    #[command(flatten)]
    pub precision: crate::commands::PrecisionArgs,
}

impl Args {
    /// The library's options these arguments ask for (orientation set later).
    pub fn options(&self) -> SmoothOptions {
        let iso = self.method == MethodArg::Isotropic;
        let base = if iso {
            SmoothOptions::isotropic()
        } else {
            SmoothOptions::default()
        };
        SmoothOptions {
            k: self.k,
            epsilon: self.radius,
            steps: self.steps.unwrap_or(base.steps),
            tau: self.tau,
            weighting: match (iso, self.weighting) {
                (true, _) => Weighting::Isotropic,
                (false, WeightingArg::Sharp) => Weighting::Sharp,
                (false, WeightingArg::Cont) => Weighting::Continuous,
            },
            lambda: self.lambda,
            feature: match self.criterion {
                CriterionArg::All => FeatureCriterion::AllPoints,
                CriterionArg::Quotient => FeatureCriterion::EdgeQuotient(self.quotient),
                CriterionArg::Principal => {
                    FeatureCriterion::PrincipalCurvature(self.feature_curvature)
                }
                CriterionArg::Directional => {
                    FeatureCriterion::DirectionalCurvature(self.feature_curvature)
                }
            },
            constrain_interior: self.constrain_interior,
            update_neighbors: self.update_neighbors,
            outputs: true,
            ..base
        }
    }
}

pub fn run(a: Args, out: &Output) -> Result<(), String> {
    let mut cloud = read_cloud(&a.input, a.from)?;
    let (points, index) = finite_points(&cloud);
    if points.is_empty() {
        return Err(format!(
            "{}: no point with finite coordinates",
            a.input.display()
        ));
    }
    let opts = SmoothOptions {
        orientation: orientation(a.orient, None, &points),
        ..a.options()
    };
    let t = std::time::Instant::now();
    let res = {
        let bar = Progress::bar(out, 1000, "smoothing");
        let mut cb = bar.smoothing_callback("smoothing");
        smooth_with_progress(&points, &opts, &mut cb)
            .map_err(|e| format!("{}: {e}", a.input.display()))?
    };
    let secs = t.elapsed().as_secs_f64();
    let moved = res
        .points
        .iter()
        .zip(&points)
        .map(|(p, q)| p.distance(*q))
        .collect::<Vec<_>>();
    let mean_move = moved.iter().sum::<f64>() / moved.len() as f64;
    let max_move = moved.iter().copied().fold(0.0, f64::max);
    for (&i, p) in index.iter().zip(&res.points) {
        cloud.positions[i] = p.to_array();
    }
    add_outputs(&mut cloud, &index, &res.outputs, true)?;
    write_cloud(&a.output, &cloud, &a.precision)?;
    if let Some(png) = &a.png {
        write_png(png, &cloud, a.view, a.up)?;
    }
    let features = res.outputs.iter().filter(|o| o.feature).count();
    let method = match a.method {
        MethodArg::Isotropic => "isotropic",
        MethodArg::Anisotropic => "anisotropic",
    };
    out.json(&json!({
        "input": a.input.display().to_string(),
        "output": a.output.display().to_string(),
        "png": a.png.as_ref().map(|p| p.display().to_string()),
        "points": cloud.len(),
        "skipped_non_finite": cloud.len() - points.len(),
        "method": method,
        "k": opts.k,
        "radius": num(res.epsilon),
        "radius_given": length_text(a.radius),
        "lambda": num(res.lambda),
        "lambda_given": curvature_text(a.lambda),
        "steps": opts.steps,
        "tau": num(opts.tau),
        "spacing_h": num(res.spacing),
        "min_neighbors": res.min_neighbors,
        "feature_points": features,
        "mean_move": num(mean_move),
        "max_move": num(max_move),
        "seconds": num(secs),
    }));
    out.text(format!(
        "{} -> {}: {} points ({} skipped as non-finite) smoothed {method}ally, {} steps of \
         τ = {}\nneighbourhoods: the {} nearest within ε = {:.6} ({}; h = {:.6}), smallest {}\n\
         {}points moved {:.3}h on average, {:.3}h at most; {:.2} s{}",
        a.input.display(),
        a.output.display(),
        cloud.len(),
        cloud.len() - points.len(),
        opts.steps,
        opts.tau,
        opts.k,
        res.epsilon,
        length_text(a.radius),
        res.spacing,
        res.min_neighbors,
        if a.method == MethodArg::Anisotropic {
            format!(
                "λ = {:.6} ({}), {} of the result's points are features\n",
                res.lambda,
                curvature_text(a.lambda),
                features
            )
        } else {
            String::new()
        },
        mean_move / res.spacing,
        max_move / res.spacing,
        secs,
        a.png
            .as_ref()
            .map_or(String::new(), |p| format!("\npicture {}", p.display())),
    ));
    Ok(())
}
