//! Writing PCD: the header, then the points in `ascii`, `binary` or `binary_compressed`.

use std::io::Write;

use super::lzf;
use crate::io::columns::{ColorStyle, Columns, Store};
use crate::io::error::{Fail, PResult};
use crate::io::{Encoding, PointCloud, Viewpoint};

pub(crate) fn write(
    w: &mut impl Write,
    cloud: &PointCloud,
    enc: Encoding,
    single: bool,
) -> PResult<()> {
    let cols = Columns::new(
        cloud,
        ["normal_x", "normal_y", "normal_z"],
        ColorStyle::PackedFloat,
        8,
    );
    write_header(w, cloud, &cols, enc, single)?;
    match enc {
        Encoding::Ascii => write_ascii(w, &cols, cloud.len(), single),
        Encoding::Binary => write_binary(w, &cols, cloud.len(), single),
        Encoding::BinaryCompressed => write_compressed(w, &cols, cloud.len(), single),
        Encoding::BinaryBigEndian => unreachable!("refused by check_writable"),
    }
}

/// The header (v0.7), one field per column.
fn write_header(
    w: &mut impl Write,
    cloud: &PointCloud,
    cols: &Columns<'_>,
    enc: Encoding,
    single: bool,
) -> PResult<()> {
    let n = cloud.len();
    let (width, height) = cloud.grid.map_or((n, 1), |g| (g.width, g.height));
    let data = match enc {
        Encoding::Ascii => "ascii",
        Encoding::Binary => "binary",
        Encoding::BinaryCompressed => "binary_compressed",
        Encoding::BinaryBigEndian => unreachable!("refused by check_writable"),
    };
    let float_size = if single { "4" } else { "8" };
    let (mut size, mut ty) = (Vec::new(), Vec::new());
    for c in 0..cols.len() {
        let (s, t) = match cols.store(c) {
            Store::Float => (float_size, "F"),
            Store::U8 => ("1", "U"),
            // PCL's PointXYZRGB: rgb is a float field holding the packed bits; in ascii PCL
            // (1.13) writes it as the unsigned integer of those bits, typed U, and reads it so.
            Store::RgbBits if enc == Encoding::Ascii => ("4", "U"),
            Store::RgbBits => ("4", "F"),
            Store::Int(t) => {
                let kind = if t.int_range().is_some_and(|(lo, _)| lo < 0.0) {
                    "I"
                } else {
                    "U"
                };
                (["1", "2", "", "4", "", "", "", "8"][t.size() - 1], kind)
            }
        };
        size.push(s);
        ty.push(t);
    }
    writeln!(w, "# .PCD v0.7 - Point Cloud Data file format")?;
    for c in &cloud.metadata.comments {
        writeln!(w, "# {}", c.replace(['\n', '\r'], " "))?;
    }
    let vp = cloud.metadata.viewpoint.unwrap_or(Viewpoint::IDENTITY);
    let vp: Vec<String> = vp
        .origin
        .iter()
        .chain(&vp.orientation)
        .map(|&v| crate::io::value::fmt_num(v, false))
        .collect();
    write!(
        w,
        "VERSION 0.7\nFIELDS {}\nSIZE {}\nTYPE {}\n\
         COUNT {}\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT {}\nPOINTS {n}\nDATA {data}\n",
        cols.names().join(" "),
        size.join(" "),
        ty.join(" "),
        vec!["1"; cols.len()].join(" "),
        vp.join(" "),
    )?;
    Ok(())
}

/// `DATA ascii`: a line per point.
fn write_ascii(w: &mut impl Write, cols: &Columns<'_>, n: usize, single: bool) -> PResult<()> {
    let mut line = String::new();
    for i in 0..n {
        cols.line(&mut line, i, single);
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// `DATA binary`: a record per point, little endian.
fn write_binary(w: &mut impl Write, cols: &Columns<'_>, n: usize, single: bool) -> PResult<()> {
    let mut buf = Vec::new();
    for i in 0..n {
        buf.clear();
        for c in 0..cols.len() {
            cols.put(&mut buf, c, i, single, false);
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

/// `DATA binary_compressed`: field by field, as PCL stores it (all points' x, then all y, ...),
/// LZF-compressed after the two sizes.
fn write_compressed(w: &mut impl Write, cols: &Columns<'_>, n: usize, single: bool) -> PResult<()> {
    let mut raw = Vec::new();
    for c in 0..cols.len() {
        for i in 0..n {
            cols.put(&mut raw, c, i, single, false);
        }
    }
    if raw.len() > u32::MAX as usize {
        return Err(Fail::unsupported(
            "binary_compressed PCD holds at most 4 GiB of data; write binary",
        ));
    }
    let c = lzf::compress(&raw);
    w.write_all(&(c.len() as u32).to_le_bytes())?;
    w.write_all(&(raw.len() as u32).to_le_bytes())?;
    w.write_all(&c)?;
    Ok(())
}
