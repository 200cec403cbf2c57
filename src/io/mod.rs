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
//! | x y z | `float` (default) or `double` | `F 4` or `F 8` | text | scaled `i32`, the input's scale and offset |
//! | normals | `nx ny nz` | `normal_x normal_y normal_z` | `nx ny nz` | extra bytes `NormalX NormalY NormalZ` |
//! | colour | `uchar red green blue` | `rgb`: `F 4` holding `0x00RRGGBB` (ascii: `U 4`, the integer) | `red green blue` 0–255 | RGB: as read from LAS, else ×257 |
//! | scalars | `float`/`double` | `F 4`/`F 8` | text | a record's own fields in their places; others extra bytes (`curvature` as `Curvature`) |
//! | file metadata | `comment`, `obj_info` | `VIEWPOINT`, `#` comments | — | the LAS header and its VLRs |
//!
//! - [`Precision::Single`] is the default, because PCL's point types are `float` and its
//!   loaders skip a `double` field; [`Precision::Double`] writes exact doubles;
//!   [`Precision::Keep`] follows [`PointCloud::source_precision`].
//! - Field names are the tools' own: a `curvature` field is read by PCL as
//!   `PointNormal::curvature`, which is the surface variation λ0/(λ0+λ1+λ2); the command-line
//!   tool writes that meaning under that name, and principal curvatures as `k1`, `k2`.
//! - PCD `binary_compressed` is LZF field by field, as PCL writes it; the encoder (`pcd/lzf.rs`)
//!   matches greedily over a hash table as liblzf does.
//! - LAS/LAZ go through the `las` crate (feature `las`, on by default): every point record
//!   comes back as read, the header in [`PointCloud::metadata`] (rules in cli/README.md, "LAS
//!   and LAZ").
//! - Nothing is dropped silently: [`ReadInfo::not_carried`] names what a file holds that the
//!   cloud does not carry, [`not_written`] what a format has no place for.
//! - Text (XYZ) columns are named by [`ReadOptions::columns`], a header line or a guess from the
//!   values, and [`ReadInfo::text_columns`] says which; written files start with CloudCompare's
//!   header line `//x y z ...`.
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

mod assemble;
mod cloud;
mod columns;
mod error;
mod format;
#[cfg(feature = "las")]
mod las;
mod meta;
mod obj;
mod pcd;
mod ply;
mod read;
mod value;
mod write;
mod xyz;

pub use cloud::{Aabb, Grid, PointCloud, Precision, ScalarField};
pub use error::{IoError, IoErrorKind, Location};
pub use format::{Encoding, Format};
pub use meta::{FieldType, LasHeader, LasVlr, Metadata, Viewpoint};
pub use read::{
    read, read_as, read_bytes, read_bytes_with, read_with, ReadInfo, ReadOptions, TextColumns,
};
pub use write::{not_written, write, write_bytes, WriteOptions};

#[cfg(not(feature = "las"))]
const NO_LAS: &str = "LAS/LAZ needs nbhd's `las` feature, which this build leaves out";
