//! PCD, the Point Cloud Library's format (v0.7; v0.5/0.6 headers without WIDTH/HEIGHT too).

use super::assemble::{assign_columns, Builder};
use super::cloud::is_packed_name;
use super::columns::{ColorStyle, Columns, Store};
use super::error::{Fail, PResult};
use super::lzf;
use super::value::{parse_num, tokens, Lines, Ty};
use super::{Encoding, Grid, PointCloud};
use std::io::Write;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Data {
    Ascii,
    Binary,
    Compressed,
}

struct Field {
    name: String,
    ty: Ty,
    count: usize,
}

fn ty_of(kind: &str, size: usize) -> Option<Ty> {
    Some(match (kind, size) {
        ("F", 4) => Ty::F32,
        ("F", 8) => Ty::F64,
        ("I", 1) => Ty::I8,
        ("I", 2) => Ty::I16,
        ("I", 4) => Ty::I32,
        ("I", 8) => Ty::I64,
        ("U", 1) => Ty::U8,
        ("U", 2) => Ty::U16,
        ("U", 4) => Ty::U32,
        ("U", 8) => Ty::U64,
        _ => return None,
    })
}

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    let mut lines = Lines::new(data, 0, 1);
    let mut names: Option<(usize, Vec<String>)> = None;
    let mut sizes: Option<(usize, Vec<usize>)> = None;
    let mut kinds: Option<(usize, Vec<String>)> = None;
    let mut counts: Option<(usize, Vec<usize>)> = None;
    let mut width = None;
    let mut height = None;
    let mut points: Option<(usize, usize)> = None;
    let mut kind = None;
    let mut data_line = 0;
    for item in lines.by_ref() {
        let (ln, line) = item?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let mut tok = tokens(t);
        let key = tok.next().unwrap_or("").to_ascii_uppercase();
        let rest: Vec<&str> = tok.collect();
        let nums = |what: &str| -> PResult<Vec<usize>> {
            rest.iter()
                .map(|s| {
                    s.parse::<usize>().map_err(|_| {
                        Fail::line(ln, format!("{what}: '{s}' is not a non-negative integer"))
                    })
                })
                .collect()
        };
        let one = |what: &str| -> PResult<usize> {
            let v = nums(what)?;
            if v.len() != 1 {
                return Err(Fail::line(ln, format!("{what} takes one number")));
            }
            Ok(v[0])
        };
        match key.as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" | "COLUMNS" => {
                names = Some((ln, rest.iter().map(|s| s.to_string()).collect()))
            }
            "SIZE" => sizes = Some((ln, nums("SIZE")?)),
            "TYPE" => kinds = Some((ln, rest.iter().map(|s| s.to_ascii_uppercase()).collect())),
            "COUNT" => counts = Some((ln, nums("COUNT")?)),
            "WIDTH" => width = Some((ln, one("WIDTH")?)),
            "HEIGHT" => height = Some((ln, one("HEIGHT")?)),
            "POINTS" => points = Some((ln, one("POINTS")?)),
            "DATA" => {
                kind = Some(
                    match rest.first().map(|s| s.to_ascii_lowercase()).as_deref() {
                        Some("ascii") => Data::Ascii,
                        Some("binary") => Data::Binary,
                        Some("binary_compressed") => Data::Compressed,
                        other => {
                            return Err(Fail::line(
                                ln,
                                format!(
                                    "DATA must be ascii, binary or binary_compressed, not '{}'",
                                    other.unwrap_or("")
                                ),
                            ))
                        }
                    },
                );
                data_line = ln;
                break;
            }
            _ => {
                return Err(Fail::line(
                    ln,
                    format!("unknown PCD header entry '{}' (is this a PCD file?)", key),
                ))
            }
        }
    }
    let header_end = lines.offset();
    let end_line = lines.line_no();
    let Some(kind) = kind else {
        return Err(Fail::line(
            end_line.max(1),
            "the PCD header has no DATA line",
        ));
    };
    let Some((fl, names)) = names else {
        return Err(Fail::line(data_line, "the PCD header has no FIELDS line"));
    };
    let nf = names.len();
    let (sl, sizes) = sizes.unwrap_or((fl, vec![4; nf]));
    let (tl, kinds) = kinds.unwrap_or((fl, vec!["F".to_string(); nf]));
    let (cl, counts) = counts.unwrap_or((fl, vec![1; nf]));
    for (l, len, what) in [
        (sl, sizes.len(), "SIZE"),
        (tl, kinds.len(), "TYPE"),
        (cl, counts.len(), "COUNT"),
    ] {
        if len != nf {
            return Err(Fail::line(
                l,
                format!("{what} has {len} entries but FIELDS names {nf}"),
            ));
        }
    }
    let mut fields = Vec::with_capacity(nf);
    for i in 0..nf {
        let ty = ty_of(&kinds[i], sizes[i]).ok_or_else(|| {
            Fail::line(
                tl,
                format!(
                    "field '{}' has TYPE {} with SIZE {}, which PCD does not define",
                    names[i], kinds[i], sizes[i]
                ),
            )
        })?;
        fields.push(Field {
            name: names[i].clone(),
            ty,
            count: counts[i],
        });
    }
    // WIDTH x HEIGHT, checked for overflow.
    let grid_points = match (width, height) {
        (Some((_, w)), Some((hl, h))) => Some(w.checked_mul(h).ok_or_else(|| {
            Fail::line(
                hl,
                format!("WIDTH x HEIGHT = {w} x {h} overflows: no file holds that many points"),
            )
        })?),
        _ => None,
    };
    let (n, n_line) = match (points, width, grid_points) {
        (Some((pl, p)), Some((_, w)), Some(wh)) if wh != p => {
            let h = height.map_or(0, |h| h.1);
            return Err(Fail::line(
                pl,
                format!("POINTS {p} differs from WIDTH x HEIGHT = {w} x {h}"),
            ));
        }
        (Some((pl, p)), _, _) => (p, pl),
        (None, Some((wl, _)), Some(wh)) => (wh, wl),
        (None, Some((wl, w)), None) => (w, wl),
        _ => {
            return Err(Fail::line(
                data_line,
                "the PCD header gives neither POINTS nor WIDTH",
            ))
        }
    };
    // Values per point and bytes per point, checked for overflow and against the file: a
    // point cannot have more values than the file has bytes.
    let mut values_per_point = 0usize;
    let mut rec = 0usize;
    for f in &fields {
        values_per_point = values_per_point
            .checked_add(f.count)
            .filter(|&v| v <= data.len())
            .ok_or_else(|| {
                Fail::line(
                    cl,
                    format!(
                        "COUNT {} of field '{}' gives more values per point than the file has \
                         bytes ({})",
                        f.count,
                        f.name,
                        data.len()
                    ),
                )
            })?;
        // Cannot overflow: count <= data.len() and size <= 8.
        rec += f.ty.size() * f.count;
    }
    let body_len = data.len() - header_end;
    match kind {
        Data::Binary => {
            if n.checked_mul(rec).is_none_or(|need| need > body_len) {
                return Err(Fail::line(
                    n_line,
                    format!(
                        "the header declares {n} points of {rec} bytes, but only {body_len} \
                         bytes follow it"
                    ),
                ));
            }
        }
        Data::Compressed => {
            if n.checked_mul(rec)
                .is_none_or(|need| need > u32::MAX as usize)
            {
                return Err(Fail::line(
                    n_line,
                    format!(
                        "the header declares {n} points of {rec} bytes, more than \
                         binary_compressed data can hold (4 GiB)"
                    ),
                ));
            }
        }
        // A point takes at least 2 bytes of text per value ("0 ").
        Data::Ascii => {
            if n.checked_mul(values_per_point.max(1))
                .is_none_or(|need| need > body_len)
            {
                return Err(Fail::line(
                    n_line,
                    format!(
                        "the header declares {n} points of {values_per_point} values, but only \
                         {body_len} bytes of text follow it"
                    ),
                ));
            }
        }
    }
    // Columns: fields expanded by COUNT; padding fields ('_') skipped.
    // A packed colour stored as the bits of a float is read as those bits (a 32-bit
    // unsigned integer): converting it as a float would change NaN-pattern colours.
    let mut col_names = Vec::new();
    let mut col_ty = Vec::new();
    let mut packed_float = Vec::new();
    for f in &fields {
        let packed = f.count == 1 && f.ty == Ty::F32 && is_packed_name(&f.name);
        for k in 0..f.count {
            col_names.push(if f.count == 1 || f.name == "_" {
                f.name.clone()
            } else {
                format!("{}_{k}", f.name)
            });
            col_ty.push(if packed { Ty::U32 } else { f.ty });
            packed_float.push(packed);
        }
    }
    let (dest, scalar_names, has_normals) =
        assign_columns(&col_names).map_err(|m| Fail::line(fl, m))?;
    let mut b = Builder::new(dest, scalar_names, has_normals, n);
    match kind {
        Data::Ascii => {
            let mut got = 0;
            let mut vals = Vec::with_capacity(col_ty.len());
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
                    let c = vals.len();
                    // A packed colour in text: PCL (1.7 on) writes the unsigned integer of its
                    // bits; older writers printed the float.
                    let packed = packed_float.get(c) == Some(&true);
                    let v = match tok.parse::<u32>() {
                        Ok(u) if packed => u as f64,
                        _ => {
                            let v = parse_num(tok).ok_or_else(|| {
                                Fail::line(ln, format!("'{tok}' is not a number (point {got})"))
                            })?;
                            match (packed, col_ty.get(c)) {
                                (true, _) => (v as f32).to_bits() as f64,
                                (false, Some(t)) => t.round_text(v),
                                (false, None) => v,
                            }
                        }
                    };
                    vals.push(v);
                }
                if vals.len() != col_ty.len() {
                    return Err(Fail::line(
                        ln,
                        format!(
                            "point {got} has {} values, the header declares {}",
                            vals.len(),
                            col_ty.len()
                        ),
                    ));
                }
                b.push(vals.iter().copied());
                got += 1;
            }
            if got < n {
                return Err(Fail::line(
                    end_line.max(1),
                    format!("the header declares {n} points but the file holds {got}"),
                )
                .at_last_line(data));
            }
        }
        Data::Binary => {
            let body = &data[header_end..];
            if body.len() < n * rec {
                let i = body.len() / rec.max(1);
                return Err(Fail::byte(
                    header_end + i * rec,
                    format!("the file ends inside point {i} of {n} ({rec} bytes per point)"),
                ));
            }
            let mut vals = Vec::with_capacity(col_ty.len());
            for i in 0..n {
                let r = &body[i * rec..(i + 1) * rec];
                vals.clear();
                let mut o = 0;
                for &ty in &col_ty {
                    vals.push(ty.read(&r[o..], false));
                    o += ty.size();
                }
                b.push(vals.iter().copied());
            }
        }
        Data::Compressed => {
            let body = &data[header_end..];
            if body.len() < 8 {
                return Err(Fail::byte(
                    header_end,
                    "binary_compressed data must start with two 32-bit sizes",
                ));
            }
            let csize = u32::from_le_bytes(body[0..4].try_into().unwrap()) as usize;
            let usize_ = u32::from_le_bytes(body[4..8].try_into().unwrap()) as usize;
            if usize_ != n * rec {
                // n * rec was checked above.
                return Err(Fail::byte(
                    header_end + 4,
                    format!(
                        "uncompressed size {usize_} differs from {n} points x {rec} bytes = {}",
                        n * rec
                    ),
                ));
            }
            if body.len() - 8 < csize {
                return Err(Fail::byte(
                    header_end,
                    format!(
                        "compressed size {csize} exceeds the {} bytes left in the file",
                        body.len() - 8
                    ),
                ));
            }
            if usize_ > lzf::max_decompressed(csize) {
                return Err(Fail::byte(
                    header_end + 4,
                    format!(
                        "uncompressed size {usize_} cannot come from {csize} bytes of LZF data"
                    ),
                ));
            }
            let raw = lzf::decompress(&body[8..8 + csize], usize_).map_err(|(o, m)| {
                Fail::byte(header_end + 8 + o, format!("corrupt LZF data: {m}"))
            })?;
            // Field by field: all points' values of field 0, then of field 1, ...
            let mut starts = Vec::with_capacity(col_ty.len());
            let mut col_sizes = Vec::with_capacity(col_ty.len());
            let mut base = 0;
            for f in &fields {
                let fs = f.ty.size() * f.count;
                for k in 0..f.count {
                    starts.push(base + k * f.ty.size());
                    col_sizes.push(fs);
                }
                base += n * fs;
            }
            let mut vals = Vec::with_capacity(col_ty.len());
            for i in 0..n {
                vals.clear();
                for c in 0..col_ty.len() {
                    let o = starts[c] + i * col_sizes[c];
                    vals.push(col_ty[c].read(&raw[o..], false));
                }
                b.push(vals.iter().copied());
            }
        }
    }
    let mut cloud = b.finish();
    cloud.source_precision = fields
        .iter()
        .find(|f| f.name == "x")
        .map(|f| super::Precision::of_type(f.ty));
    if let (Some((_, w)), Some((_, h)), Some(wh)) = (width, height, grid_points) {
        if h > 1 && wh == n {
            cloud.grid = Some(Grid {
                width: w,
                height: h,
            });
        }
    }
    Ok(cloud)
}

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
    );
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
        };
        size.push(s);
        ty.push(t);
    }
    write!(
        w,
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {}\nSIZE {}\nTYPE {}\n\
         COUNT {}\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n",
        cols.names().join(" "),
        size.join(" "),
        ty.join(" "),
        vec!["1"; cols.len()].join(" "),
    )?;
    match enc {
        Encoding::Ascii => {
            let mut line = String::new();
            for i in 0..n {
                cols.line(&mut line, i, single);
                w.write_all(line.as_bytes())?;
            }
        }
        Encoding::Binary => {
            let mut buf = Vec::new();
            for i in 0..n {
                buf.clear();
                for c in 0..cols.len() {
                    cols.put(&mut buf, c, i, single, false);
                }
                w.write_all(&buf)?;
            }
        }
        Encoding::BinaryCompressed => {
            // Field by field, as PCL stores it: all points' x, then all y, ...
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
        }
        Encoding::BinaryBigEndian => unreachable!(),
    }
    Ok(())
}
