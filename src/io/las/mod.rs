//! LAS and LAZ, the ASPRS lidar formats, through the `las` crate (LAZ with its `laz`
//! feature): what is read comes back when written, record by record.
//!
//! - `read.rs`: x y z (the file's integers times scale plus offset, as `f64`), every standard
//!   field of the records as a scalar field under laspy's name (`fields.rs`), the extra bytes
//!   the extra-bytes VLR describes (`extra.rs`; `NormalX NormalY NormalZ` become the normals),
//!   and the header with its VLRs in the cloud's `metadata.las`.
//! - `write.rs`: the input's point format and version where they hold what the cloud carries
//!   (else the smallest format that does), the input's scale and offset where they hold the
//!   coordinates, the standard fields back into their places, and normals, curvature and
//!   every other field as described extra bytes under PDAL's and CloudCompare's names.
//!
//! The rules, with the names, are documented for users in cli/README.md ("LAS and LAZ").

mod extra;
mod fields;
mod read;
mod write;

use super::error::{Fail, PResult};
use super::PointCloud;
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

/// Reads a LAS/LAZ file; also returns what it holds that the cloud does not carry.
pub(crate) fn read(data: &[u8]) -> PResult<(PointCloud, Vec<String>)> {
    guarded("LAS", || read::read(data))
}

/// Checks the raw header's point count against the file before the `las` crate uses it (it
/// computes `offset + count * record length` unchecked).
fn check_raw_header(data: &[u8]) -> PResult<las::raw::Header> {
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
        _ if compressed => {
            check_laz_chunk_table(data, raw.offset_to_point_data as usize).map(|()| raw)
        }
        _ => Ok(raw),
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

/// The fields of `cloud` that a LAS file does not hold and [`write`] leaves out, in words.
pub(crate) fn not_written(cloud: &PointCloud) -> Vec<String> {
    write::Plan::new(cloud, true).not_written
}

/// The LAS (or, `compressed`, LAZ) file of `cloud`; extra bytes nbhd adds are `f32` if
/// `single`, else `f64`.
pub(crate) fn write(cloud: &PointCloud, compressed: bool, single: bool) -> PResult<Vec<u8>> {
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
    guarded("LAS writer", || {
        write::Plan::new(cloud, single).write(compressed)
    })
}
