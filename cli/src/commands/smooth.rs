//! `nbhd smooth IN OUT`: the robust smoothing (`nbhd::smooth::robust`, the default), or the
//! thesis' methods: isotropic Gaussian fairing (Section 2.1.3) and anisotropic mean curvature
//! flow (Section 2.3) with the thesis' settings (Section 7.3).

use crate::args::{
    curvature_text, length_text, named, orientation, parse_curvature, parse_length, parse_orient,
    parse_vec3, InputArgs, OrientArg, PrecisionArgs, RobustArgs,
};
use crate::error::{Context, Result};
use crate::output::{num, Output};
use crate::progress::Progress;
use crate::read::finite_points;
use crate::write;
use nbhd::smooth::robust::{
    smooth_robust_report, RobustOptions, NOISE_SCALE_DIMENSION, NOISE_SCALE_FACTOR,
};
use nbhd::smooth::{
    smooth_with_progress, Curvature, FeatureCriterion, Length, SmoothOptions, SmoothResult,
    Weighting,
};
use serde_json::json;
use std::path::PathBuf;

/// Smoothing method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// The default, chosen by measurement: normals chosen among shifted neighbourhoods'
    /// planes, weights and stopping set by the estimated noise. On every shape and noise level
    /// measured (docs/smoothing-results.md) it leaves about half the error of the thesis'
    /// methods and keeps edges sharper (cube at 1h noise: RMS 0.17h, edges 0.34h, against
    /// 0.40h / 0.82h anisotropic), at 2–3 times the time of 10 anisotropic steps
    Robust,
    /// The thesis' anisotropic mean curvature flow: neighbours across a feature pull less
    /// (eq. 2.30)
    Anisotropic,
    /// The thesis' isotropic Gaussian fairing: every neighbour pulls alike (eq. 2.16); rounds
    /// edges
    Isotropic,
}

impl MethodArg {
    fn name(self) -> &'static str {
        match self {
            MethodArg::Robust => "robust",
            MethodArg::Anisotropic => "anisotropic",
            MethodArg::Isotropic => "isotropic",
        }
    }
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
/// The default, --method robust, iterates until the estimated noise stops falling: each
/// iteration picks every point's normal among its own and its farthest neighbours'
/// covariance planes (the one that explains most of its neighbours), then moves the point
/// onto the weighted mean of its neighbours' tangent planes, neighbours whose plane lies far
/// (another face) dropping out. The thesis' methods, one flag away (--method anisotropic or
/// isotropic): each step moves every point by τ times the mean of (x_j − p_i) over its
/// neighbourhood N_i, the k nearest other points within ε (computed once on the input unless
/// --update-neighbors); anisotropically each neighbour is weighted by g(|κ_ij|), its
/// directional curvature against the threshold λ. Lengths may be given in units of the mean
/// spacing h of the input (6h), curvatures in units of 1/h (0.2/h).
#[derive(clap::Args, Debug)]
// `mut_arg` moves the argument to the end of the list: the explicit indices keep
// `<INPUT> <OUTPUT>` in that order.
#[command(mut_arg("input", |a| a.index(1).help(
    "Input file (.ply, .pcd, .las/.laz, .obj, .xyz/.txt/.pts/.asc/.csv); NaN points are kept as they are"
)))]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    /// Output file (.ply, .pcd, .las/.laz, .xyz) with normals and curvature fields of the result
    #[arg(index = 2)]
    pub output: PathBuf,

    /// Smoothing method
    #[arg(long, short, value_enum, default_value = "robust")]
    pub method: MethodArg,

    /// Maximum valence k: at most the k nearest other points form a neighbourhood (the
    /// umbrella N_i) [default: 24 robust, 15 thesis' methods]. Robust: for noise up to about
    /// 1.5 spacings; tripled by itself while the cloud reads as a ball of noise (2–3 spacings
    /// and more); raise it for noise that varies more slowly than a few spacings
    #[arg(short, long)]
    pub k: Option<usize>,

    /// Influence radius ε: neighbours lie within this distance (points' units, or 6h)
    /// [default: 12h robust, 6h thesis' methods]
    #[arg(long, short = 'r', value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Option<Length>,

    /// Step size τ = λ·∂t of the explicit Euler step (eq. 2.18), in (0, 1] for robust
    /// [default: 1 robust, 0.5 thesis' methods]
    #[arg(long, allow_hyphen_values = true)]
    pub tau: Option<f64>,

    #[command(flatten)]
    pub robust: RobustArgs,

    /// Thesis' methods: number of steps [default: 2 isotropic, 3 anisotropic]
    #[arg(long, short)]
    pub steps: Option<usize>,

    /// Anisotropic: curvature threshold λ of g_sharp / g_cont (inverse units, or 0.2/h)
    /// [default: 0.2/h]
    #[arg(long, short, value_parser = parse_curvature, allow_hyphen_values = true)]
    pub lambda: Option<Curvature>,

    /// Anisotropic: weights g_ij: sharp (g_sharp, eq. 2.31, 'Sharp Cutoff': 1 below the
    /// curvature threshold λ, 0 above), continuous (g_cont, eq. 2.32: 1 below λ, falling off
    /// continuously above), or isotropic (g = 1) [default: sharp]
    #[arg(long, short, value_parser = named::<Weighting>())]
    pub weighting: Option<Weighting>,

    /// Anisotropic: feature criterion, which points are smoothed anisotropically [default: all]
    #[arg(long, short, value_enum)]
    pub criterion: Option<CriterionArg>,

    /// Anisotropic: edge quotient Q of --criterion quotient [default: 0.3]
    #[arg(long, short = 'Q', allow_hyphen_values = true)]
    pub quotient: Option<f64>,

    /// Anisotropic: threshold K or D of --criterion principal / directional (inverse units, or
    /// 0.5/h) [default: 0.5/h]
    #[arg(long, value_parser = parse_curvature, allow_hyphen_values = true)]
    pub feature_curvature: Option<Curvature>,

    /// Thesis' methods: 'Constrain Interior', points whose covariance quotient
    /// λ0/(λ0+λ1+λ2) is below this interior threshold stay where they are
    #[arg(long)]
    pub constrain_interior: Option<f64>,

    /// Thesis' methods: 'Update Neighbors', recompute the neighbourhoods before every step
    /// (the robust method always does)
    #[arg(long)]
    pub update_neighbors: bool,

    /// How to orient the normals written out
    #[arg(long, value_parser = parse_orient, default_value = "propagate")]
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
    pub precision: PrecisionArgs,
}

impl Args {
    /// The options given that the chosen method does not read: an error naming the first.
    fn check_method_options(&self) -> Result<()> {
        let robust_only = self.robust.given();
        let thesis_only = [
            ("--steps", self.steps.is_some()),
            ("--constrain-interior", self.constrain_interior.is_some()),
            ("--update-neighbors", self.update_neighbors),
        ];
        let anisotropic_only = [
            ("--lambda", self.lambda.is_some()),
            ("--weighting", self.weighting.is_some()),
            ("--criterion", self.criterion.is_some()),
            ("--quotient", self.quotient.is_some()),
            ("--feature-curvature", self.feature_curvature.is_some()),
        ];
        let refused: Vec<&(&str, bool)> = match self.method {
            MethodArg::Robust => thesis_only.iter().chain(&anisotropic_only).collect(),
            MethodArg::Anisotropic => robust_only.iter().collect(),
            MethodArg::Isotropic => robust_only.iter().chain(&anisotropic_only).collect(),
        };
        match refused.iter().find(|(_, given)| *given) {
            Some((name, _)) => {
                Err(format!("{name} does not apply to --method {}", self.method.name()).into())
            }
            None => Ok(()),
        }
    }

    /// The library's options of the thesis' methods (orientation set later).
    pub fn options(&self) -> SmoothOptions {
        let iso = self.method == MethodArg::Isotropic;
        let base = if iso {
            SmoothOptions::isotropic()
        } else {
            SmoothOptions::default()
        };
        let feature_curvature = self.feature_curvature.unwrap_or(Curvature::Relative(0.5));
        SmoothOptions {
            k: self.k.unwrap_or(base.k),
            epsilon: self.radius.unwrap_or(base.epsilon),
            steps: self.steps.unwrap_or(base.steps),
            tau: self.tau.unwrap_or(base.tau),
            weighting: if iso {
                Weighting::Isotropic
            } else {
                self.weighting.unwrap_or(Weighting::Sharp)
            },
            lambda: self.lambda.unwrap_or(base.lambda),
            feature: match self.criterion.unwrap_or(CriterionArg::All) {
                CriterionArg::All => FeatureCriterion::AllPoints,
                CriterionArg::Quotient => {
                    FeatureCriterion::EdgeQuotient(self.quotient.unwrap_or(0.3))
                }
                CriterionArg::Principal => FeatureCriterion::PrincipalCurvature(feature_curvature),
                CriterionArg::Directional => {
                    FeatureCriterion::DirectionalCurvature(feature_curvature)
                }
            },
            constrain_interior: self.constrain_interior,
            update_neighbors: self.update_neighbors,
            outputs: true,
            ..base
        }
    }

    /// The library's options of the robust method (orientation set later).
    pub fn robust_options(&self) -> RobustOptions {
        self.robust.options(self.k, self.radius, self.tau)
    }
}

/// What one method's run reports beyond the smoothed cloud.
struct Run {
    result: SmoothResult,
    /// Lines of text and JSON fields that describe the method's settings and course.
    text: String,
    json: serde_json::Value,
}

/// The thesis' isotropic or anisotropic smoothing.
fn run_thesis(a: &Args, points: &[glam::DVec3], out: &Output) -> Result<Run> {
    let opts = SmoothOptions {
        orientation: orientation(a.orient, None, points),
        ..a.options()
    };
    let res = {
        let bar = Progress::bar(out, 1000, "smoothing");
        let mut cb = bar.smoothing_callback("smoothing");
        smooth_with_progress(points, &opts, &mut cb).context(a.input.input.display())?
    };
    let features = res.outputs.iter().filter(|o| o.feature).count();
    let radius_given = length_text(a.radius.unwrap_or(opts.epsilon));
    let lambda_given = curvature_text(a.lambda.unwrap_or(opts.lambda));
    let mut text = format!(
        "{} steps of τ = {}\nneighbourhoods: the {} nearest within ε = {:.6} ({radius_given}; h = \
         {:.6}), smallest {}\n",
        opts.steps, opts.tau, opts.k, res.epsilon, res.spacing, res.min_neighbors,
    );
    if a.method == MethodArg::Anisotropic {
        text += &format!(
            "λ = {:.6} ({lambda_given}), {features} of the result's points are features\n",
            res.lambda
        );
    }
    let json = json!({
        "k": opts.k,
        "radius": num(res.epsilon),
        "radius_given": radius_given,
        "lambda": num(res.lambda),
        "lambda_given": lambda_given,
        "steps": opts.steps,
        "tau": num(opts.tau),
        "feature_points": features,
    });
    Ok(Run {
        result: res,
        text,
        json,
    })
}

/// `n` and the noun, in the plural unless `n` is 1.
fn count(n: usize, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// What the robust run did: iterations, the noise estimates, the neighbourhoods.
fn robust_text(
    opts: &RobustOptions,
    noise: &[f64],
    moved: &[f64],
    res: &nbhd::smooth::SmoothResult,
    radius_given: &str,
) -> String {
    let noise: Vec<String> = noise.iter().map(|v| format!("{v:.3}h")).collect();
    // the estimate is measured before each iteration and once more on the result of the last
    // one, which is what the stopping rule compares: one more estimate than iterations
    let stop = if noise.len() > moved.len() {
        " (the last one, on the result, stopped the iterations)"
    } else {
        ""
    };
    format!(
        "{} (at most {}, stopping once the noise estimate falls by less than {}), τ = {}\n\
         noise estimate σ̂ before each iteration{stop}: {}\nneighbourhoods: the {} nearest \
         within ε = {:.6} ({radius_given}; h = {:.6}), smallest {}; planes over the {} nearest\n",
        count(moved.len(), "iteration"),
        opts.max_iterations,
        opts.tolerance,
        opts.tau,
        noise.join(", "),
        opts.k,
        res.epsilon,
        res.spacing,
        res.min_neighbors,
        opts.k_plane,
    )
}

/// The noise scale's line: the local dimension measured, and the iterations it widened.
fn noise_scale_text(dimension: &[f64], wide: usize, opts: &RobustOptions) -> String {
    if !opts.noise_scale {
        return "noise scale: off (--noise-scale false): the neighbourhoods as given\n".to_string();
    }
    let Some(first) = dimension.first() else {
        return String::new();
    };
    let then = if wide > 0 {
        format!(
            "{} with the {} nearest (planes over {}) while the cloud read as a ball of noise",
            count(wide, "iteration"),
            NOISE_SCALE_FACTOR * opts.k,
            NOISE_SCALE_FACTOR * opts.k_plane
        )
    } else {
        "a surface at this scale: the usual neighbourhoods".to_string()
    };
    format!(
        "noise scale: local dimension {first:.2} (2 a surface, 3 a ball of noise; wider \
         neighbourhoods from {NOISE_SCALE_DIMENSION}): {then}\n"
    )
}

/// A hint where the robust run barely moved the points (RMS displacement below 0.1h): what
/// the noise estimate found and what to change if the cloud is noisier than that.
fn barely_moved_hint(
    points: &[glam::DVec3],
    res: &nbhd::smooth::SmoothResult,
    noise: &[f64],
    opts: &RobustOptions,
) -> String {
    let h = res.spacing;
    if h.is_nan() || h <= 0.0 || points.is_empty() {
        return String::new();
    }
    let ms = res
        .points
        .iter()
        .zip(points)
        .map(|(a, b)| a.distance_squared(*b))
        .sum::<f64>()
        / points.len() as f64;
    let rms = ms.sqrt() / h;
    let sigma = noise.first().copied().unwrap_or(0.0);
    if rms >= 0.1 {
        return String::new();
    }
    format!(
        "note: the points moved by {rms:.3}h (RMS) only. The noise estimate found σ̂ = {sigma:.3}h: \
         at the scale of the {} nearest (a few h) the points lie that close to their local planes, \
         so there is little noise to remove at that scale. Noise that varies more slowly than \
         that (e.g. the depth steps and ripples of structured-light and stereo sensors) reads as \
         surface: to smooth it, widen the neighbourhoods (--k-plane 192 -k 96) and the inlier \
         weight (--inlier-width 10), or use --method isotropic with more --steps.\n",
        opts.k_plane
    )
}

/// The robust smoothing (`nbhd::smooth::robust`).
fn run_robust(a: &Args, points: &[glam::DVec3], out: &Output) -> Result<Run> {
    let opts = RobustOptions {
        orientation: orientation(a.orient, None, points),
        ..a.robust_options()
    };
    let rep = {
        let bar = Progress::bar(out, 1000, "smoothing");
        let mut cb = bar.smoothing_callback("robust smoothing");
        smooth_robust_report(points, &opts, &mut cb).context(a.input.input.display())?
    };
    let res = rep.result;
    let radius_given = length_text(a.radius.unwrap_or(opts.epsilon));
    let text = robust_text(&opts, &rep.noise, &rep.moved, &res, &radius_given)
        + &noise_scale_text(&rep.dimension, rep.wide_iterations, &opts)
        + &barely_moved_hint(points, &res, &rep.noise, &opts);
    let json = json!({
        "k": opts.k,
        "k_plane": opts.k_plane,
        "radius": num(res.epsilon),
        "radius_given": radius_given,
        "iterations": rep.moved.len(),
        "max_iterations": opts.max_iterations,
        "tolerance": num(opts.tolerance),
        "inlier_width": num(opts.inlier_width),
        "feature_angle": num(opts.feature_angle),
        "tau": num(opts.tau),
        "noise_scale": opts.noise_scale,
        "noise_h": rep.noise.iter().map(|&v| num(v)).collect::<Vec<_>>(),
        "local_dimension": rep.dimension.iter().map(|&v| num(v)).collect::<Vec<_>>(),
        "wide_iterations": rep.wide_iterations,
        "moved_h": rep.moved.iter().map(|&v| num(v)).collect::<Vec<_>>(),
    });
    Ok(Run {
        result: res,
        text,
        json,
    })
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    a.check_method_options()?;
    let input = &a.input.input;
    let mut cloud = a.input.read()?;
    let (points, index) = finite_points(&cloud);
    if points.is_empty() {
        return Err(format!("{}: no point with finite coordinates", input.display()).into());
    }
    let t = std::time::Instant::now();
    let run = match a.method {
        MethodArg::Robust => run_robust(&a, &points, out)?,
        MethodArg::Anisotropic | MethodArg::Isotropic => run_thesis(&a, &points, out)?,
    };
    let secs = t.elapsed().as_secs_f64();
    let res = &run.result;
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
    write::add_fields(&mut cloud, &index, &res.outputs, true)?;
    write::cloud(&a.output, &cloud, &a.precision.write_options())?;
    if let Some(png) = &a.png {
        write::surface_variation_png(png, &cloud, a.view, a.up)?;
    }
    let method = a.method.name();
    let mut summary = json!({
        "input": input.display().to_string(),
        "output": a.output.display().to_string(),
        "png": a.png.as_ref().map(|p| p.display().to_string()),
        "points": cloud.len(),
        "skipped_non_finite": cloud.len() - points.len(),
        "method": method,
        "spacing_h": num(res.spacing),
        "min_neighbors": res.min_neighbors,
        "mean_move": num(mean_move),
        "max_move": num(max_move),
        "seconds": num(secs),
    });
    if let (Some(all), Some(own)) = (summary.as_object_mut(), run.json.as_object()) {
        all.extend(own.clone());
    }
    out.json(&summary);
    out.text(format!(
        "{} -> {}: {} points ({} skipped as non-finite) smoothed, method {method}: {}\
         points moved {:.3}h on average, {:.3}h at most; {:.2} s{}",
        input.display(),
        a.output.display(),
        cloud.len(),
        cloud.len() - points.len(),
        run.text,
        mean_move / res.spacing,
        max_move / res.spacing,
        secs,
        a.png
            .as_ref()
            .map_or(String::new(), |p| format!("\npicture {}", p.display())),
    ));
    Ok(())
}
