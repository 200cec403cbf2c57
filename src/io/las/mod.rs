//! LAS and LAZ, the ASPRS lidar formats, through the `las` crate (LAZ with its `laz`
//! feature).
//!
//! Read: the points (x y z, as the file's scaled 32-bit integers times scale plus offset,
//! in `f64`), `intensity` (0..65535), `classification` (0..255) and, for point formats with
//! colour, `red green blue` as 8-bit values: 16-bit colours (any channel above 255, the LAS
//! convention) are divided by 256, files that store 8-bit values in the 16-bit fields are
//! kept as they are.
//!
//! Written: LAS 1.2, point format 0 (or 2 with colour), compressed for `.laz`: the positions
//! with the bounding box's minimum as offset and as scale the finest power of ten that keeps
//! the extent within 2^30 steps (at least 1e-9: 1e-6 for a 1 km scan), so a coordinate moves
//! by at most half a step; `intensity` if its values are integers in 0..65535;
//! `classification` if they are integers in 0..31 other than 12 (point formats 0-5); colour
//! channels times 257 (255 -> 65535). What LAS cannot hold (normals, other scalar fields) is
//! not written, and `not_written` names it; non-finite coordinates are refused.

use super::error::{Fail, PResult};
use super::{PointCloud, Precision};
use std::io::Cursor;

/// Points read per call into the `las` reader (its buffers never exceed this).
const CHUNK: u64 = 1 << 16;

/// Bytes of records read per call: the `las` reader sizes its buffer to the chunk's points
/// times the record length before decompressing, and a LAZ file's declared count cannot be
/// checked against its size (records up to 65,535 bytes × [`CHUNK`] would be 4 GiB).
const CHUNK_BYTES: u64 = 16 << 20;

fn las_err(what: &str, e: las::Error) -> Fail {
    Fail {
        at: None,
        kind: super::IoErrorKind::Malformed(format!("{what}: {e}")),
    }
}

/// Runs `f`, turning a panic inside the `las` crate into an error: a file must never take
/// the host process down.
fn guarded<T>(what: &str, f: impl FnOnce() -> PResult<T>) -> PResult<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown".into());
            Err(Fail {
                at: None,
                kind: super::IoErrorKind::Malformed(format!(
                    "{what}: the LAS reader failed on this file ({msg})"
                )),
            })
        }
    }
}

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    guarded("LAS", || read_inner(data))
}

/// Checks the raw header's point count against the file before the `las` crate uses it (it
/// computes `offset + count * record length` unchecked).
fn check_raw_header(data: &[u8]) -> PResult<()> {
    let raw =
        las::raw::Header::read_from(Cursor::new(data)).map_err(|e| las_err("LAS header", e))?;
    let legacy = u64::from(raw.number_of_point_records);
    let count = match raw.large_file {
        Some(lf) if legacy == 0 => lf.number_of_point_records,
        _ => legacy,
    };
    let bad = |msg: String| Fail {
        at: Some(super::Location::Byte(107)),
        kind: super::IoErrorKind::Malformed(msg),
    };
    let end = count
        .checked_mul(u64::from(raw.point_data_record_length))
        .and_then(|b| b.checked_add(u64::from(raw.offset_to_point_data)));
    let compressed = raw.point_data_record_format & 0x80 != 0;
    // The `las` crate reads the first extended VLR and resizes its data to the 64-bit length
    // in the record's header (byte 20 of 60) before reading: check the file holds it.
    if let Some(evlr) = raw.evlr {
        let at = evlr.start_of_first_evlr;
        let len = usize::try_from(at)
            .ok()
            .and_then(|a| data.get(a.checked_add(20)?..a.checked_add(28)?))
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()));
        if let Some(len) = len {
            if at.saturating_add(60).saturating_add(len) > data.len() as u64 {
                return Err(Fail {
                    at: Some(super::Location::Byte(at + 20)),
                    kind: super::IoErrorKind::Malformed(format!(
                        "the extended VLR at byte {at} declares {len} bytes of data, but the \
                         file has {} bytes",
                        data.len()
                    )),
                });
            }
        }
    }
    match end {
        None => Err(bad(format!(
            "the LAS header declares {count} points of {} bytes, which overflows",
            raw.point_data_record_length
        ))),
        Some(end) if !compressed && end > data.len() as u64 => Err(bad(format!(
            "the LAS header declares {count} points of {} bytes from byte {}, but the file \
             has {} bytes",
            raw.point_data_record_length,
            raw.offset_to_point_data,
            data.len()
        ))),
        _ if compressed => check_laz_chunk_table(data, raw.offset_to_point_data as usize),
        _ => Ok(()),
    }
}

/// The LAZ chunk table's count, which the `laz` crate reserves for unchecked: each chunk
/// takes at least a byte of the file. (Where to find the table, as LASzip writes it: an i64
/// offset at the start of the point data, or the file's last 8 bytes when that was not
/// filled in.)
fn check_laz_chunk_table(data: &[u8], start: usize) -> PResult<()> {
    let i64_at = |o: usize| -> Option<i64> {
        data.get(o..o.checked_add(8)?)
            .map(|b| i64::from_le_bytes(b.try_into().unwrap()))
    };
    let mut table = i64_at(start).unwrap_or(-1);
    if table <= start as i64 {
        table = data.len().checked_sub(8).and_then(i64_at).unwrap_or(-1);
        if table <= start as i64 {
            return Ok(());
        }
    }
    let at = table as u64 + 4;
    let count = usize::try_from(at)
        .ok()
        .and_then(|a| data.get(a..a.checked_add(4)?))
        .map(|b| u32::from_le_bytes(b.try_into().unwrap()));
    match count {
        Some(c) if c as usize > data.len() => Err(Fail {
            at: Some(super::Location::Byte(at)),
            kind: super::IoErrorKind::Malformed(format!(
                "the LAZ chunk table declares {c} chunks, more than the file has bytes ({})",
                data.len()
            )),
        }),
        _ => Ok(()),
    }
}

fn read_inner(data: &[u8]) -> PResult<PointCloud> {
    check_raw_header(data)?;
    let mut reader =
        las::Reader::new(Cursor::new(data.to_vec())).map_err(|e| las_err("LAS header", e))?;
    let header = reader.header().clone();
    let declared = header.number_of_points();
    let format = *header.point_format();
    // Never trust the count: an uncompressed record has its full length in the file.
    if !format.is_compressed {
        let rec = u64::from(format.len()).max(1);
        if declared.saturating_mul(rec) > data.len() as u64 {
            return Err(Fail {
                at: None,
                kind: super::IoErrorKind::Malformed(format!(
                    "LAS header: {declared} points of {rec} bytes do not fit in the {} bytes \
                     of the file",
                    data.len()
                )),
            });
        }
    }
    let n_hint = (declared.min(super::assemble::MAX_RESERVE as u64)) as usize;
    let mut positions = Vec::with_capacity(n_hint);
    let mut intensity = Vec::with_capacity(n_hint);
    let mut class = Vec::with_capacity(n_hint);
    let mut rgb: Vec<[u16; 3]> = Vec::new();
    // At most CHUNK_BYTES of records per call (at least one record).
    let chunk = (CHUNK_BYTES / u64::from(format.len()).max(1)).clamp(1, CHUNK);
    loop {
        let pd = reader
            .read_points(chunk)
            .map_err(|e| las_err(&format!("LAS point {}", positions.len()), e))?;
        if pd.is_empty() {
            break;
        }
        for p in pd.points() {
            let p = p.map_err(|e| las_err(&format!("LAS point {}", positions.len()), e))?;
            positions.push([p.x, p.y, p.z]);
            intensity.push(p.intensity as f64);
            class.push(u8::from(p.classification) as f64);
            if format.has_color {
                let c = p.color.unwrap_or_default();
                rgb.push([c.red, c.green, c.blue]);
            }
        }
        if positions.len() as u64 >= declared {
            break;
        }
    }
    let mut cloud = PointCloud::from_positions(positions);
    cloud.source_precision = Some(Precision::Double);
    let n = cloud.len();
    let _ = cloud.set_scalar("intensity", intensity);
    let _ = cloud.set_scalar("classification", class);
    if format.has_color && rgb.len() == n {
        let wide = rgb.iter().any(|c| c.iter().any(|&v| v > 255));
        for (k, name) in ["red", "green", "blue"].iter().enumerate() {
            let v = rgb
                .iter()
                .map(|c| {
                    if wide {
                        (c[k] >> 8) as f64
                    } else {
                        c[k] as f64
                    }
                })
                .collect();
            let _ = cloud.set_scalar(name, v);
        }
    }
    Ok(cloud)
}

/// `values` as integers in `0..=max`, if they all are.
fn integers(values: Option<&[f64]>, max: f64) -> Option<Vec<f64>> {
    let v = values?;
    v.iter()
        .all(|&x| (0.0..=max).contains(&x) && x.fract() == 0.0)
        .then(|| v.to_vec())
}

/// Classes that LAS 1.2 point formats hold (5 bits; 12 is "overlap", a flag in `las`).
fn classes(values: Option<&[f64]>) -> Option<Vec<f64>> {
    integers(values, 31.0).filter(|v| v.iter().all(|&c| c != 12.0))
}

/// The fields of `cloud` that a LAS file cannot hold and [`write`] leaves out.
pub(crate) fn not_written(cloud: &PointCloud) -> Vec<String> {
    let mut v = Vec::new();
    if cloud.normals.is_some() {
        v.push("normals".to_string());
    }
    let colors = cloud.colors().is_some();
    for s in &cloud.scalars {
        let kept = match s.name.as_str() {
            "intensity" => integers(Some(&s.values), 65535.0).is_some(),
            "classification" => classes(Some(&s.values)).is_some(),
            "rgb" | "rgba" | "red" | "green" | "blue" => colors,
            _ => false,
        };
        if !kept {
            v.push(s.name.clone());
        }
    }
    v
}

pub(crate) fn write(cloud: &PointCloud, compressed: bool) -> PResult<Vec<u8>> {
    if let Some(i) = cloud
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(Fail::invalid(format!(
            "LAS cannot store non-finite coordinates: point {i} (and {} in all) has NaN or \
             infinite coordinates",
            cloud.non_finite_count()
        )));
    }
    let colors = cloud.colors();
    let intensity = integers(cloud.scalar("intensity"), 65535.0);
    let class = classes(cloud.scalar("classification"));
    let mut builder = las::Builder::from((1, 2));
    builder.point_format = las::point::Format::new(if colors.is_some() { 2 } else { 0 })
        .map_err(|e| las_err("LAS point format", e))?;
    builder.point_format.is_compressed = compressed;
    builder.generating_software = format!("nbhd {}", env!("CARGO_PKG_VERSION"));
    let bbox = cloud.bounding_box();
    let t = |j: usize| {
        let (lo, hi) = bbox.map_or((0.0, 0.0), |b| (b.min[j], b.max[j]));
        // The finest power of ten that keeps the extent within 2^30 steps, at least 1e-9.
        let extent = (hi - lo).max(1e-300);
        let need = (extent / (1u64 << 30) as f64).log10().ceil().max(-9.0);
        las::Transform {
            scale: 10f64.powi(need as i32),
            offset: lo,
        }
    };
    builder.transforms = las::Vector {
        x: t(0),
        y: t(1),
        z: t(2),
    };
    let header = builder
        .into_header()
        .map_err(|e| las_err("LAS header", e))?;
    let mut writer =
        las::Writer::new(Cursor::new(Vec::new()), header).map_err(|e| las_err("LAS writer", e))?;
    for (i, p) in cloud.positions.iter().enumerate() {
        let mut q = las::Point {
            x: p[0],
            y: p[1],
            z: p[2],
            ..Default::default()
        };
        if let Some(v) = &intensity {
            q.intensity = v[i] as u16;
        }
        if let Some(v) = &class {
            q.classification = las::point::Classification::new(v[i] as u8)
                .unwrap_or(las::point::Classification::CreatedNeverClassified);
        }
        if let Some(c) = &colors {
            let w = |k: usize| c[i][k] as u16 * 257;
            q.color = Some(las::Color::new(w(0), w(1), w(2)));
        }
        writer
            .write_point(q)
            .map_err(|e| las_err(&format!("LAS point {i}"), e))?;
    }
    writer
        .into_inner()
        .map(|c| c.into_inner())
        .map_err(|e| las_err("LAS writer", e))
}
