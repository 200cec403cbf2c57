//! `nbhd crop`, `nbhd sor`, `nbhd ror`: keep the points inside a box, or remove statistical
//! or radius outliers, and write the kept points (with their normals and fields) to a file.
//! Points with a NaN coordinate are never kept.

use crate::args::{length_text, parse_length, parse_vec3, InputArgs, PrecisionArgs};
use crate::error::{Context, Result};
use crate::output::{ms, num, Output};
use crate::write;
use nbhd::filter::{
    radius_outlier_removal, statistical_outlier_removal, voxel_grid, RadiusOutlierOptions,
    StatisticalOutlierOptions, VoxelGrid, VoxelGridOptions,
};
use nbhd::io::{PointCloud, Precision, ScalarField};
use nbhd::smooth::Length;
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, NonFinitePolicy};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Keep the points inside an axis-aligned box (closed: min <= x <= max), like PCL's CropBox
#[derive(clap::Args, Debug)]
pub struct CropArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file (.ply, .pcd, .las/.laz, .xyz)
    pub output: PathBuf,
    /// Lower corner x,y,z (a coordinate may be -inf)
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub min: [f64; 3],
    /// Upper corner x,y,z (a coordinate may be inf)
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub max: [f64; 3],
    #[command(flatten)]
    pub precision: PrecisionArgs,
}

/// Remove statistical outliers (PCL StatisticalOutlierRemoval, Open3D remove_statistical_outlier)
///
/// A point is kept when its mean distance to its k nearest other points is at most
/// mean + std-ratio × σ over all points (σ the sample standard deviation).
#[derive(clap::Args, Debug)]
pub struct SorArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file (.ply, .pcd, .las/.laz, .xyz)
    pub output: PathBuf,
    /// Nearest other points averaged (PCL's setMeanK)
    #[arg(long, short, default_value_t = StatisticalOutlierOptions::default().k)]
    pub k: usize,
    /// Multiple of σ above the mean that is still kept (PCL's setStddevMulThresh)
    #[arg(long, default_value_t = StatisticalOutlierOptions::default().std_ratio, allow_hyphen_values = true)]
    pub std_ratio: f64,
    #[command(flatten)]
    pub precision: PrecisionArgs,
}

/// Remove radius outliers (PCL RadiusOutlierRemoval, Open3D remove_radius_outlier)
///
/// A point is kept when at least --min-neighbors other points lie within --radius
/// (inclusive); the radius is in the points' units (0.05) or in the mean spacing h (3h).
#[derive(clap::Args, Debug)]
pub struct RorArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file (.ply, .pcd, .las/.laz, .xyz)
    pub output: PathBuf,
    /// Radius: a length like 0.05, or a multiple of the mean spacing h like 3h
    #[arg(long, short, value_parser = parse_length)]
    pub radius: Length,
    /// Other points needed within the radius (PCL's setMinNeighborsInRadius)
    #[arg(long, short, default_value_t = RadiusOutlierOptions::within(0.0).min_neighbors)]
    pub min_neighbors: usize,
    #[command(flatten)]
    pub precision: PrecisionArgs,
}

/// Downsample on a voxel grid (PCL VoxelGrid, Open3D voxel_down_sample)
///
/// One point per occupied voxel, in PCL's order: the centroid of the voxel's points, with
/// their fields averaged (normals averaged and renormalised); or, with --nearest, the
/// original point nearest that centroid, with its own fields. Float files are computed in
/// float, as PCL does.
#[derive(clap::Args, Debug)]
pub struct VoxelArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file (.ply, .pcd, .las/.laz, .xyz)
    pub output: PathBuf,
    /// Voxel edge: a length like 0.01, or a multiple of the mean spacing h like 3h
    #[arg(long, short, value_parser = parse_length)]
    pub leaf: Length,
    /// Keep the original point nearest each centroid instead of the centroid
    #[arg(long)]
    pub nearest: bool,
    /// Leave out voxels with fewer points (PCL's setMinimumPointsNumberPerVoxel)
    #[arg(long, default_value_t = 0)]
    pub min_points: usize,
    #[command(flatten)]
    pub precision: PrecisionArgs,
}

/// The tree over the finite points of `cloud` (NaN points skipped, indices kept).
fn tree(cloud: &PointCloud, name: &str) -> Result<KdTree<f64>> {
    let view = cloud.view().context(name)?;
    let opts = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    KdTree::build(&view, &opts).context(name)
}

/// The points `kept` (ascending indices) of `cloud`, with their normals and fields.
fn subset(cloud: &PointCloud, kept: &[u32]) -> PointCloud {
    let pick = |v: &[f64]| kept.iter().map(|&i| v[i as usize]).collect();
    PointCloud {
        positions: kept.iter().map(|&i| cloud.positions[i as usize]).collect(),
        normals: cloud
            .normals
            .as_ref()
            .map(|n| kept.iter().map(|&i| n[i as usize]).collect()),
        scalars: cloud
            .scalars
            .iter()
            .map(|s| ScalarField {
                name: s.name.clone(),
                values: pick(&s.values),
            })
            .collect(),
        grid: None,
        source_precision: cloud.source_precision,
        metadata: cloud.metadata.clone(),
    }
}

/// Writes the kept points and reports.
#[allow(clippy::too_many_arguments)]
fn finish(
    what: &str,
    input: &std::path::Path,
    output: &std::path::Path,
    cloud: &PointCloud,
    kept: &[u32],
    precision: &PrecisionArgs,
    extra: serde_json::Value,
    millis: f64,
    out: &Output,
) -> Result<()> {
    let stored = write::cloud(output, &subset(cloud, kept), &precision.write_options())?;
    out.json(&json!({
        "command": what,
        "input": input.display().to_string(),
        "output": output.display().to_string(),
        "points": cloud.len(),
        "kept": kept.len(),
        "removed": cloud.len() - kept.len(),
        "parameters": extra,
        "filter_ms": num(millis),
        "precision": stored,
    }));
    out.text(format!(
        "{what}: kept {} of {} points ({} removed, NaN points included) in {millis:.1} ms -> {}",
        kept.len(),
        cloud.len(),
        cloud.len() - kept.len(),
        output.display()
    ));
    Ok(())
}

pub fn run_crop(a: CropArgs, out: &Output) -> Result<()> {
    let name = a.input.input.display().to_string();
    let cloud = a.input.read()?;
    let tree = tree(&cloud, &name)?;
    let t = Instant::now();
    let mut kept = Vec::new();
    tree.in_box(&a.min, &a.max, &mut kept)?;
    let extra = json!({"min": a.min.map(num), "max": a.max.map(num)});
    finish(
        "crop",
        &a.input.input,
        &a.output,
        &cloud,
        &kept,
        &a.precision,
        extra,
        ms(t),
        out,
    )
}

pub fn run_sor(a: SorArgs, out: &Output) -> Result<()> {
    let name = a.input.input.display().to_string();
    let cloud = a.input.read()?;
    let tree = tree(&cloud, &name)?;
    let t = Instant::now();
    let opts = StatisticalOutlierOptions {
        k: a.k,
        std_ratio: a.std_ratio,
        threads: 0,
    };
    let kept = statistical_outlier_removal(&tree, &opts).context(&name)?;
    let extra = json!({"k": a.k, "std_ratio": num(a.std_ratio)});
    finish(
        "sor",
        &a.input.input,
        &a.output,
        &cloud,
        &kept.indices,
        &a.precision,
        extra,
        ms(t),
        out,
    )
}

pub fn run_ror(a: RorArgs, out: &Output) -> Result<()> {
    let name = a.input.input.display().to_string();
    let cloud = a.input.read()?;
    let tree = tree(&cloud, &name)?;
    let t = Instant::now();
    let h = match a.radius {
        Length::Relative(_) => tree.spacing(0).context(&name)?.mean,
        _ => 1.0,
    };
    let radius = a.radius.resolve(h);
    let opts = RadiusOutlierOptions {
        radius,
        min_neighbors: a.min_neighbors,
        threads: 0,
    };
    let kept = radius_outlier_removal(&tree, &opts).context(&name)?;
    let extra = json!({
        "radius": length_text(a.radius),
        "radius_resolved": num(radius),
        "min_neighbors": a.min_neighbors,
    });
    finish(
        "ror",
        &a.input.input,
        &a.output,
        &cloud,
        &kept.indices,
        &a.precision,
        extra,
        ms(t),
        out,
    )
}

/// The centroid cloud of `g`: positions, averaged normals (renormalised) and fields.
fn centroid_cloud<T: nbhd::Scalar>(cloud: &PointCloud, g: &VoxelGrid<T>) -> PointCloud {
    let mean =
        |v: &[f64], m: &[u32]| m.iter().map(|&i| v[i as usize]).sum::<f64>() / m.len() as f64;
    let voxels = 0..g.len();
    PointCloud {
        positions: voxels
            .clone()
            .map(|v| {
                let c = g.centroid(v);
                [c[0].to_f64(), c[1].to_f64(), c[2].to_f64()]
            })
            .collect(),
        normals: cloud.normals.as_ref().map(|n| {
            voxels
                .clone()
                .map(|v| {
                    let mut s = [0.0; 3];
                    for &i in g.members_of(v) {
                        (0..3).for_each(|a| s[a] += n[i as usize][a]);
                    }
                    let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
                    if len > 0.0 {
                        s.map(|x| x / len)
                    } else {
                        s
                    }
                })
                .collect()
        }),
        scalars: cloud
            .scalars
            .iter()
            .map(|f| ScalarField {
                name: f.name.clone(),
                values: voxels
                    .clone()
                    .map(|v| mean(&f.values, g.members_of(v)))
                    .collect(),
            })
            .collect(),
        grid: None,
        source_precision: cloud.source_precision,
        metadata: cloud.metadata.clone(),
    }
}

pub fn run_voxel(a: VoxelArgs, out: &Output) -> Result<()> {
    let name = a.input.input.display().to_string();
    let cloud = a.input.read()?;
    let leaf = match a.leaf {
        Length::Relative(_) => a
            .leaf
            .resolve(tree(&cloud, &name)?.spacing(0).context(&name)?.mean),
        _ => a.leaf.resolve(1.0),
    };
    let view = cloud.view().context(&name)?;
    let opts = VoxelGridOptions {
        leaf: vec![leaf],
        min_points_per_voxel: a.min_points,
        threads: 0,
    };
    let t = Instant::now();
    let single = cloud.source_precision == Some(Precision::Single);
    let (result, voxels) = if single {
        let g = voxel_grid::<f32>(&view, &opts).context(&name)?;
        let c = (!a.nearest).then(|| centroid_cloud(&cloud, &g));
        let n = g.len();
        (c.ok_or(g.nearest), n)
    } else {
        let g = voxel_grid::<f64>(&view, &opts).context(&name)?;
        let c = (!a.nearest).then(|| centroid_cloud(&cloud, &g));
        let n = g.len();
        (c.ok_or(g.nearest), n)
    };
    let millis = ms(t);
    let written = match &result {
        Ok(c) => c.clone(),
        Err(nearest) => subset(&cloud, nearest),
    };
    let stored = write::cloud(&a.output, &written, &a.precision.write_options())?;
    out.json(&json!({
        "command": "voxel",
        "input": a.input.input.display().to_string(),
        "output": a.output.display().to_string(),
        "points": cloud.len(),
        "voxels": voxels,
        "parameters": {
            "leaf": length_text(a.leaf),
            "leaf_resolved": num(leaf),
            "nearest": a.nearest,
            "min_points": a.min_points,
            "arithmetic": if single { "f32" } else { "f64" },
        },
        "filter_ms": num(millis),
        "precision": stored,
    }));
    out.text(format!(
        "voxel: {} points -> {voxels} {} (leaf {}) in {millis:.1} ms -> {}",
        cloud.len(),
        if a.nearest {
            "nearest points"
        } else {
            "centroids"
        },
        num(leaf),
        a.output.display()
    ));
    Ok(())
}
