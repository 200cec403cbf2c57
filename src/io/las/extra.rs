//! LAS "extra bytes": per-point values after the standard fields of a record, described by the
//! extra-bytes VLR (user id `LASF_Spec`, record 4; LAS 1.4 R15 section 2.5.5 "Extra Bytes").
//! The `las` crate carries the bytes of each record but not their meaning; this is that layer.
//!
//! A description is 192 bytes: data type (1–10: `u8 i8 u16 i16 u32 i32 u64 i64 f32 f64`; 0:
//! undocumented bytes, `options` of them), options (bit 0 no-data, 1 min, 2 max, 3 scale,
//! 4 offset), name (32 bytes), no-data, min and max (8 bytes each, as `u64`, `i64` or `f64` by
//! the type), scale and offset (`f64`), description (32 bytes). A value is
//! `raw * scale + offset`, each applied only when its option bit is set.

use crate::io::LasVlr;

/// User id and record id of the extra-bytes VLR.
pub(super) const USER_ID: &str = "LASF_Spec";
pub(super) const RECORD_ID: u16 = 4;
/// Bytes of one description.
const DESCRIPTOR_LEN: usize = 192;

const NO_DATA: u8 = 1;
const MIN: u8 = 2;
const MAX: u8 = 4;
const SCALE: u8 = 8;
const OFFSET: u8 = 16;

/// One described value of every record.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Dim {
    pub name: String,
    /// Data type 1–10.
    pub ty: u8,
    pub options: u8,
    /// No-data value in the raw type's 8-byte form.
    pub no_data: [u8; 8],
    pub scale: f64,
    pub offset: f64,
    pub description: String,
}

/// Bytes of a value of data type `ty` (1–10), `None` for others.
fn size_of(ty: u8) -> Option<usize> {
    Some(match ty {
        1 | 2 => 1,
        3 | 4 => 2,
        5 | 6 | 9 => 4,
        7 | 8 | 10 => 8,
        _ => return None,
    })
}

fn is_signed(ty: u8) -> bool {
    matches!(ty, 2 | 4 | 6 | 8)
}

fn is_float(ty: u8) -> bool {
    matches!(ty, 9 | 10)
}

/// A fixed-size text field (NUL-padded).
fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).trim().to_string()
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// The extra bytes of a record format: the described values in record order (with their byte
/// offset in the extra bytes) and, as words, what is not described in a way nbhd reads.
pub(super) struct Layout {
    pub dims: Vec<(usize, Dim)>,
    pub unread: Vec<String>,
}

/// Reads the descriptions of the `extra_bytes` bytes of each record from the file's VLRs.
pub(super) fn layout(vlrs: &[LasVlr], extra_bytes: usize) -> Layout {
    let mut l = Layout {
        dims: Vec::new(),
        unread: Vec::new(),
    };
    let Some(vlr) = vlrs.iter().find(|v| is_extra_bytes(v)) else {
        if extra_bytes > 0 {
            l.unread.push(format!(
                "{extra_bytes} extra bytes per point without an extra-bytes description"
            ));
        }
        return l;
    };
    let mut at = 0usize;
    for d in vlr.data.chunks_exact(DESCRIPTOR_LEN) {
        let name = text(&d[4..36]);
        let (ty, options) = (d[2], d[3]);
        let size = match (ty, size_of(ty)) {
            (0, _) => usize::from(options),
            (_, Some(s)) => s,
            // Deprecated array types (11-30): 2 or 3 values of a base type.
            (_, None) => size_of((ty - 1) % 10 + 1).unwrap_or(0) * (2 + usize::from(ty > 20)),
        };
        if at + size > extra_bytes {
            l.unread.push(format!(
                "extra bytes from '{name}' on: described beyond the {extra_bytes} bytes a record has"
            ));
            return l;
        }
        if size_of(ty).is_some() {
            let dim = Dim {
                name,
                ty,
                options,
                no_data: d[40..48].try_into().expect("8 bytes"),
                scale: f64_at(d, 112),
                offset: f64_at(d, 136),
                description: text(&d[160..192]),
            };
            l.dims.push((at, dim));
        } else {
            l.unread.push(format!(
                "extra bytes '{name}' (data type {ty}: {size} bytes per point)"
            ));
        }
        at += size;
    }
    if at < extra_bytes {
        l.unread.push(format!(
            "{} undescribed extra bytes per point",
            extra_bytes - at
        ));
    }
    l
}

/// Whether `v` is the extra-bytes VLR.
pub(super) fn is_extra_bytes(v: &LasVlr) -> bool {
    v.user_id == USER_ID && v.record_id == RECORD_ID
}

impl Dim {
    /// A new description of values stored as `f32` (`single`) or `f64`.
    pub fn float(name: &str, description: &str, single: bool) -> Dim {
        Dim {
            name: name.to_string(),
            ty: if single { 9 } else { 10 },
            options: 0,
            no_data: [0; 8],
            scale: 1.0,
            offset: 0.0,
            description: description.to_string(),
        }
    }

    /// Bytes per point.
    pub fn size(&self) -> usize {
        size_of(self.ty).expect("data types 1-10 only")
    }

    /// The raw value at the start of `b` in the 8-byte form of the type (`u64`, `i64` bits, or
    /// `f64` bits).
    fn raw(&self, b: &[u8]) -> [u8; 8] {
        let n = self.size();
        let mut w = [0u8; 8];
        if self.ty == 9 {
            let f = f32::from_le_bytes(b[..4].try_into().expect("4 bytes"));
            return (f as f64).to_le_bytes();
        }
        w[..n].copy_from_slice(&b[..n]);
        if is_signed(self.ty) && b[n - 1] & 0x80 != 0 {
            w[n..].fill(0xff);
        }
        w
    }

    /// The 8-byte raw form as a number.
    fn number(&self, w: [u8; 8]) -> f64 {
        if is_float(self.ty) {
            f64::from_le_bytes(w)
        } else if is_signed(self.ty) {
            i64::from_le_bytes(w) as f64
        } else {
            u64::from_le_bytes(w) as f64
        }
    }

    /// The value stored at the start of `b`: NaN for the no-data value, scaled and offset as
    /// the options say.
    pub fn decode(&self, b: &[u8]) -> f64 {
        let w = self.raw(b);
        if self.options & NO_DATA != 0 && w == self.no_data_raw() {
            return f64::NAN;
        }
        let mut v = self.number(w);
        if self.options & SCALE != 0 {
            v *= self.scale;
        }
        if self.options & OFFSET != 0 {
            v += self.offset;
        }
        v
    }

    /// The no-data value as the type's 8-byte form (an `f32` type's stored as `f64`).
    fn no_data_raw(&self) -> [u8; 8] {
        self.no_data
    }

    /// `v` as the stored raw number, if the type holds it (NaN only as a no-data value).
    fn unscaled(&self, v: f64) -> Option<f64> {
        if v.is_nan() {
            return (self.options & NO_DATA != 0).then(|| self.number(self.no_data));
        }
        let mut r = v;
        if self.options & OFFSET != 0 {
            r -= self.offset;
        }
        if self.options & SCALE != 0 {
            r /= self.scale;
        }
        if is_float(self.ty) {
            return Some(r);
        }
        let r = r.round();
        let (lo, hi) = match self.ty {
            1 => (0.0, u8::MAX as f64),
            2 => (i8::MIN as f64, i8::MAX as f64),
            3 => (0.0, u16::MAX as f64),
            4 => (i16::MIN as f64, i16::MAX as f64),
            5 => (0.0, u32::MAX as f64),
            6 => (i32::MIN as f64, i32::MAX as f64),
            // 2^64 and -2^63 are exact doubles; the top of each range is not reachable.
            7 => (0.0, 18_446_744_073_709_549_568.0),
            _ => (i64::MIN as f64, 9_223_372_036_854_774_784.0),
        };
        (lo..=hi).contains(&r).then_some(r)
    }

    /// Whether every value of `values` can be stored.
    pub fn holds(&self, mut values: impl Iterator<Item = f64>) -> bool {
        values.all(|v| self.unscaled(v).is_some())
    }

    /// Appends `v` in the record's form; `holds` must have accepted it.
    pub fn encode(&self, v: f64, out: &mut Vec<u8>) {
        let r = self.unscaled(v).unwrap_or(0.0);
        match self.ty {
            1 => out.push(r as u8),
            2 => out.push(r as i8 as u8),
            3 => out.extend_from_slice(&(r as u16).to_le_bytes()),
            4 => out.extend_from_slice(&(r as i16).to_le_bytes()),
            5 => out.extend_from_slice(&(r as u32).to_le_bytes()),
            6 => out.extend_from_slice(&(r as i32).to_le_bytes()),
            7 => out.extend_from_slice(&(r as u64).to_le_bytes()),
            8 => out.extend_from_slice(&(r as i64).to_le_bytes()),
            9 => out.extend_from_slice(&(r as f32).to_le_bytes()),
            _ => out.extend_from_slice(&r.to_le_bytes()),
        }
    }

    /// The 192-byte description, with the min and max of `values` if the options ask for
    /// them.
    fn descriptor(&self, values: impl Iterator<Item = f64> + Clone) -> [u8; DESCRIPTOR_LEN] {
        let mut d = [0u8; DESCRIPTOR_LEN];
        d[2] = self.ty;
        d[3] = self.options;
        put_text(&mut d[4..36], &self.name);
        d[40..48].copy_from_slice(&self.no_data);
        let raws = || {
            values
                .clone()
                .filter(|v| !v.is_nan())
                .filter_map(|v| self.unscaled(v))
        };
        let as_raw = |r: f64| -> [u8; 8] {
            if is_float(self.ty) {
                r.to_le_bytes()
            } else if is_signed(self.ty) {
                (r as i64).to_le_bytes()
            } else {
                (r as u64).to_le_bytes()
            }
        };
        if self.options & MIN != 0 {
            let m = raws().fold(f64::INFINITY, f64::min);
            d[64..72].copy_from_slice(&as_raw(if m.is_finite() { m } else { 0.0 }));
        }
        if self.options & MAX != 0 {
            let m = raws().fold(f64::NEG_INFINITY, f64::max);
            d[88..96].copy_from_slice(&as_raw(if m.is_finite() { m } else { 0.0 }));
        }
        d[112..120].copy_from_slice(&self.scale.to_le_bytes());
        d[136..144].copy_from_slice(&self.offset.to_le_bytes());
        put_text(&mut d[160..192], &self.description);
        d
    }
}

/// Writes `s` into a fixed-size text field, cut at a character boundary to fit with a NUL.
fn put_text(field: &mut [u8], s: &str) {
    let mut end = s.len().min(field.len() - 1);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    field[..end].copy_from_slice(&s.as_bytes()[..end]);
}

/// The extra-bytes VLR describing each dimension, given with its values per point.
pub(super) fn vlr<'d, I>(dims: impl IntoIterator<Item = (&'d Dim, I)>) -> LasVlr
where
    I: Iterator<Item = f64> + Clone,
{
    let mut data = Vec::new();
    for (d, v) in dims {
        data.extend_from_slice(&d.descriptor(v));
    }
    LasVlr {
        user_id: USER_ID.to_string(),
        record_id: RECORD_ID,
        description: "Extra bytes".to_string(),
        data,
    }
}
