//! Binary scalar types shared by PLY and PCD, text lines with their numbers, number formatting.

use super::error::{Fail, PResult};

/// A stored scalar type: [`FieldType`](super::FieldType), the type a file stores a field as;
/// its methods here are the readers' and writers' own.
pub(crate) type Ty = super::FieldType;

impl Ty {
    /// The smallest and largest value of an integer type (64-bit ones as far as an `f64`
    /// holds every integer exactly), `None` for floats.
    pub(crate) fn int_range(self) -> Option<(f64, f64)> {
        Some(match self {
            Ty::I8 => (i8::MIN as f64, i8::MAX as f64),
            Ty::U8 => (0.0, u8::MAX as f64),
            Ty::I16 => (i16::MIN as f64, i16::MAX as f64),
            Ty::U16 => (0.0, u16::MAX as f64),
            Ty::I32 => (i32::MIN as f64, i32::MAX as f64),
            Ty::U32 => (0.0, u32::MAX as f64),
            Ty::I64 => (-(2f64.powi(53)), 2f64.powi(53)),
            Ty::U64 => (0.0, 2f64.powi(53)),
            Ty::F32 | Ty::F64 => return None,
        })
    }

    /// Whether every value of `values` is an integer this (integer) type holds.
    pub(crate) fn holds_all(self, values: &[f64]) -> bool {
        self.int_range().is_some_and(|(lo, hi)| {
            values
                .iter()
                .all(|&v| (lo..=hi).contains(&v) && v.fract() == 0.0)
        })
    }

    /// Appends `v` in this type's bytes (an integer type's: `v` is an integer it holds).
    pub(crate) fn put(self, v: f64, buf: &mut Vec<u8>, big_endian: bool) {
        macro_rules! put {
            ($x:expr) => {
                if big_endian {
                    buf.extend_from_slice(&$x.to_be_bytes())
                } else {
                    buf.extend_from_slice(&$x.to_le_bytes())
                }
            };
        }
        match self {
            Ty::I8 => buf.push(v as i8 as u8),
            Ty::U8 => buf.push(v as u8),
            Ty::I16 => put!(v as i16),
            Ty::U16 => put!(v as u16),
            Ty::I32 => put!(v as i32),
            Ty::U32 => put!(v as u32),
            Ty::I64 => put!(v as i64),
            Ty::U64 => put!(v as u64),
            Ty::F32 => put!(v as f32),
            Ty::F64 => put!(v),
        }
    }

    pub(crate) fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::I64 | Ty::U64 | Ty::F64 => 8,
        }
    }

    /// A number read from text, rounded to this type as a binary file would hold it
    /// (a `float` property written as `0.33333334` is the `f32` nearest to it).
    pub(crate) fn round_text(self, v: f64) -> f64 {
        if self == Ty::F32 {
            v as f32 as f64
        } else {
            v
        }
    }

    /// Reads one value from the first `size()` bytes of `b`.
    pub(crate) fn read(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                if big_endian {
                    <$t>::from_be_bytes(a) as f64
                } else {
                    <$t>::from_le_bytes(a) as f64
                }
            }};
        }
        match self {
            Ty::I8 => b[0] as i8 as f64,
            Ty::U8 => b[0] as f64,
            Ty::I16 => rd!(i16, 2),
            Ty::U16 => rd!(u16, 2),
            Ty::I32 => rd!(i32, 4),
            Ty::U32 => rd!(u32, 4),
            Ty::I64 => rd!(i64, 8),
            Ty::U64 => rd!(u64, 8),
            Ty::F32 => rd!(f32, 4),
            Ty::F64 => rd!(f64, 8),
        }
    }
}

/// Parses a number of a text format: decimal, exponent, `nan`, `inf` (any case, signed).
pub(crate) fn parse_num(tok: &str) -> Option<f64> {
    tok.parse::<f64>().ok()
}

/// Formats a value for a text format: shortest representation that reads back exactly at
/// the given precision; `nan`, `inf`, `-inf` as C's `printf` and PCL write them.
pub(crate) fn fmt_num(v: f64, single: bool) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else if single {
        format!("{}", v as f32)
    } else {
        format!("{v}")
    }
}

/// The lines of a text, with 1-based line numbers and the byte offset after each line.
pub(crate) struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    pub fn new(data: &'a [u8], start: usize, first_line: usize) -> Self {
        Self {
            data,
            pos: start,
            line: first_line - 1,
        }
    }

    /// Byte offset of the next line.
    pub fn offset(&self) -> usize {
        self.pos
    }

    /// Number of the last line returned.
    pub fn line_no(&self) -> usize {
        self.line
    }
}

impl<'a> Iterator for Lines<'a> {
    /// (line number, text without the line break)
    type Item = PResult<(usize, &'a str)>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let end = rest.iter().position(|&b| b == b'\n');
        let (raw, adv) = match end {
            Some(e) => (&rest[..e], e + 1),
            None => (rest, rest.len()),
        };
        self.pos += adv;
        self.line += 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        Some(match std::str::from_utf8(raw) {
            Ok(s) => Ok((self.line, s)),
            Err(_) => Err(Fail::line(self.line, "the line is not valid text (UTF-8)")),
        })
    }
}

/// Splits a text line into tokens (whitespace; for XYZ also commas and semicolons).
pub(crate) fn tokens(line: &str) -> impl Iterator<Item = &str> {
    line.split_ascii_whitespace()
}
