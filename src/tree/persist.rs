//! The saved format of a static tree (the envelope and the save and load family are
//! `envelope.rs`'s, [`Persist`](super::Persist)), and [`SavedTreeInfo`] to read a saved tree's
//! header without loading it. The layout, what is checked and the compatibility promise are in
//! docs/tree-file-format.md.
//!
//! A saved tree is a 128-byte header followed by a payload: the coordinates and caller indices
//! in tree order, the node array and a bitmap of the caller indices the tree holds. The tree is
//! stored as built, so a loaded tree answers every query exactly as the saved one did, bit for
//! bit. Loading trusts nothing: the header and the payload carry CRC-32 checksums (accidental
//! damage), and every field and the node structure are checked (anything else, a crafted file
//! included) before a tree is handed out, so that no query on a loaded tree can panic, loop or
//! read out of bounds, and every answer is exact. No length read from the input is allocated
//! before the input is known to hold that many bytes.

use std::io::Write;
use std::sync::OnceLock;

use super::envelope::saved_header;
use super::envelope::{
    check_start, header, invalid, pad8, period_section_len, periodic_flag, read_codes, read_period,
    scalar_bytes, scalar_name, size, u32_at, u64_at, write_period, written_by, Kind, SavedFormat,
    FORMAT_VERSION, HEADER_LEN, MAGIC,
};
use super::envelope::{DYNAMIC_KIND, FOREST_MAGIC, STATIC_KIND};
use super::node::{Node, LEAF};
use super::{BuildOptions, KdTree};
use crate::error::Result;
use crate::parallel::MAX_THREADS;
use crate::points::MAX_POINTS;
use crate::scalar::{Scalar, ScalarType};

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
    /// Whether the tree is periodic (a torus; its box ends the payload).
    pub periodic: bool,
    /// Bytes of the saved tree: header and payload.
    pub total_len: u64,
    /// The payload's CRC-32.
    payload_crc: u32,
}

/// Bytes of one node record: split, dimension, `a`, `b` (and 4 zero bytes for f64).
fn node_record(scalar: ScalarType) -> usize {
    match scalar {
        ScalarType::F32 => 16,
        ScalarType::F64 => 24,
    }
}

/// The byte sizes of the payload's sections (the period's 0 unless the tree is periodic), or
/// `None` if they overflow 64 bits.
#[derive(Clone, Copy, Debug)]
struct Sections {
    coords: u64,
    ids: u64,
    nodes: u64,
    bitmap: u64,
    period: u64,
}

impl Sections {
    fn new(
        scalar: ScalarType,
        dim: u64,
        points: u64,
        nodes: u64,
        source_len: u64,
        periodic: bool,
    ) -> Option<Self> {
        Some(Self {
            coords: pad8(points.checked_mul(dim)?.checked_mul(scalar.size() as u64)?)?,
            ids: pad8(points.checked_mul(4)?)?,
            nodes: nodes.checked_mul(node_record(scalar) as u64)?,
            bitmap: source_len.div_ceil(64).checked_mul(8)?,
            period: period_section_len(periodic, dim, scalar)?,
        })
    }

    fn total(&self) -> Option<u64> {
        self.coords
            .checked_add(self.ids)?
            .checked_add(self.nodes)?
            .checked_add(self.bitmap)?
            .checked_add(self.period)
    }
}

/// A saved static tree.
pub(crate) const STATIC: Kind = Kind {
    magic: MAGIC,
    name: STATIC_KIND,
    version: FORMAT_VERSION,
    other_magic: FOREST_MAGIC,
    other_name: DYNAMIC_KIND,
};

impl SavedTreeInfo {
    /// Reads and checks the header at the start of `bytes` (the payload need not follow):
    /// magic, byte order, format version, header checksum and every field's range.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let h = check_start(bytes, &STATIC)?;
        let version = u32_at(h, 12);
        let written_by = written_by(h);
        let periodic = periodic_flag(h)?;
        if u32_at(h, 100) != 0 || u32_at(h, 124) != 0 {
            return Err(invalid("a reserved header field is not zero"));
        }
        if h[104..120].iter().any(|&b| b != 0) {
            return Err(invalid("a reserved header field is not zero"));
        }
        let (scalar, codes) = read_codes(h)?;
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
        let sections = Sections::new(scalar, dim, points, nodes, source_len, periodic)
            .and_then(|s| s.total())
            .ok_or_else(|| invalid(format!("dimension {dim} overflows the payload's size")))?;
        if payload_len != sections {
            return Err(invalid(format!(
                "payload length {payload_len}, but {dim}-dimensional {} points, {nodes} nodes \
                 and {source_len} indices{} take {sections} bytes",
                scalar_name(scalar),
                if periodic {
                    " and the periodic box (a periodic tree saved before nbhd kept its box \
                     lacks it: build it again)"
                } else {
                    ""
                }
            )));
        }
        let total_len = payload_len
            .checked_add(HEADER_LEN as u64)
            .ok_or_else(|| invalid("payload length overflows"))?;
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
                leaf_size: size(leaf_size)?,
                threads: size(threads)?,
                ..codes
            },
            periodic,
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
            self.periodic,
        )
        .expect("sizes checked with the header")
    }
}

saved_header!(SavedTreeInfo);

/// Bytes handed to the writer at a time when a tree is written.
const CHUNK: usize = 1 << 16;

impl<T: Scalar> SavedFormat for KdTree<T> {
    const WHAT: &'static str = "tree";
    const SCALAR: ScalarType = T::TYPE;
    type Info = SavedTreeInfo;

    fn read_header(bytes: &[u8]) -> Result<SavedTreeInfo> {
        SavedTreeInfo::from_bytes(bytes)
    }

    fn payload_len(&self) -> u64 {
        Sections::new(
            T::TYPE,
            self.dim as u64,
            self.len() as u64,
            self.nodes.len() as u64,
            self.source_len as u64,
            self.periodic.is_some(),
        )
        .and_then(|s| s.total())
        .expect("a tree in memory has a payload that fits in memory")
    }

    fn header(&self, payload_len: u64, payload_crc: u32) -> [u8; HEADER_LEN] {
        let o = &self.options;
        let fields = [
            self.dim,
            self.len(),
            self.source_len,
            self.nodes.len(),
            self.depth,
            o.leaf_size,
            o.threads,
        ]
        .map(|v| v as u64);
        let mut all = [0u64; 8];
        all[..7].copy_from_slice(&fields);
        all[7] = payload_len;
        header(
            &STATIC,
            T::TYPE,
            o,
            self.periodic.is_some(),
            &all,
            96,
            payload_crc,
        )
    }

    /// The coordinates and caller indices in tree order, the nodes and the bitmap of the caller
    /// indices held, handed to `w` in chunks of about [`CHUNK`] bytes.
    fn payload(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let mut buf = Vec::with_capacity(CHUNK + 64);
        let mut flush = |buf: &mut Vec<u8>, force: bool| -> std::io::Result<()> {
            if force || buf.len() >= CHUNK {
                w.write_all(buf)?;
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
        for word in words {
            buf.extend_from_slice(&word.to_ne_bytes());
            flush(&mut buf, false)?;
        }
        write_period(self.period(), &mut buf);
        flush(&mut buf, true)
    }

    /// The tree from a payload of exactly the length `info` declares: parse, check.
    fn from_payload(info: &SavedTreeInfo, payload: &[u8]) -> Result<Self> {
        let s = info.sections();
        let (coords_bytes, rest) = payload.split_at(s.coords as usize);
        let (ids_bytes, rest) = rest.split_at(s.ids as usize);
        let (node_bytes, rest) = rest.split_at(s.nodes as usize);
        let (bitmap_bytes, period_bytes) = rest.split_at(s.bitmap as usize);
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
            periodic: None,
        };
        tree.check_points(bitmap_bytes)?;
        tree.check_nodes()?;
        // Derived, not saved: made once the nodes are known to be well formed.
        tree.derive(1)?;
        if !info.periodic {
            return Ok(tree);
        }
        // Its points checked to lie in the box, as a periodic build checks them.
        let period = read_period(period_bytes, info.dim)?;
        tree.with_period(period).map_err(|e| invalid(e.to_string()))
    }
}

impl<T: Scalar> KdTree<T> {
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
        self.check_node_shape()?;
        if self.is_empty() {
            return Ok(()); // one empty leaf, checked by the shape: no split
        }
        self.check_node_splits()
    }

    /// Pass 1 of [`Self::check_nodes`], the shape: a preorder walk in which the nodes must come
    /// in index order, each leaf holding the points due to it and each split well-formed, to
    /// the depth stated.
    fn check_node_shape(&self) -> Result<()> {
        let (nodes, n, d) = (&self.nodes, self.len(), self.dim);
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
        Ok(())
    }

    /// Pass 2 of [`Self::check_nodes`], the splits of a non-empty tree of a valid shape: every
    /// point of a left subtree ≤ its split ≤ every point of the right one. Tight boxes are built
    /// bottom-up: in reverse preorder a subtree leaves exactly its box on the stack, so at an
    /// internal node the top box is its left child's and the one below its right child's.
    fn check_node_splits(&self) -> Result<()> {
        let (nodes, d) = (&self.nodes, self.dim);
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
