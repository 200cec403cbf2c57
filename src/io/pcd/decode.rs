//! The points after a PCD header, one function per `DATA` encoding: `ascii`, `binary` (records
//! of all fields, little endian) and `binary_compressed` (LZF, field by field).

use super::header::{Field, Header};
use super::lzf;
use crate::io::assemble::Builder;
use crate::io::cloud::is_packed_name;
use crate::io::error::{Fail, PResult};
use crate::io::value::{parse_num, tokens, Lines, Ty};

/// The values of a point: the fields expanded by `COUNT` (`name_0`, `name_1`, ...), each with
/// the type it is read as.
pub(super) struct PointColumns {
    /// Column names; padding fields (`_`) keep their name, which the reader skips.
    pub names: Vec<String>,
    /// Type each column is read as.
    pub types: Vec<Ty>,
    /// Whether a column is a packed colour stored as the bits of a float. It is read as those
    /// bits (a 32-bit unsigned integer): converting it as a float would change NaN-pattern
    /// colours.
    pub packed: Vec<bool>,
}

impl PointColumns {
    pub fn of(fields: &[Field]) -> Self {
        let mut c = PointColumns {
            names: Vec::new(),
            types: Vec::new(),
            packed: Vec::new(),
        };
        for f in fields {
            let packed = f.count == 1 && f.ty == Ty::F32 && is_packed_name(&f.name);
            for k in 0..f.count {
                c.names.push(if f.count == 1 || f.name == "_" {
                    f.name.clone()
                } else {
                    format!("{}_{k}", f.name)
                });
                c.types.push(if packed { Ty::U32 } else { f.ty });
                c.packed.push(packed);
            }
        }
        c
    }
}

/// `DATA ascii`: one point per line, values separated by whitespace; blank and `#` lines
/// skipped.
pub(super) fn ascii(
    data: &[u8],
    header: &Header,
    cols: &PointColumns,
    b: &mut Builder,
) -> PResult<()> {
    let n = header.points;
    let lines = Lines::new(data, header.end, header.end_line + 1);
    let mut got = 0;
    let mut vals = Vec::with_capacity(cols.types.len());
    for item in lines {
        if got == n {
            break;
        }
        let (ln, line) = item?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        vals.clear();
        for tok in tokens(t) {
            vals.push(ascii_value(cols, vals.len(), tok, ln, got)?);
        }
        if vals.len() != cols.types.len() {
            return Err(Fail::line(
                ln,
                format!(
                    "point {got} has {} values, the header declares {}",
                    vals.len(),
                    cols.types.len()
                ),
            ));
        }
        b.push(vals.iter().copied());
        got += 1;
    }
    if got < n {
        return Err(Fail::line(
            header.end_line.max(1),
            format!("the header declares {n} points but the file holds {got}"),
        )
        .at_last_line(data));
    }
    Ok(())
}

/// The text `tok` of column `c` of point `point`, on line `ln`.
fn ascii_value(cols: &PointColumns, c: usize, tok: &str, ln: usize, point: usize) -> PResult<f64> {
    // A packed colour in text: PCL (1.7 on) writes the unsigned integer of its bits; older
    // writers printed the float.
    let packed = cols.packed.get(c) == Some(&true);
    Ok(match tok.parse::<u32>() {
        Ok(u) if packed => u as f64,
        _ => {
            let v = parse_num(tok).ok_or_else(|| {
                Fail::line(ln, format!("'{tok}' is not a number (point {point})"))
            })?;
            match (packed, cols.types.get(c)) {
                (true, _) => (v as f32).to_bits() as f64,
                (false, Some(t)) => t.round_text(v),
                (false, None) => v,
            }
        }
    })
}

/// `DATA binary`: `points` records of `record` bytes, little endian.
pub(super) fn binary(
    data: &[u8],
    header: &Header,
    cols: &PointColumns,
    b: &mut Builder,
) -> PResult<()> {
    let (n, rec) = (header.points, header.record);
    let body = &data[header.end..];
    if body.len() < n * rec {
        let i = body.len() / rec.max(1);
        return Err(Fail::byte(
            header.end + i * rec,
            format!("the file ends inside point {i} of {n} ({rec} bytes per point)"),
        ));
    }
    let mut vals = Vec::with_capacity(cols.types.len());
    for i in 0..n {
        let r = &body[i * rec..(i + 1) * rec];
        vals.clear();
        let mut o = 0;
        for &ty in &cols.types {
            vals.push(ty.read(&r[o..], false));
            o += ty.size();
        }
        b.push(vals.iter().copied());
    }
    Ok(())
}

/// `DATA binary_compressed`: the compressed and the uncompressed size (32-bit little endian),
/// then LZF data that holds all points' values of field 0, then of field 1, ...
pub(super) fn compressed(
    data: &[u8],
    header: &Header,
    cols: &PointColumns,
    b: &mut Builder,
) -> PResult<()> {
    let n = header.points;
    let raw = decompress(data, header)?;
    // Where column c of point i starts: starts[c] + i * strides[c].
    let mut starts = Vec::with_capacity(cols.types.len());
    let mut strides = Vec::with_capacity(cols.types.len());
    let mut base = 0;
    for f in &header.fields {
        let fs = f.ty.size() * f.count;
        for k in 0..f.count {
            starts.push(base + k * f.ty.size());
            strides.push(fs);
        }
        base += n * fs;
    }
    let mut vals = Vec::with_capacity(cols.types.len());
    for i in 0..n {
        vals.clear();
        for (c, ty) in cols.types.iter().enumerate() {
            let o = starts[c] + i * strides[c];
            vals.push(ty.read(&raw[o..], false));
        }
        b.push(vals.iter().copied());
    }
    Ok(())
}

/// The uncompressed bytes of `binary_compressed` data, after checking both sizes against the
/// header and the file.
fn decompress(data: &[u8], header: &Header) -> PResult<Vec<u8>> {
    let (start, n, rec) = (header.end, header.points, header.record);
    let body = &data[start..];
    if body.len() < 8 {
        return Err(Fail::byte(
            start,
            "binary_compressed data must start with two 32-bit sizes",
        ));
    }
    let size_at = |o: usize| u32::from_le_bytes([body[o], body[o + 1], body[o + 2], body[o + 3]]);
    let csize = size_at(0) as usize;
    let usize_ = size_at(4) as usize;
    if usize_ != n * rec {
        // n * rec was checked with the header.
        return Err(Fail::byte(
            start + 4,
            format!(
                "uncompressed size {usize_} differs from {n} points x {rec} bytes = {}",
                n * rec
            ),
        ));
    }
    if body.len() - 8 < csize {
        return Err(Fail::byte(
            start,
            format!(
                "compressed size {csize} exceeds the {} bytes left in the file",
                body.len() - 8
            ),
        ));
    }
    if usize_ > lzf::max_decompressed(csize) {
        return Err(Fail::byte(
            start + 4,
            format!("uncompressed size {usize_} cannot come from {csize} bytes of LZF data"),
        ));
    }
    lzf::decompress(&body[8..8 + csize], usize_)
        .map_err(|(o, m)| Fail::byte(start + 8 + o, format!("corrupt LZF data: {m}")))
}
