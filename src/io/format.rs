//! What a file is: its format (by extension or by its first bytes) and how its numbers are
//! encoded.

use std::path::Path;

#[cfg(doc)]
use super::{ReadOptions, TextColumns};

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
