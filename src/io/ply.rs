//! PLY (Stanford polygon format): the `vertex` element is the cloud; other elements (faces,
//! ...) are skipped.

use super::assemble::{assign_columns, Builder};
use super::columns::{ColorStyle, Columns, Store};
use super::error::{Fail, PResult};
use super::value::{parse_num, tokens, Lines, Ty};
use super::{Encoding, PointCloud};
use std::io::Write;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Fmt {
    Ascii,
    Le,
    Be,
}

enum Prop {
    Scalar(Ty),
    List(Ty, Ty),
}

struct Element {
    name: String,
    count: usize,
    props: Vec<(String, Prop)>,
    /// Header line of the `element` entry, for errors about its count.
    line: usize,
}

impl Element {
    /// Fewest bytes one binary record can take: the scalars plus each list's length field.
    fn min_record(&self) -> usize {
        self.props
            .iter()
            .map(|(_, p)| match p {
                Prop::Scalar(t) => t.size(),
                Prop::List(ct, _) => ct.size(),
            })
            .sum()
    }
}

fn ty_of(s: &str) -> Option<Ty> {
    Some(match s {
        "char" | "int8" => Ty::I8,
        "uchar" | "uint8" => Ty::U8,
        "short" | "int16" => Ty::I16,
        "ushort" | "uint16" => Ty::U16,
        "int" | "int32" => Ty::I32,
        "uint" | "uint32" => Ty::U32,
        "float" | "float32" => Ty::F32,
        "double" | "float64" => Ty::F64,
        _ => return None,
    })
}

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    let mut lines = Lines::new(data, 0, 1);
    match lines.next() {
        Some(Ok((_, "ply"))) => {}
        _ => {
            return Err(Fail::line(
                1,
                "not a PLY file: the first line must be 'ply'",
            ))
        }
    }
    let mut fmt = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut ended = false;
    for item in lines.by_ref() {
        let (ln, line) = item?;
        let mut tok = tokens(line);
        let Some(key) = tok.next() else { continue };
        let rest: Vec<&str> = tok.collect();
        match key {
            "comment" | "obj_info" => {}
            "format" => {
                fmt = Some(match rest.first().copied() {
                    Some("ascii") => Fmt::Ascii,
                    Some("binary_little_endian") => Fmt::Le,
                    Some("binary_big_endian") => Fmt::Be,
                    other => {
                        return Err(Fail::line(
                            ln,
                            format!(
                                "format must be ascii, binary_little_endian or \
                                 binary_big_endian, not '{}'",
                                other.unwrap_or("")
                            ),
                        ))
                    }
                })
            }
            "element" => {
                let (Some(name), Some(count)) = (rest.first(), rest.get(1)) else {
                    return Err(Fail::line(ln, "element needs a name and a count"));
                };
                let count = count.parse::<usize>().map_err(|_| {
                    Fail::line(ln, format!("element count '{count}' is not an integer"))
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line: ln,
                });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(Fail::line(ln, "property before any element"));
                };
                let bad = |t: &str| Fail::line(ln, format!("unknown property type '{t}'"));
                let prop = match rest.as_slice() {
                    ["list", ct, it, name] => (
                        name.to_string(),
                        Prop::List(
                            ty_of(ct).ok_or_else(|| bad(ct))?,
                            ty_of(it).ok_or_else(|| bad(it))?,
                        ),
                    ),
                    [t, name] if *t != "list" => (
                        name.to_string(),
                        Prop::Scalar(ty_of(t).ok_or_else(|| bad(t))?),
                    ),
                    _ => {
                        return Err(Fail::line(
                            ln,
                            "property must be 'property TYPE NAME' or \
                             'property list COUNT_TYPE ITEM_TYPE NAME'",
                        ))
                    }
                };
                el.props.push(prop);
            }
            "end_header" => {
                ended = true;
                break;
            }
            other => {
                return Err(Fail::line(
                    ln,
                    format!("unknown PLY header keyword '{other}'"),
                ))
            }
        }
    }
    let header_lines = lines.line_no();
    if !ended {
        return Err(Fail::line(
            header_lines.max(1),
            "the PLY header has no end_header",
        ));
    }
    let Some(fmt) = fmt else {
        return Err(Fail::line(2, "the PLY header has no format line"));
    };
    let Some(vi) = elements.iter().position(|e| e.name == "vertex") else {
        return Err(Fail::line(
            header_lines,
            "the PLY file has no vertex element",
        ));
    };
    let vertex = &elements[vi];
    let n = vertex.count;
    // Vertex columns: scalar properties; list properties are skipped.
    let names: Vec<String> = vertex
        .props
        .iter()
        .filter(|(_, p)| matches!(p, Prop::Scalar(_)))
        .map(|(s, _)| s.clone())
        .collect();
    let (dest, scalar_names, has_normals) = assign_columns(&names)
        .map_err(|m| Fail::line(header_lines, format!("vertex element: {m}")))?;
    let mut b = Builder::new(dest, scalar_names, has_normals, n);
    let mut vals = Vec::with_capacity(names.len());
    if fmt == Fmt::Ascii {
        let mut it = lines.filter(|r| !matches!(r, Ok((_, l)) if l.trim().is_empty()));
        for el in &elements[..vi] {
            for i in 0..el.count {
                if it.next().transpose()?.is_none() {
                    return Err(Fail::line(
                        header_lines,
                        format!(
                            "the file ends inside element '{}' ({i} of {})",
                            el.name, el.count
                        ),
                    )
                    .at_last_line(data));
                }
            }
        }
        for i in 0..n {
            let Some((ln, line)) = it.next().transpose()? else {
                return Err(Fail::line(
                    header_lines,
                    format!("the header declares {n} vertices but the file holds {i}"),
                )
                .at_last_line(data));
            };
            vals.clear();
            let mut tok = tokens(line);
            for (pname, p) in &vertex.props {
                let mut next = |what: &str| -> PResult<f64> {
                    let t = tok.next().ok_or_else(|| {
                        Fail::line(ln, format!("vertex {i}: missing {what} '{pname}'"))
                    })?;
                    parse_num(t).ok_or_else(|| {
                        Fail::line(ln, format!("vertex {i}: '{t}' ({pname}) is not a number"))
                    })
                };
                match p {
                    Prop::Scalar(t) => vals.push(t.round_text(next("value of")?)),
                    Prop::List(..) => {
                        let c = next("list count of")?;
                        for _ in 0..(c.max(0.0) as usize) {
                            next("list item of")?;
                        }
                    }
                }
            }
            b.push(vals.iter().copied());
        }
    } else {
        let be = fmt == Fmt::Be;
        let mut pos = lines.offset();
        // A record cut short is reported at the byte where it starts.
        let need = |start: usize, pos: usize, k: usize, what: &dyn Fn() -> String| -> PResult<()> {
            if pos + k > data.len() {
                Err(Fail::byte(
                    start,
                    format!("the file ends inside {}", what()),
                ))
            } else {
                Ok(())
            }
        };
        for (ei, el) in elements[..=vi].iter().enumerate() {
            let is_vertex = ei == vi;
            // Never trust the count: the records must fit in the bytes that are left.
            let left = data.len() - pos;
            let min = el.min_record();
            match el.count.checked_mul(min) {
                Some(need) if need <= left => {}
                _ => {
                    return Err(Fail::line(
                        el.line,
                        format!(
                            "element '{}' declares {} records of at least {min} bytes, but only \
                             {left} bytes follow the header",
                            el.name, el.count
                        ),
                    ))
                }
            }
            if min == 0 {
                // No properties: the records take no bytes (and are not looped over).
                continue;
            }
            if !is_vertex && el.props.iter().all(|(_, p)| matches!(p, Prop::Scalar(_))) {
                pos += el.count * min;
                continue;
            }
            for i in 0..el.count {
                let what = || format!("element '{}' {i} of {}", el.name, el.count);
                let start = pos;
                if is_vertex {
                    vals.clear();
                }
                for (_, p) in &el.props {
                    match p {
                        Prop::Scalar(t) => {
                            need(start, pos, t.size(), &what)?;
                            if is_vertex {
                                vals.push(t.read(&data[pos..], be));
                            }
                            pos += t.size();
                        }
                        Prop::List(ct, it) => {
                            need(start, pos, ct.size(), &what)?;
                            let c = ct.read(&data[pos..], be);
                            if !(0.0..=u32::MAX as f64).contains(&c) {
                                return Err(Fail::byte(
                                    pos,
                                    format!("list length {c} in {}", what()),
                                ));
                            }
                            pos += ct.size();
                            let k = c as usize * it.size();
                            need(start, pos, k, &what)?;
                            pos += k;
                        }
                    }
                }
                if is_vertex {
                    b.push(vals.iter().copied());
                }
            }
        }
    }
    let mut cloud = b.finish();
    cloud.source_precision = vertex.props.iter().find_map(|(name, p)| match p {
        Prop::Scalar(t) if name == "x" => Some(super::Precision::of_type(*t)),
        _ => None,
    });
    Ok(cloud)
}

pub(crate) fn write(
    w: &mut impl Write,
    cloud: &PointCloud,
    enc: Encoding,
    single: bool,
) -> PResult<()> {
    let cols = Columns::new(cloud, ["nx", "ny", "nz"], ColorStyle::Channels);
    let fmt = match enc {
        Encoding::Ascii => "ascii",
        Encoding::Binary => "binary_little_endian",
        Encoding::BinaryBigEndian => "binary_big_endian",
        Encoding::BinaryCompressed => unreachable!("refused by check_writable"),
    };
    let float = if single { "float" } else { "double" };
    let mut h = format!(
        "ply\nformat {fmt} 1.0\ncomment written by nbhd {}\nelement vertex {}\n",
        env!("CARGO_PKG_VERSION"),
        cloud.len()
    );
    for (c, name) in cols.names().iter().enumerate() {
        let ty = match cols.store(c) {
            Store::Float => float,
            Store::U8 => "uchar",
            Store::RgbBits => "uint",
        };
        h.push_str(&format!("property {ty} {name}\n"));
    }
    h.push_str("end_header\n");
    w.write_all(h.as_bytes())?;
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
