//! Point-cloud files: read PLY, PCD, LAS/LAZ, OBJ (vertices) and XYZ text; write PLY, PCD,
//! LAS/LAZ and XYZ.
//!
//! ```no_run
//! use nbhd::io::{self, WriteOptions};
//! let cloud = io::read("scan.pcd")?;
//! println!("{} points, {} NaN", cloud.len(), cloud.non_finite_count());
//! io::write("scan.ply", &cloud, &WriteOptions::default())?;
//! # Ok::<(), nbhd::io::IoError>(())
//! ```
//!
//! Points with NaN coordinates (holes of organized scans) are kept as read, so indices stay
//! the file's; the tree skips or rejects them by its `NonFinitePolicy`.
//!
//! # What is written, and for whom
//!
//! Files are written so that PCL, MeshLab, CloudCompare and lidar tools read them back (the
//! ctest `pcl_loads_nbhd_files` in cpp_examples/ loads each with PCL's own loaders):
//!
//! | | PLY | PCD | XYZ | LAS/LAZ |
//! |---|---|---|---|---|
//! | x y z | `float` (default) or `double` | `F 4` or `F 8` | text | scaled `i32` |
//! | normals | `nx ny nz` | `normal_x normal_y normal_z` | `nx ny nz` | not stored |
//! | colour | `uchar red green blue` | `rgb`: `F 4` holding `0x00RRGGBB` (ascii: `U 4`, the integer) | `red green blue` 0–255 | RGB ×257 |
//! | scalars | `float`/`double` | `F 4`/`F 8` | text | `intensity`, `classification` only |
//!
//! - [`Precision::Single`] is the default, because PCL's point types are `float` and its
//!   loaders skip a `double` field; [`Precision::Double`] writes exact doubles;
//!   [`Precision::Keep`] follows [`PointCloud::source_precision`].
//! - Field names are the tools' own: a `curvature` field is read by PCL as
//!   `PointNormal::curvature`, which is the surface variation λ0/(λ0+λ1+λ2); the command-line
//!   tool writes that meaning under that name, and principal curvatures as `k1`, `k2`.
//! - PCD `binary_compressed` is LZF field by field, as PCL writes it; the encoder (`lzf.rs`)
//!   matches greedily over a hash table as liblzf does.
//! - LAS/LAZ go through the `las` crate (feature `las`, on by default); see [`not_written`]
//!   for what LAS cannot hold.
//! - Text (XYZ) columns are named by [`ReadOptions::columns`], a header line or a guess from the
//!   values, and [`ReadInfo::text_columns`] says which.
//!
//! # Hostile files
//!
//! Readers never trust a count in a header: element, point, field and LZF sizes are checked
//! for overflow and against the bytes that follow before anything is reserved or looped over,
//! and a malformed file is an [`IoError`] naming the line or byte. LAS/LAZ headers are checked
//! the same way before the `las`/`laz` crates see them, and a panic inside those crates is
//! caught and returned as an error. The readers are fuzzed (fuzz/, scripts/fuzz.sh).
//!
//! The PLY, PCD, OBJ and XYZ parsers are written here rather than taken from crates so that
//! every error can name the line or byte where a file went wrong, and the `io` feature alone
//! adds no dependency: `pcd-rs` (which reads `binary_compressed` since 0.13) reports no byte
//! offsets in binary data and brings `regex` and a derive macro; the `lzf` crate is
//! deprecated; `tobj` re-indexes vertices per object and drops unreferenced ones, whereas here
//! an OBJ's `v` lines are the points, in file order.

mod error;
#[cfg(feature = "las")]
mod las;
mod lzf;
mod obj;
mod pcd;
mod ply;
mod value;
mod xyz;

pub use error::{IoError, IoErrorKind, Location};

use crate::error::{NbhdError, Result as NbhdResult};
use crate::points::PointsView;
use error::{Fail, PResult};
use std::io::Write;
use std::path::Path;

/// A named per-point scalar, e.g. `curvature` or `intensity`.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarField {
    /// Name as in the file (`curvature`, `intensity`, `rgb`, ...).
    pub name: String,
    /// One value per point.
    pub values: Vec<f64>,
}

/// Width and height of an organized cloud (a depth image: point `i` is pixel
/// `(i % width, i / width)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

/// Axis-aligned bounding box of the finite points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest x, y, z.
    pub min: [f64; 3],
    /// Largest x, y, z.
    pub max: [f64; 3],
}

impl Aabb {
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        (0..3)
            .map(|j| (self.max[j] - self.min[j]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// A point cloud as read from or written to a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    /// Positions, in file order; non-finite ones kept.
    pub positions: Vec<[f64; 3]>,
    /// Per-point normals, if the file has them (`nx ny nz` or `normal_x ...`).
    pub normals: Option<Vec<[f64; 3]>>,
    /// Other per-point values, in file order.
    pub scalars: Vec<ScalarField>,
    /// Width and height of an organized cloud (PCD with `HEIGHT` > 1).
    pub grid: Option<Grid>,
    /// How precisely the file read held the coordinates: [`Precision::Double`] for PLY
    /// `double`/`int`/`uint`, PCD `F 8`/`I 4`/`U 4`/64-bit, LAS (scaled 32-bit integers), and
    /// text with a coordinate that a `float` does not hold exactly; [`Precision::Single`]
    /// otherwise; `None` for a cloud made in memory. [`Precision::Keep`] writes by it.
    pub source_precision: Option<Precision>,
}

impl PointCloud {
    /// A cloud of positions only.
    pub fn from_positions(positions: Vec<[f64; 3]>) -> Self {
        Self {
            positions,
            ..Self::default()
        }
    }

    /// Number of points (non-finite ones included).
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// `true` if there are no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Sets the normals. Errors: [`NbhdError::BufferTooSmall`] if there is not one per point.
    pub fn set_normals(&mut self, normals: Vec<[f64; 3]>) -> NbhdResult<()> {
        if normals.len() != self.len() {
            return Err(NbhdError::BufferTooSmall {
                what: "normals (points)",
                len: normals.len(),
                needed: self.len(),
            });
        }
        self.normals = Some(normals);
        Ok(())
    }

    /// Adds a scalar field, replacing one of the same name. Errors:
    /// [`NbhdError::BufferTooSmall`] if there is not one value per point.
    pub fn set_scalar(&mut self, name: &str, values: Vec<f64>) -> NbhdResult<()> {
        if values.len() != self.len() {
            return Err(NbhdError::BufferTooSmall {
                what: "scalar values (points)",
                len: values.len(),
                needed: self.len(),
            });
        }
        match self.scalars.iter_mut().find(|s| s.name == name) {
            Some(s) => s.values = values,
            None => self.scalars.push(ScalarField {
                name: name.to_string(),
                values,
            }),
        }
        Ok(())
    }

    /// The values of the scalar field `name`.
    pub fn scalar(&self, name: &str) -> Option<&[f64]> {
        self.scalars
            .iter()
            .find(|s| s.name == name)
            .map(|s| s.values.as_slice())
    }

    /// Per-point colours, if the cloud has them: a packed `rgb`/`rgba` field (as PCL writes
    /// them) or `red`, `green`, `blue` fields (as PLY files have them, 0..255).
    pub fn colors(&self) -> Option<Vec<[u8; 3]>> {
        if let Some(v) = self.packed_color_field() {
            return Some(
                v.iter()
                    .map(|&c| {
                        let c = if c.is_finite() { c as u32 } else { 0 };
                        [(c >> 16) as u8, (c >> 8) as u8, c as u8]
                    })
                    .collect(),
            );
        }
        let (r, g, b) = (
            self.scalar("red")?,
            self.scalar("green")?,
            self.scalar("blue")?,
        );
        let ch = |v: f64| v.clamp(0.0, 255.0) as u8;
        Some(
            (0..self.len())
                .map(|i| [ch(r[i]), ch(g[i]), ch(b[i])])
                .collect(),
        )
    }

    /// The packed colour field (`rgb`, else `rgba`) if it holds 32-bit unsigned integers.
    fn packed_color_field(&self) -> Option<&[f64]> {
        ["rgb", "rgba"]
            .iter()
            .filter_map(|n| self.scalar(n))
            .find(|v| {
                v.iter()
                    .all(|&x| (0.0..=u32::MAX as f64).contains(&x) && x.fract() == 0.0)
            })
    }

    /// Number of points with a NaN or infinite coordinate.
    pub fn non_finite_count(&self) -> usize {
        self.positions
            .iter()
            .filter(|p| !p.iter().all(|c| c.is_finite()))
            .count()
    }

    /// Bounding box of the finite points, `None` if there is none.
    pub fn bounding_box(&self) -> Option<Aabb> {
        let mut it = self
            .positions
            .iter()
            .filter(|p| p.iter().all(|c| c.is_finite()));
        let first = *it.next()?;
        let mut b = Aabb {
            min: first,
            max: first,
        };
        for p in it {
            for (j, &c) in p.iter().enumerate() {
                b.min[j] = b.min[j].min(c);
                b.max[j] = b.max[j].max(c);
            }
        }
        Some(b)
    }

    /// Names of the per-point fields: `x y z`, then `nx ny nz` if there are normals, then the
    /// scalar fields.
    pub fn field_names(&self) -> Vec<String> {
        let mut v: Vec<String> = ["x", "y", "z"].iter().map(|s| s.to_string()).collect();
        if self.normals.is_some() {
            v.extend(["nx", "ny", "nz"].iter().map(|s| s.to_string()));
        }
        v.extend(self.scalars.iter().map(|s| s.name.clone()));
        v
    }

    /// The positions as a [`PointsView`] for the trees (3 dimensions, `f64`).
    /// Errors: [`NbhdError::EmptyInput`] for an empty cloud.
    pub fn view(&self) -> NbhdResult<PointsView<'_>> {
        PointsView::from_rows(&self.positions)
    }

    /// Checks that normals and scalar fields have one entry per point and that the grid,
    /// if any, covers the points.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let n = self.len();
        if let Some(nr) = &self.normals {
            if nr.len() != n {
                return Err(format!("{n} positions but {} normals", nr.len()));
            }
        }
        for s in &self.scalars {
            if s.values.len() != n {
                return Err(format!(
                    "{n} positions but {} values of scalar field '{}'",
                    s.values.len(),
                    s.name
                ));
            }
        }
        if let Some(g) = self.grid {
            if g.width * g.height != n {
                return Err(format!(
                    "grid {} x {} does not hold {n} points",
                    g.width, g.height
                ));
            }
        }
        Ok(())
    }
}

/// A point-cloud file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Stanford polygon format (`.ply`): ascii, binary little or big endian.
    Ply,
    /// Point Cloud Library format (`.pcd`): ascii, binary, binary_compressed.
    Pcd,
    /// Wavefront OBJ (`.obj`): the `v` lines are the points. Read only.
    Obj,
    /// ASPRS LAS lidar format (`.las`, and `.laz` compressed): points, intensity,
    /// classification, colour (needs the `las` feature, on by default).
    Las,
    /// Text, one point per line (`.xyz`, `.txt`, `.pts`, `.asc`, `.csv`): `x y z` and more
    /// columns, named by [`ReadOptions::columns`], by a header line (`x y z`, `x,y,z`,
    /// `//X,Y,Z,R,G,B`), or else guessed from the values and reported in [`TextColumns`]
    /// (6 columns: colour if 0..255 integers, normals if unit vectors, scalars otherwise).
    Xyz,
}

impl Format {
    /// The format named by the extension of `path`, if any.
    pub fn from_path(path: impl AsRef<Path>) -> Option<Format> {
        let ext = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "ply" => Format::Ply,
            "pcd" => Format::Pcd,
            "obj" => Format::Obj,
            "las" | "laz" => Format::Las,
            "xyz" | "txt" | "pts" | "asc" | "csv" | "xyzn" => Format::Xyz,
            _ => return None,
        })
    }

    /// Short name (`PLY`, `PCD`, `OBJ`, `LAS`, `XYZ`).
    pub fn name(self) -> &'static str {
        match self {
            Format::Ply => "PLY",
            Format::Pcd => "PCD",
            Format::Obj => "OBJ",
            Format::Las => "LAS",
            Format::Xyz => "XYZ",
        }
    }

    /// Recognises PLY, PCD and LAS/LAZ by their first bytes.
    pub fn sniff(data: &[u8]) -> Option<Format> {
        if data.starts_with(b"ply\n") || data.starts_with(b"ply\r\n") {
            return Some(Format::Ply);
        }
        if data.starts_with(b"LASF") {
            return Some(Format::Las);
        }
        let head = &data[..data.len().min(4096)];
        let text = String::from_utf8_lossy(head);
        for line in text.lines() {
            let t = line.trim_start();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            if t.starts_with("VERSION") || t.starts_with("FIELDS") {
                return Some(Format::Pcd);
            }
            break;
        }
        None
    }
}

/// How numbers are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Text.
    Ascii,
    /// Binary, little endian (PLY `binary_little_endian`, PCD `binary`).
    Binary,
    /// Binary, big endian (PLY only).
    BinaryBigEndian,
    /// LZF-compressed, stored field by field (PCD `binary_compressed` only).
    BinaryCompressed,
}

/// Width of the stored floating-point values (coordinates, normals, scalar fields).
///
/// The default is [`Single`](Precision::Single), because that is what other tools load:
/// PCL's `PointXYZ`, `PointNormal`, `PointXYZRGB` are `float` types and its loaders match a
/// field only if its type is `float` (a `double` x is "Failed to find match for field 'x'"
/// and the point stays 0); MeshLab and CloudCompare read both.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Precision {
    /// 32-bit `float` (PLY `float`, PCD `F 4`): what PCL's point types hold, about 7 digits.
    #[default]
    Single,
    /// 64-bit `double` (PLY `double`, PCD `F 8`): exact for nbhd's `f64` values.
    Double,
    /// As the cloud was read ([`PointCloud::source_precision`]): double if the file held
    /// the coordinates more precisely than a `float` does, single otherwise.
    Keep,
}

impl Precision {
    /// Whether `cloud` is written in single precision.
    pub fn is_single_for(self, cloud: &PointCloud) -> bool {
        match self {
            Precision::Single => true,
            Precision::Double => false,
            Precision::Keep => cloud.source_precision != Some(Precision::Double),
        }
    }

    /// The precision a file's coordinate type holds.
    pub(crate) fn of_type(ty: value::Ty) -> Precision {
        use value::Ty;
        match ty {
            Ty::F64 | Ty::I32 | Ty::U32 | Ty::I64 | Ty::U64 => Precision::Double,
            _ => Precision::Single,
        }
    }

    /// The precision text coordinates need: double if one is not exactly a `float`.
    pub(crate) fn of_text(positions: &[[f64; 3]]) -> Precision {
        let exact = |v: f64| !v.is_finite() || v as f32 as f64 == v;
        if positions.iter().all(|p| p.iter().all(|&v| exact(v))) {
            Precision::Single
        } else {
            Precision::Double
        }
    }
}

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

#[cfg(not(feature = "las"))]
const NO_LAS: &str = "LAS/LAZ needs nbhd's `las` feature, which this build leaves out";

/// The fields of `cloud` that writing it as `format` leaves out: for LAS, normals and scalar
/// fields other than integer `intensity` and `classification` and the colour (PLY, PCD and
/// XYZ write every field).
pub fn not_written(cloud: &PointCloud, format: Format) -> Vec<String> {
    match format {
        #[cfg(feature = "las")]
        Format::Las => las::not_written(cloud),
        _ => Vec::new(),
    }
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
    let cloud = match format {
        Format::Ply => ply::read(data)?,
        Format::Pcd => pcd::read(data)?,
        Format::Obj => obj::read(data)?,
        #[cfg(feature = "las")]
        Format::Las => las::read(data)?,
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
        },
    ))
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
            Ok(w.write_all(&las::write(cloud, compressed)?)?)
        }
        #[cfg(not(feature = "las"))]
        Format::Las => unreachable!("refused by check_writable"),
        Format::Obj => unreachable!("refused by check_writable"),
    }
}

/// A property or field name usable in a PLY or PCD header: whitespace replaced by `_`.
pub(crate) fn header_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if s.is_empty() {
        "unnamed".into()
    } else {
        s
    }
}

/// Collects per-point columns into a cloud: `dest` says where each column goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dest {
    Pos(usize),
    Normal(usize),
    Scalar(usize),
    Skip,
}

/// Maps property/field names to destinations; returns them with the scalar names.
/// Errors (as a message) if x, y or z is missing.
pub(crate) fn assign_columns(
    names: &[String],
) -> std::result::Result<(Vec<Dest>, Vec<String>, bool), String> {
    let mut dest = Vec::with_capacity(names.len());
    let mut scalars = Vec::new();
    let mut found = [false; 6];
    for name in names {
        let d = match name.as_str() {
            "x" => Dest::Pos(0),
            "y" => Dest::Pos(1),
            "z" => Dest::Pos(2),
            "nx" | "normal_x" => Dest::Normal(0),
            "ny" | "normal_y" => Dest::Normal(1),
            "nz" | "normal_z" => Dest::Normal(2),
            "_" => Dest::Skip,
            _ => {
                scalars.push(name.clone());
                Dest::Scalar(scalars.len() - 1)
            }
        };
        match d {
            Dest::Pos(j) | Dest::Normal(j) => {
                let k = if matches!(d, Dest::Pos(_)) { j } else { 3 + j };
                if found[k] {
                    scalars.push(name.clone());
                    dest.push(Dest::Scalar(scalars.len() - 1));
                    continue;
                }
                found[k] = true;
            }
            _ => {}
        }
        dest.push(d);
    }
    if let Some(j) = (0..3).find(|&j| !found[j]) {
        return Err(format!(
            "no '{}' field: nbhd needs x, y and z per point",
            ["x", "y", "z"][j]
        ));
    }
    let normals = found[3] && found[4] && found[5];
    if !normals {
        // A partial normal is kept as scalars.
        for (d, name) in dest.iter_mut().zip(names) {
            if matches!(d, Dest::Normal(_)) {
                scalars.push(name.clone());
                *d = Dest::Scalar(scalars.len() - 1);
            }
        }
    }
    Ok((dest, scalars, normals))
}

/// Most points reserved from a file's declared count before they are read: the readers check
/// counts against the bytes left, and this bounds what a hint can allocate in any case.
pub(crate) const MAX_RESERVE: usize = 1 << 20;

/// Builds a cloud point by point from column values.
pub(crate) struct Builder {
    dest: Vec<Dest>,
    cloud: PointCloud,
    normals: Vec<[f64; 3]>,
    has_normals: bool,
}

impl Builder {
    /// `n` is the number of points the file declares: a hint only, never trusted for more
    /// than [`MAX_RESERVE`] points (the vectors grow as points are pushed).
    pub fn new(dest: Vec<Dest>, scalar_names: Vec<String>, has_normals: bool, n: usize) -> Self {
        let n = n.min(MAX_RESERVE);
        let scalars = scalar_names
            .into_iter()
            .map(|name| ScalarField {
                name,
                values: Vec::with_capacity(n),
            })
            .collect();
        Self {
            dest,
            cloud: PointCloud {
                positions: Vec::with_capacity(n),
                normals: None,
                scalars,
                grid: None,
                source_precision: None,
            },
            normals: Vec::with_capacity(if has_normals { n } else { 0 }),
            has_normals,
        }
    }

    /// Adds a point from its column values (one per destination).
    pub fn push(&mut self, values: impl Iterator<Item = f64>) {
        let mut p = [0.0; 3];
        let mut nr = [0.0; 3];
        for (d, v) in self.dest.iter().zip(values) {
            match *d {
                Dest::Pos(j) => p[j] = v,
                Dest::Normal(j) => nr[j] = v,
                Dest::Scalar(s) => self.cloud.scalars[s].values.push(v),
                Dest::Skip => {}
            }
        }
        self.cloud.positions.push(p);
        if self.has_normals {
            self.normals.push(nr);
        }
    }

    pub fn finish(mut self) -> PointCloud {
        if self.has_normals {
            self.cloud.normals = Some(self.normals);
        }
        self.cloud
    }
}

/// How a writer lays out colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ColorStyle {
    /// `red green blue` as 8-bit unsigned integers (PLY `uchar`, XYZ integers): what MeshLab,
    /// CloudCompare and PCL's PLY reader take as colour.
    Channels,
    /// One `rgb` field holding `0x00RRGGBB` in the bits of a 32-bit float (PCD `F 4`), as
    /// PCL's `PointXYZRGB` stores it.
    PackedFloat,
}

/// How a column is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Store {
    /// `float` or `double` by the precision asked for.
    Float,
    /// 8-bit unsigned integer (colour channels).
    U8,
    /// A packed colour: the 32 bits of a PCD `F 4` field (text: the unsigned integer).
    RgbBits,
}

#[derive(Clone, Copy)]
enum Col<'a> {
    Pos(usize),
    Normal(usize),
    Scalar(&'a [f64]),
    Channel(usize),
    Rgb,
}

/// The columns a writer emits, with their names and storage.
pub(crate) struct Columns<'a> {
    cloud: &'a PointCloud,
    names: Vec<String>,
    cols: Vec<Col<'a>>,
    colors: Vec<[u8; 3]>,
    packed: Vec<u32>,
}

impl<'a> Columns<'a> {
    /// `x y z`, the normals under `normal_names`, the colour (if the cloud has one, in
    /// `style`), then the other scalar fields in order.
    pub fn new(cloud: &'a PointCloud, normal_names: [&str; 3], style: ColorStyle) -> Self {
        let mut c = Columns {
            cloud,
            names: Vec::new(),
            cols: Vec::new(),
            colors: Vec::new(),
            packed: Vec::new(),
        };
        for (j, n) in ["x", "y", "z"].iter().enumerate() {
            c.push(n, Col::Pos(j));
        }
        if cloud.normals.is_some() {
            for (j, n) in normal_names.iter().enumerate() {
                c.push(n, Col::Normal(j));
            }
        }
        let colors = cloud.colors();
        if let Some(colors) = colors.clone() {
            match style {
                ColorStyle::Channels => {
                    for (k, n) in ["red", "green", "blue"].iter().enumerate() {
                        c.push(n, Col::Channel(k));
                    }
                    c.colors = colors;
                }
                ColorStyle::PackedFloat => {
                    // A packed field read from a file keeps its 32 bits (alpha included);
                    // channels are packed as 0x00RRGGBB.
                    c.packed = match cloud.packed_color_field() {
                        Some(v) => v.iter().map(|&x| x as u32).collect(),
                        None => colors
                            .iter()
                            .map(|[r, g, b]| (*r as u32) << 16 | (*g as u32) << 8 | *b as u32)
                            .collect(),
                    };
                    c.push("rgb", Col::Rgb);
                }
            }
        }
        for s in &cloud.scalars {
            if colors.is_some() && is_color_name(&s.name) {
                continue;
            }
            c.push(&header_name(&s.name), Col::Scalar(&s.values));
        }
        c
    }

    fn push(&mut self, name: &str, col: Col<'a>) {
        self.names.push(name.to_string());
        self.cols.push(col);
    }

    /// Column names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of columns.
    pub fn len(&self) -> usize {
        self.cols.len()
    }

    /// How column `c` is stored.
    pub fn store(&self, c: usize) -> Store {
        match self.cols[c] {
            Col::Channel(_) => Store::U8,
            Col::Rgb => Store::RgbBits,
            _ => Store::Float,
        }
    }

    /// The value of column `c` at point `i`.
    pub fn get(&self, c: usize, i: usize) -> f64 {
        match self.cols[c] {
            Col::Pos(j) => self.cloud.positions[i][j],
            Col::Normal(j) => self.cloud.normals.as_ref().map_or(0.0, |n| n[i][j]),
            Col::Scalar(v) => v[i],
            Col::Channel(k) => self.colors[i][k] as f64,
            Col::Rgb => self.packed[i] as f64,
        }
    }

    /// Column `c` of point `i` as text: floats as the shortest form that reads back exactly
    /// at the precision, colours as unsigned integers (PCL writes `rgb` so in ascii PCD).
    pub fn text(&self, c: usize, i: usize, single: bool) -> String {
        match self.cols[c] {
            Col::Channel(k) => self.colors[i][k].to_string(),
            Col::Rgb => self.packed[i].to_string(),
            _ => value::fmt_num(self.get(c, i), single),
        }
    }

    /// Appends column `c` of point `i` in binary.
    pub fn put(&self, buf: &mut Vec<u8>, c: usize, i: usize, single: bool, big_endian: bool) {
        macro_rules! put {
            ($v:expr) => {
                if big_endian {
                    buf.extend_from_slice(&$v.to_be_bytes())
                } else {
                    buf.extend_from_slice(&$v.to_le_bytes())
                }
            };
        }
        match self.cols[c] {
            Col::Channel(k) => buf.push(self.colors[i][k]),
            Col::Rgb => put!(self.packed[i]),
            _ => {
                let v = self.get(c, i);
                if single {
                    put!(v as f32)
                } else {
                    put!(v)
                }
            }
        }
    }

    /// One text line of point `i`, columns separated by a space.
    pub fn line(&self, out: &mut String, i: usize, single: bool) {
        out.clear();
        for c in 0..self.len() {
            if c > 0 {
                out.push(' ');
            }
            out.push_str(&self.text(c, i, single));
        }
        out.push('\n');
    }
}

/// Scalar fields that hold a colour: a packed `rgb`/`rgba`, or `red`/`green`/`blue`.
fn is_color_name(name: &str) -> bool {
    matches!(name, "rgb" | "rgba" | "red" | "green" | "blue")
}

/// `rgb` and `rgba` fields hold a colour packed as `0xAARRGGBB`: PCL stores it as the bits of
/// a float (`F 4`) or as `U 4`. nbhd keeps the integer and writes it as a 32-bit unsigned
/// integer, which is bit-identical to PCL's float.
pub(crate) fn is_packed_name(name: &str) -> bool {
    name == "rgb" || name == "rgba"
}
