//! Writing: the entry points, the checks that refuse a write before a file is created, and the
//! dispatch to each format's writer.

use std::io::Write;
use std::path::Path;

use super::cloud::PointCloud;
use super::cloud::Precision;
use super::error::{Fail, IoError, IoErrorKind, PResult};
use super::format::{Encoding, Format};
#[cfg(feature = "las")]
use super::las;
use super::meta::Viewpoint;
#[cfg(not(feature = "las"))]
use super::NO_LAS;
use super::{pcd, ply, xyz};

/// Options of [`write()`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct WriteOptions {
    /// Format; `None` takes it from the extension of the path.
    pub format: Option<Format>,
    /// Encoding; `None` is binary for PLY and PCD, text for XYZ.
    pub encoding: Option<Encoding>,
    /// Width of positions, normals and scalar fields (colours are always 8-bit channels or
    /// PCL's packed `rgb`).
    pub precision: Precision,
}

impl WriteOptions {
    /// Text output, single precision.
    pub fn ascii() -> Self {
        Self {
            encoding: Some(Encoding::Ascii),
            ..Self::default()
        }
    }
}

/// What of `cloud` writing it as `format` leaves out, in words: per-point fields a LAS record
/// cannot hold (values out of a standard field's range, names an extra-bytes description
/// cannot take), and what the cloud's [`metadata`](PointCloud::metadata) holds that the
/// format has no place for (a PCD viewpoint other than the identity, header comments, the
/// LAS header's VLRs). PLY, PCD and XYZ write every per-point field. Empty if nothing is
/// left out.
pub fn not_written(cloud: &PointCloud, format: Format) -> Vec<String> {
    let mut v = match format {
        #[cfg(feature = "las")]
        Format::Las => las::not_written(cloud),
        _ => Vec::new(),
    };
    let m = &cloud.metadata;
    if format != Format::Pcd {
        if let Some(vp) = m.viewpoint.filter(|vp| *vp != Viewpoint::IDENTITY) {
            let n: Vec<String> = vp
                .origin
                .iter()
                .chain(&vp.orientation)
                .map(|c| c.to_string())
                .collect();
            v.push(format!("the PCD viewpoint {}", n.join(" ")));
        }
    }
    if matches!(format, Format::Las | Format::Xyz) && !m.comments.is_empty() {
        v.push(format!("{} header comment line(s)", m.comments.len()));
    }
    if let Some(h) = m.las.as_ref().filter(|_| format != Format::Las) {
        let vlrs: Vec<String> = h
            .vlrs
            .iter()
            .chain(&h.evlrs)
            .filter(|r| !(r.user_id == "LASF_Spec" && r.record_id == 4))
            .map(|r| format!("{} {} ({})", r.user_id, r.record_id, r.description))
            .collect();
        if !vlrs.is_empty() {
            v.push(format!("the LAS header's records: {}", vlrs.join(", ")));
        }
    }
    v
}

/// Writes a point cloud: PLY (ascii, binary little or big endian), PCD (ascii, binary,
/// binary_compressed) or XYZ text. Normals go out as `nx ny nz` (PLY) or
/// `normal_x normal_y normal_z` (PCD); scalar fields as float properties/fields, which MeshLab
/// and CloudCompare offer for colouring.
pub fn write(
    path: impl AsRef<Path>,
    cloud: &PointCloud,
    options: &WriteOptions,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let format =
        match options.format.or_else(|| Format::from_path(path)) {
            Some(f) => f,
            None => return Err(IoError::new(
                path,
                IoErrorKind::Unsupported(
                    "cannot tell the format to write from the extension; use .ply, .pcd, .las, .laz or .xyz"
                        .into(),
                ),
            )),
        };
    // `.laz` is LAS compressed.
    let laz = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("laz"));
    let mut options = *options;
    if format == Format::Las && laz && options.encoding.is_none() {
        options.encoding = Some(Encoding::BinaryCompressed);
    }
    let options = &options;
    // Check before creating the file, so that a refused write leaves nothing behind.
    check_writable(cloud, format, options).map_err(|f| f.with_path(path))?;
    let file = std::fs::File::create(path).map_err(|e| IoError::new(path, IoErrorKind::Io(e)))?;
    let mut w = std::io::BufWriter::new(file);
    write_to(&mut w, cloud, format, options).map_err(|f| f.with_path(path))?;
    w.flush()
        .map_err(|e| IoError::new(path, IoErrorKind::Io(e)))
}

/// Writes a point cloud in `format` to memory (`options.format` is ignored).
pub fn write_bytes(
    cloud: &PointCloud,
    format: Format,
    options: &WriteOptions,
) -> Result<Vec<u8>, IoError> {
    let mut out = Vec::new();
    check_writable(cloud, format, options)
        .and_then(|_| write_to(&mut out, cloud, format, options))
        .map_err(|f| f.with_path(Path::new("<memory>")))?;
    Ok(out)
}

fn check_writable(cloud: &PointCloud, format: Format, options: &WriteOptions) -> PResult<()> {
    cloud.validate().map_err(Fail::invalid)?;
    let enc = options.encoding;
    match (format, enc) {
        (Format::Obj, _) => Err(Fail::unsupported(
            "writing OBJ is not supported (it is read for its vertices); write PLY instead",
        )),
        (Format::Ply, Some(Encoding::BinaryCompressed)) => Err(Fail::unsupported(
            "PLY has no compressed encoding; use ascii, binary or binary big endian",
        )),
        (Format::Pcd, Some(Encoding::BinaryBigEndian)) => {
            Err(Fail::unsupported("PCD binary data is little endian only"))
        }
        (Format::Xyz, Some(e)) if e != Encoding::Ascii => Err(Fail::unsupported(
            "XYZ is a text format; it has no binary encoding",
        )),
        (Format::Las, Some(Encoding::Ascii | Encoding::BinaryBigEndian)) => Err(Fail::unsupported(
            "LAS is binary little endian: write it as binary (LAS) or compressed (LAZ)",
        )),
        #[cfg(not(feature = "las"))]
        (Format::Las, _) => Err(Fail::unsupported(NO_LAS)),
        (Format::Las, _) => match cloud
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            Some(i) => Err(Fail::invalid(format!(
                "LAS cannot store non-finite coordinates: point {i} (and {} in all) has NaN or \
                 infinite coordinates",
                cloud.non_finite_count()
            ))),
            None => Ok(()),
        },
        _ => Ok(()),
    }
}

fn write_to(
    w: &mut impl Write,
    cloud: &PointCloud,
    format: Format,
    options: &WriteOptions,
) -> PResult<()> {
    let single = options.precision.is_single_for(cloud);
    match format {
        Format::Ply => ply::write(
            w,
            cloud,
            options.encoding.unwrap_or(Encoding::Binary),
            single,
        ),
        Format::Pcd => pcd::write(
            w,
            cloud,
            options.encoding.unwrap_or(Encoding::Binary),
            single,
        ),
        Format::Xyz => xyz::write(w, cloud, single),
        #[cfg(feature = "las")]
        Format::Las => {
            let compressed = options.encoding == Some(Encoding::BinaryCompressed);
            Ok(w.write_all(&las::write(cloud, compressed, single)?)?)
        }
        #[cfg(not(feature = "las"))]
        Format::Las => unreachable!("refused by check_writable"),
        Format::Obj => unreachable!("refused by check_writable"),
    }
}
