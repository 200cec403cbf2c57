//! `nbhd convert IN OUT`: from one point-cloud format to another.

use crate::args::{InputArgs, PrecisionArgs};
use crate::error::Result;
use crate::output::Output;
use crate::read::{columns_note, not_carried_note};
use crate::write;
use nbhd::io::{self, Encoding, Format, Precision, WriteOptions};
use serde_json::json;
use std::path::PathBuf;

/// How numbers are stored in the output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EncodingArg {
    /// Text (PLY ascii, PCD ascii; XYZ is always text)
    Ascii,
    /// Binary little endian (the default for PLY and PCD)
    Binary,
    /// Binary big endian (PLY only)
    BinaryBigEndian,
    /// LZF-compressed, field by field (PCD binary_compressed), or LAZ
    Compressed,
}

/// Convert a point cloud between formats, keeping normals and scalar fields
///
/// The output format is taken from OUT's extension: .ply, .pcd, .las, .laz or .xyz (OBJ is
/// read only). Coordinates, normals and scalar fields are float32 unless --precision says
/// otherwise (PCL's point types load float only). Normals are written as nx ny nz (PLY, XYZ)
/// or normal_x normal_y normal_z (PCD); colour as uchar red green blue (PLY, XYZ) or PCL's
/// packed float rgb (PCD); scalar fields such as curvature as float properties, which
/// MeshLab and CloudCompare offer for colouring. LAS to LAS keeps every point record and the
/// header's records (CRS); normals and other fields go to LAS extra bytes (NormalX NormalY
/// NormalZ, Curvature, ...). What a format has no place for (a PCD viewpoint in PLY, a PLY's
/// faces, ...) is named on standard error. NaN points are kept, and an organized PCD stays
/// organized when written as PCD.
#[derive(clap::Args, Debug)]
// `mut_arg` moves the argument to the end of the list: the explicit indices keep
// `<INPUT> <OUTPUT>` in that order.
#[command(mut_arg("input", |a| a.index(1).help(
    "Input file (.ply, .pcd, .las/.laz, .obj, .xyz/.txt/.pts/.asc/.csv)"
)))]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,

    /// Output file (.ply, .pcd, .las, .laz, .xyz)
    #[arg(index = 2)]
    pub output: PathBuf,

    /// Encoding of the output [default: binary for PLY, PCD and LAS, compressed for .laz,
    /// text for XYZ]
    #[arg(long, short, value_enum)]
    pub encoding: Option<EncodingArg>,

    #[command(flatten)]
    pub precision: PrecisionArgs,
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    let input = &a.input.input;
    let (cloud, info) = a.input.read_info()?;
    let from = info.format;
    let opts = WriteOptions {
        format: None,
        encoding: a.encoding.map(|e| match e {
            EncodingArg::Ascii => Encoding::Ascii,
            EncodingArg::Binary => Encoding::Binary,
            EncodingArg::BinaryBigEndian => Encoding::BinaryBigEndian,
            EncodingArg::Compressed => Encoding::BinaryCompressed,
        }),
        precision: a.precision.get(),
    };
    let to_format = Format::from_path(&a.output);
    let dropped = to_format.map_or_else(Vec::new, |f| io::not_written(&cloud, f));
    // names what `dropped` holds on standard error
    let stored = write::cloud(&a.output, &cloud, &opts)?;
    let stored = if to_format == Some(Format::Las) {
        "LAS scaled integers"
    } else {
        stored
    };
    let to = Format::from_path(&a.output).map_or("?", |f| f.name());
    out.json(&json!({
        "input": input.display().to_string(),
        "output": a.output.display().to_string(),
        "from": from.name(),
        "to": to,
        "points": cloud.len(),
        "non_finite": cloud.non_finite_count(),
        "fields": cloud.field_names(),
        "columns": info.text_columns.as_ref().map(|t| json!({"names": t.names, "from": t.from})),
        "precision": stored,
        "not_written": dropped,
        "not_carried": info.not_carried,
        "input_precision": match cloud.source_precision {
            Some(Precision::Double) => "float64",
            Some(_) => "float32",
            None => "unknown",
        },
    }));
    out.text(format!(
        "{} -> {}: {} points ({} -> {}), fields {} ({stored})",
        input.display(),
        a.output.display(),
        cloud.len(),
        from.name(),
        to,
        cloud.field_names().join(" ")
    ));
    for note in [columns_note(&info), not_carried_note(&info)]
        .into_iter()
        .flatten()
    {
        out.text(format!("{}: {note}", input.display()));
    }
    if stored == "float32" && cloud.source_precision == Some(Precision::Double) {
        out.text(
            "note: the input held double-precision coordinates; they were written as float32 \
             (what PCL's point types load). Use --precision keep or double to keep them.",
        );
    }
    Ok(())
}
