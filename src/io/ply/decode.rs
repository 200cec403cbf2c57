//! The elements after a PLY header, one function per format: `ascii` (a line per record) and
//! binary (records of packed values, little or big endian). Elements before `vertex` are
//! skipped, the vertex records are read, elements after it are not looked at.

use super::header::{Element, Header, Prop};
use crate::io::assemble::Builder;
use crate::io::error::{Fail, PResult};
use crate::io::value::{parse_num, tokens, Lines};

/// `format ascii`: a line per record, values separated by whitespace; blank lines skipped.
pub(super) fn ascii(data: &[u8], header: &Header, b: &mut Builder) -> PResult<()> {
    let lines = Lines::new(data, header.end, header.end_line + 1);
    let mut it = lines.filter(|r| !matches!(r, Ok((_, l)) if l.trim().is_empty()));
    for el in &header.elements[..header.vertex] {
        for i in 0..el.count {
            if it.next().transpose()?.is_none() {
                return Err(Fail::line(
                    header.end_line,
                    format!(
                        "the file ends inside element '{}' ({i} of {})",
                        el.name, el.count
                    ),
                )
                .at_last_line(data));
            }
        }
    }
    let vertex = header.vertex();
    let n = vertex.count;
    let mut vals = Vec::new();
    for i in 0..n {
        let Some((ln, line)) = it.next().transpose()? else {
            return Err(Fail::line(
                header.end_line,
                format!("the header declares {n} vertices but the file holds {i}"),
            )
            .at_last_line(data));
        };
        vals.clear();
        ascii_vertex(vertex, i, ln, line, &mut vals)?;
        b.push(vals.iter().copied());
    }
    Ok(())
}

/// The scalar values of vertex `i` from its text `line` (line `ln`); list properties are read
/// past.
fn ascii_vertex(
    vertex: &Element,
    i: usize,
    ln: usize,
    line: &str,
    vals: &mut Vec<f64>,
) -> PResult<()> {
    let mut tok = tokens(line);
    for (pname, p) in &vertex.props {
        let mut next = |what: &str| -> PResult<f64> {
            let t = tok
                .next()
                .ok_or_else(|| Fail::line(ln, format!("vertex {i}: missing {what} '{pname}'")))?;
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
    Ok(())
}

/// `format binary_little_endian` (`big_endian` false) or `binary_big_endian`.
pub(super) fn binary(
    data: &[u8],
    header: &Header,
    big_endian: bool,
    b: &mut Builder,
) -> PResult<()> {
    let mut r = Records {
        data,
        pos: header.end,
        big_endian,
    };
    let mut vals = Vec::new();
    for (ei, el) in header.elements[..=header.vertex].iter().enumerate() {
        let is_vertex = ei == header.vertex;
        let min = r.check_count(el)?;
        if min == 0 {
            // No properties: the records take no bytes (and are not looped over).
            continue;
        }
        if !is_vertex && el.props.iter().all(|(_, p)| matches!(p, Prop::Scalar(_))) {
            r.pos += el.count * min;
            continue;
        }
        for i in 0..el.count {
            if is_vertex {
                vals.clear();
                r.record(el, i, Some(&mut vals))?;
                b.push(vals.iter().copied());
            } else {
                r.record(el, i, None)?;
            }
        }
    }
    Ok(())
}

/// Binary records read from `pos` on.
struct Records<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Records<'_> {
    /// Never trusts the count: the records of `el` must fit in the bytes that are left.
    /// Returns the fewest bytes a record takes.
    fn check_count(&self, el: &Element) -> PResult<usize> {
        let left = self.data.len() - self.pos;
        let min = el.min_record();
        match el.count.checked_mul(min) {
            Some(need) if need <= left => Ok(min),
            _ => Err(Fail::line(
                el.line,
                format!(
                    "element '{}' declares {} records of at least {min} bytes, but only {left} \
                     bytes follow the header",
                    el.name, el.count
                ),
            )),
        }
    }

    /// Reads record `i` of `el`, pushing its scalar values to `vals` if given.
    fn record(&mut self, el: &Element, i: usize, mut vals: Option<&mut Vec<f64>>) -> PResult<()> {
        let what = || format!("element '{}' {i} of {}", el.name, el.count);
        let start = self.pos;
        for (_, p) in &el.props {
            match p {
                Prop::Scalar(t) => {
                    self.need(start, t.size(), &what)?;
                    if let Some(vals) = vals.as_deref_mut() {
                        vals.push(t.read(&self.data[self.pos..], self.big_endian));
                    }
                    self.pos += t.size();
                }
                Prop::List(ct, it) => {
                    self.need(start, ct.size(), &what)?;
                    let c = ct.read(&self.data[self.pos..], self.big_endian);
                    if !(0.0..=u32::MAX as f64).contains(&c) {
                        return Err(Fail::byte(
                            self.pos,
                            format!("list length {c} in {}", what()),
                        ));
                    }
                    self.pos += ct.size();
                    let k = c as usize * it.size();
                    self.need(start, k, &what)?;
                    self.pos += k;
                }
            }
        }
        Ok(())
    }

    /// Whether `k` more bytes are left; a record cut short is reported at the byte where it
    /// starts (`start`).
    fn need(&self, start: usize, k: usize, what: &dyn Fn() -> String) -> PResult<()> {
        if self.pos + k > self.data.len() {
            Err(Fail::byte(
                start,
                format!("the file ends inside {}", what()),
            ))
        } else {
            Ok(())
        }
    }
}
