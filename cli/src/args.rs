//! Command-line arguments that several commands share: the input file and its format, the
//! precision of written files, how the k-d tree is built, how normals are oriented, and the
//! parsers of lengths (`6h`), curvatures (`0.2/h`) and vectors (`x,y,z`).

use crate::error::Result;
use glam::DVec3;
use nbhd::geometry::Orientation;
use nbhd::io::{Format, PointCloud};
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

/// Pivot policy of the k-d tree (thesis Sections 3.2 and 5.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PivotArg {
    /// Dimensions in turn, split at the median (thesis Algorithm 4)
    CyclicMedian,
    /// Median of the dimension of largest spread (Omohundro)
    SpreadMedian,
    /// Point closest to the middle of the most spread dimension (Moore, eq. 5.1); unbalanced
    ClosestToMiddle,
    /// Middle of the most spread dimension, slid to the nearest point (ANN, FLANN)
    SlidingMidpoint,
}

impl From<PivotArg> for PivotPolicy {
    fn from(p: PivotArg) -> Self {
        match p {
            PivotArg::CyclicMedian => PivotPolicy::CyclicMedian,
            PivotArg::SpreadMedian => PivotPolicy::SpreadMedian,
            PivotArg::ClosestToMiddle => PivotPolicy::ClosestToMiddle,
            PivotArg::SlidingMidpoint => PivotPolicy::SlidingMidpoint,
        }
    }
}

/// How the median policies find the median (thesis Section 3.3 and Chapter 6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MedianArg {
    /// Lists presorted once and kept sorted by stable partition (Algorithm 6, "Sorting")
    Presorted,
    /// Sort each node's points, then pick ("Median (Sorting)")
    Sort,
    /// Randomised quickselect, median-of-three pivot (Algorithm 10)
    Quickselect,
    /// Floyd-Rivest selection ("Median (Floyd-Rivest)")
    FloydRivest,
    /// Deterministic median of medians (Algorithm 11, "Median (Linear Det.)")
    MedianOfMedians,
}

impl From<MedianArg> for MedianAlgorithm {
    fn from(m: MedianArg) -> Self {
        match m {
            MedianArg::Presorted => MedianAlgorithm::Presorted,
            MedianArg::Sort => MedianAlgorithm::Sort,
            MedianArg::Quickselect => MedianAlgorithm::Quickselect,
            MedianArg::FloydRivest => MedianAlgorithm::FloydRivest,
            MedianArg::MedianOfMedians => MedianAlgorithm::MedianOfMedians,
        }
    }
}

/// How the k-d tree is built.
#[derive(clap::Args, Debug, Clone)]
pub struct TreeArgs {
    /// Pivot policy: how a node picks its splitting dimension and value
    #[arg(long, value_enum, default_value = "sliding-midpoint")]
    pub pivot: PivotArg,

    /// Median algorithm of the median policies (every one gives the identical tree)
    #[arg(long, value_enum, default_value = "floyd-rivest")]
    pub median: MedianArg,

    /// Most points in a leaf bucket (1 gives the thesis' one point per node)
    #[arg(long, default_value_t = nbhd::tree::DEFAULT_LEAF_SIZE)]
    pub leaf_size: usize,
}

impl TreeArgs {
    /// Build options; points with a NaN or infinite coordinate are skipped (they keep their
    /// indices and get empty neighbourhoods).
    pub fn options(&self) -> BuildOptions {
        BuildOptions {
            pivot: self.pivot.into(),
            median: self.median.into(),
            leaf_size: self.leaf_size,
            non_finite: NonFinitePolicy::Skip,
            threads: 0,
        }
    }
}

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
