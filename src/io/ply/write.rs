//! Writing PLY: a `vertex` element with a property per column, in ascii or binary.

use std::io::Write;

use crate::io::columns::{ColorStyle, Columns, Store};
use crate::io::error::PResult;
use crate::io::value::Ty;
use crate::io::{Encoding, PointCloud};

pub(crate) fn write(
    w: &mut impl Write,
    cloud: &PointCloud,
    enc: Encoding,
    single: bool,
) -> PResult<()> {
    let cols = Columns::new(cloud, ["nx", "ny", "nz"], ColorStyle::Channels, 4);
    w.write_all(header(&cols, cloud, enc, single).as_bytes())?;
    let mut buf = Vec::new();
    let mut line = String::new();
    let be = enc == Encoding::BinaryBigEndian;
    for i in 0..cloud.len() {
        if enc == Encoding::Ascii {
            cols.line(&mut line, i, single);
            w.write_all(line.as_bytes())?;
        } else {
            buf.clear();
            for c in 0..cols.len() {
                cols.put(&mut buf, c, i, single, be);
            }
            w.write_all(&buf)?;
        }
    }
    Ok(())
}

/// The header of the vertices of `cloud` with the properties `cols`, and the comments it
/// carries.
fn header(cols: &Columns<'_>, cloud: &PointCloud, enc: Encoding, single: bool) -> String {
    let n = cloud.len();
    let fmt = match enc {
        Encoding::Ascii => "ascii",
        Encoding::Binary => "binary_little_endian",
        Encoding::BinaryBigEndian => "binary_big_endian",
        Encoding::BinaryCompressed => unreachable!("refused by check_writable"),
    };
    let float = if single { "float" } else { "double" };
    let mut h = format!(
        "ply\nformat {fmt} 1.0\ncomment written by nbhd {}\n",
        env!("CARGO_PKG_VERSION"),
    );
    for c in &cloud.metadata.comments {
        let c = c.replace(['\n', '\r'], " ");
        match c.strip_prefix("obj_info ") {
            Some(info) => h.push_str(&format!("obj_info {info}\n")),
            None => h.push_str(&format!("comment {c}\n")),
        }
    }
    h.push_str(&format!("element vertex {n}\n"));
    for (c, name) in cols.names().iter().enumerate() {
        let ty = match cols.store(c) {
            Store::Float => float,
            Store::U8 => "uchar",
            Store::RgbBits => "uint",
            Store::Int(t) => match t {
                Ty::I8 => "char",
                Ty::U8 => "uchar",
                Ty::I16 => "short",
                Ty::U16 => "ushort",
                Ty::I32 => "int",
                _ => "uint",
            },
        };
        h.push_str(&format!("property {ty} {name}\n"));
    }
    h.push_str("end_header\n");
    h
}
