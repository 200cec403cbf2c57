//! Saving a dynamic tree and loading it back: [`DynamicKdTree::save`], [`DynamicKdTree::to_bytes`],
//! [`DynamicKdTree::load`], [`DynamicKdTree::from_bytes`] and the file helpers, and
//! [`SavedDynamicInfo`] to read a saved dynamic tree's header. The layout, what is checked and
//! the compatibility promise are in docs/tree-file-format.md ("Dynamic trees").
//!
//! A saved dynamic tree is a 128-byte header of the static tree's shape (magic `NBHDFRST`)
//! followed by a payload: a table of the static trees (first index, saved length), the bitmaps
//! of indices not live and of indices skipped at insertion, the coordinates kept for the
//! indices from `base` on, then every static tree of the forest saved in the static format
//! (`src/tree/persist.rs`), back to back. The forest is stored as it is, so a loaded one
//! answers every query bit for bit as the saved one, and grows and shrinks the same way.
//! Nothing is trusted: besides the checksums and each static tree's own checks, what spans the
//! trees is checked (disjoint index ranges, the bitmaps, every live index held by exactly one
//! tree with the same coordinates as kept, the live count).

use std::io::{Read, Write};
use std::path::Path;

use super::{bit, DynamicKdTree, Part};
use crate::cloud::NonFinitePolicy;
use crate::error::{NbhdError, Result, SavedTreeError};
use crate::parallel::MAX_THREADS;
use crate::points::point_bytes;
use crate::query::NeighborSearch;
use crate::scalar::{Scalar, ScalarType};
use crate::tree::persist::{
    check_len, check_start, in_file, invalid, library_version, median_code, non_finite_code, pad8,
    pivot_code, read_payload, read_up_to, scalar_bytes, scalar_name, u32_at, u64_at, written_by,
    Kind, BYTE_ORDER_MARK, DYNAMIC_KIND, FOREST_MAGIC, STATIC_KIND,
};
use crate::tree::{
    BuildOptions, KdTree, LoadOptions, MedianAlgorithm, PivotPolicy, HEADER_LEN, MAGIC,
};

/// The format version of saved dynamic trees this library writes and reads.
pub const DYNAMIC_FORMAT_VERSION: u32 = 1;
/// Where the header checksum sits (it covers the bytes before it).
const HEADER_CRC_AT: usize = 120;
/// A saved dynamic tree.
const DYNAMIC: Kind = Kind {
    magic: FOREST_MAGIC,
    name: DYNAMIC_KIND,
    version: DYNAMIC_FORMAT_VERSION,
    other_magic: MAGIC,
    other_name: STATIC_KIND,
};
/// Bytes of one entry of the table of static trees: first index, saved length.
const TABLE_ENTRY: u64 = 16;

/// What a saved dynamic tree's header says, read and checked without loading it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SavedDynamicInfo {
    /// The format version (always [`DYNAMIC_FORMAT_VERSION`] once checked).
    pub format_version: u32,
    /// The nbhd version that wrote the file, as `(major, minor, patch)`.
    pub library_version: (u32, u32, u32),
    /// The coordinate type.
    pub scalar: ScalarType,
    /// Dimension.
    pub dim: usize,
    /// Indices given so far (`next_index()`).
    pub next_index: u32,
    /// First index whose coordinates are kept.
    base: u32,
    /// Live points.
    pub live: usize,
    /// Static trees in the forest.
    pub trees: usize,
    /// The growth factor.
    pub growth: usize,
    /// The options the static trees are built with, as the file states them (its `threads`
    /// is what the saving tree used: a loaded tree builds on the default 0 instead).
    pub options: BuildOptions,
    /// Bytes of the saved dynamic tree: header and payload.
    pub total_len: u64,
    payload_crc: u32,
}

/// Bytes of a bitmap over `n` indices.
fn bitmap_len(n: u64) -> u64 {
    n.div_ceil(64) * 8
}

impl SavedDynamicInfo {
    /// Reads and checks the header at the start of `bytes` (the payload need not follow):
    /// magic (a static tree is named as such), byte order, format version, header checksum
    /// and every field's range.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let h = check_start(bytes, &DYNAMIC)?;
        let version = u32_at(h, 12);
        let written_by = written_by(h);
        if u32_at(h, 28) != 0 || h[108..120].iter().any(|&b| b != 0) || u32_at(h, 124) != 0 {
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
        let pivot = PivotPolicy::ALL
            .into_iter()
            .find(|&p| pivot_code(p) == h[25])
            .ok_or_else(|| invalid(format!("pivot policy code {}", h[25])))?;
        let median = MedianAlgorithm::ALL
            .into_iter()
            .find(|&m| median_code(m) == h[26])
            .ok_or_else(|| invalid(format!("median algorithm code {}", h[26])))?;
        let non_finite = [NonFinitePolicy::Reject, NonFinitePolicy::Skip]
            .into_iter()
            .find(|&p| non_finite_code(p) == h[27])
            .ok_or_else(|| invalid(format!("non-finite policy code {}", h[27])))?;
        let [dim, next, base, live, trees, growth, leaf_size, threads, payload_len] =
            [32, 40, 48, 56, 64, 72, 80, 88, 96].map(|at| u64_at(h, at));
        if dim == 0 {
            return Err(invalid("dimension 0"));
        }
        // As a new tree refuses it: no point of such a dimension fits in the address space
        // (an empty saved tree would otherwise load with any).
        usize::try_from(dim)
            .ok()
            .filter(|&d| point_bytes(d, scalar).is_ok())
            .ok_or_else(|| invalid(format!("dimension {dim} (a point would not fit in memory)")))?;
        if next > u64::from(u32::MAX) {
            return Err(invalid(format!("{next} indices given (at most 2^32 - 1)")));
        }
        if base > next {
            return Err(invalid(format!(
                "coordinates kept from index {base} of {next}"
            )));
        }
        if live > next - base {
            return Err(invalid(format!(
                "{live} live points among the {} indices from {base} on",
                next - base
            )));
        }
        if (live == 0) != (trees == 0) || trees > live {
            return Err(invalid(format!(
                "{trees} static trees for {live} live points"
            )));
        }
        if growth < 2 {
            return Err(invalid(format!("growth factor {growth} (at least 2)")));
        }
        if leaf_size == 0 || leaf_size > u64::from(u32::MAX) {
            return Err(invalid(format!("leaf size {leaf_size}")));
        }
        if threads > MAX_THREADS as u64 {
            return Err(invalid(format!(
                "threads {threads} (at most {MAX_THREADS})"
            )));
        }
        // The fixed sections and the smallest trees must fit in the payload; the trees'
        // lengths are checked against it once the table is read.
        let fixed = (|| {
            trees
                .checked_mul(TABLE_ENTRY)?
                .checked_add(2 * bitmap_len(next))?
                .checked_add(pad8(
                    (next - base)
                        .checked_mul(dim)?
                        .checked_mul(scalar.size() as u64)?,
                )?)
        })()
        .ok_or_else(|| invalid(format!("dimension {dim} overflows the payload's size")))?;
        let smallest = trees
            .checked_mul(HEADER_LEN as u64)
            .and_then(|t| t.checked_add(fixed));
        if smallest.is_none_or(|s| s > payload_len) {
            return Err(invalid(format!(
                "payload length {payload_len} is shorter than its {trees} trees and \
                 {dim}-dimensional {} coordinates of {} indices need",
                scalar_name(scalar),
                next - base
            )));
        }
        let total_len = payload_len
            .checked_add(HEADER_LEN as u64)
            .ok_or_else(|| invalid("payload length overflows"))?;
        let size = |v: u64| {
            usize::try_from(v).map_err(|_| invalid(format!("{v} is too large for this machine")))
        };
        size(total_len)?;
        Ok(Self {
            format_version: version,
            library_version: written_by,
            scalar,
            dim: size(dim)?,
            next_index: next as u32,
            base: base as u32,
            live: size(live)?,
            trees: size(trees)?,
            growth: size(growth)?,
            options: BuildOptions {
                pivot,
                median,
                leaf_size: size(leaf_size)?,
                non_finite,
                threads: size(threads)?,
            },
            total_len,
            payload_crc: u32_at(h, 104),
        })
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

/// A `Write` that only feeds a CRC-32 (the payload is produced twice: once for its checksum,
/// once for the output).
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

fn not_live_bits<T: Scalar>() -> u64 {
    T::from_f64(f64::NAN).to_f64().to_bits()
}

impl<T: Scalar> DynamicKdTree<T> {
    /// Bytes [`DynamicKdTree::save`] writes.
    pub fn saved_len(&self) -> usize {
        HEADER_LEN + self.payload_len() as usize
    }

    fn payload_len(&self) -> u64 {
        let n = u64::from(self.next);
        let coords = self.store.len() as u64 * T::TYPE.size() as u64;
        self.parts.len() as u64 * TABLE_ENTRY
            + 2 * bitmap_len(n)
            + coords.next_multiple_of(8)
            + self
                .parts
                .iter()
                .map(|p| p.tree.saved_len() as u64)
                .sum::<u64>()
    }

    fn header(&self, payload_len: u64, payload_crc: u32) -> [u8; HEADER_LEN] {
        let mut h = [0u8; HEADER_LEN];
        h[..8].copy_from_slice(&FOREST_MAGIC);
        h[8..12].copy_from_slice(&BYTE_ORDER_MARK.to_ne_bytes());
        h[12..16].copy_from_slice(&DYNAMIC_FORMAT_VERSION.to_ne_bytes());
        h[16..20].copy_from_slice(&(HEADER_LEN as u32).to_ne_bytes());
        h[20..24].copy_from_slice(&library_version().to_ne_bytes());
        h[24] = T::TYPE.size() as u8;
        h[25] = pivot_code(self.options.pivot);
        h[26] = median_code(self.options.median);
        h[27] = non_finite_code(self.options.non_finite);
        let fields = [
            self.dim as u64,
            u64::from(self.next),
            u64::from(self.base),
            self.live as u64,
            self.parts.len() as u64,
            self.growth as u64,
            self.options.leaf_size as u64,
            self.options.threads as u64,
            payload_len,
        ];
        for (i, v) in fields.into_iter().enumerate() {
            h[32 + 8 * i..40 + 8 * i].copy_from_slice(&v.to_ne_bytes());
        }
        h[104..108].copy_from_slice(&payload_crc.to_ne_bytes());
        let crc = crc32fast::hash(&h[..HEADER_CRC_AT]);
        h[HEADER_CRC_AT..HEADER_CRC_AT + 4].copy_from_slice(&crc.to_ne_bytes());
        h
    }

    /// Writes the payload to `w`.
    fn payload(&self, w: &mut dyn Write) -> Result<()> {
        let context = "writing the saved dynamic tree";
        let io = |e: std::io::Error| NbhdError::io(context, &e);
        let mut buf = Vec::with_capacity(1 << 16);
        for p in &self.parts {
            buf.extend_from_slice(&u64::from(p.lo).to_ne_bytes());
            buf.extend_from_slice(&(p.tree.saved_len() as u64).to_ne_bytes());
        }
        for bits in [&self.not_live, &self.skipped] {
            for word in bits.iter() {
                buf.extend_from_slice(&word.to_ne_bytes());
            }
            w.write_all(&buf).map_err(io)?;
            buf.clear();
        }
        for chunk in self.store.chunks(1 << 13) {
            for &c in chunk {
                scalar_bytes(c, &mut buf);
            }
            w.write_all(&buf).map_err(io)?;
            buf.clear();
        }
        let written = self.store.len() * T::TYPE.size();
        w.write_all(&[0; 8][..written.next_multiple_of(8) - written])
            .map_err(io)?;
        for p in &self.parts {
            p.tree.save(&mut *w)?;
        }
        Ok(())
    }

    /// Writes the dynamic tree to `w` in the format of docs/tree-file-format.md ("Dynamic
    /// trees"). Errors: [`NbhdError::Io`] if `w` fails.
    pub fn save<W: Write>(&self, mut w: W) -> Result<()> {
        let mut crc = CrcSink(crc32fast::Hasher::new());
        self.payload(&mut crc)?;
        let header = self.header(self.payload_len(), crc.0.finalize());
        let context = "writing the saved dynamic tree";
        w.write_all(&header)
            .map_err(|e| NbhdError::io(context, &e))?;
        self.payload(&mut w)?;
        w.flush().map_err(|e| NbhdError::io(context, &e))
    }

    /// The dynamic tree as the bytes [`DynamicKdTree::save`] writes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.saved_len());
        out.extend_from_slice(&[0; HEADER_LEN]);
        self.payload(&mut out)
            .expect("writing to memory does not fail");
        let crc = crc32fast::hash(&out[HEADER_LEN..]);
        let header = self.header((out.len() - HEADER_LEN) as u64, crc);
        out[..HEADER_LEN].copy_from_slice(&header);
        out
    }

    /// Writes the dynamic tree to the file `path` (created or truncated).
    pub fn save_file(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let context = || format!("writing the saved dynamic tree to {}", path.display());
        let file = std::fs::File::create(path).map_err(|e| NbhdError::io(context(), &e))?;
        self.save(std::io::BufWriter::with_capacity(1 << 20, file))
            .map_err(|e| in_file(e, context()))
    }

    /// Loads a dynamic tree saved by [`DynamicKdTree::save`] from exactly `bytes`.
    ///
    /// Errors: [`NbhdError::SavedTree`] naming what differs or is damaged: not a saved tree
    /// (or a static tree: [`SavedTreeError::OtherKind`]), another byte order or format
    /// version, the other scalar type, truncated or followed by other bytes, a checksum that
    /// does not match, or a field, static tree or cross-tree fact that is inconsistent.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        Self::from_bytes_with(bytes, &LoadOptions::default())
    }

    /// [`DynamicKdTree::from_bytes`], also refusing another dimension than `options.dim`.
    pub fn from_bytes_with(bytes: &[u8], options: &LoadOptions) -> Result<Self> {
        let info = SavedDynamicInfo::from_bytes(bytes)?;
        info.expect::<T>(options)?;
        check_len(bytes.len() as u64, info.total_len)?;
        Self::from_payload(&info, &bytes[HEADER_LEN..])
    }

    /// Loads a dynamic tree saved by [`DynamicKdTree::save`] from `r`, reading exactly its
    /// bytes. Errors: as [`DynamicKdTree::from_bytes`], and [`NbhdError::Io`] if `r` fails.
    pub fn load<R: Read>(r: R) -> Result<Self> {
        Self::load_with(r, &LoadOptions::default())
    }

    /// [`DynamicKdTree::load`], also refusing another dimension than `options.dim`.
    pub fn load_with<R: Read>(mut r: R, options: &LoadOptions) -> Result<Self> {
        let context = "reading the saved dynamic tree";
        let mut header = [0u8; HEADER_LEN];
        let got = read_up_to(&mut r, &mut header).map_err(|e| NbhdError::io(context, &e))?;
        let info = SavedDynamicInfo::from_bytes(&header[..got])?;
        info.expect::<T>(options)?;
        let payload = read_payload(&mut r, info.total_len, context)?;
        Self::from_payload(&info, &payload)
    }

    /// Loads the dynamic tree saved in the file `path`.
    pub fn load_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let context = || format!("reading the saved dynamic tree from {}", path.display());
        let bytes = std::fs::read(path).map_err(|e| NbhdError::io(context(), &e))?;
        Self::from_bytes(&bytes)
    }

    /// The dynamic tree from a payload of exactly the length `info` declares.
    fn from_payload(info: &SavedDynamicInfo, payload: &[u8]) -> Result<Self> {
        let crc = crc32fast::hash(payload);
        if crc != info.payload_crc {
            return Err(SavedTreeError::Checksum {
                part: "payload",
                stored: info.payload_crc,
                computed: crc,
            }
            .into());
        }
        let (d, next, base) = (info.dim, info.next_index, info.base);
        let table_len = info.trees * TABLE_ENTRY as usize;
        let words = (next as usize).div_ceil(64);
        let kept = (next - base) as usize;
        let size = T::TYPE.size();
        let coords_len = (kept * d * size).next_multiple_of(8);
        let (table, rest) = payload.split_at(table_len);
        let (not_live_bytes, rest) = rest.split_at(words * 8);
        let (skipped_bytes, rest) = rest.split_at(words * 8);
        let (coord_bytes, mut tree_bytes) = rest.split_at(coords_len);

        let read_bits =
            |b: &[u8]| -> Vec<u64> { b.chunks_exact(8).map(|w| u64_at(w, 0)).collect() };
        let not_live = read_bits(not_live_bytes);
        let skipped = read_bits(skipped_bytes);
        if next % 64 != 0 {
            let beyond = !0u64 << (next % 64);
            if not_live.last().is_some_and(|w| w & beyond != 0)
                || skipped.last().is_some_and(|w| w & beyond != 0)
            {
                return Err(invalid(format!(
                    "a bitmap marks an index at or past the {next} given"
                )));
            }
        }
        if let Some(w) = (0..words).find(|&w| skipped[w] & !not_live[w] != 0) {
            return Err(invalid(format!(
                "an index skipped at insertion is marked live (bitmap word {w})"
            )));
        }
        if coord_bytes[kept * d * size..].iter().any(|&b| b != 0) {
            return Err(invalid("padding after the coordinates is not zero"));
        }
        let store: Vec<T> = coord_bytes[..kept * d * size]
            .chunks_exact(size)
            .map(T::read_ne)
            .collect();
        let nan = not_live_bits::<T>();
        for g in base..next {
            if bit(&not_live, g) {
                let at = (g - base) as usize * d;
                if store[at..at + d]
                    .iter()
                    .any(|c| c.to_f64().to_bits() != nan)
                {
                    return Err(invalid(format!(
                        "index {g} is not live but has coordinates kept"
                    )));
                }
            }
        }

        let tree_options = BuildOptions {
            non_finite: NonFinitePolicy::Skip,
            ..info.options
        };
        let mut parts: Vec<Part<T>> = Vec::with_capacity(info.trees);
        let mut live_total = 0usize;
        let mut end = base;
        for (i, entry) in table.chunks_exact(TABLE_ENTRY as usize).enumerate() {
            let (lo, len) = (u64_at(entry, 0), u64_at(entry, 8));
            if lo < u64::from(end) || lo >= u64::from(next) {
                return Err(invalid(format!(
                    "static tree {i} starts at index {lo}, outside {end}..{next}"
                )));
            }
            let lo = lo as u32;
            if len > tree_bytes.len() as u64 {
                return Err(invalid(format!(
                    "static tree {i} takes {len} bytes but {} remain",
                    tree_bytes.len()
                )));
            }
            let (bytes, rest) = tree_bytes.split_at(len as usize);
            tree_bytes = rest;
            let tree = KdTree::<T>::from_bytes_with(bytes, &LoadOptions { dim: Some(d) })
                .map_err(|e| invalid(format!("static tree {i}: {e}")))?;
            let hi = u64::from(lo) + tree.source_len() as u64;
            if hi > u64::from(next) {
                return Err(invalid(format!(
                    "static tree {i} covers indices {lo}..{hi}, past the {next} given"
                )));
            }
            let o = tree.options();
            if (o.pivot, o.median, o.leaf_size, o.non_finite)
                != (
                    tree_options.pivot,
                    tree_options.median,
                    tree_options.leaf_size,
                    tree_options.non_finite,
                )
            {
                return Err(invalid(format!(
                    "static tree {i} was built with other options than the dynamic tree's"
                )));
            }
            let mut live = 0usize;
            for pos in 0..tree.len() {
                let g = lo + tree.tree_order()[pos];
                if bit(&skipped, g) {
                    return Err(invalid(format!(
                        "static tree {i} holds index {g}, skipped at insertion"
                    )));
                }
                if bit(&not_live, g) {
                    continue;
                }
                live += 1;
                let at = (g - base) as usize * d;
                let same = tree
                    .point_at(pos)
                    .iter()
                    .zip(&store[at..at + d])
                    .all(|(a, b)| a.to_f64().to_bits() == b.to_f64().to_bits());
                if !same {
                    return Err(invalid(format!(
                        "static tree {i} holds other coordinates for index {g} than those kept"
                    )));
                }
            }
            if live == 0 {
                return Err(invalid(format!("static tree {i} holds no live point")));
            }
            live_total += live;
            parts.push(Part::new(tree, lo, hi as u32, live));
            end = hi as u32;
        }
        if !tree_bytes.is_empty() {
            return Err(invalid(format!(
                "{} bytes follow the last static tree",
                tree_bytes.len()
            )));
        }
        // Every live index is held by a tree (the trees' live points are distinct live
        // indices, so equal counts mean the same sets).
        let marked_live = next as usize
            - not_live
                .iter()
                .map(|w| w.count_ones() as usize)
                .sum::<usize>();
        if live_total != info.live || marked_live != info.live {
            return Err(invalid(format!(
                "{} live points stated, {marked_live} marked live, {live_total} held live by \
                 the static trees",
                info.live
            )));
        }
        info.options.validate()?;
        Ok(Self {
            dim: d,
            // The file's thread count is not obeyed (a file is untrusted input: one saying
            // 1024 made every later insertion start 1024 threads): the loader's default,
            // changed by `set_threads`.
            options: BuildOptions {
                threads: 0,
                ..info.options
            },
            store,
            base,
            next,
            not_live,
            skipped,
            parts,
            live: info.live,
            growth: info.growth,
        })
    }
}
