//! Command-line arguments that several commands share: the input file and its format, the
//! precision of written files, how the k-d tree is built, how normals are oriented, the robust
//! smoothing's options, and the parsers of lengths (`6h`), curvatures (`0.2/h`) and vectors
//! (`x,y,z`).

use crate::error::Result;
use glam::DVec3;
use nbhd::geometry::{Orientation, OrientationKind};
use nbhd::io::{Format, PointCloud};
use nbhd::names::OptionName;
use nbhd::smooth::robust::RobustOptions;
use nbhd::smooth::{Curvature, Length};
use nbhd::{BuildOptions, MedianAlgorithm, NonFinitePolicy, PivotPolicy};
use std::path::PathBuf;

/// The input of a command: a point-cloud file and, if its content and extension are not to be
/// trusted, its format. Each command words the help of `<INPUT>` for itself (`mut_arg`), since
/// commands treat NaN points and formats differently.
#[derive(clap::Args, Debug, Clone)]
pub struct InputArgs {
    /// Input file (.ply, .pcd, .las/.laz, .obj, .xyz/.txt/.pts/.asc/.csv)
    pub input: PathBuf,

    /// Read the input as this format instead of recognising it
    #[arg(long, value_enum)]
    pub from: Option<FormatArg>,
}

impl InputArgs {
    /// Reads the input with the global `--columns`; see [`crate::read::cloud`].
    pub fn read(&self) -> Result<PointCloud> {
        crate::read::cloud(&self.input, self.from.map(Into::into))
    }

    /// Reads the input with the global `--columns`, and tells what was read.
    pub fn read_info(&self) -> Result<(PointCloud, nbhd::io::ReadInfo)> {
        crate::read::cloud_info(&self.input, self.from.map(Into::into))
    }
}

/// Input format named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    Ply,
    Pcd,
    Obj,
    /// LAS or LAZ
    Las,
    Xyz,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Ply => Format::Ply,
            FormatArg::Pcd => Format::Pcd,
            FormatArg::Obj => Format::Obj,
            FormatArg::Las => Format::Las,
            FormatArg::Xyz => Format::Xyz,
        }
    }
}

/// Width of the stored floats of an output file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PrecisionArg {
    /// 32-bit float: what PCL's point types (PointXYZ, PointNormal, ...) load; ~7 digits
    Single,
    /// 64-bit double: exact, but PCL's float point types do not load it
    Double,
    /// Double if the input held its coordinates more precisely than float (PLY double, PCD
    /// F 8, LAS, text with more digits), float otherwise
    Keep,
}

impl From<PrecisionArg> for nbhd::io::Precision {
    fn from(p: PrecisionArg) -> Self {
        match p {
            PrecisionArg::Single => nbhd::io::Precision::Single,
            PrecisionArg::Double => nbhd::io::Precision::Double,
            PrecisionArg::Keep => nbhd::io::Precision::Keep,
        }
    }
}

/// The `--precision` option of the commands that write a point-cloud file.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct PrecisionArgs {
    /// Width of the stored coordinates, normals and scalar fields (colours are always 8-bit)
    #[arg(long, short = 'p', value_enum, default_value = "single")]
    pub precision: PrecisionArg,

    /// The same as --precision single, the default (kept for older scripts)
    #[arg(long, hide = true)]
    pub single: bool,
}

impl PrecisionArgs {
    /// The library's precision.
    pub fn get(&self) -> nbhd::io::Precision {
        self.precision.into()
    }

    /// Write options with this precision and the format's default encoding.
    pub fn write_options(&self) -> nbhd::io::WriteOptions {
        nbhd::io::WriteOptions {
            precision: self.get(),
            ..nbhd::io::WriteOptions::default()
        }
    }
}

/// The robust smoothing's own options (`nbhd::smooth::robust`), for `smooth` and `tiles`: the
/// wide neighbourhood, the iterations and their stopping rule, the inlier weight, the feature
/// angle and the noise scale.
#[derive(clap::Args, Debug, Clone)]
pub struct RobustArgs {
    /// Robust: size of the wide neighbourhood the candidate planes are fitted and scored on
    /// (≥ k) [default: 48]: planes that tell a face from the chamfer across an edge at noise
    /// of about one spacing; tripled by itself, as k, while the cloud reads as a ball of noise
    #[arg(long)]
    pub k_plane: Option<usize>,

    /// Robust: at most this many iterations [default: 10]; the stopping rule usually ends
    /// earlier (2–4 on clean or smooth clouds, 6–9 on flat faces or strong noise)
    #[arg(long)]
    pub iterations: Option<usize>,

    /// Robust: stop once an iteration lowered the noise estimate by less than this fraction
    /// [default: 0.05]; one value for every noise level (a clean cloud stops after one
    /// iteration); 0 runs all --iterations
    #[arg(long, allow_hyphen_values = true)]
    pub tolerance: Option<f64>,

    /// Robust: width of the inlier weight of plane distances, in units of the estimated noise
    /// [default: 5], so the same value suits every noise level; larger smooths across
    /// structured noise the estimate does not see (sensor ripples), smaller keeps finer detail
    #[arg(long, allow_hyphen_values = true)]
    pub inlier_width: Option<f64>,

    /// Robust: angle in degrees between normals at which neighbours count as across a feature
    /// [default: 20]: for every shape; smaller keeps the edges of machined parts sharper but
    /// lets strongly curved surfaces drift outward slightly
    #[arg(long, allow_hyphen_values = true)]
    pub feature_angle: Option<f64>,

    /// Robust: scale the neighbourhoods from the noise [default: true]: while the cloud reads
    /// as a ball of noise (noise of about two spacings or more, as in dense scans of noisy
    /// sensors), iterate with k and --k-plane tripled; clouds with noise up to about 1.5
    /// spacings are smoothed the same either way. false keeps k and --k-plane as given
    #[arg(long)]
    pub noise_scale: Option<bool>,
}

impl RobustArgs {
    /// Each option's flag and whether it was given.
    pub fn given(&self) -> [(&'static str, bool); 6] {
        [
            ("--k-plane", self.k_plane.is_some()),
            ("--iterations", self.iterations.is_some()),
            ("--tolerance", self.tolerance.is_some()),
            ("--inlier-width", self.inlier_width.is_some()),
            ("--feature-angle", self.feature_angle.is_some()),
            ("--noise-scale", self.noise_scale.is_some()),
        ]
    }

    /// The library's options with these and `k`, ε (`radius`) and τ (`tau`), the library's
    /// defaults for what is not given, and the per-point outputs on (orientation set later).
    pub fn options(
        &self,
        k: Option<usize>,
        radius: Option<Length>,
        tau: Option<f64>,
    ) -> RobustOptions {
        let d = RobustOptions::default();
        RobustOptions {
            k: k.unwrap_or(d.k),
            k_plane: self.k_plane.unwrap_or(d.k_plane),
            epsilon: radius.unwrap_or(d.epsilon),
            max_iterations: self.iterations.unwrap_or(d.max_iterations),
            tolerance: self.tolerance.unwrap_or(d.tolerance),
            inlier_width: self.inlier_width.unwrap_or(d.inlier_width),
            feature_angle: self.feature_angle.unwrap_or(d.feature_angle),
            tau: tau.unwrap_or(d.tau),
            noise_scale: self.noise_scale.unwrap_or(d.noise_scale),
            outputs: true,
            ..d
        }
    }
}

/// Parses `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not three numbers x,y,z"))?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("'{s}' is not three numbers x,y,z"))
}

/// Parses a length: `0.05` in the points' units, or `6h` in units of the mean spacing `h`
/// (mean distance of a point to its nearest other point). Range checks are the library's.
/// The sizes of `--boxsize`: a periodic box's size per axis (0 for an open axis), or one for
/// every axis; the library checks them when it builds the tree.
#[derive(Clone, Debug)]
pub struct BoxSize(pub Vec<f64>);

pub fn parse_boxsize(s: &str) -> Result<BoxSize, String> {
    s.split(',')
        .map(|v| v.trim().parse::<f64>().map_err(|e| format!("{v:?}: {e}")))
        .collect::<Result<Vec<_>, _>>()
        .map(BoxSize)
}

pub fn parse_length(s: &str) -> Result<Length, String> {
    let t = s.trim();
    let bad = || format!("'{s}' is not a length (a number like 0.05, or a multiple of h like 6h)");
    match t.strip_suffix('h') {
        Some(v) => v.trim().parse().map(Length::Relative).map_err(|_| bad()),
        None => t.parse().map(Length::Absolute).map_err(|_| bad()),
    }
}

/// Parses a curvature: `3.5` in inverse units of the points, or `0.2/h` in units of `1/h`.
pub fn parse_curvature(s: &str) -> Result<Curvature, String> {
    let t = s.trim();
    let bad =
        || format!("'{s}' is not a curvature (a number like 3.5, or a multiple of 1/h like 0.2/h)");
    match t.strip_suffix("/h") {
        Some(v) => v.trim().parse().map(Curvature::Relative).map_err(|_| bad()),
        None => t.parse().map(Curvature::Absolute).map_err(|_| bad()),
    }
}

/// A length as text, as the user would type it.
pub fn length_text(l: Length) -> String {
    match l {
        Length::Absolute(v) => format!("{v}"),
        Length::Relative(v) => format!("{v}h"),
    }
}

/// A curvature as text, as the user would type it.
pub fn curvature_text(c: Curvature) -> String {
    match c {
        Curvature::Absolute(v) => format!("{v}"),
        Curvature::Relative(v) => format!("{v}/h"),
    }
}

/// A parser of the values of the library's option `T` by their names (`nbhd::names`), the words
/// Python takes too: the names are listed in the help, older spellings accepted but not shown.
pub fn named<T>() -> impl clap::builder::TypedValueParser<Value = T>
where
    T: OptionName + Send + Sync,
{
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let shown = T::NAMES.iter().map(|&(_, n)| PossibleValue::new(n));
    let hidden = T::ALIASES
        .iter()
        .map(|&(n, _)| PossibleValue::new(n).hide(true));
    PossibleValuesParser::new(shown.chain(hidden))
        .map(|s| nbhd::names::parse_name::<T>(&s).expect("one of the possible values"))
}

/// How the k-d tree is built.
#[derive(clap::Args, Debug, Clone)]
pub struct TreeArgs {
    /// Pivot policy: how a node picks its splitting dimension and value (thesis Sections 3.2
    /// and 5.4): dimensions in turn split at the median (cyclic-median, Algorithm 4), the median
    /// of the most spread dimension (spread-median), the point closest to its middle
    /// (closest-to-middle, unbalanced), or its middle slid to the nearest point
    /// (sliding-midpoint, ANN and FLANN)
    #[arg(long, value_parser = named::<PivotPolicy>(), default_value = "sliding-midpoint")]
    pub pivot: PivotPolicy,

    /// Median algorithm of the median policies (every one gives the identical tree; thesis
    /// Section 3.3 and Chapter 6)
    #[arg(long, value_parser = named::<MedianAlgorithm>(), default_value = "floyd-rivest")]
    pub median: MedianAlgorithm,

    /// Most points in a leaf bucket (1 gives the thesis' one point per node)
    #[arg(long, default_value_t = nbhd::tree::DEFAULT_LEAF_SIZE)]
    pub leaf_size: usize,
}

impl TreeArgs {
    /// Build options; points with a NaN or infinite coordinate are skipped (they keep their
    /// indices and get empty neighbourhoods).
    pub fn options(&self) -> BuildOptions {
        BuildOptions {
            pivot: self.pivot,
            median: self.median,
            leaf_size: self.leaf_size,
            non_finite: NonFinitePolicy::Skip,
            threads: 0,
        }
    }
}

/// How normals are oriented (covariance normals have no sign of their own): the library's
/// orientations by name, or `outward`, away from the centroid of the points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrientArg {
    /// One of the library's orientations (`unoriented`, also `none`; `toward-point` and
    /// `away-from-point` about the viewpoint; `propagate`).
    Kind(OrientationKind),
    /// Away from the centroid of the points (outward for star-shaped objects).
    Outward,
}

/// Parses `--orient`: the library's names of the orientations, or `outward`.
pub fn parse_orient(s: &str) -> std::result::Result<OrientArg, String> {
    if s == "outward" {
        return Ok(OrientArg::Outward);
    }
    s.parse::<OrientationKind>()
        .map(OrientArg::Kind)
        .map_err(|e| format!("{e}, or outward"))
}

/// The orientation the arguments ask for, given the points.
pub fn orientation(
    orient: OrientArg,
    viewpoint: Option<[f64; 3]>,
    points: &[DVec3],
) -> Orientation {
    let centroid = || points.iter().fold(DVec3::ZERO, |a, &p| a + p) / points.len().max(1) as f64;
    match (orient, viewpoint) {
        (OrientArg::Kind(OrientationKind::AwayFromPoint), Some(v)) => {
            Orientation::AwayFrom(DVec3::from_array(v))
        }
        // a viewpoint orients toward it
        (_, Some(v)) => Orientation::TowardViewpoint(DVec3::from_array(v)),
        (OrientArg::Outward | OrientArg::Kind(OrientationKind::AwayFromPoint), None) => {
            Orientation::AwayFrom(centroid())
        }
        (OrientArg::Kind(kind), None) => Orientation::of_kind(kind, centroid()),
    }
}
