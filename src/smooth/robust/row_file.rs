//! A tile's rows kept in files between the tasks of a split run.
//!
//! A driver that holds no tile between rounds (`nbhd.dask`: one task per tile and round) makes
//! the tile anew at every round. Its rows are a function of the input points alone (the
//! `k_plane` or `WIDE`·`k_plane` nearest of the gathered input, `robust/rows.rs`), whatever the
//! round: so the first task that searches them writes them here, and every later task of the
//! same tile reads them back instead of searching again — a read of 4 bytes per candidate in
//! place of a k-d tree search. What is kept is exactly what the search gave (the candidates in
//! their searched order, each row's searched farthest distance, the tree's order, every
//! point's nearest distance, and the reach flags of `robust/reach.rs`, which depend on those
//! alone), so a tile that reads the file computes the same bits as one that searched.
//!
//! A step reads the rows and planes its generation's measure computed: a measure of a tile with
//! files also writes its rows as measured (sorted on the proxy and cut at ε) and its planes,
//! under a key of the row set, the generation, ε and a hash of the proxy; the step of the same
//! generation on the same proxy reads them instead of re-sorting the rows and fitting the
//! planes again — the same values, as the rows' order and the planes are functions of the
//! candidates and the proxy.
//!
//! A file names its tile by a fingerprint of everything the search depends on (the input's
//! coordinates, `k`, the region): a file of another tile or of a tile gathered with another
//! halo reads as absent, and so does a file that is short, fails its checksum or names a
//! candidate beyond the tile — the tile then searches and writes it anew. A file that cannot
//! be written costs only a later task's search.
//!
//! Layout (little-endian): the magic `NBHDROW2`, the fingerprint, the point count `n` and the
//! row width (u64 each), the flags (u8: 1 searched farthest distances, 2 reach flags, 4 a
//! measure, 8 nearest distances), with flag 4 the measure's key (set, `at`, generation, ε's
//! bits, proxy hash: u64 each); then `order`, the candidate counts and the counts within ε
//! (n u32 each), the candidates (n·width u32); with their flags the nearest squared
//! distances (n f64, NaN for none), the reach flags (2·n u8), the farthest (n f64) and the
//! planes (6·n f64: normal, barycentre); and a checksum of every value after the magic (u64).

use super::planes::Plane;
use super::reach::{Reach, Region};
use super::rows::Rows;
use super::run::RowSet;
use glam::DVec3;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::Path;

const MAGIC: &[u8; 8] = b"NBHDROW2";

const FARTHEST: u8 = 1;
const REACH: u8 = 2;
const MEASURED: u8 = 4;
const NEAREST: u8 = 8;

/// A tile's rows as kept: searched (with each point's nearest distance) or measured (with the
/// planes of that measure), in the k-d tree's order `order`.
pub(super) struct Kept {
    pub(super) rows: Rows,
    pub(super) order: Vec<u32>,
    /// Each point's squared distance to its nearest other, by local index (empty when not
    /// kept).
    pub(super) nearest: Vec<Option<f64>>,
    pub(super) reach: Option<Reach>,
    pub(super) measured: Option<(MeasuredKey, Vec<Plane>)>,
}

/// What rows and planes kept by a measure were measured on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct MeasuredKey {
    pub(super) set: RowSet,
    pub(super) generation: usize,
    /// ε's bits.
    pub(super) eps: u64,
    /// [`proxy_hash`] of the proxy.
    pub(super) proxy: u64,
}

impl MeasuredKey {
    fn words(&self) -> [u64; 5] {
        let (tag, at) = match self.set {
            RowSet::Plain => (0, 0),
            RowSet::Wide => (1, 0),
            RowSet::Shrunk { at } => (2, at as u64),
        };
        [tag, at, self.generation as u64, self.eps, self.proxy]
    }
}

/// The fingerprint of a search: a hash of `k`, the region's bounds and every input
/// coordinate's bits (a name, not a protection against a crafted file).
pub(super) fn fingerprint(input: &[DVec3], k: usize, region: Option<&Region>) -> u64 {
    let mut h = Hash::default();
    h.add(k as u64);
    h.add(input.len() as u64);
    if let Some(r) = region {
        for v in r.lo.to_array().into_iter().chain(r.hi.to_array()) {
            h.add(v.to_bits());
        }
    }
    for p in input {
        for v in p.to_array() {
            h.add(v.to_bits());
        }
    }
    h.0
}

/// A hash of a proxy that does not depend on the order the points are stored in: the sum of
/// each point's hash with its local index `local(s)`, so the stored and the local order give
/// the same value.
pub(super) fn proxy_hash(points: &[DVec3], local: impl Fn(usize) -> u32) -> u64 {
    points.iter().enumerate().fold(0u64, |sum, (s, p)| {
        let mut h = Hash::default();
        h.add(u64::from(local(s)));
        for v in p.to_array() {
            h.add(v.to_bits());
        }
        // an avalanche, so that sums of nearby hashes do not cancel
        let z = (h.0 ^ (h.0 >> 33)).wrapping_mul(0xff51_afd7_ed55_8ccd);
        sum.wrapping_add(z ^ (z >> 33))
    })
}

/// FNV-1a's step taken a word at a time (one multiply per word, not per byte): the
/// fingerprint, and the checksum that ends a file.
struct Hash(u64);

impl Default for Hash {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Hash {
    fn add(&mut self, word: u64) {
        self.0 = (self.0 ^ word).wrapping_mul(0x0100_0000_01b3);
    }
}

/// Writes `kept` to `path` (under a temporary name, then renamed: a reader never sees a
/// partial file). Failures are returned for the caller to ignore or report.
pub(super) fn write(path: &Path, print: u64, kept: &KeptRef<'_>) -> io::Result<()> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let written = write_to(&tmp, print, kept);
    match written {
        Ok(()) => std::fs::rename(&tmp, path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// [`Kept`] borrowed from a tile's state, for [`write`].
pub(super) struct KeptRef<'a> {
    pub(super) rows: &'a Rows,
    pub(super) order: &'a [u32],
    pub(super) nearest: &'a [Option<f64>],
    pub(super) reach: Option<&'a Reach>,
    pub(super) measured: Option<(MeasuredKey, &'a [Plane])>,
}

impl Kept {
    pub(super) fn borrowed(&self) -> KeptRef<'_> {
        KeptRef {
            rows: &self.rows,
            order: &self.order,
            nearest: &self.nearest,
            reach: self.reach.as_ref(),
            measured: self.measured.as_ref().map(|(k, p)| (*k, p.as_slice())),
        }
    }
}

/// A buffered file that adds every value written to its checksum.
struct Writer {
    w: BufWriter<File>,
    sum: Hash,
}

impl Writer {
    fn put<const N: usize>(&mut self, word: u64, bytes: [u8; N]) -> io::Result<()> {
        self.sum.add(word);
        self.w.write_all(&bytes)
    }

    fn u32s(&mut self, values: &[u32]) -> io::Result<()> {
        values
            .iter()
            .try_for_each(|&v| self.put(u64::from(v), v.to_le_bytes()))
    }

    fn f64s(&mut self, values: impl IntoIterator<Item = f64>) -> io::Result<()> {
        values
            .into_iter()
            .try_for_each(|v| self.put(v.to_bits(), v.to_le_bytes()))
    }

    fn flags(&mut self, values: &[bool]) -> io::Result<()> {
        values
            .iter()
            .try_for_each(|&v| self.put(u64::from(v), [u8::from(v)]))
    }
}

fn write_to(tmp: &Path, print: u64, kept: &KeptRef<'_>) -> io::Result<()> {
    if let Some(dir) = tmp.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let (width, index, candidates, len, farthest) = kept.rows.as_parts();
    let mut w = Writer {
        w: BufWriter::new(File::create(tmp)?),
        sum: Hash::default(),
    };
    w.w.write_all(MAGIC)?;
    for v in [print, kept.order.len() as u64, width as u64] {
        w.put(v, v.to_le_bytes())?;
    }
    let flag = |set: bool, bit: u8| if set { bit } else { 0 };
    let flags = flag(farthest.is_some(), FARTHEST)
        | flag(kept.reach.is_some(), REACH)
        | flag(kept.measured.is_some(), MEASURED)
        | flag(!kept.nearest.is_empty(), NEAREST);
    w.put(u64::from(flags), [flags])?;
    if let Some((key, _)) = &kept.measured {
        for v in key.words() {
            w.put(v, v.to_le_bytes())?;
        }
    }
    w.u32s(kept.order)?;
    w.u32s(candidates)?;
    w.u32s(len)?;
    w.u32s(index)?;
    w.f64s(kept.nearest.iter().map(|d| d.unwrap_or(f64::NAN)))?;
    if let Some(reach) = kept.reach {
        w.flags(reach.cert())?;
        w.flags(reach.step())?;
    }
    w.f64s(farthest.unwrap_or(&[]).iter().copied())?;
    if let Some((_, planes)) = &kept.measured {
        let words = planes.iter().flat_map(|p| {
            p.normal
                .to_array()
                .into_iter()
                .chain(p.barycentre.to_array())
        });
        w.f64s(words)?;
    }
    let sum = w.sum.0;
    w.w.write_all(&sum.to_le_bytes())?;
    // no fsync: a file torn by a crash fails the checksum of `read` and is searched anew
    w.w.flush()
}

/// The rows `path` holds for a search of fingerprint `print` over `n` points — searched rows
/// when `measured` is `None`, else rows measured under that key — or `None` when the file is
/// absent, of another search or measure, or not a whole and consistent file.
pub(super) fn read(
    path: &Path,
    print: u64,
    n: usize,
    measured: Option<MeasuredKey>,
) -> Option<Kept> {
    let mut r = Reader {
        r: BufReader::new(File::open(path).ok()?),
        sum: Hash::default(),
    };
    let mut magic = [0u8; 8];
    r.r.read_exact(&mut magic).ok()?;
    let head = r.words::<8, u64>(3, u64::from_le_bytes)?;
    if &magic != MAGIC || head[0] != print || head[1] != n as u64 {
        return None;
    }
    let width = usize::try_from(head[2]).ok()?;
    let flags = r.words::<1, u8>(1, |[b]| b)?[0];
    if flags >= 16 || (flags & MEASURED != 0) != measured.is_some() {
        return None;
    }
    if let Some(key) = measured {
        if r.words::<8, u64>(5, u64::from_le_bytes)? != key.words() {
            return None;
        }
    }
    let order = r.words(n, u32::from_le_bytes)?;
    let candidates = r.words(n, u32::from_le_bytes)?;
    let len = r.words(n, u32::from_le_bytes)?;
    let index = r.words(n.checked_mul(width)?, u32::from_le_bytes)?;
    let nearest = r.optional(flags & NEAREST, n, f64::from_le_bytes)?;
    let nearest = nearest.into_iter().flatten();
    let nearest = nearest.map(|d| Some(d).filter(|d| !d.is_nan())).collect();
    let reach = r.optional(flags & REACH, 2 * n, |[b]| b)?;
    let farthest = r.optional(flags & FARTHEST, n, f64::from_le_bytes)?;
    let planes = r.optional(flags & MEASURED, 6 * n, f64::from_le_bytes)?;
    let sum = r.sum.0;
    let mut end = [0u8; 9];
    let tail = r.r.read(&mut end).ok()? + r.r.read(&mut end[8..]).ok()?;
    if tail != 8 || u64::from_le_bytes(end[..8].try_into().ok()?) != sum {
        return None;
    }
    if !is_permutation(&order) {
        return None;
    }
    let reach = match reach {
        None => None,
        Some(flags) => Some(Reach::from_flags(&flags[..n], &flags[n..])?),
    };
    Some(Kept {
        rows: Rows::from_parts(width, index, candidates, len, farthest)?,
        order,
        nearest,
        reach,
        measured: measured.zip(planes.map(|words| planes_of(&words))),
    })
}

fn planes_of(words: &[f64]) -> Vec<Plane> {
    words
        .chunks_exact(6)
        .map(|w| Plane {
            normal: DVec3::new(w[0], w[1], w[2]),
            barycentre: DVec3::new(w[3], w[4], w[5]),
        })
        .collect()
}

fn is_permutation(order: &[u32]) -> bool {
    let mut seen = vec![false; order.len()];
    order.iter().all(|&o| {
        let fresh = seen.get(o as usize) == Some(&false);
        if fresh {
            seen[o as usize] = true;
        }
        fresh
    })
}

/// A file read a word at a time into its checksum.
struct Reader {
    r: BufReader<File>,
    sum: Hash,
}

/// Words of `N` bytes as the checksum takes them.
trait Word: Copy {
    fn word(self) -> u64;
}

impl Word for u8 {
    fn word(self) -> u64 {
        u64::from(self)
    }
}

impl Word for u32 {
    fn word(self) -> u64 {
        u64::from(self)
    }
}

impl Word for u64 {
    fn word(self) -> u64 {
        self
    }
}

impl Word for f64 {
    fn word(self) -> u64 {
        self.to_bits()
    }
}

impl Reader {
    /// `count` values of `N` bytes each, read a block at a time (no second copy of the
    /// array) and added to the checksum.
    fn words<const N: usize, T: Word>(
        &mut self,
        count: usize,
        of: impl Fn([u8; N]) -> T,
    ) -> Option<Vec<T>> {
        const BLOCK: usize = 1 << 16;
        let mut out = Vec::new();
        out.try_reserve_exact(count).ok()?;
        let mut buf = vec![0u8; BLOCK.min(count) * N];
        let mut left = count;
        while left > 0 {
            let take = left.min(BLOCK);
            let bytes = &mut buf[..take * N];
            self.r.read_exact(bytes).ok()?;
            for c in bytes.chunks_exact(N) {
                let v = of(c.try_into().expect("N bytes"));
                self.sum.add(v.word());
                out.push(v);
            }
            left -= take;
        }
        Some(out)
    }

    /// [`Reader::words`] when `flag` is set: `Some(None)` when it is not, `None` on a failed
    /// read.
    fn optional<const N: usize, T: Word>(
        &mut self,
        flag: u8,
        count: usize,
        of: impl Fn([u8; N]) -> T,
    ) -> Option<Option<Vec<T>>> {
        if flag == 0 {
            return Some(None);
        }
        self.words(count, of).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let t = i as f64 * 0.37;
                // duplicates: every seventh point repeats its predecessor
                let t = if i % 7 == 6 { t - 0.37 } else { t };
                DVec3::new(t.cos() * (1.0 + 0.01 * t), t.sin(), 0.02 * t)
            })
            .collect()
    }

    /// The searched rows of `input` with the reach of `region`, as a tile keeps them.
    fn searched(input: &[DVec3], k: usize, region: &Region) -> Kept {
        let (rows, order, nearest) = Rows::search(input, k).unwrap();
        let stored: Vec<DVec3> = order.iter().map(|&o| input[o as usize]).collect();
        let reach = Some(Reach::new(&stored, &rows, k, region));
        Kept {
            rows,
            order,
            nearest,
            reach,
            measured: None,
        }
    }

    fn same(a: &Kept, b: &Kept) -> bool {
        let reach = |k: &Kept| {
            k.reach
                .as_ref()
                .map(|r| (r.cert().to_vec(), r.step().to_vec()))
        };
        let planes = |k: &Kept| {
            k.measured.as_ref().map(|(key, p)| {
                let words: Vec<[f64; 6]> = p
                    .iter()
                    .map(|p| {
                        let (n, b) = (p.normal, p.barycentre);
                        [n.x, n.y, n.z, b.x, b.y, b.z]
                    })
                    .collect();
                (*key, words)
            })
        };
        a.rows.as_parts() == b.rows.as_parts()
            && a.order == b.order
            && a.nearest == b.nearest
            && reach(a) == reach(b)
            && planes(a) == planes(b)
    }

    fn scratch(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("nbhd-row-file-{name}-{}", std::process::id()))
    }

    /// The offset of the first candidate count in a searched file of `n` points.
    fn counts_at(n: usize) -> usize {
        8 + 8 * 3 + 1 + 4 * n
    }

    #[test]
    fn rows_read_back_are_the_rows_searched() {
        let dir = scratch("searched");
        let path = dir.join("rows.bin");
        let input = cloud(500);
        let region = Region {
            lo: DVec3::splat(-10.0),
            hi: DVec3::splat(f64::INFINITY),
        };
        let print = fingerprint(&input, 12, Some(&region));
        let kept = searched(&input, 12, &region);
        write(&path, print, &kept.borrowed()).unwrap();
        let back = read(&path, print, input.len(), None).expect("read back");
        assert!(same(&back, &kept));
        // another k, region or point: another fingerprint, so the file reads as absent
        let mut moved = input.clone();
        moved[3].x = f64::from_bits(moved[3].x.to_bits() + 1);
        for other in [
            fingerprint(&input, 13, Some(&region)),
            fingerprint(&input, 12, None),
            fingerprint(&moved, 12, Some(&region)),
        ] {
            assert_ne!(other, print);
            assert!(read(&path, other, input.len(), None).is_none());
        }
        assert!(read(&path, print, input.len() - 1, None).is_none());
        // truncated or extended: absent, never a panic
        let bytes = std::fs::read(&path).unwrap();
        for cut in [0, 7, 30, bytes.len() / 2, bytes.len() - 1] {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            assert!(
                read(&path, print, input.len(), None).is_none(),
                "cut at {cut}"
            );
        }
        let mut longer = bytes.clone();
        longer.push(0);
        std::fs::write(&path, &longer).unwrap();
        assert!(read(&path, print, input.len(), None).is_none());
        // one flipped bit anywhere after the magic: the checksum no longer matches
        for at in [9, 8 + 8 * 3, counts_at(input.len()) + 2, bytes.len() - 3] {
            let mut flipped = bytes.clone();
            flipped[at] ^= 4;
            std::fs::write(&path, &flipped).unwrap();
            assert!(
                read(&path, print, input.len(), None).is_none(),
                "bit flipped at {at}"
            );
        }
        // a whole file of inconsistent rows: an order that is no permutation
        let Kept {
            rows,
            mut order,
            nearest,
            reach,
            ..
        } = kept;
        order[0] = order[1];
        let bad = Kept {
            rows,
            order,
            nearest,
            reach,
            measured: None,
        };
        write(&path, print, &bad.borrowed()).unwrap();
        assert!(
            read(&path, print, input.len(), None).is_none(),
            "order not a permutation"
        );
        assert!(read(&dir.join("absent.bin"), print, input.len(), None).is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn measured_rows_are_read_only_under_their_key() {
        let dir = scratch("measured");
        let path = dir.join("measured.bin");
        let input = cloud(300);
        let region = Region {
            lo: DVec3::splat(f64::NEG_INFINITY),
            hi: DVec3::splat(f64::INFINITY),
        };
        let print = fingerprint(&input, 10, Some(&region));
        let mut kept = searched(&input, 10, &region);
        kept.rows.update(&input, &kept.order, 0.5);
        kept.nearest.clear();
        let stored: Vec<DVec3> = kept.order.iter().map(|&o| input[o as usize]).collect();
        let proxy = proxy_hash(&stored, |s| kept.order[s]);
        assert_eq!(
            proxy,
            proxy_hash(&input, |i| i as u32),
            "any order, one hash"
        );
        let key = MeasuredKey {
            set: RowSet::Shrunk { at: 2 },
            generation: 3,
            eps: 0.5f64.to_bits(),
            proxy,
        };
        let planes = (0..input.len())
            .map(|i| Plane {
                normal: DVec3::Z,
                barycentre: DVec3::splat(i as f64),
            })
            .collect();
        kept.measured = Some((key, planes));
        write(&path, print, &kept.borrowed()).unwrap();
        let back = read(&path, print, input.len(), Some(key)).expect("read back");
        assert!(same(&back, &kept));
        assert!(
            read(&path, print, input.len(), None).is_none(),
            "not searched rows"
        );
        for other in [
            MeasuredKey {
                set: RowSet::Shrunk { at: 1 },
                ..key
            },
            MeasuredKey {
                set: RowSet::Wide,
                ..key
            },
            MeasuredKey {
                generation: 2,
                ..key
            },
            MeasuredKey {
                eps: 0.25f64.to_bits(),
                ..key
            },
            MeasuredKey {
                proxy: proxy ^ 1,
                ..key
            },
        ] {
            assert!(
                read(&path, print, input.len(), Some(other)).is_none(),
                "{other:?}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn inconsistent_rows_and_flags_are_refused() {
        let ok = |width, index: Vec<u32>, cand: Vec<u32>, len: Vec<u32>| {
            Rows::from_parts(width, index, cand, len, None).is_some()
        };
        let index = || vec![1, 2, 0, 2, 0, 1];
        assert!(ok(2, index(), vec![2, 2, 1], vec![2, 1, 0]));
        assert!(
            !ok(2, vec![1, 3, 0, 2, 0, 1], vec![2, 2, 1], vec![2, 2, 1]),
            "beyond the tile"
        );
        assert!(
            !ok(2, index(), vec![2, 3, 1], vec![2, 2, 1]),
            "a count beyond the width"
        );
        assert!(
            !ok(2, index(), vec![2, 2, 1], vec![2, 2, 2]),
            "more within ε than candidates"
        );
        assert!(
            !ok(2, vec![1, 2, 0, 2, 0], vec![2, 2, 1], vec![2, 2, 1]),
            "a short table"
        );
        assert!(
            Rows::from_parts(2, index(), vec![2, 2, 1], vec![2, 2, 1], Some(vec![1.0])).is_none()
        );
        assert!(Reach::from_flags(&[1, 0], &[0, 0]).is_some());
        assert!(
            Reach::from_flags(&[1, 2], &[0, 0]).is_none(),
            "a flag that is not 0 or 1"
        );
        assert!(Reach::from_flags(&[1, 0], &[0]).is_none());
    }
}
