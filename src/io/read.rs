//! Reading: the entry points, the format decision (options, content, extension) and the
//! dispatch to each format's reader.

use std::path::Path;

use super::cloud::PointCloud;
#[cfg(not(feature = "las"))]
use super::error::Fail;
use super::error::{IoError, IoErrorKind, PResult};
use super::format::Format;
#[cfg(feature = "las")]
use super::las;
#[cfg(not(feature = "las"))]
use super::NO_LAS;
use super::{obj, pcd, ply, xyz};

/// Known formats that nbhd does not read, with a hint.
fn unsupported_extension(path: &Path) -> Option<String> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    let what = match ext.as_str() {
        "e57" => "E57 scanner files",
        "stl" => "STL meshes",
        "off" => "OFF meshes",
        "vtk" | "vtp" => "VTK files",
        _ => return None,
    };
    Some(format!(
        "{what} are not read by nbhd; convert to PLY, PCD, LAS, OBJ or XYZ first (e.g. with CloudCompare)"
    ))
}

/// Reads a point cloud. The format is recognised by content (PLY and PCD headers) and
/// otherwise by extension (`.obj`, `.xyz`/`.txt`/`.pts`/`.asc`/`.csv`).
pub fn read(path: impl AsRef<Path>) -> Result<PointCloud, IoError> {
    read_as(path, None).map(|(cloud, _)| cloud)
}

/// Reads a point cloud as [`read`] does, or in the given format, and tells the format read.
pub fn read_as(
    path: impl AsRef<Path>,
    format: Option<Format>,
) -> Result<(PointCloud, Format), IoError> {
    let opts = ReadOptions {
        format,
        ..ReadOptions::default()
    };
    read_with(path, &opts).map(|(c, info)| (c, info.format))
}

/// Options of [`read_with`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Format; `None` recognises it by content, then by extension.
    pub format: Option<Format>,
    /// Names of the columns of a text (XYZ) file, e.g. `x y z red green blue` or
    /// `x y z nx ny nz`: they override a header line and the guess from the values (see
    /// [`Format::Xyz`]). Ignored for the other formats.
    pub columns: Option<Vec<String>>,
}

/// What the columns of a text file were read as, and what decided it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextColumns {
    /// Column names as read (`x y z red green blue`, `x y z nx ny nz`, ...).
    pub names: Vec<String>,
    /// What decided them, in words: "the header on line 1", "the column names given", or
    /// the guess from the values and why.
    pub from: String,
}

/// What [`read_with`] read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadInfo {
    /// The format read.
    pub format: Format,
    /// For text (XYZ) files: the columns and what decided them.
    pub text_columns: Option<TextColumns>,
    /// What the file holds that the cloud does not carry, in words (a PLY's faces, an OBJ's
    /// faces and normals, LAS extra bytes without a description); empty if nothing.
    pub not_carried: Vec<String>,
}

/// Reads a point cloud with options, and tells what was read.
pub fn read_with(
    path: impl AsRef<Path>,
    options: &ReadOptions,
) -> Result<(PointCloud, ReadInfo), IoError> {
    let path = path.as_ref();
    let data = std::fs::read(path).map_err(|e| IoError::new(path, IoErrorKind::Io(e)))?;
    let format = match options
        .format
        .or_else(|| Format::sniff(&data))
        .or_else(|| Format::from_path(path))
    {
        Some(f) => f,
        None => {
            let msg = unsupported_extension(path).unwrap_or_else(|| {
                "unknown point-cloud format: not a PLY, PCD or LAS file, and the extension is \
                 none of .ply .pcd .las .laz .obj .xyz .txt .pts .asc .csv"
                    .to_string()
            });
            return Err(IoError::new(path, IoErrorKind::Unsupported(msg)));
        }
    };
    parse(&data, format, options).map_err(|f| f.with_path(path))
}

/// Reads a point cloud of the given format from memory; errors name the path `<memory>`.
pub fn read_bytes(data: &[u8], format: Format) -> Result<PointCloud, IoError> {
    let opts = ReadOptions::default();
    read_bytes_with(data, format, &opts).map(|(c, _)| c)
}

/// Reads a point cloud of the given format from memory with options (`options.format` is
/// ignored); errors name the path `<memory>`.
pub fn read_bytes_with(
    data: &[u8],
    format: Format,
    options: &ReadOptions,
) -> Result<(PointCloud, ReadInfo), IoError> {
    parse(data, format, options).map_err(|f| f.with_path(Path::new("<memory>")))
}

fn parse(data: &[u8], format: Format, options: &ReadOptions) -> PResult<(PointCloud, ReadInfo)> {
    let mut text_columns = None;
    let mut not_carried = Vec::new();
    let cloud = match format {
        Format::Ply => {
            let (c, n) = ply::read(data)?;
            not_carried = n;
            c
        }
        Format::Pcd => pcd::read(data)?,
        Format::Obj => {
            let (c, n) = obj::read(data)?;
            not_carried = n;
            c
        }
        #[cfg(feature = "las")]
        Format::Las => {
            let (c, n) = las::read(data)?;
            not_carried = n;
            c
        }
        #[cfg(not(feature = "las"))]
        Format::Las => return Err(Fail::unsupported(NO_LAS)),
        Format::Xyz => {
            let (c, t) = xyz::read(data, options.columns.as_deref())?;
            text_columns = Some(t);
            c
        }
    };
    Ok((
        cloud,
        ReadInfo {
            format,
            text_columns,
            not_carried,
        },
    ))
}
