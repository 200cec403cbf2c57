//! The PLY header: the format line and the elements with their properties, up to `end_header`.

use crate::io::error::{Fail, PResult};
use crate::io::value::{tokens, Lines, Ty};

/// How the elements are stored after the header (`format`).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Fmt {
    Ascii,
    Le,
    Be,
}

impl Fmt {
    fn parse(ln: usize, word: Option<&str>) -> PResult<Fmt> {
        match word {
            Some("ascii") => Ok(Fmt::Ascii),
            Some("binary_little_endian") => Ok(Fmt::Le),
            Some("binary_big_endian") => Ok(Fmt::Be),
            other => Err(Fail::line(
                ln,
                format!(
                    "format must be ascii, binary_little_endian or binary_big_endian, not '{}'",
                    other.unwrap_or("")
                ),
            )),
        }
    }
}

/// A property: one value, or a list (its length, then its items).
pub(super) enum Prop {
    Scalar(Ty),
    List(Ty, Ty),
}

/// An element (`vertex`, `face`, ...): `count` records of its properties.
pub(super) struct Element {
    pub name: String,
    pub count: usize,
    pub props: Vec<(String, Prop)>,
    /// Header line of the `element` entry, for errors about its count.
    pub line: usize,
}

impl Element {
    /// Fewest bytes one binary record can take: the scalars plus each list's length field.
    pub fn min_record(&self) -> usize {
        self.props
            .iter()
            .map(|(_, p)| match p {
                Prop::Scalar(t) => t.size(),
                Prop::List(ct, _) => ct.size(),
            })
            .sum()
    }

    /// `element NAME COUNT` on line `ln`, with no properties yet.
    fn parse(ln: usize, rest: &[&str]) -> PResult<Element> {
        let (Some(name), Some(count)) = (rest.first(), rest.get(1)) else {
            return Err(Fail::line(ln, "element needs a name and a count"));
        };
        let count = count
            .parse::<usize>()
            .map_err(|_| Fail::line(ln, format!("element count '{count}' is not an integer")))?;
        Ok(Element {
            name: name.to_string(),
            count,
            props: Vec::new(),
            line: ln,
        })
    }
}

/// `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME` on line `ln`.
fn parse_property(ln: usize, rest: &[&str]) -> PResult<(String, Prop)> {
    let ty =
        |t: &str| ty_of(t).ok_or_else(|| Fail::line(ln, format!("unknown property type '{t}'")));
    match rest {
        ["list", ct, it, name] => Ok((name.to_string(), Prop::List(ty(ct)?, ty(it)?))),
        [t, name] if *t != "list" => Ok((name.to_string(), Prop::Scalar(ty(t)?))),
        _ => Err(Fail::line(
            ln,
            "property must be 'property TYPE NAME' or \
             'property list COUNT_TYPE ITEM_TYPE NAME'",
        )),
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

/// The header's keyword lines as written, up to `end_header`; nothing checked across lines yet.
#[derive(Default)]
struct Keywords {
    fmt: Option<Fmt>,
    elements: Vec<Element>,
    comments: Vec<String>,
    ended: bool,
}

impl Keywords {
    /// Reads the lines after `ply` up to and including `end_header` (or to the end of the
    /// file).
    fn read(lines: &mut Lines<'_>) -> PResult<Keywords> {
        let mut k = Keywords::default();
        for item in lines.by_ref() {
            let (ln, line) = item?;
            let mut tok = tokens(line);
            let Some(key) = tok.next() else { continue };
            if key == "comment" || key == "obj_info" {
                k.comment(key, line);
                continue;
            }
            let rest: Vec<&str> = tok.collect();
            k.take(ln, key, &rest)?;
            if k.ended {
                break;
            }
        }
        Ok(k)
    }

    /// Keeps a `comment` line's text (`obj_info` lines as `obj_info TEXT`), but nbhd's own
    /// `written by nbhd ...`, which its writer puts anew.
    fn comment(&mut self, key: &str, line: &str) {
        let text = line.trim_start()[key.len()..].trim();
        if key == "obj_info" {
            self.comments.push(format!("obj_info {text}"));
        } else if !text.starts_with("written by nbhd") {
            self.comments.push(text.to_string());
        }
    }

    /// Takes the keyword `key` with its words `rest`, on line `ln`.
    fn take(&mut self, ln: usize, key: &str, rest: &[&str]) -> PResult<()> {
        match key {
            "format" => self.fmt = Some(Fmt::parse(ln, rest.first().copied())?),
            "element" => self.elements.push(Element::parse(ln, rest)?),
            "property" => {
                let Some(el) = self.elements.last_mut() else {
                    return Err(Fail::line(ln, "property before any element"));
                };
                el.props.push(parse_property(ln, rest)?);
            }
            "end_header" => self.ended = true,
            other => {
                return Err(Fail::line(
                    ln,
                    format!("unknown PLY header keyword '{other}'"),
                ))
            }
        }
        Ok(())
    }
}

/// A checked PLY header.
pub(super) struct Header {
    /// How the elements are stored.
    pub fmt: Fmt,
    /// The elements, in file order.
    pub elements: Vec<Element>,
    /// Index of the `vertex` element in `elements`.
    pub vertex: usize,
    /// Byte offset of the data, just after `end_header`.
    pub end: usize,
    /// Line number of `end_header`.
    pub end_line: usize,
    /// `comment` lines' text, `obj_info` lines as `obj_info TEXT`.
    pub comments: Vec<String>,
}

impl Header {
    /// Reads the header of the PLY file `data`: `ply`, then keyword lines up to `end_header`,
    /// with a format and a `vertex` element.
    pub fn parse(data: &[u8]) -> PResult<Header> {
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
        let Keywords {
            fmt,
            elements,
            comments,
            ended,
        } = Keywords::read(&mut lines)?;
        let end_line = lines.line_no();
        if !ended {
            return Err(Fail::line(
                end_line.max(1),
                "the PLY header has no end_header",
            ));
        }
        let Some(fmt) = fmt else {
            return Err(Fail::line(2, "the PLY header has no format line"));
        };
        let Some(vertex) = elements.iter().position(|e| e.name == "vertex") else {
            return Err(Fail::line(end_line, "the PLY file has no vertex element"));
        };
        Ok(Header {
            fmt,
            elements,
            vertex,
            end: lines.offset(),
            end_line,
            comments,
        })
    }

    /// The `vertex` element.
    pub fn vertex(&self) -> &Element {
        &self.elements[self.vertex]
    }
}
