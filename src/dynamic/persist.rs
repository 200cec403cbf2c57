//! The saved format of a growing tree (the envelope and the save and load family are the
//! static tree's, [`Persist`](crate::tree::Persist)), and [`SavedDynamicInfo`] to read a saved
//! dynamic tree's header. The layout, what is checked and the compatibility promise are in
//! docs/tree-file-format.md ("Dynamic trees").
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

use std::io::Write;

use super::{bit, DynamicKdTree, Part};
use crate::error::Result;
use crate::packed::NonFinitePolicy;
use crate::parallel::MAX_THREADS;
use crate::points::point_bytes;
use crate::query::NeighborSearch;
use crate::scalar::{Scalar, ScalarType};
use crate::tree::{
    check_start, header, invalid, pad8, period_section_len, periodic_flag, read_codes, read_period,
    scalar_bytes, scalar_name, size, u32_at, u64_at, write_period, write_saved, written_by, Kind,
    DYNAMIC_KIND, FOREST_MAGIC, STATIC_KIND,
};
use crate::tree::{
    saved_header, BuildOptions, KdTree, LoadOptions, Persist, SavedFormat, HEADER_LEN, MAGIC,
};

/// The format version of saved dynamic trees this library writes and reads.
pub const DYNAMIC_FORMAT_VERSION: u32 = 1;
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
    /// Whether the tree is periodic (a torus; its box follows the kept coordinates).
    pub periodic: bool,
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
        let periodic = periodic_flag(h)?;
        if h[108..120].iter().any(|&b| b != 0) || u32_at(h, 124) != 0 {
            return Err(invalid("a reserved header field is not zero"));
        }
        let (scalar, codes) = read_codes(h)?;
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
                )?)?
                .checked_add(period_section_len(periodic, dim, scalar)?)
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
                leaf_size: size(leaf_size)?,
                threads: size(threads)?,
                ..codes
            },
            periodic,
            total_len,
            payload_crc: u32_at(h, 104),
        })
    }
}

saved_header!(SavedDynamicInfo);

/// The bits of the coordinates kept for an index that is not live (NaN in `T`).
fn not_live_bits<T: Scalar>() -> u64 {
    T::from_f64(f64::NAN).to_f64().to_bits()
}

impl<T: Scalar> SavedFormat for DynamicKdTree<T> {
    const WHAT: &'static str = "dynamic tree";
    const SCALAR: ScalarType = T::TYPE;
    type Info = SavedDynamicInfo;

    fn read_header(bytes: &[u8]) -> Result<SavedDynamicInfo> {
        SavedDynamicInfo::from_bytes(bytes)
    }

    fn payload_len(&self) -> u64 {
        let n = u64::from(self.next);
        let coords = self.store.len() as u64 * T::TYPE.size() as u64;
        self.parts.len() as u64 * TABLE_ENTRY
            + 2 * bitmap_len(n)
            + coords.next_multiple_of(8)
            + period_section_len(self.period.is_some(), self.dim as u64, T::TYPE)
                .expect("a box of a tree in memory")
            + self
                .parts
                .iter()
                .map(|p| p.tree.saved_len() as u64)
                .sum::<u64>()
    }

    fn header(&self, payload_len: u64, payload_crc: u32) -> [u8; HEADER_LEN] {
        let o = &self.options;
        let fields = [
            self.dim as u64,
            u64::from(self.next),
            u64::from(self.base),
            self.live as u64,
            self.parts.len() as u64,
            self.growth as u64,
            o.leaf_size as u64,
            o.threads as u64,
            payload_len,
        ];
        header(
            &DYNAMIC,
            T::TYPE,
            o,
            self.period.is_some(),
            &fields,
            104,
            payload_crc,
        )
    }

    /// The table of static trees, the two bitmaps, the kept coordinates, then every static
    /// tree saved whole.
    fn payload(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let mut buf = Vec::with_capacity(1 << 16);
        for p in &self.parts {
            buf.extend_from_slice(&u64::from(p.lo).to_ne_bytes());
            buf.extend_from_slice(&(p.tree.saved_len() as u64).to_ne_bytes());
        }
        for bits in [&self.not_live, &self.skipped] {
            for word in bits.iter() {
                buf.extend_from_slice(&word.to_ne_bytes());
            }
            w.write_all(&buf)?;
            buf.clear();
        }
        for chunk in self.store.chunks(1 << 13) {
            for &c in chunk {
                scalar_bytes(c, &mut buf);
            }
            w.write_all(&buf)?;
            buf.clear();
        }
        let written = self.store.len() * T::TYPE.size();
        w.write_all(&[0; 8][..written.next_multiple_of(8) - written])?;
        write_period(self.period.as_ref(), &mut buf);
        w.write_all(&buf)?;
        for p in &self.parts {
            write_saved(&*p.tree, w)?;
        }
        Ok(())
    }

    /// The dynamic tree from a payload of exactly the length `info` declares: the bitmaps and
    /// the kept coordinates, every static tree, and the facts that span them.
    fn from_payload(info: &SavedDynamicInfo, payload: &[u8]) -> Result<Self> {
        let table_len = info.trees * TABLE_ENTRY as usize;
        let (table, rest) = payload.split_at(table_len);
        let (kept, rest) = Kept::<T>::read(info, rest)?;
        let period_len = period_section_len(info.periodic, info.dim as u64, T::TYPE)
            .expect("checked with the header") as usize;
        let (period_bytes, tree_bytes) = rest.split_at(period_len);
        let period = match info.periodic {
            true => Some(read_period::<T>(period_bytes, info.dim)?),
            false => None,
        };
        let parts = read_trees(info, &kept, table, tree_bytes)?;
        if let Some(i) = parts
            .iter()
            .position(|p| p.tree.period() != period.as_ref())
        {
            return Err(invalid(format!(
                "static tree {i} has another periodic box than the dynamic tree"
            )));
        }
        let live_total: usize = parts.iter().map(|p| p.live).sum();
        // Every live index is held by a tree (the trees' live points are distinct live
        // indices, so equal counts mean the same sets).
        let marked_live = info.next_index as usize
            - kept
                .not_live
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
            dim: info.dim,
            // The file's thread count is not obeyed (a file is untrusted input: one saying
            // 1024 made every later insertion start 1024 threads): the loader's default,
            // changed by `set_threads`.
            options: BuildOptions {
                threads: 0,
                ..info.options
            },
            store: kept.store,
            base: info.base,
            next: info.next_index,
            not_live: kept.not_live,
            skipped: kept.skipped,
            parts,
            live: info.live,
            growth: info.growth,
            period,
        })
    }
}

/// What a saved dynamic tree keeps beside its static trees: the bitmaps of indices not live and
/// skipped, and the coordinates of the indices from `base` on.
struct Kept<T> {
    not_live: Vec<u64>,
    skipped: Vec<u64>,
    store: Vec<T>,
}

impl<T: Scalar> Kept<T> {
    /// Reads and checks the bitmaps and the kept coordinates at the start of `bytes`; returns
    /// them and the bytes after them (the static trees).
    fn read<'a>(info: &SavedDynamicInfo, bytes: &'a [u8]) -> Result<(Self, &'a [u8])> {
        let (d, next, base) = (info.dim, info.next_index, info.base);
        let words = (next as usize).div_ceil(64);
        let kept = (next - base) as usize;
        let size = T::TYPE.size();
        let coords_len = (kept * d * size).next_multiple_of(8);
        let (not_live_bytes, rest) = bytes.split_at(words * 8);
        let (skipped_bytes, rest) = rest.split_at(words * 8);
        let (coord_bytes, tree_bytes) = rest.split_at(coords_len);
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
        let kept = Self {
            not_live,
            skipped,
            store,
        };
        Ok((kept, tree_bytes))
    }
}

/// The static trees of a saved dynamic tree, from its table of trees and their bytes, each
/// checked against the kept bitmaps and coordinates.
fn read_trees<T: Scalar>(
    info: &SavedDynamicInfo,
    kept: &Kept<T>,
    table: &[u8],
    mut tree_bytes: &[u8],
) -> Result<Vec<Part<T>>> {
    let mut parts: Vec<Part<T>> = Vec::with_capacity(info.trees);
    let mut end = info.base;
    for (i, entry) in table.chunks_exact(TABLE_ENTRY as usize).enumerate() {
        let (lo, len) = (u64_at(entry, 0), u64_at(entry, 8));
        if lo < u64::from(end) || lo >= u64::from(info.next_index) {
            return Err(invalid(format!(
                "static tree {i} starts at index {lo}, outside {end}..{}",
                info.next_index
            )));
        }
        if len > tree_bytes.len() as u64 {
            return Err(invalid(format!(
                "static tree {i} takes {len} bytes but {} remain",
                tree_bytes.len()
            )));
        }
        let (bytes, rest) = tree_bytes.split_at(len as usize);
        tree_bytes = rest;
        let part = read_tree(info, kept, i, lo as u32, bytes)?;
        end = part.hi;
        parts.push(part);
    }
    if !tree_bytes.is_empty() {
        return Err(invalid(format!(
            "{} bytes follow the last static tree",
            tree_bytes.len()
        )));
    }
    Ok(parts)
}

/// The static tree `i` of a saved dynamic tree, first index `lo`, saved in `bytes`: checked to
/// be built with the dynamic tree's options, to cover indices given, to hold no index skipped
/// at insertion, the kept coordinates of its live points, and at least one live point.
fn read_tree<T: Scalar>(
    info: &SavedDynamicInfo,
    kept: &Kept<T>,
    i: usize,
    lo: u32,
    bytes: &[u8],
) -> Result<Part<T>> {
    let (d, next, base) = (info.dim, info.next_index, info.base);
    let tree = KdTree::<T>::from_bytes_with(bytes, &LoadOptions { dim: Some(d) })
        .map_err(|e| invalid(format!("static tree {i}: {e}")))?;
    let hi = u64::from(lo) + tree.source_len() as u64;
    if hi > u64::from(next) {
        return Err(invalid(format!(
            "static tree {i} covers indices {lo}..{hi}, past the {next} given"
        )));
    }
    let tree_options = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        ..info.options
    };
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
        if bit(&kept.skipped, g) {
            return Err(invalid(format!(
                "static tree {i} holds index {g}, skipped at insertion"
            )));
        }
        if bit(&kept.not_live, g) {
            continue;
        }
        live += 1;
        let at = (g - base) as usize * d;
        let same = tree
            .point_at(pos)
            .iter()
            .zip(&kept.store[at..at + d])
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
    Ok(Part::new(tree, lo, hi as u32, live))
}
