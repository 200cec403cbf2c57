//! Writing a cloud as LAS/LAZ: the point format and version (the input's where they hold what
//! the cloud carries), the coordinates' scale and offset, the standard fields of each record,
//! and the other fields as described extra bytes. The rules are documented in cli/README.md
//! ("LAS and LAZ").

use std::io::Cursor;

use las::{PointDataBuilder, Transform, Vector};

use super::extra::{self, Dim};
use super::fields::{self, Caps, Std, ALL};
use super::{las_err, CHUNK};
use crate::io::error::{Fail, PResult};
use crate::io::{LasHeader, LasVlr, PointCloud};

/// Where the colour channels of the records come from.
enum Colour<'a> {
    /// The `red green blue` fields of a cloud read from LAS: the file's 16-bit values.
    Exact([&'a [f64]; 3]),
    /// 8-bit colours (PLY, PCD, XYZ), stored times 257 (255 -> 65535).
    Eight(Vec<[u8; 3]>),
}

/// The values of an extra-bytes dimension, read from the cloud as they are written.
#[derive(Clone, Copy)]
enum Values<'a> {
    Field(&'a [f64]),
    /// Component `j` of the normals.
    Normal(&'a [[f64; 3]], usize),
}

impl<'a> Values<'a> {
    fn get(self, i: usize) -> f64 {
        match self {
            Values::Field(v) => v[i],
            Values::Normal(n, j) => n[i][j],
        }
    }

    fn iter(self) -> impl Iterator<Item = f64> + Clone + 'a {
        let n = match self {
            Values::Field(v) => v.len(),
            Values::Normal(v, _) => v.len(),
        };
        (0..n).map(move |i| self.get(i))
    }
}

/// An extra-bytes value of every point: its description and its values.
struct Extra<'a> {
    dim: Dim,
    values: Values<'a>,
}

/// How a cloud is written as LAS, and what of it is not.
pub(super) struct Plan<'a> {
    cloud: &'a PointCloud,
    format: u8,
    version: (u8, u8),
    transforms: Vector<Transform>,
    colour: Option<Colour<'a>>,
    /// The standard fields of the format, with the cloud's values where it has them (else 0).
    std: Vec<(Std, Option<&'a [f64]>)>,
    extra: Vec<Extra<'a>>,
    /// What is not written, in words.
    pub not_written: Vec<String>,
}

/// The colour of the records: the input's 16-bit values if the cloud was read from a LAS file
/// with colour and still holds them, else the cloud's 8-bit colours.
fn colour(cloud: &PointCloud) -> Option<Colour<'_>> {
    let from_las = cloud
        .metadata
        .las
        .as_ref()
        .is_some_and(|h| Caps::of(h.point_format).rgb);
    if from_las {
        let ch = |n: &str| {
            cloud
                .scalar(n)
                .filter(|v| Std::Red.holds(Caps::default(), v))
        };
        if let (Some(r), Some(g), Some(b)) = (ch("red"), ch("green"), ch("blue")) {
            return Some(Colour::Exact([r, g, b]));
        }
    }
    cloud.colors().map(Colour::Eight)
}

/// What the cloud's fields ask of the point format beyond `base`.
fn caps_needed(cloud: &PointCloud, base: Caps, rgb: bool) -> Caps {
    let has = |n: &str| cloud.scalar(n).is_some();
    let beyond_legacy = |s: Std| {
        cloud.scalar(s.name()).is_some_and(|v| {
            let ext = Caps {
                extended: true,
                ..Caps::default()
            };
            s.holds(ext, v) && !s.holds(Caps::default(), v)
        })
    };
    let mut c = base.with(Caps {
        extended: ["overlap", "scanner_channel", "scan_angle"]
            .iter()
            .any(|n| has(n))
            || [Std::Classification, Std::ReturnNumber, Std::NumberOfReturns]
                .into_iter()
                .any(beyond_legacy),
        gps: has("gps_time"),
        rgb,
        nir: has("nir"),
        waveform: ["wavepacket_index", "wavepacket_offset", "wavepacket_size"]
            .iter()
            .any(|n| has(n)),
    });
    // NIR exists only in the extended formats.
    c.extended |= c.nir;
    Caps::of(c.format())
}

/// The LAS version: the input's if it has the point format `f`, else the first that has it
/// (1.2 for a cloud not read from LAS).
fn version(src: Option<&LasHeader>, f: u8) -> (u8, u8) {
    let needed = match f {
        0 | 1 => 0,
        2 | 3 => 2,
        4 | 5 => 3,
        _ => 4,
    };
    match src {
        Some(h) if h.version.0 == 1 => (1, h.version.1.clamp(needed, 4)),
        _ => (1, needed.max(2)),
    }
}

/// Whether the coordinates `lo..=hi` are stored as 32-bit integers with `scale` and `offset`.
fn fits(lo: f64, hi: f64, scale: f64, offset: f64) -> bool {
    let r = |v: f64| ((v - offset) / scale).round();
    scale > 0.0 && scale.is_finite() && r(lo) >= f64::from(i32::MIN) && r(hi) <= f64::from(i32::MAX)
}

/// Scale and offset of each axis, and a note if the input's scale could not be kept.
///
/// The rule (cli/README.md): a cloud read from LAS keeps the input's scale and offset if every
/// coordinate is stored with them (a coordinate the cloud did not change is then written as
/// the same integer; a smoothed one to the nearest step of the input's grid, half a step at
/// most); else it keeps the scale with an offset moved by whole steps to the middle of the
/// coordinates, so the grid stays the input's. Only if the extent needs more than 2^32 steps,
/// and for a cloud not read from LAS, the scale is the finest power of ten that keeps the
/// extent within 2^30 steps (at least 1e-9) and the offset the smallest coordinate.
fn transforms(
    cloud: &PointCloud,
    src: Option<&LasHeader>,
    notes: &mut Vec<String>,
) -> Vector<Transform> {
    let bbox = cloud.bounding_box();
    let axis = |j: usize, notes: &mut Vec<String>| {
        let (lo, hi) = bbox.map_or((0.0, 0.0), |b| (b.min[j], b.max[j]));
        if let Some(h) = src {
            let (s, o) = (h.scale[j], h.offset[j]);
            if fits(lo, hi, s, o) {
                return Transform {
                    scale: s,
                    offset: o,
                };
            }
            let o2 = o + (((lo + hi) / 2.0 - o) / s).round() * s;
            if fits(lo, hi, s, o2) {
                return Transform {
                    scale: s,
                    offset: o2,
                };
            }
        }
        let extent = (hi - lo).max(1e-300);
        let need = (extent / (1u64 << 30) as f64).log10().ceil().max(-9.0);
        let t = Transform {
            scale: 10f64.powi(need as i32),
            offset: lo,
        };
        if let Some(h) = src {
            notes.push(format!(
                "{}: the input's scale {} cannot hold an extent of {extent}; stored at scale {}",
                ["x", "y", "z"][j],
                h.scale[j],
                t.scale
            ));
        }
        t
    };
    Vector {
        x: axis(0, notes),
        y: axis(1, notes),
        z: axis(2, notes),
    }
}

/// What a field of nbhd's is called in a LAS file's extra bytes (PDAL's and CloudCompare's
/// names), with a description.
fn extra_name(name: &str) -> (String, &'static str) {
    match name {
        "curvature" => ("Curvature".into(), "surface variation l0/(l0+l1+l2)"),
        "k1" => (name.into(), "principal curvature k1"),
        "k2" => (name.into(), "principal curvature k2"),
        "mean_curvature" => (name.into(), "(k1 + k2) / 2"),
        "max_abs_curvature" => (name.into(), "max(|k1|, |k2|)"),
        _ => (name.into(), ""),
    }
}

/// The description of an extra-bytes value named `name`: the input's (any case) if it holds
/// `values`, else a new `f32`/`f64` one.
fn describe(src: &[Dim], name: &str, what: &str, values: Values<'_>, single: bool) -> Dim {
    match src.iter().find(|d| d.name.eq_ignore_ascii_case(name)) {
        Some(d) if d.holds(values.iter()) => d.clone(),
        Some(d) => Dim::float(&d.name, &d.description, single),
        None => Dim::float(name, what, single),
    }
}

impl<'a> Plan<'a> {
    /// How `cloud` is written; extra bytes nbhd adds are `f32` if `single`, else `f64`.
    pub fn new(cloud: &'a PointCloud, single: bool) -> Plan<'a> {
        let src = cloud.metadata.las.as_ref();
        let colour = colour(cloud);
        let base = src.map_or(Caps::default(), |h| Caps::of(h.point_format));
        let caps = caps_needed(cloud, base, colour.is_some());
        let format = caps.format();
        let mut not_written = Vec::new();
        let transforms = transforms(cloud, src, &mut not_written);
        let mut std = Vec::new();
        for s in ALL.into_iter().filter(|s| s.in_format(caps)) {
            let values = cloud.scalar(s.name());
            match values {
                Some(v) if !s.holds(caps, v) && !matches!(s, Std::Red | Std::Green | Std::Blue) => {
                    not_written.push(format!(
                        "{} (values that point format {format} does not hold)",
                        s.name()
                    ));
                    std.push((s, None));
                }
                _ => std.push((s, values)),
            }
        }
        let mut version = version(src, format);
        // A header before LAS 1.4 counts returns 1-5 only, and the las crate refuses to write
        // one with more: such returns need 1.4 (which has every point format).
        let many_returns = cloud
            .scalar("return_number")
            .is_some_and(|v| v.iter().any(|&r| r > 5.0));
        if version.1 < 4 && many_returns {
            not_written.push(format!(
                "LAS version 1.{} (written as 1.4: it counts return numbers above 5)",
                version.1
            ));
            version = (1, 4);
        }
        let mut plan = Plan {
            cloud,
            format,
            version,
            transforms,
            colour,
            std,
            extra: Vec::new(),
            not_written,
        };
        plan.add_extra(src, caps, single);
        if src.is_some_and(|h| h.global_encoding & 6 != 0) {
            plan.not_written.push(
                "the waveform bits of the LAS global encoding (the las crate does not write them)"
                    .into(),
            );
        }
        plan
    }

    /// The fields that are not standard fields of the format go to extra bytes: the normals as
    /// `NormalX NormalY NormalZ`, `curvature` as `Curvature`, the others under their names.
    fn add_extra(&mut self, src: Option<&LasHeader>, caps: Caps, single: bool) {
        let cloud = self.cloud;
        let src_dims: Vec<Dim> = src.map_or_else(Vec::new, |h| {
            let vlrs: Vec<LasVlr> = h.vlrs.iter().chain(&h.evlrs).cloned().collect();
            extra::layout(&vlrs, usize::MAX)
                .dims
                .into_iter()
                .map(|(_, d)| d)
                .collect()
        });
        if let Some(n) = &cloud.normals {
            for (j, name) in ["NormalX", "NormalY", "NormalZ"].iter().enumerate() {
                let values = Values::Normal(n, j);
                let dim = describe(&src_dims, name, "normal", values, single);
                self.extra.push(Extra { dim, values });
            }
        }
        let colour = self.colour.is_some();
        for s in &cloud.scalars {
            let standard = Std::named(&s.name).is_some_and(|f| f.in_format(caps));
            let colour_field = matches!(s.name.as_str(), "red" | "green" | "blue" | "rgb" | "rgba");
            if standard || (colour && colour_field) {
                continue;
            }
            let (name, what) = extra_name(&s.name);
            let taken = self
                .extra
                .iter()
                .any(|e| e.dim.name.eq_ignore_ascii_case(&name));
            if name.len() > 31 || name.is_empty() || taken {
                self.not_written.push(format!(
                    "{} (an extra-bytes name must be 1-31 bytes and unique)",
                    s.name
                ));
                continue;
            }
            let values = Values::Field(&s.values);
            let dim = describe(&src_dims, &name, what, values, single);
            self.extra.push(Extra { dim, values });
        }
    }

    /// Value of the standard field `s` of point `i`.
    fn value(&self, s: Std, i: usize) -> f64 {
        let k = match s {
            Std::Red => 0,
            Std::Green => 1,
            Std::Blue => 2,
            _ => {
                return self
                    .std
                    .iter()
                    .find(|(f, _)| *f == s)
                    .and_then(|(_, v)| *v)
                    .map_or(0.0, |v| v[i])
            }
        };
        match &self.colour {
            Some(Colour::Exact(c)) => c[k][i],
            Some(Colour::Eight(c)) => f64::from(c[i][k]) * 257.0,
            None => 0.0,
        }
    }

    /// The header: the input's (version, GUID, file source id, global encoding, system
    /// identifier, VLRs and EVLRs) where the cloud was read from LAS, with the point format,
    /// scale and offset of this plan and the extra-bytes VLR made anew.
    fn header(&self, compressed: bool) -> PResult<las::Header> {
        let src = self.cloud.metadata.las.as_ref();
        let extra_len: usize = self.extra.iter().map(|e| e.dim.size()).sum();
        let format =
            las::point::Format::new(self.format).map_err(|e| las_err("LAS point format", e))?;
        let record_len = usize::from(format.len()) + extra_len;
        let mut raw = las::raw::Header {
            version: las::Version::new(self.version.0, self.version.1),
            point_data_record_format: self.format,
            point_data_record_length: u16::try_from(record_len)
                .map_err(|_| Fail::unsupported("LAS records hold at most 65,535 bytes"))?,
            ..las::raw::Header::default()
        };
        let (year, day) = today();
        raw.file_creation_year = year;
        raw.file_creation_day_of_year = day;
        put(
            &mut raw.generating_software,
            &format!("nbhd {}", env!("CARGO_PKG_VERSION")),
        );
        let mut vlrs = Vec::new();
        let mut evlrs = Vec::new();
        if let Some(h) = src {
            raw.file_source_id = h.file_source_id;
            raw.global_encoding = h.global_encoding & 0b11001;
            raw.guid = h.guid;
            put(&mut raw.system_identifier, &h.system_identifier);
            vlrs = h
                .vlrs
                .iter()
                .filter(|v| !extra::is_extra_bytes(v))
                .map(to_las)
                .collect();
            evlrs = h
                .evlrs
                .iter()
                .filter(|v| !extra::is_extra_bytes(v))
                .map(to_las)
                .collect();
        }
        if !self.extra.is_empty() {
            let dims = self.extra.iter().map(|e| (&e.dim, e.values.iter()));
            vlrs.push(to_las(&extra::vlr(dims)));
        }
        let mut b = las::Builder::new(raw).map_err(|e| las_err("LAS header", e))?;
        b.point_format.is_compressed = compressed;
        b.transforms = self.transforms;
        b.vlrs = vlrs;
        b.evlrs = evlrs;
        b.into_header().map_err(|e| las_err("LAS header", e))
    }

    /// The file's bytes.
    pub fn write(&self, compressed: bool) -> PResult<Vec<u8>> {
        let header = self.header(compressed)?;
        let format = *header.point_format();
        let t = *header.transforms();
        let caps = Caps::of(self.format);
        let mut writer = las::Writer::new(Cursor::new(Vec::new()), header)
            .map_err(|e| las_err("LAS writer", e))?;
        let n = self.cloud.len();
        let mut bytes = Vec::new();
        for i in 0..n {
            let mut p = fields::record(caps, |s| self.value(s, i));
            let q = self.cloud.positions[i];
            let inv = |t: &Transform, v: f64| {
                t.inverse(v)
                    .map_err(|e| las_err(&format!("LAS point {i}"), e))
            };
            (p.x, p.y, p.z) = (inv(&t.x, q[0])?, inv(&t.y, q[1])?, inv(&t.z, q[2])?);
            for e in &self.extra {
                e.dim.encode(e.values.get(i), &mut p.extra_bytes);
            }
            p.write_to(&mut bytes, &format)
                .map_err(|e| las_err(&format!("LAS point {i}"), e))?;
            if (i + 1) as u64 % CHUNK == 0 || i + 1 == n {
                let pd = PointDataBuilder::new()
                    .for_header(writer.header())
                    .build_from_bytes(std::mem::take(&mut bytes))
                    .map_err(|e| las_err("LAS points", e))?;
                writer
                    .write_points(&pd)
                    .map_err(|e| las_err("LAS points", e))?;
            }
        }
        writer
            .into_inner()
            .map(|c| c.into_inner())
            .map_err(|e| las_err("LAS writer", e))
    }
}

fn to_las(v: &LasVlr) -> las::Vlr {
    las::Vlr {
        user_id: v.user_id.clone(),
        record_id: v.record_id,
        description: v.description.clone(),
        data: v.data.clone(),
    }
}

/// Writes `s` into a fixed-size, NUL-padded text field of a header.
fn put(field: &mut [u8; 32], s: &str) {
    let mut end = s.len().min(32);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    field.fill(0);
    field[..end].copy_from_slice(&s.as_bytes()[..end]);
}

/// Today's year and day of the year (1-366, UTC), the header's creation date.
fn today() -> (u16, u16) {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let mut days = secs / 86_400;
    let mut year = 1970u64;
    loop {
        let leap = year % 4 == 0 && (year % 100 != 0 || year % 400 == 0);
        let len = if leap { 366 } else { 365 };
        if days < len {
            return (year as u16, days as u16 + 1);
        }
        days -= len;
        year += 1;
    }
}
