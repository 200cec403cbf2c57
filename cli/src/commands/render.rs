//! `nbhd render IN OUT.png`: a picture of a point cloud.

use crate::args::{parse_vec3, InputArgs};
use crate::error::{Context, Result};
use crate::output::Output;
use crate::render::{render_cloud, ColorMap, RenderOptions};
use crate::write;
use nbhd::io;
use serde_json::json;
use std::path::PathBuf;

/// Draw a point cloud into a PNG picture
///
/// Orthographic splats seen along --view, coloured by a scalar field (e.g. curvature) through
/// a colour map from its minimum to its maximum, or in one flat colour. With normals in the
/// file a fixed light shades the surface; without, farther points are drawn darker.
/// NaN points are left out.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    /// Output picture (.png)
    pub output: PathBuf,

    /// Colour by this scalar field (e.g. curvature, intensity), a coordinate (x, y, z), or
    /// rgb for the scan's own colours
    #[arg(long, short)]
    pub color: Option<String>,

    /// Colour map for --color
    #[arg(long, value_enum, default_value = "viridis")]
    pub colormap: ColorMap,

    /// Viewing direction x,y,z: the way the camera looks, into the scene
    #[arg(long, default_value = "-1,-1,-1", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub view: [f64; 3],

    /// World direction x,y,z shown upwards
    #[arg(long, default_value = "0,1,0", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: [f64; 3],

    /// Picture width in pixels
    #[arg(long, default_value_t = 800)]
    pub width: u32,

    /// Picture height in pixels
    #[arg(long, default_value_t = 600)]
    pub height: u32,

    /// Splat radius in pixels [default: from the point density]
    #[arg(long)]
    pub point_radius: Option<f64>,
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    let input = &a.input.input;
    // The plain reader: `render` reads text columns as the library guesses them, without the
    // global --columns and without the note on them.
    let (cloud, _) = io::read_as(input, a.input.from.map(Into::into))?;
    if a.width == 0 || a.height == 0 || a.width > 16384 || a.height > 16384 {
        return Err("--width and --height must be between 1 and 16384".into());
    }
    let opts = RenderOptions {
        width: a.width,
        height: a.height,
        view: a.view,
        up: a.up,
        point_radius: a.point_radius,
        colormap: a.colormap,
        ..RenderOptions::default()
    };
    let img = render_cloud(&cloud, a.color.as_deref(), &opts).context(input.display())?;
    write::png(&a.output, &img)?;
    let covered = img.coverage(opts.background);
    out.json(&json!({
        "input": input.display().to_string(),
        "output": a.output.display().to_string(),
        "points": cloud.len(),
        "drawn": cloud.len() - cloud.non_finite_count(),
        "width": a.width,
        "height": a.height,
        "covered_pixels": covered,
    }));
    out.text(format!(
        "{}: {} x {} picture of {} points ({} pixels covered)",
        a.output.display(),
        a.width,
        a.height,
        cloud.len() - cloud.non_finite_count(),
        covered
    ));
    Ok(())
}
