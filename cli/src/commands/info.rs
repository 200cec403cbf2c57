//! `nbhd info FILE`: what a point-cloud file holds.

use crate::args::FormatArg;
use crate::error::Result;
use crate::output::{num, Output};
use crate::read;
use nbhd::io;
use nbhd::NeighborIndex;
use serde_json::json;
use std::path::PathBuf;

/// Show what a point-cloud file holds: point count, NaN points, bounding box, spacing, fields
///
/// Points with a NaN or infinite coordinate (holes of organized depth scans) are counted
/// but left out of the bounding box and the spacing; they keep their indices, and the tree
/// skips or rejects them. The spacing h is the mean (and median) distance of a finite point
/// to its nearest other point: the unit of every relative length (6h).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The file (.ply, .pcd, .las/.laz, .obj, .xyz/.txt/.pts/.asc/.csv)
    pub file: PathBuf,

    /// Read as this format instead of recognising it by content and extension
    #[arg(long, value_enum)]
    pub format: Option<FormatArg>,
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    let (cloud, info) = read::cloud_info(&a.file, a.format.map(Into::into))?;
    let format = info.format;
    let n = cloud.len();
    let bad = cloud.non_finite_count();
    let bbox = cloud.bounding_box();
    let spacing = spacing(&cloud);
    let scalars: Vec<serde_json::Value> = cloud
        .scalars
        .iter()
        .map(|s| {
            let (lo, hi) = finite_range(&s.values);
            json!({"name": s.name, "min": num(lo), "max": num(hi)})
        })
        .collect();
    out.json(&json!({
        "file": a.file.display().to_string(),
        "format": format.name(),
        "points": n,
        "non_finite": bad,
        "organized": cloud.grid.map(|g| json!({"width": g.width, "height": g.height})),
        "bbox": bbox.map(|b| json!({
            "min": b.min.map(num),
            "max": b.max.map(num),
            "diagonal": num(b.diagonal()),
        })),
        "spacing": spacing.map(|s| json!({"mean": num(s.mean), "median": num(s.median)})),
        "normals": cloud.normals.is_some(),
        "fields": cloud.field_names(),
        "scalars": scalars,
        "precision": match cloud.source_precision {
            Some(io::Precision::Double) => "float64",
            Some(_) => "float32",
            None => "unknown",
        },
        "columns": info.text_columns.as_ref().map(|t| json!({"names": t.names, "from": t.from})),
    }));
    let mut t = String::new();
    t.push_str(&format!("file       {}\n", a.file.display()));
    t.push_str(&format!("format     {}\n", format.name()));
    if let Some(note) = read::columns_note(&info) {
        t.push_str(&format!("read as    {note}\n"));
    }
    t.push_str(&format!("points     {n}\n"));
    t.push_str(&format!(
        "non-finite {bad}{}\n",
        if n > 0 {
            format!(" ({:.1}%)", 100.0 * bad as f64 / n as f64)
        } else {
            String::new()
        }
    ));
    if let Some(g) = cloud.grid {
        t.push_str(&format!("organized  {} x {}\n", g.width, g.height));
    }
    match bbox {
        Some(b) => {
            let f = |v: [f64; 3]| format!("{:.6} {:.6} {:.6}", v[0], v[1], v[2]);
            t.push_str(&format!("bbox min   {}\n", f(b.min)));
            t.push_str(&format!("bbox max   {}\n", f(b.max)));
            t.push_str(&format!("diagonal   {:.6}\n", b.diagonal()));
        }
        None => t.push_str("bbox       (no finite point)\n"),
    }
    match spacing {
        Some(s) => t.push_str(&format!(
            "spacing h  mean {:.6}, median {:.6} (nearest-neighbour distance)\n",
            s.mean, s.median
        )),
        None => t.push_str("spacing h  (fewer than two finite points)\n"),
    }
    t.push_str(&format!("fields     {}\n", cloud.field_names().join(" ")));
    t.push_str(&format!(
        "normals    {}",
        if cloud.normals.is_some() { "yes" } else { "no" }
    ));
    for s in &cloud.scalars {
        let (lo, hi) = finite_range(&s.values);
        t.push_str(&format!("\nscalar     {} in [{lo}, {hi}]", s.name));
    }
    out.text(t);
    Ok(())
}

/// The nearest-neighbour spacing of the finite points (`None` with fewer than two).
fn spacing(cloud: &io::PointCloud) -> Option<nbhd::Spacing> {
    let view = cloud.view().ok()?;
    let opts = nbhd::BuildOptions {
        non_finite: nbhd::NonFinitePolicy::Skip,
        ..nbhd::BuildOptions::default()
    };
    let tree = nbhd::KdTree::<f64>::build(&view, &opts).ok()?;
    tree.spacing(0).ok()
}

fn finite_range(v: &[f64]) -> (f64, f64) {
    v.iter()
        .filter(|x| x.is_finite())
        .fold((f64::NAN, f64::NAN), |(a, b), &x| (a.min(x), b.max(x)))
}
