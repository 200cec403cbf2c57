//! What a file says about its cloud as a whole rather than per point: the PCD viewpoint, the
//! comments of a PLY or PCD header, the header of a LAS file. Readers fill it in and writers of
//! the same format put it back, so that reading and writing a file loses nothing;
//! [`not_written`](super::not_written) names what another format has no place for.

/// Where a scan was taken from: PCD's `VIEWPOINT tx ty tz qw qx qy qz`, the sensor's position
/// and its orientation as a unit quaternion (PCL's `sensor_origin_` and
/// `sensor_orientation_`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewpoint {
    /// Position `tx ty tz`.
    pub origin: [f64; 3],
    /// Orientation quaternion `qw qx qy qz` (the identity is `1 0 0 0`).
    pub orientation: [f64; 4],
}

impl Viewpoint {
    /// PCL's default: the origin, looking along the axes (`0 0 0 1 0 0 0`).
    pub const IDENTITY: Viewpoint = Viewpoint {
        origin: [0.0; 3],
        orientation: [1.0, 0.0, 0.0, 0.0],
    };
}

/// A variable-length record of a LAS file (VLR or extended VLR): its key and its bytes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LasVlr {
    /// `LASF_Projection` (coordinate reference system), `LASF_Spec` (classification lookup,
    /// extra bytes, ...) or a vendor's name.
    pub user_id: String,
    /// The record's number under its user id (e.g. 2112: the CRS as OGC WKT; 4: extra bytes).
    pub record_id: u16,
    /// Free text.
    pub description: String,
    /// The record's data.
    pub data: Vec<u8>,
}

/// The header of a LAS/LAZ file read: what nbhd's LAS writer keeps when it writes the cloud
/// back (docs in cli/README.md, "LAS and LAZ").
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LasHeader {
    /// LAS version (major, minor), e.g. (1, 4).
    pub version: (u8, u8),
    /// Point data record format, 0–10.
    pub point_format: u8,
    /// Scale of the stored integer coordinates, per axis.
    pub scale: [f64; 3],
    /// Offset of the stored integer coordinates, per axis.
    pub offset: [f64; 3],
    /// File source id (e.g. the flight line).
    pub file_source_id: u16,
    /// Global encoding bits (GPS time type, synthetic return numbers, WKT CRS, ...).
    pub global_encoding: u16,
    /// Project GUID.
    pub guid: [u8; 16],
    /// System identifier.
    pub system_identifier: String,
    /// Software that wrote the file.
    pub generating_software: String,
    /// Variable-length records (coordinate reference system, extra-bytes descriptions, ...);
    /// LAZ's own compression record is not listed.
    pub vlrs: Vec<LasVlr>,
    /// Extended variable-length records (LAS 1.4).
    pub evlrs: Vec<LasVlr>,
}

/// How a file stored a per-point field (PLY property and PCD field types).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldType {
    /// 8-bit signed integer (PLY `char`, PCD `I 1`).
    I8,
    /// 8-bit unsigned integer (PLY `uchar`, PCD `U 1`).
    U8,
    /// 16-bit signed integer.
    I16,
    /// 16-bit unsigned integer.
    U16,
    /// 32-bit signed integer.
    I32,
    /// 32-bit unsigned integer (PCL's `label`).
    U32,
    /// 64-bit signed integer (PCD only).
    I64,
    /// 64-bit unsigned integer (PCD only).
    U64,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

/// What a file said about its cloud as a whole; see the module docs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metadata {
    /// PCD `VIEWPOINT`, if the file gave one other than PCL's default, the identity (which a
    /// PCD is written with when there is none).
    pub viewpoint: Option<Viewpoint>,
    /// Comment lines of a PLY (`comment`; `obj_info` lines kept as `obj_info ...`) or PCD
    /// header (`#` lines after the first), without the keyword.
    pub comments: Vec<String>,
    /// The LAS header, for a cloud read from LAS/LAZ.
    pub las: Option<LasHeader>,
    /// How a PLY or PCD file stored its scalar fields, by name: the PLY and PCD writers store a
    /// field of an integer type in that type again while its values fit it (a PCD `label`
    /// stays `U 4`, a PLY `uchar` stays `uchar`); floats follow the precision asked for.
    pub field_types: Vec<(String, FieldType)>,
}

impl Metadata {
    /// The type the file stored the field `name` as, if it said.
    pub fn field_type(&self, name: &str) -> Option<FieldType> {
        self.field_types
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, t)| t)
    }
}
