//! Reading LAS/LAZ into a cloud: positions, every standard field of the records, the described
//! extra bytes, and the header (kept in [`Metadata::las`](crate::io::Metadata::las)).

use std::io::Cursor;

use las::raw::Point as RawPoint;

use super::extra::{self, Dim};
use super::fields::{Caps, Std, ALL};
use super::{check_raw_header, las_err, CHUNK, CHUNK_BYTES};
use crate::io::error::{Fail, PResult};
use crate::io::{IoErrorKind, LasHeader, LasVlr, PointCloud, Precision};

/// What a LAS file's records hold, column by column, as read so far.
struct Columns {
    positions: Vec<[f64; 3]>,
    std: Vec<(Std, Vec<f64>)>,
    extra: Vec<(usize, Dim, Vec<f64>)>,
}

/// A file's VLR as the cloud keeps it.
fn vlr(v: &las::Vlr) -> LasVlr {
    LasVlr {
        user_id: v.user_id.clone(),
        record_id: v.record_id,
        description: v.description.clone(),
        data: v.data.clone(),
    }
}

/// Whether `v` is LAZ's own record, which the writer of a `.laz` puts anew.
fn is_laszip(v: &las::Vlr) -> bool {
    v.user_id.eq_ignore_ascii_case("laszip encoded") && v.record_id == 22204
}

/// The header as the cloud keeps it.
fn las_header(raw: &las::raw::Header, h: &las::Header) -> LasHeader {
    let text = |b: &[u8]| {
        let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
        String::from_utf8_lossy(&b[..end]).trim().to_string()
    };
    LasHeader {
        version: (raw.version.major, raw.version.minor),
        point_format: raw.point_data_record_format & 0x3f,
        scale: [raw.x_scale_factor, raw.y_scale_factor, raw.z_scale_factor],
        offset: [raw.x_offset, raw.y_offset, raw.z_offset],
        file_source_id: raw.file_source_id,
        global_encoding: raw.global_encoding,
        guid: raw.guid,
        system_identifier: text(&raw.system_identifier),
        generating_software: text(&raw.generating_software),
        vlrs: h.vlrs().iter().filter(|v| !is_laszip(v)).map(vlr).collect(),
        evlrs: h.evlrs().iter().map(vlr).collect(),
    }
}

/// Reads a LAS/LAZ file; also returns what it holds that the cloud does not carry.
pub(super) fn read(data: &[u8]) -> PResult<(PointCloud, Vec<String>)> {
    let raw = check_raw_header(data)?;
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
                kind: IoErrorKind::Malformed(format!(
                    "LAS header: {declared} points of {rec} bytes do not fit in the {} bytes \
                     of the file",
                    data.len()
                )),
            });
        }
    }
    let meta = las_header(&raw, &header);
    let caps = Caps::of(meta.point_format);
    let described: Vec<LasVlr> = meta.vlrs.iter().chain(&meta.evlrs).cloned().collect();
    let layout = extra::layout(&described, usize::from(format.extra_bytes));
    let n_hint = (declared.min(crate::io::assemble::MAX_RESERVE as u64)) as usize;
    let mut cols = Columns {
        positions: Vec::with_capacity(n_hint),
        std: ALL
            .into_iter()
            .filter(|s| s.in_format(caps))
            .map(|s| (s, Vec::with_capacity(n_hint)))
            .collect(),
        extra: layout
            .dims
            .into_iter()
            .map(|(at, d)| (at, d, Vec::with_capacity(n_hint)))
            .collect(),
    };
    let t = *header.transforms();
    // At most CHUNK_BYTES of records per call (at least one record).
    let chunk = (CHUNK_BYTES / u64::from(format.len()).max(1)).clamp(1, CHUNK);
    loop {
        let at = cols.positions.len();
        let pd = reader
            .read_points(chunk)
            .map_err(|e| las_err(&format!("LAS point {at}"), e))?;
        if pd.is_empty() {
            break;
        }
        for rec in pd.raw_bytes().chunks_exact(pd.record_len()) {
            let i = cols.positions.len();
            let p = RawPoint::read_from(rec, &format)
                .map_err(|e| las_err(&format!("LAS point {i}"), e))?;
            cols.positions
                .push([t.x.direct(p.x), t.y.direct(p.y), t.z.direct(p.z)]);
            for (s, v) in &mut cols.std {
                v.push(s.get(&p));
            }
            for (at, d, v) in &mut cols.extra {
                v.push(d.decode(&p.extra_bytes[*at..]));
            }
        }
        if cols.positions.len() as u64 >= declared {
            break;
        }
    }
    let mut cloud = assemble(cols);
    cloud.metadata.las = Some(meta);
    Ok((cloud, layout.unread))
}

/// The cloud of the columns read: every standard field that is kept (see
/// [`Std::always_kept`]: the others only if some point has a value other than 0), the extra
/// bytes `NormalX NormalY NormalZ` as normals, `Curvature` as `curvature`, the others under
/// their names.
fn assemble(cols: Columns) -> PointCloud {
    let mut cloud = PointCloud::from_positions(cols.positions);
    cloud.source_precision = Some(Precision::Double);
    for (s, v) in cols.std {
        if s.always_kept() || v.iter().any(|&x| x != 0.0) {
            cloud.scalars.push(crate::io::ScalarField {
                name: s.name().to_string(),
                values: v,
            });
        }
    }
    let mut extra = cols.extra;
    let normal = |name: &str| {
        ["normalx", "normaly", "normalz"]
            .iter()
            .position(|n| name.eq_ignore_ascii_case(n))
    };
    let picks: Vec<Option<usize>> = (0..3)
        .map(|j| {
            extra
                .iter()
                .position(|(_, d, _)| normal(&d.name) == Some(j))
        })
        .collect();
    if let [Some(a), Some(b), Some(c)] = picks[..] {
        let n = cloud.len();
        let normals = (0..n)
            .map(|i| [extra[a].2[i], extra[b].2[i], extra[c].2[i]])
            .collect();
        cloud.normals = Some(normals);
        let mut taken = [a, b, c];
        taken.sort_unstable();
        for k in taken.into_iter().rev() {
            extra.remove(k);
        }
    }
    for (_, d, values) in extra {
        let mut name = if d.name.eq_ignore_ascii_case("curvature") {
            "curvature".to_string()
        } else {
            d.name
        };
        if cloud.scalar(&name).is_some() {
            name.push_str("_extra");
        }
        cloud.scalars.push(crate::io::ScalarField { name, values });
    }
    cloud
}
