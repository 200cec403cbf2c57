//! Saving a built tree and loading it back: [`KdTree::save`], [`KdTree::to_bytes`],
//! [`KdTree::load`], [`KdTree::from_bytes`] and the file helpers, and [`SavedTreeInfo`] to read
//! a saved tree's header without loading it. The layout, what is checked and the compatibility
//! promise are in docs/tree-file-format.md.
//!
//! A saved tree is a 128-byte header followed by a payload: the coordinates and caller indices
//! in tree order, the node array and a bitmap of the caller indices the tree holds. The tree is
//! stored as built, so a loaded tree answers every query exactly as the saved one did, bit for
//! bit. Loading trusts nothing: the header and the payload carry CRC-32 checksums (accidental
//! damage), and every field and the node structure are checked (anything else, a crafted file
//! included) before a tree is handed out, so that no query on a loaded tree can panic, loop or
//! read out of bounds, and every answer is exact. No length read from the input is allocated
//! before the input is known to hold that many bytes.

use std::io::{Read, Write};
use std::path::Path;
use std::sync::OnceLock;

use super::node::{Node, LEAF};
use super::{BuildOptions, KdTree, MedianAlgorithm, PivotPolicy};
use crate::cloud::NonFinitePolicy;
use crate::error::{NbhdError, Result, SavedTreeError};
use crate::parallel::MAX_THREADS;
use crate::points::MAX_POINTS;
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

/// What a saved tree's header says, read and checked without loading the tree
/// ([`SavedTreeInfo::from_bytes`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SavedTreeInfo {
    /// The format version (always [`FORMAT_VERSION`] once checked).
    pub format_version: u32,
    /// The nbhd version that wrote the file, as `(major, minor, patch)`.
    pub library_version: (u32, u32, u32),
    /// The coordinate type of the tree.
    pub scalar: ScalarType,
    /// Dimension.
    pub dim: usize,
    /// Points held.
    pub points: usize,
    /// Points the tree was built from (skipped non-finite ones included): the index range.
    pub source_len: usize,
    /// Nodes.
    pub nodes: usize,
    /// Depth (edges on the longest root-to-leaf path).
    pub depth: usize,
    /// The options the tree was built with.
    pub options: BuildOptions,
    /// Bytes of the saved tree: header and payload.
    pub total_len: u64,
    /// The payload's CRC-32.
    payload_crc: u32,
}

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

/// Bytes of one node record: split, dimension, `a`, `b` (and 4 zero bytes for f64).
fn node_record(scalar: ScalarType) -> usize {
    match scalar {
        ScalarType::F32 => 16,
        ScalarType::F64 => 24,
    }
}

/// The byte sizes of the payload's four sections, or `None` if they overflow 64 bits.
#[derive(Clone, Copy, Debug)]
struct Sections {
    coords: u64,
    ids: u64,
    nodes: u64,
    bitmap: u64,
}

impl Sections {
    fn new(scalar: ScalarType, dim: u64, points: u64, nodes: u64, source_len: u64) -> Option<Self> {
        Some(Self {
            coords: pad8(points.checked_mul(dim)?.checked_mul(scalar.size() as u64)?)?,
            ids: pad8(points.checked_mul(4)?)?,
            nodes: nodes.checked_mul(node_record(scalar) as u64)?,
            bitmap: source_len.div_ceil(64).checked_mul(8)?,
        })
    }

    fn total(&self) -> Option<u64> {
        self.coords
            .checked_add(self.ids)?
            .checked_add(self.nodes)?
            .checked_add(self.bitmap)
    }
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

/// A saved static tree.
pub(crate) const STATIC: Kind = Kind {
    magic: MAGIC,
    name: STATIC_KIND,
    version: FORMAT_VERSION,
    other_magic: FOREST_MAGIC,
    other_name: DYNAMIC_KIND,
};

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

impl SavedTreeInfo {
    /// Reads and checks the header at the start of `bytes` (the payload need not follow):
    /// magic, byte order, format version, header checksum and every field's range.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let h = check_start(bytes, &STATIC)?;
        let version = u32_at(h, 12);
        let written_by = written_by(h);
        if u32_at(h, 28) != 0 || u32_at(h, 100) != 0 || u32_at(h, 124) != 0 {
            return Err(invalid("a reserved header field is not zero"));
        }
        if h[104..120].iter().any(|&b| b != 0) {
            return Err(invalid("a reserved header field is not zero"));
        }
        let scalar = match h[24] {
            4 => ScalarType::F32,
            8 => ScalarType::F64,
            s => {
                return Err(invalid(format!(
                    "scalar type code {s} (4 is f32, 8 is f64)"
                )))
            }
        };
        let pivot = match h[25] {
            0 => PivotPolicy::CyclicMedian,
            1 => PivotPolicy::SpreadMedian,
            2 => PivotPolicy::ClosestToMiddle,
            3 => PivotPolicy::SlidingMidpoint,
            c => return Err(invalid(format!("pivot policy code {c}"))),
        };
        let median = match h[26] {
            0 => MedianAlgorithm::Presorted,
            1 => MedianAlgorithm::Sort,
            2 => MedianAlgorithm::Quickselect,
            3 => MedianAlgorithm::FloydRivest,
            4 => MedianAlgorithm::MedianOfMedians,
            c => return Err(invalid(format!("median algorithm code {c}"))),
        };
        let non_finite = match h[27] {
            0 => NonFinitePolicy::Reject,
            1 => NonFinitePolicy::Skip,
            c => return Err(invalid(format!("non-finite policy code {c}"))),
        };
        let [dim, points, source_len, nodes, depth, leaf_size, threads, payload_len] =
            [32, 40, 48, 56, 64, 72, 80, 88].map(|at| u64_at(h, at));
        let max = MAX_POINTS as u64;
        if dim == 0 {
            return Err(invalid("dimension 0"));
        }
        if points > max {
            return Err(invalid(format!("{points} points (0 to {max})")));
        }
        if source_len < points || source_len > max {
            return Err(invalid(format!(
                "{source_len} source points for {points} held points"
            )));
        }
        // Every split leaves both sides non-empty, so there are at most 2n - 1 nodes (and one
        // empty leaf for a tree of no point).
        if nodes == 0 || nodes > 2 * points.max(1) - 1 {
            return Err(invalid(format!("{nodes} nodes for {points} points")));
        }
        if depth >= nodes {
            return Err(invalid(format!("depth {depth} with {nodes} nodes")));
        }
        if leaf_size == 0 || leaf_size > u64::from(u32::MAX) {
            return Err(invalid(format!("leaf size {leaf_size}")));
        }
        if threads > MAX_THREADS as u64 {
            return Err(invalid(format!(
                "threads {threads} (at most {MAX_THREADS})"
            )));
        }
        let sections = Sections::new(scalar, dim, points, nodes, source_len)
            .and_then(|s| s.total())
            .ok_or_else(|| invalid(format!("dimension {dim} overflows the payload's size")))?;
        if payload_len != sections {
            return Err(invalid(format!(
                "payload length {payload_len}, but {dim}-dimensional {} points, {nodes} nodes \
                 and {source_len} indices take {sections} bytes",
                scalar_name(scalar)
            )));
        }
        let total_len = payload_len
            .checked_add(HEADER_LEN as u64)
            .ok_or_else(|| invalid("payload length overflows"))?;
        let size = |v: u64| {
            usize::try_from(v).map_err(|_| invalid(format!("{v} is too large for this machine")))
        };
        // Every section's length then fits in memory sizes too.
        size(total_len)?;
        Ok(Self {
            format_version: version,
            library_version: written_by,
            scalar,
            dim: size(dim)?,
            points: size(points)?,
            source_len: size(source_len)?,
            nodes: size(nodes)?,
            depth: size(depth)?,
            options: BuildOptions {
                pivot,
                median,
                leaf_size: size(leaf_size)?,
                non_finite,
                threads: size(threads)?,
            },
            total_len,
            payload_crc: u32_at(h, 96),
        })
    }

    fn sections(&self) -> Sections {
        // Checked when the header was read.
        Sections::new(
            self.scalar,
            self.dim as u64,
            self.points as u64,
            self.nodes as u64,
            self.source_len as u64,
        )
        .expect("sizes checked with the header")
    }

    /// Refuses a tree of another scalar type or (if asked) dimension.
    fn expect<T: Scalar>(&self, options: &LoadOptions) -> Result<()> {
        if self.scalar != T::TYPE {
            return Err(SavedTreeError::ScalarType {
                file: scalar_name(self.scalar),
                expected: scalar_name(T::TYPE),
            }
            .into());
        }
        match options.dim {
            Some(d) if d != self.dim => Err(SavedTreeError::Dimension {
                file: self.dim,
                expected: d,
            }
            .into()),
            _ => Ok(()),
        }
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

/// Bytes handed to the sink at a time when a tree is written.
const CHUNK: usize = 1 << 16;

impl<T: Scalar> KdTree<T> {
    /// Bytes [`KdTree::save`] writes.
    pub fn saved_len(&self) -> usize {
        let s = Sections::new(
            T::TYPE,
            self.dim as u64,
            self.len() as u64,
            self.nodes.len() as u64,
            self.source_len as u64,
        )
        .and_then(|s| s.total())
        .expect("a tree in memory has a payload that fits in memory");
        HEADER_LEN + s as usize
    }

    /// The header of the tree, with the payload's checksum `payload_crc`.
    fn header(&self, payload_len: u64, payload_crc: u32) -> [u8; HEADER_LEN] {
        let mut h = [0u8; HEADER_LEN];
        h[..8].copy_from_slice(&MAGIC);
        h[8..12].copy_from_slice(&BYTE_ORDER_MARK.to_ne_bytes());
        h[12..16].copy_from_slice(&FORMAT_VERSION.to_ne_bytes());
        h[16..20].copy_from_slice(&(HEADER_LEN as u32).to_ne_bytes());
        h[20..24].copy_from_slice(&library_version().to_ne_bytes());
        h[24] = T::TYPE.size() as u8;
        h[25] = pivot_code(self.options.pivot);
        h[26] = median_code(self.options.median);
        h[27] = non_finite_code(self.options.non_finite);
        let fields = [
            self.dim,
            self.len(),
            self.source_len,
            self.nodes.len(),
            self.depth,
            self.options.leaf_size,
            self.options.threads,
        ];
        for (i, v) in fields.into_iter().enumerate() {
            h[32 + 8 * i..40 + 8 * i].copy_from_slice(&(v as u64).to_ne_bytes());
        }
        h[88..96].copy_from_slice(&payload_len.to_ne_bytes());
        h[96..100].copy_from_slice(&payload_crc.to_ne_bytes());
        let crc = crc32fast::hash(&h[..HEADER_CRC_AT]);
        h[HEADER_CRC_AT..HEADER_CRC_AT + 4].copy_from_slice(&crc.to_ne_bytes());
        h
    }

    /// Hands the payload to `sink` in chunks of about [`CHUNK`] bytes.
    fn payload(&self, sink: &mut dyn FnMut(&[u8]) -> Result<()>) -> Result<()> {
        let mut buf = Vec::with_capacity(CHUNK + 64);
        let mut flush = |buf: &mut Vec<u8>, force: bool| -> Result<()> {
            if force || buf.len() >= CHUNK {
                sink(buf)?;
                buf.clear();
            }
            Ok(())
        };
        let pad = |buf: &mut Vec<u8>, written: usize| {
            buf.resize(buf.len() + (written.next_multiple_of(8) - written), 0);
        };
        for &c in &self.coords {
            scalar_bytes(c, &mut buf);
            flush(&mut buf, false)?;
        }
        pad(&mut buf, self.coords.len() * T::TYPE.size());
        for &id in &self.ids {
            buf.extend_from_slice(&id.to_ne_bytes());
            flush(&mut buf, false)?;
        }
        pad(&mut buf, self.ids.len() * 4);
        for n in &self.nodes {
            scalar_bytes(n.split, &mut buf);
            for v in [n.dim, n.a, n.b] {
                buf.extend_from_slice(&v.to_ne_bytes());
            }
            if T::TYPE == ScalarType::F64 {
                buf.extend_from_slice(&[0; 4]);
            }
            flush(&mut buf, false)?;
        }
        let mut words = vec![0u64; self.source_len.div_ceil(64)];
        for &id in &self.ids {
            words[id as usize / 64] |= 1 << (id % 64);
        }
        for w in words {
            buf.extend_from_slice(&w.to_ne_bytes());
            flush(&mut buf, false)?;
        }
        flush(&mut buf, true)
    }

    fn payload_crc(&self) -> u32 {
        let mut hasher = crc32fast::Hasher::new();
        let _ = self.payload(&mut |b| {
            hasher.update(b);
            Ok(())
        });
        hasher.finalize()
    }

    /// Writes the tree to `w` in the format of docs/tree-file-format.md (the payload is
    /// produced twice, once for its checksum and once for `w`, so that nothing the size of
    /// the tree is buffered). Errors: [`NbhdError::Io`] if `w` fails.
    pub fn save<W: Write>(&self, mut w: W) -> Result<()> {
        let payload_len = (self.saved_len() - HEADER_LEN) as u64;
        let header = self.header(payload_len, self.payload_crc());
        let context = "writing the saved tree";
        w.write_all(&header)
            .map_err(|e| NbhdError::io(context, &e))?;
        self.payload(&mut |b| w.write_all(b).map_err(|e| NbhdError::io(context, &e)))?;
        w.flush().map_err(|e| NbhdError::io(context, &e))
    }

    /// The tree as the bytes [`KdTree::save`] writes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.saved_len());
        out.extend_from_slice(&[0; HEADER_LEN]);
        let _ = self.payload(&mut |b| {
            out.extend_from_slice(b);
            Ok(())
        });
        let crc = crc32fast::hash(&out[HEADER_LEN..]);
        let header = self.header((out.len() - HEADER_LEN) as u64, crc);
        out[..HEADER_LEN].copy_from_slice(&header);
        out
    }

    /// Writes the tree to the file `path` (created or truncated).
    pub fn save_file(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let context = || format!("writing the saved tree to {}", path.display());
        let file = std::fs::File::create(path).map_err(|e| NbhdError::io(context(), &e))?;
        self.save(std::io::BufWriter::with_capacity(1 << 20, file))
            .map_err(|e| in_file(e, context()))
    }

    /// Loads a tree saved by [`KdTree::save`] from exactly `bytes`.
    ///
    /// Errors: [`NbhdError::SavedTree`] naming what differs or is damaged: not a saved tree,
    /// another byte order or format version, coordinates of the other scalar type, truncated
    /// or followed by other bytes, a checksum that does not match, or a field or node structure
    /// that is inconsistent.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        Self::from_bytes_with(bytes, &LoadOptions::default())
    }

    /// [`KdTree::from_bytes`], also refusing a tree of another dimension than `options.dim`.
    pub fn from_bytes_with(bytes: &[u8], options: &LoadOptions) -> Result<Self> {
        let info = SavedTreeInfo::from_bytes(bytes)?;
        info.expect::<T>(options)?;
        check_len(bytes.len() as u64, info.total_len)?;
        Self::from_payload(&info, &bytes[HEADER_LEN..])
    }

    /// Loads a tree saved by [`KdTree::save`] from `r`, reading exactly its bytes (so that
    /// what follows in `r` stays unread). Errors: as [`KdTree::from_bytes`], and
    /// [`NbhdError::Io`] if `r` fails.
    pub fn load<R: Read>(r: R) -> Result<Self> {
        Self::load_with(r, &LoadOptions::default())
    }

    /// [`KdTree::load`], also refusing a tree of another dimension than `options.dim`.
    pub fn load_with<R: Read>(mut r: R, options: &LoadOptions) -> Result<Self> {
        let context = "reading the saved tree";
        let mut header = [0u8; HEADER_LEN];
        let got = read_up_to(&mut r, &mut header).map_err(|e| NbhdError::io(context, &e))?;
        let info = SavedTreeInfo::from_bytes(&header[..got])?;
        info.expect::<T>(options)?;
        let payload = read_payload(&mut r, info.total_len, context)?;
        Self::from_payload(&info, &payload)
    }

    /// Loads the tree saved in the file `path`.
    pub fn load_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let context = || format!("reading the saved tree from {}", path.display());
        let bytes = std::fs::read(path).map_err(|e| NbhdError::io(context(), &e))?;
        Self::from_bytes(&bytes)
    }

    /// The tree from a payload of exactly the length `info` declares: checksum, parse, check.
    fn from_payload(info: &SavedTreeInfo, payload: &[u8]) -> Result<Self> {
        let crc = crc32fast::hash(payload);
        if crc != info.payload_crc {
            return Err(SavedTreeError::Checksum {
                part: "payload",
                stored: info.payload_crc,
                computed: crc,
            }
            .into());
        }
        let s = info.sections();
        let (coords_bytes, rest) = payload.split_at(s.coords as usize);
        let (ids_bytes, rest) = rest.split_at(s.ids as usize);
        let (node_bytes, bitmap_bytes) = rest.split_at(s.nodes as usize);
        let size = T::TYPE.size();
        let coords: Vec<T> = coords_bytes[..info.points * info.dim * size]
            .chunks_exact(size)
            .map(T::read_ne)
            .collect();
        let ids: Vec<u32> = ids_bytes[..info.points * 4]
            .chunks_exact(4)
            .map(|b| u32_at(b, 0))
            .collect();
        if coords_bytes[coords.len() * size..].iter().any(|&b| b != 0)
            || ids_bytes[ids.len() * 4..].iter().any(|&b| b != 0)
        {
            return Err(invalid(
                "padding after the coordinates or indices is not zero",
            ));
        }
        let record = node_record(T::TYPE);
        let mut nodes = Vec::with_capacity(info.nodes);
        for r in node_bytes.chunks_exact(record) {
            nodes.push(Node {
                split: T::read_ne(&r[..size]),
                dim: u32_at(r, size),
                a: u32_at(r, size + 4),
                b: u32_at(r, size + 8),
            });
            if record > size + 12 && u32_at(r, size + 12) != 0 {
                return Err(invalid("padding of a node is not zero"));
            }
        }
        let mut tree = KdTree {
            dim: info.dim,
            coords,
            min_id: Vec::new(),
            descent: None,
            ids,
            nodes,
            depth: info.depth,
            source_len: info.source_len,
            options: info.options,
            position_of: OnceLock::new(),
        };
        tree.check_points(bitmap_bytes)?;
        tree.check_nodes()?;
        // Derived, not saved: made once the nodes are known to be well formed.
        tree.derive(1)?;
        Ok(tree)
    }

    /// Checks that every coordinate is finite and that the caller indices are distinct, below
    /// the source length and exactly the ones the bitmap of held indices marks.
    fn check_points(&self, bitmap: &[u8]) -> Result<()> {
        if let Some(p) = self.coords.iter().position(|c| !c.is_finite()) {
            return Err(invalid(format!(
                "the point at tree position {} has a non-finite coordinate",
                p / self.dim
            )));
        }
        let mut seen = vec![0u64; self.source_len.div_ceil(64)];
        for (pos, &id) in self.ids.iter().enumerate() {
            if id as usize >= self.source_len {
                return Err(invalid(format!(
                    "index {id} at tree position {pos} is not below the {} source points",
                    self.source_len
                )));
            }
            let (w, bit) = (id as usize / 64, 1u64 << (id % 64));
            if seen[w] & bit != 0 {
                return Err(invalid(format!("index {id} is held twice")));
            }
            seen[w] |= bit;
        }
        for (w, (stored, seen)) in bitmap.chunks_exact(8).zip(&seen).enumerate() {
            if u64_at(stored, 0) != *seen {
                return Err(invalid(format!(
                    "the bitmap of held indices differs from the indices at word {w}"
                )));
            }
        }
        Ok(())
    }

    /// Checks the node array: exactly one tree in preorder (the left child of node `i` is
    /// `i + 1`, the right one is where the left subtree ends: no cycle, no node shared or left
    /// out), leaves covering the tree positions in order with non-empty ranges, both children
    /// of every split non-empty, split dimensions below the dimension, finite splits, the depth
    /// stated, and every point of a left subtree ≤ its split ≤ every point of the right one in
    /// the split's dimension — what the search's pruning (search.rs) relies on for exact
    /// answers.
    fn check_nodes(&self) -> Result<()> {
        let (nodes, n, d) = (&self.nodes, self.len(), self.dim);
        // Pass 1, the shape: a preorder walk in which the nodes must come in index order.
        // Frames: (node, first point, one past the last point, depth).
        let mut stack = vec![(0usize, 0usize, n, 0usize)];
        let mut next = 0usize;
        let mut depth = 0usize;
        while let Some((i, start, end, level)) = stack.pop() {
            if i != next {
                return Err(invalid(format!(
                    "node {i} is reached where node {next} should come (nodes in preorder)"
                )));
            }
            next += 1;
            let nd = &nodes[i];
            if nd.b as usize != end {
                return Err(invalid(format!(
                    "node {i} ends at point {} instead of {end}",
                    nd.b
                )));
            }
            depth = depth.max(level);
            if nd.dim == LEAF {
                // Only a tree of no point has an empty leaf: its root.
                if nd.a as usize != start || (start >= end && n > 0) {
                    return Err(invalid(format!(
                        "leaf {i} holds points {}..{} where {start}..{end} are due",
                        nd.a, nd.b
                    )));
                }
                if nd.split.to_f64() != 0.0 {
                    return Err(invalid(format!("leaf {i} has a split value")));
                }
                continue;
            }
            if nd.dim as usize >= d || !nd.split.is_finite() {
                return Err(invalid(format!(
                    "node {i} splits dimension {} at {} (dimension {d})",
                    nd.dim, nd.split
                )));
            }
            let (left, right) = (i + 1, nd.a as usize);
            if left >= nodes.len() || right <= left || right >= nodes.len() {
                return Err(invalid(format!(
                    "node {i} has its right child at {right} ({} nodes)",
                    nodes.len()
                )));
            }
            let mid = nodes[left].b as usize;
            if mid <= start || mid >= end {
                return Err(invalid(format!(
                    "node {i} splits points {start}..{end} at {mid}"
                )));
            }
            stack.push((right, mid, end, level + 1));
            stack.push((left, start, mid, level + 1));
        }
        if next != nodes.len() {
            return Err(invalid(format!(
                "{} of {} nodes are not in the tree",
                nodes.len() - next,
                nodes.len()
            )));
        }
        if depth != self.depth {
            return Err(invalid(format!(
                "the depth is {depth}, not {} as stated",
                self.depth
            )));
        }
        if n == 0 {
            return Ok(()); // one empty leaf, checked above: no split
        }
        // Pass 2, the splits: tight boxes bottom-up. In reverse preorder a subtree leaves
        // exactly its box on the stack, so at an internal node the top box is its left child's
        // and the one below its right child's.
        let mut boxes: Vec<T> = Vec::new();
        for (i, nd) in nodes.iter().enumerate().rev() {
            if nd.is_leaf() {
                let at = boxes.len();
                let first = self.point_at(nd.a as usize);
                boxes.extend_from_slice(first);
                boxes.extend_from_slice(first);
                let (lo, hi) = boxes[at..].split_at_mut(d);
                for p in nd.a as usize + 1..nd.b as usize {
                    for (j, &c) in self.point_at(p).iter().enumerate() {
                        lo[j] = lo[j].min_of(c);
                        hi[j] = hi[j].max_of(c);
                    }
                }
                continue;
            }
            let at = boxes
                .len()
                .checked_sub(4 * d)
                .ok_or_else(|| invalid(format!("node {i} lacks children")))?;
            let (right, left) = boxes[at..].split_at_mut(2 * d);
            let j = nd.dim as usize;
            // left = [lo | hi] of the left child, right of the right child.
            if left[d + j] > nd.split || right[j] < nd.split {
                return Err(invalid(format!(
                    "node {i} splits dimension {j} at {} but its left points reach {} and its \
                     right points start at {}",
                    nd.split,
                    left[d + j],
                    right[j]
                )));
            }
            for k in 0..d {
                right[k] = right[k].min_of(left[k]);
                right[d + k] = right[d + k].max_of(left[d + k]);
            }
            boxes.truncate(at + 2 * d);
        }
        Ok(())
    }
}

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
