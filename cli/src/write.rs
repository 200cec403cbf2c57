//! Writing results, for every command that writes point clouds or their pictures: the normals
//! and curvature fields of a smoothing result, point-cloud files at the precision asked for,
//! and pictures coloured by the surface variation.

use crate::error::{Context, Result};
use crate::render::{render_cloud, ColorMap, Image, RenderOptions};
use nbhd::geometry::NormalEstimate;
use nbhd::io::{Format, PointCloud, Precision, WriteOptions};
use nbhd::smooth::PointOutput;
use std::path::Path;

/// Surface variation λ0/(λ0+λ1+λ2) drawn at the hot end of the colour map. The covariance
/// quotient of the thesis' program ('CovQuotient', Section 7.3) and PCL's `curvature`: 0 on a
/// plane, about 0.02 on faces with 0.5h noise, 0.06–0.16 along a cube edge. The pictures of all
/// shapes and stages share this scale.
pub const SURFACE_VARIATION_RANGE: f64 = 0.08;

/// Adds normals and per-point fields of `outputs` (computed on the finite points `index` of
/// `cloud`, in that order) to `cloud`; NaN for skipped points.
///
/// `curvature` is what PCL's `PointNormal::curvature` holds, the surface variation
/// λ0/(λ0+λ1+λ2) of the neighbourhood's covariance (thesis eq. 2.8; 0 on a plane, at most 1/3).
/// `all` adds the principal curvatures `k1`, `k2` (Weingarten estimate, eq. 2.25, signed
/// against the normal), `mean_curvature` (k1+k2)/2 and `max_abs_curvature` max(|k1|,|k2|)
/// ('Max Princ').
pub fn add_fields(
    cloud: &mut PointCloud,
    index: &[usize],
    outputs: &[PointOutput],
    all: bool,
) -> Result<()> {
    let n = cloud.len();
    let mut normals = vec![[f64::NAN; 3]; n];
    for (&i, o) in index.iter().zip(outputs) {
        normals[i] = o.normal.to_array();
    }
    cloud.set_normals(normals)?;
    let mut field = |name: &str, f: &dyn Fn(&PointOutput) -> f64| -> Result<()> {
        let mut v = vec![f64::NAN; n];
        for (&i, o) in index.iter().zip(outputs) {
            v[i] = f(o);
        }
        Ok(cloud.set_scalar(name, v)?)
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

/// Adds the normals of `estimates` (of the points `index`, the others NaN) to `cloud`, and their
/// surface variation as the `curvature` field (PCL's name).
pub fn add_normals(
    cloud: &mut PointCloud,
    index: &[usize],
    estimates: &[NormalEstimate],
) -> Result<()> {
    let n = cloud.len();
    let (mut normals, mut variation) = (vec![[f64::NAN; 3]; n], vec![f64::NAN; n]);
    for (&i, e) in index.iter().zip(estimates) {
        normals[i] = e.normal.to_array();
        variation[i] = e.surface_variation;
    }
    cloud.set_normals(normals)?;
    Ok(cloud.set_scalar("curvature", variation)?)
}

/// `float32` or `float64`: what `precision` writes for `cloud`.
pub fn precision_text(precision: Precision, cloud: &PointCloud) -> &'static str {
    if precision.is_single_for(cloud) {
        "float32"
    } else {
        "float64"
    }
}

/// Writes `cloud` to `path` (format from the extension unless `opts` names one); errors name
/// the file. Says on standard error (unless --quiet or --json) what the format has no place
/// for. Returns `float32` or `float64`, what was written.
pub fn cloud(path: &Path, cloud: &PointCloud, opts: &WriteOptions) -> Result<&'static str> {
    nbhd::io::write(path, cloud, opts)?;
    let format = opts.format.or_else(|| Format::from_path(path));
    let dropped = format.map_or_else(Vec::new, |f| nbhd::io::not_written(cloud, f));
    if let (false, Some(f)) = (dropped.is_empty(), format) {
        crate::read::note(format!(
            "{}: not written ({} has no place for them): {}",
            path.display(),
            f.name(),
            dropped.join("; ")
        ));
    }
    Ok(precision_text(opts.precision, cloud))
}

/// A picture of `cloud` coloured by its `curvature` (surface variation) field on the fixed
/// scale [`SURFACE_VARIATION_RANGE`] (flat pale, edges and noise in orange to red), lit by its
/// normals; size and camera from `opts`.
pub fn surface_variation_picture(cloud: &PointCloud, opts: RenderOptions) -> Result<Image> {
    let opts = RenderOptions {
        colormap: ColorMap::Heat,
        range: Some((0.0, SURFACE_VARIATION_RANGE)),
        ..opts
    };
    render_cloud(cloud, Some("curvature"), &opts)
}

/// Draws [`surface_variation_picture`] of `cloud` seen along `view` into the PNG file `path`.
pub fn surface_variation_png(
    path: &Path,
    cloud: &PointCloud,
    view: [f64; 3],
    up: [f64; 3],
) -> Result<()> {
    let opts = RenderOptions {
        view,
        up,
        ..RenderOptions::default()
    };
    let img = surface_variation_picture(cloud, opts).context(path.display())?;
    png(path, &img)
}

/// Writes a picture as a PNG file; errors name the file.
pub fn png(path: &Path, img: &Image) -> Result<()> {
    img.save_png(path).context(path.display())
}
