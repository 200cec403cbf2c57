//! The envelope every saved index shares (docs/tree-file-format.md): a 128-byte header —
//! magic, byte order, format version, the library's version, scalar type and build options,
//! the format's own fields, the payload's length and CRC-32, and the header's own CRC-32 —
//! followed by the payload, and the save and load family ([`Persist`]) written once over what
//! each format provides ([`SavedFormat`]): the static tree's (`persist.rs`) and the growing
//! tree's (`src/dynamic/persist.rs`).
//!
//! Loading trusts nothing: the header is checked field by field and both checksums before the
//! payload is parsed, no length read from the input is allocated before the input is known to
//! hold that many bytes, and each format checks its payload whole.

use std::io::{Read, Write};
use std::path::Path;

use super::{BuildOptions, MedianAlgorithm, PivotPolicy};
use crate::error::{NbhdError, Result, SavedTreeError};
use crate::metric::Period;
use crate::packed::NonFinitePolicy;
use crate::scalar::{Scalar, ScalarType};

/// The first 8 bytes of a saved tree.
pub const MAGIC: [u8; 8] = *b"NBHDTREE";
/// The first 8 bytes of a saved dynamic tree (`src/dynamic/persist.rs`): known here so that
/// loading one as a static tree names what it is.
pub(crate) const FOREST_MAGIC: [u8; 8] = *b"NBHDFRST";
/// What a file of each magic holds, for [`SavedTreeError::OtherKind`].
pub(crate) const STATIC_KIND: &str = "a static tree (NBHDTREE)";
/// See [`STATIC_KIND`].
pub(crate) const DYNAMIC_KIND: &str = "a dynamic tree (NBHDFRST)";
/// The format version this library writes and reads.
pub const FORMAT_VERSION: u32 = 1;
/// Bytes of the header.
pub const HEADER_LEN: usize = 128;
/// Written in the machine's byte order: its bytes tell the reader the file's byte order.
pub(crate) const BYTE_ORDER_MARK: u32 = 0x0A0B_0C0D;
/// Where the header checksum sits (it covers the bytes before it).
const HEADER_CRC_AT: usize = 120;

/// What a load checks beyond the file itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Refuse a tree of another dimension ([`SavedTreeError::Dimension`]).
    pub dim: Option<usize>,
}

pub(crate) fn invalid(what: impl Into<String>) -> NbhdError {
    SavedTreeError::Invalid(what.into()).into()
}

pub(crate) fn this_machine() -> &'static str {
    if cfg!(target_endian = "little") {
        "little-endian"
    } else {
        "big-endian"
    }
}

pub(crate) fn other_order() -> &'static str {
    if cfg!(target_endian = "little") {
        "big-endian"
    } else {
        "little-endian"
    }
}

pub(crate) fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_ne_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

pub(crate) fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&b[at..at + 8]);
    u64::from_ne_bytes(w)
}

pub(crate) fn library_version() -> u32 {
    let part = |s: &str| s.parse::<u32>().unwrap_or(0);
    part(env!("CARGO_PKG_VERSION_MAJOR")) * 1_000_000
        + part(env!("CARGO_PKG_VERSION_MINOR")) * 1_000
        + part(env!("CARGO_PKG_VERSION_PATCH"))
}

pub(crate) fn pivot_code(p: PivotPolicy) -> u8 {
    match p {
        PivotPolicy::CyclicMedian => 0,
        PivotPolicy::SpreadMedian => 1,
        PivotPolicy::ClosestToMiddle => 2,
        PivotPolicy::SlidingMidpoint => 3,
    }
}

pub(crate) fn median_code(m: MedianAlgorithm) -> u8 {
    match m {
        MedianAlgorithm::Presorted => 0,
        MedianAlgorithm::Sort => 1,
        MedianAlgorithm::Quickselect => 2,
        MedianAlgorithm::FloydRivest => 3,
        MedianAlgorithm::MedianOfMedians => 4,
    }
}

pub(crate) fn non_finite_code(p: NonFinitePolicy) -> u8 {
    match p {
        NonFinitePolicy::Reject => 0,
        NonFinitePolicy::Skip => 1,
    }
}

pub(crate) fn scalar_name(s: ScalarType) -> &'static str {
    match s {
        ScalarType::F32 => "f32",
        ScalarType::F64 => "f64",
    }
}

/// Rounds up to a multiple of 8 (the payload's sections start 8-byte aligned).
pub(crate) fn pad8(n: u64) -> Option<u64> {
    n.checked_add(7).map(|v| v & !7)
}

/// One kind of saved tree: its magic and format version, and the other kind's magic, so that
/// each loader names what it was given.
pub(crate) struct Kind {
    pub magic: [u8; 8],
    pub name: &'static str,
    pub version: u32,
    pub other_magic: [u8; 8],
    pub other_name: &'static str,
}

/// The nbhd version that wrote a header, as `(major, minor, patch)`.
pub(crate) fn written_by(h: &[u8]) -> (u32, u32, u32) {
    let w = u32_at(h, 20);
    (w / 1_000_000, w / 1_000 % 1_000, w % 1_000)
}

/// The checks every saved tree's header starts with, in order: magic (the other kind named as
/// such), length, byte order, format version, header CRC-32 (at byte 120), byte-order mark,
/// header length. Returns the header's bytes.
pub(crate) fn check_start<'a>(bytes: &'a [u8], kind: &Kind) -> Result<&'a [u8]> {
    let head = &bytes[..bytes.len().min(8)];
    if head == kind.other_magic {
        return Err(SavedTreeError::OtherKind {
            file: kind.other_name,
            expected: kind.name,
        }
        .into());
    }
    if head != &kind.magic[..head.len()] {
        return Err(SavedTreeError::NotATree {
            found: head.to_vec(),
            expected: if kind.magic == MAGIC {
                "NBHDTREE"
            } else {
                "NBHDFRST"
            },
        }
        .into());
    }
    if bytes.len() < HEADER_LEN {
        return Err(SavedTreeError::Truncated {
            needed: HEADER_LEN as u64,
            available: bytes.len() as u64,
        }
        .into());
    }
    let h = &bytes[..HEADER_LEN];
    let bom = u32_at(h, 8);
    if bom == BYTE_ORDER_MARK.swap_bytes() {
        return Err(SavedTreeError::ByteOrder {
            file: other_order(),
            machine: this_machine(),
        }
        .into());
    }
    let version = u32_at(h, 12);
    if version != kind.version && bom == BYTE_ORDER_MARK {
        // Another version may lay its header out differently: its checksum cannot be
        // checked here, and the version is what differs.
        let (a, b, c) = written_by(h);
        return Err(SavedTreeError::FormatVersion {
            file: version,
            supported: kind.version,
            written_by: format!("{a}.{b}.{c}"),
        }
        .into());
    }
    let stored_crc = u32_at(h, HEADER_CRC_AT);
    let crc = crc32fast::hash(&h[..HEADER_CRC_AT]);
    if crc != stored_crc {
        return Err(SavedTreeError::Checksum {
            part: "header",
            stored: stored_crc,
            computed: crc,
        }
        .into());
    }
    if bom != BYTE_ORDER_MARK {
        return Err(invalid(format!("byte-order mark {bom:#010x}")));
    }
    let header_len = u32_at(h, 16);
    if header_len as usize != HEADER_LEN {
        return Err(invalid(format!(
            "header length {header_len} (format {} has {HEADER_LEN})",
            kind.version
        )));
    }
    Ok(h)
}

/// Refuses `have` bytes for a saved tree of `total` bytes: truncated, or followed by others.
pub(crate) fn check_len(have: u64, total: u64) -> Result<()> {
    if have < total {
        return Err(SavedTreeError::Truncated {
            needed: total,
            available: have,
        }
        .into());
    }
    if have > total {
        return Err(invalid(format!(
            "{} bytes follow the end of the tree",
            have - total
        )));
    }
    Ok(())
}

/// Reads the payload of a saved tree of `total` bytes from `r` (the header read), as it
/// arrives — never reserved from the declared length, so a header that lies about it costs
/// what the input really holds.
pub(crate) fn read_payload<R: Read>(r: &mut R, total: u64, context: &str) -> Result<Vec<u8>> {
    let declared = (total - HEADER_LEN as u64) as usize;
    let mut payload = Vec::new();
    loop {
        let start = payload.len();
        let step = (declared - start).min(READ_STEP);
        if step == 0 {
            break;
        }
        payload.resize(start + step, 0);
        let got = read_up_to(r, &mut payload[start..]).map_err(|e| NbhdError::io(context, &e))?;
        payload.truncate(start + got);
        if got < step {
            break;
        }
    }
    check_len((HEADER_LEN + payload.len()) as u64, total)?;
    Ok(payload)
}

/// Gives an I/O error of a save the file's context.
pub(crate) fn in_file(e: NbhdError, context: String) -> NbhdError {
    match e {
        NbhdError::Io { kind, message, .. } => NbhdError::Io {
            context,
            kind,
            message,
        },
        e => e,
    }
}

/// Bytes of a scalar, in the machine's order.
pub(crate) fn scalar_bytes<T: Scalar>(v: T, out: &mut Vec<u8>) {
    match T::TYPE {
        // `to_f64` is exact and an f32 converted to f64 converts back to itself.
        ScalarType::F32 => out.extend_from_slice(&(v.to_f64() as f32).to_ne_bytes()),
        ScalarType::F64 => out.extend_from_slice(&v.to_f64().to_ne_bytes()),
    }
}

/// Most bytes a load from a reader asks for at once (and reserves before they arrive).
pub(crate) const READ_STEP: usize = 16 << 20;

/// Reads until `buf` is full or `r` ends; returns the bytes read.
pub(crate) fn read_up_to<R: Read>(r: &mut R, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// The header of a saved index: `kind`'s magic and version, this machine's byte order, this
/// library's version, the scalar type and build options (bytes 0 to 27), [`PERIODIC`] at byte
/// 28 for a periodic index, then `fields` as 64-bit values from byte 32, the payload's CRC-32
/// at `payload_crc_at`, and the header's own CRC-32 at byte 120.
pub(crate) fn header(
    kind: &Kind,
    scalar: ScalarType,
    options: &BuildOptions,
    periodic: bool,
    fields: &[u64],
    payload_crc_at: usize,
    payload_crc: u32,
) -> [u8; HEADER_LEN] {
    let mut h = [0u8; HEADER_LEN];
    h[..8].copy_from_slice(&kind.magic);
    h[8..12].copy_from_slice(&BYTE_ORDER_MARK.to_ne_bytes());
    h[12..16].copy_from_slice(&kind.version.to_ne_bytes());
    h[16..20].copy_from_slice(&(HEADER_LEN as u32).to_ne_bytes());
    h[20..24].copy_from_slice(&library_version().to_ne_bytes());
    h[24] = scalar.size() as u8;
    h[25] = pivot_code(options.pivot);
    h[26] = median_code(options.median);
    h[27] = non_finite_code(options.non_finite);
    if periodic {
        h[28..32].copy_from_slice(&PERIODIC.to_ne_bytes());
    }
    for (i, v) in fields.iter().enumerate() {
        h[32 + 8 * i..40 + 8 * i].copy_from_slice(&v.to_ne_bytes());
    }
    h[payload_crc_at..payload_crc_at + 4].copy_from_slice(&payload_crc.to_ne_bytes());
    let crc = crc32fast::hash(&h[..HEADER_CRC_AT]);
    h[HEADER_CRC_AT..HEADER_CRC_AT + 4].copy_from_slice(&crc.to_ne_bytes());
    h
}

/// The word at byte 28 of a saved periodic index (0 otherwise). Its payload ends with the
/// period section ([`period_section_len`]): the box, which nbhd 0.1 files of this flag lacked
/// (they were refused on loading, and still are: their payload is a section short).
pub(crate) const PERIODIC: u32 = 1;

/// Whether the header `h` is a periodic index's (byte 28, [`PERIODIC`]); any other non-zero
/// word is refused.
pub(crate) fn periodic_flag(h: &[u8]) -> Result<bool> {
    match u32_at(h, 28) {
        0 => Ok(false),
        PERIODIC => Ok(true),
        w => Err(invalid(format!(
            "flags {w:#x} at byte 28 (0, or 1 for a periodic index)"
        ))),
    }
}

/// Bytes of the period section of a periodic index of dimension `dim` (0 when not periodic):
/// the box size of every axis in the scalar type (0 on an open axis), padded to 8 bytes.
pub(crate) fn period_section_len(periodic: bool, dim: u64, scalar: ScalarType) -> Option<u64> {
    if !periodic {
        return Some(0);
    }
    pad8(dim.checked_mul(scalar.size() as u64)?)
}

/// Appends the period section of `period` (nothing for `None`) to `buf`.
pub(crate) fn write_period<T: Scalar>(period: Option<&Period<T>>, buf: &mut Vec<u8>) {
    if let Some(p) = period {
        let start = buf.len();
        for l in p.sizes() {
            scalar_bytes(T::from_f64(l), buf);
        }
        let written = buf.len() - start;
        buf.resize(start + written.next_multiple_of(8), 0);
    }
}

/// The box a period section `bytes` of dimension `dim` holds, checked as a new periodic index
/// checks its box (sizes 0, positive or +∞, at least one periodic axis, zero padding).
pub(crate) fn read_period<T: Scalar>(bytes: &[u8], dim: usize) -> Result<Period<T>> {
    let size = T::TYPE.size();
    if bytes[dim * size..].iter().any(|&b| b != 0) {
        return Err(invalid("padding after the periodic box is not zero"));
    }
    let sizes: Vec<f64> = bytes[..dim * size]
        .chunks_exact(size)
        .map(|b| T::read_ne(b).to_f64())
        .collect();
    match Period::new(&sizes, dim) {
        Ok(Some(p)) => Ok(p),
        Ok(None) => Err(invalid("the periodic box has no periodic axis")),
        Err(e) => Err(invalid(format!("the periodic box: {e}"))),
    }
}

/// The scalar type and the policies a checked header (bytes 24 to 27) names; its leaf size
/// and threads are the format's fields.
pub(crate) fn read_codes(h: &[u8]) -> Result<(ScalarType, BuildOptions)> {
    let scalar = match h[24] {
        4 => ScalarType::F32,
        8 => ScalarType::F64,
        s => {
            return Err(invalid(format!(
                "scalar type code {s} (4 is f32, 8 is f64)"
            )))
        }
    };
    let pivot = PivotPolicy::ALL
        .into_iter()
        .find(|&p| pivot_code(p) == h[25])
        .ok_or_else(|| invalid(format!("pivot policy code {}", h[25])))?;
    let median = MedianAlgorithm::ALL
        .into_iter()
        .find(|&m| median_code(m) == h[26])
        .ok_or_else(|| invalid(format!("median algorithm code {}", h[26])))?;
    let non_finite = NonFinitePolicy::ALL
        .into_iter()
        .find(|&p| non_finite_code(p) == h[27])
        .ok_or_else(|| invalid(format!("non-finite policy code {}", h[27])))?;
    let options = BuildOptions {
        pivot,
        median,
        non_finite,
        ..BuildOptions::default()
    };
    Ok((scalar, options))
}

/// A value of a header as a size of this machine.
pub(crate) fn size(v: u64) -> Result<usize> {
    usize::try_from(v).map_err(|_| invalid(format!("{v} is too large for this machine")))
}

/// What the envelope reads of a checked header.
#[doc(hidden)]
pub trait SavedHeader {
    /// Bytes of the saved index: header and payload.
    fn total_len(&self) -> u64;
    /// The payload's CRC-32.
    fn payload_crc(&self) -> u32;
    /// The coordinate type.
    fn scalar(&self) -> ScalarType;
    /// Dimension.
    fn dim(&self) -> usize;
}

/// Implements [`SavedHeader`] for a header struct from its fields of the same names
/// (`total_len`, `payload_crc`, `scalar`, `dim`): every saved format's header has them.
macro_rules! saved_header {
    ($info:ty) => {
        impl $crate::tree::SavedHeader for $info {
            fn total_len(&self) -> u64 {
                self.total_len
            }
            fn payload_crc(&self) -> u32 {
                self.payload_crc
            }
            fn scalar(&self) -> $crate::scalar::ScalarType {
                self.scalar
            }
            fn dim(&self) -> usize {
                self.dim
            }
        }
    };
}
pub(crate) use saved_header;

/// A format of saved index: its header and payload (the plumbing [`Persist`] is written over).
#[doc(hidden)]
pub trait SavedFormat: Sized {
    /// The kind of index, in messages: "tree", "dynamic tree".
    const WHAT: &'static str;
    /// The scalar type of its coordinates.
    const SCALAR: ScalarType;
    /// The header, read and checked.
    type Info: SavedHeader;
    /// Reads and checks the header at the start of `bytes`.
    fn read_header(bytes: &[u8]) -> Result<Self::Info>;
    /// Bytes of the payload.
    fn payload_len(&self) -> u64;
    /// The header, for a payload of `payload_len` bytes with checksum `payload_crc`.
    fn header(&self, payload_len: u64, payload_crc: u32) -> [u8; HEADER_LEN];
    /// Writes the payload to `w` (its bytes depend only on the index).
    fn payload(&self, w: &mut dyn Write) -> std::io::Result<()>;
    /// The index from a payload of the length and checksum `info` declares (both checked).
    fn from_payload(info: &Self::Info, payload: &[u8]) -> Result<Self>;
}

/// A `Write` that only feeds a CRC-32 (the payload is produced twice: once for its checksum,
/// once for the output, so that nothing the size of the index is buffered).
struct CrcSink(crc32fast::Hasher);

impl Write for CrcSink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.update(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Writes `index` whole (header and payload) to `w`.
pub(crate) fn write_saved<F: SavedFormat>(index: &F, w: &mut dyn Write) -> std::io::Result<()> {
    let mut crc = CrcSink(crc32fast::Hasher::new());
    index.payload(&mut crc)?;
    w.write_all(&index.header(index.payload_len(), crc.0.finalize()))?;
    index.payload(w)
}

/// The index a checked header `info` and its payload describe: refused if the payload's
/// checksum differs.
fn from_parts<F: SavedFormat>(info: &F::Info, payload: &[u8]) -> Result<F> {
    let crc = crc32fast::hash(payload);
    if crc != info.payload_crc() {
        return Err(SavedTreeError::Checksum {
            part: "payload",
            stored: info.payload_crc(),
            computed: crc,
        }
        .into());
    }
    F::from_payload(info, payload)
}

/// Refuses a saved index of another scalar type than `scalar` or (if asked) dimension.
fn expect(info: &impl SavedHeader, scalar: ScalarType, options: &LoadOptions) -> Result<()> {
    if info.scalar() != scalar {
        return Err(SavedTreeError::ScalarType {
            file: scalar_name(info.scalar()),
            expected: scalar_name(scalar),
        }
        .into());
    }
    match options.dim {
        Some(d) if d != info.dim() => Err(SavedTreeError::Dimension {
            file: info.dim(),
            expected: d,
        }
        .into()),
        _ => Ok(()),
    }
}

/// Saving an index and loading it back (docs/tree-file-format.md), the same family for the
/// static [`KdTree`](super::KdTree) and the growing `DynamicKdTree`: to and from a writer, bytes
/// and files. A loaded index answers every query bit for bit as the saved one did.
///
/// ```
/// use nbhd::{BuildOptions, KdTree, Persist, PointsView};
///
/// let pts = [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0];
/// let tree = KdTree::<f32>::build(&PointsView::from_flat(&pts, 2)?, &BuildOptions::default())?;
/// let bytes = tree.to_bytes();
/// assert_eq!(bytes.len(), tree.saved_len());
/// let back = KdTree::<f32>::from_bytes(&bytes)?;
/// assert!(back.same_structure(&tree));
/// // the other scalar type is refused, naming both
/// assert!(KdTree::<f64>::from_bytes(&bytes).is_err());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub trait Persist: SavedFormat {
    /// Bytes [`Persist::save`] writes.
    fn saved_len(&self) -> usize {
        HEADER_LEN + self.payload_len() as usize
    }

    /// Writes the index to `w` (the payload is produced twice, once for its checksum and once
    /// for `w`, so that nothing the size of the index is buffered). Errors: [`NbhdError::Io`]
    /// if `w` fails.
    fn save<W: Write>(&self, mut w: W) -> Result<()> {
        let context = format!("writing the saved {}", Self::WHAT);
        write_saved(self, &mut w)
            .and_then(|()| w.flush())
            .map_err(|e| NbhdError::io(context, &e))
    }

    /// The index as the bytes [`Persist::save`] writes.
    fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.saved_len());
        write_saved(self, &mut out).expect("writing to memory does not fail");
        out
    }

    /// Writes the index to the file `path` (created or truncated).
    fn save_file(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let context = || format!("writing the saved {} to {}", Self::WHAT, path.display());
        let file = std::fs::File::create(path).map_err(|e| NbhdError::io(context(), &e))?;
        self.save(std::io::BufWriter::with_capacity(1 << 20, file))
            .map_err(|e| in_file(e, context()))
    }

    /// Loads an index saved by [`Persist::save`] from exactly `bytes`.
    ///
    /// Errors: [`NbhdError::SavedTree`] naming what differs or is damaged: not a saved index
    /// (or one of the other kind: [`SavedTreeError::OtherKind`]), another byte order or format
    /// version, coordinates of the other scalar type, truncated or followed by other bytes, a
    /// checksum that does not match, or a field or structure that is inconsistent.
    fn from_bytes(bytes: &[u8]) -> Result<Self> {
        Self::from_bytes_with(bytes, &LoadOptions::default())
    }

    /// [`Persist::from_bytes`], also refusing an index of another dimension than
    /// `options.dim`.
    fn from_bytes_with(bytes: &[u8], options: &LoadOptions) -> Result<Self> {
        let info = Self::read_header(bytes)?;
        expect(&info, Self::SCALAR, options)?;
        check_len(bytes.len() as u64, info.total_len())?;
        from_parts::<Self>(&info, &bytes[HEADER_LEN..])
    }

    /// Loads an index saved by [`Persist::save`] from `r`, reading exactly its bytes (so that
    /// what follows in `r` stays unread). Errors: as [`Persist::from_bytes`], and
    /// [`NbhdError::Io`] if `r` fails.
    fn load<R: Read>(r: R) -> Result<Self> {
        Self::load_with(r, &LoadOptions::default())
    }

    /// [`Persist::load`], also refusing an index of another dimension than `options.dim`.
    fn load_with<R: Read>(mut r: R, options: &LoadOptions) -> Result<Self> {
        let context = format!("reading the saved {}", Self::WHAT);
        let mut header = [0u8; HEADER_LEN];
        let got = read_up_to(&mut r, &mut header).map_err(|e| NbhdError::io(&context, &e))?;
        let info = Self::read_header(&header[..got])?;
        expect(&info, Self::SCALAR, options)?;
        let payload = read_payload(&mut r, info.total_len(), &context)?;
        from_parts::<Self>(&info, &payload)
    }

    /// Loads the index saved in the file `path`.
    fn load_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let context = || format!("reading the saved {} from {}", Self::WHAT, path.display());
        let bytes = std::fs::read(path).map_err(|e| NbhdError::io(context(), &e))?;
        Self::from_bytes(&bytes)
    }
}

impl<F: SavedFormat> Persist for F {}
