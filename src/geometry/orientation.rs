//! Orientation of the sign-free covariance normals (thesis eq. 2.10 gives a normal only up to
//! its sign): toward a viewpoint, away from a centre, or propagated consistently over the
//! neighbour graph (Hoppe et al. 1992).

use super::normals::{check_table, LocalFrame};
use crate::error::{NbhdError, Result};
use crate::named_option;
use crate::names::OptionName;
use crate::table::NeighborTable;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

/// How to orient the (sign-free) covariance normals.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Orientation {
    /// Keep the eigen-solver's sign (arbitrary but deterministic).
    #[default]
    Unoriented,
    /// Every normal points toward this viewpoint (`⟨n, v − p⟩ ≥ 0`).
    TowardViewpoint(DVec3),
    /// Every normal points away from this point (outward for star-shaped closed surfaces).
    AwayFrom(DVec3),
    /// Consistent orientation propagated over the neighbour graph (symmetrised) along a
    /// maximum spanning tree of `|⟨n_i, n_j⟩|` (Hoppe et al. 1992), so that the sign travels
    /// along smooth paths rather than across creases. In each connected component the point with
    /// the largest z gets a normal with `n_z ≥ 0` (outward for closed surfaces).
    Propagate,
}

/// The kinds of [`Orientation`], by name (`unoriented`, `toward-point`, `away-from-point`,
/// `propagate`): what the command line and Python pass, the point given beside it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum OrientationKind {
    /// [`Orientation::Unoriented`].
    #[default]
    Unoriented,
    /// [`Orientation::TowardViewpoint`].
    TowardPoint,
    /// [`Orientation::AwayFrom`].
    AwayFromPoint,
    /// [`Orientation::Propagate`].
    Propagate,
}

impl OptionName for OrientationKind {
    const OPTION: &'static str = "orientation";
    const WHAT: &'static str = "orientation";
    const NAMES: &'static [(Self, &'static str)] = &[
        (OrientationKind::Unoriented, "unoriented"),
        (OrientationKind::TowardPoint, "toward-point"),
        (OrientationKind::AwayFromPoint, "away-from-point"),
        (OrientationKind::Propagate, "propagate"),
    ];
    const ALIASES: &'static [(&'static str, Self)] = &[
        ("none", OrientationKind::Unoriented),
        ("toward-viewpoint", OrientationKind::TowardPoint),
    ];
}
named_option!(OrientationKind);

impl Orientation {
    /// The orientation of kind `kind`, with `point` for the kinds that have one.
    pub fn of_kind(kind: OrientationKind, point: DVec3) -> Self {
        match kind {
            OrientationKind::Unoriented => Orientation::Unoriented,
            OrientationKind::TowardPoint => Orientation::TowardViewpoint(point),
            OrientationKind::AwayFromPoint => Orientation::AwayFrom(point),
            OrientationKind::Propagate => Orientation::Propagate,
        }
    }

    /// The orientation's kind.
    pub fn kind(&self) -> OrientationKind {
        match self {
            Orientation::Unoriented => OrientationKind::Unoriented,
            Orientation::TowardViewpoint(_) => OrientationKind::TowardPoint,
            Orientation::AwayFrom(_) => OrientationKind::AwayFromPoint,
            Orientation::Propagate => OrientationKind::Propagate,
        }
    }
}

/// Flips normals in place as `orientation` asks. Only the sign of `frame.normal` changes (the
/// tangent frame keeps `major × minor` parallel to the normal after the call).
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::{local_frames, neighbors::neighbor_table, orient, Orientation};
/// use nbhd::Neighborhood;
///
/// let points: Vec<DVec3> = (0..100).map(|i| DVec3::new((i % 10) as f64, (i / 10) as f64, 0.0)).collect();
/// let table = neighbor_table(&points, Neighborhood::Knn { k: 8 }, true)?;
/// let mut frames = local_frames(&points, &table)?;
/// orient(&points, &table, &mut frames, Orientation::TowardViewpoint(DVec3::new(0.0, 0.0, 10.0)))?;
/// assert!(frames.iter().all(|f| f.normal.z > 0.0));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn orient(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    frames: &mut [LocalFrame],
    orientation: Orientation,
) -> Result<()> {
    orient_with_progress(points, table, frames, orientation, &mut |_| true)
}

/// [`orient`] with a progress callback, called on the calling thread with the fraction of the
/// orientation done (0 to 1); returning `false` stops with [`NbhdError::Cancelled`] (the
/// frames are then left as they were). Only [`Orientation::Propagate`] takes long enough to
/// report in between.
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::neighbors::neighbor_table;
/// use nbhd::geometry::{local_frames, orient_with_progress, Orientation};
/// use nbhd::{NbhdError, Neighborhood};
///
/// let points: Vec<DVec3> = (0..100).map(|i| DVec3::new((i % 10) as f64, (i / 10) as f64, 0.0)).collect();
/// let table = neighbor_table(&points, Neighborhood::Knn { k: 8 }, true)?;
/// let mut frames = local_frames(&points, &table)?;
/// let up = Orientation::TowardViewpoint(DVec3::new(0.0, 0.0, 10.0));
/// // the first report is 0 and the last is 1
/// let mut seen = Vec::new();
/// orient_with_progress(&points, &table, &mut frames, up, &mut |f| { seen.push(f); true })?;
/// assert_eq!((seen[0], *seen.last().unwrap()), (0.0, 1.0));
/// assert!(frames.iter().all(|f| f.normal.z > 0.0));
/// // a callback that says stop cancels the call and leaves the frames as they were
/// let down = Orientation::TowardViewpoint(DVec3::new(0.0, 0.0, -10.0));
/// let r = orient_with_progress(&points, &table, &mut frames, down, &mut |_| false);
/// assert!(matches!(r, Err(NbhdError::Cancelled)));
/// assert!(frames.iter().all(|f| f.normal.z > 0.0));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn orient_with_progress(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    frames: &mut [LocalFrame],
    orientation: Orientation,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<()> {
    if frames.len() != points.len() {
        return Err(NbhdError::InvalidOption {
            name: "frames",
            reason: "one frame per point is needed".into(),
        });
    }
    let mut normals: Vec<DVec3> = frames.par_iter().map(|f| f.normal).collect();
    orient_normals_with_progress(points, table, &mut normals, orientation, progress)?;
    frames.par_iter_mut().zip(&normals).for_each(|(f, &n)| {
        f.normal = n;
        f.minor = f.normal.cross(f.major);
    });
    Ok(())
}

/// [`orient_with_progress`] of bare unit normals (what normal estimation computes, see
/// `src/geometry/estimate.rs`): only their signs change, exactly as the frames' normals would.
/// Crate-internal: users orient frames ([`orient_with_progress`]) or estimate oriented normals.
pub(crate) fn orient_normals_with_progress(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    normals: &mut [DVec3],
    orientation: Orientation,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<()> {
    check_table(points, table)?;
    if normals.len() != points.len() {
        return Err(NbhdError::InvalidOption {
            name: "normals",
            reason: "one normal per point is needed".into(),
        });
    }
    let mut report = |f: f64| {
        if progress(f) {
            Ok(())
        } else {
            Err(NbhdError::Cancelled)
        }
    };
    report(0.0)?;
    match orientation {
        Orientation::Unoriented => {}
        Orientation::TowardViewpoint(v) => {
            normals.par_iter_mut().zip(points).for_each(|(n, &p)| {
                flip(n, n.dot(v - p) >= 0.0);
            });
        }
        Orientation::AwayFrom(c) => {
            normals.par_iter_mut().zip(points).for_each(|(n, &p)| {
                flip(n, n.dot(p - c) >= 0.0);
            });
        }
        Orientation::Propagate => {
            let keep = propagate(points, table, normals, &mut report)?;
            normals
                .par_iter_mut()
                .zip(&keep)
                .for_each(|(n, &k)| flip(n, k));
        }
    }
    report(1.0)
}

/// Keeps the normal's sign if `want_positive`, flips it otherwise.
#[inline]
fn flip(n: &mut DVec3, want_positive: bool) {
    if !want_positive {
        *n = -*n;
    }
}

/// Bits of an edge's place in the neighbour table inside a [`propagate`] key.
const PLACE_BITS: u32 = 40;
/// Mask of the place bits.
const PLACE_MASK: u64 = (1 << PLACE_BITS) - 1;

/// The key of the table entry at `place` with weight `w` in `[0, 1]`: larger weights first
/// (quantised to 24 bits), ties by the earlier place; the largest key is the preferred edge.
/// Keys are distinct, so the maximum spanning forest is unique and does not depend on the
/// threads nor on the order the edges are visited in.
#[inline]
fn edge_key(w: f32, place: usize) -> u64 {
    // in [0, 2^24) or NaN (then 0): `as i32` gives what `as u64` would, with fewer steps
    let q = (w.clamp(0.0, 1.0) * ((1 << 24) - 1) as f32) as i32 as u64;
    (q << PLACE_BITS) | (PLACE_MASK - place as u64)
}

/// The table place an [`edge_key`] was made from.
#[inline]
fn place_of(key: u64) -> usize {
    (PLACE_MASK - (key & PLACE_MASK)) as usize
}

/// Union-find root of `i`, halving paths on the way.
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let g = parent[parent[i as usize] as usize];
        parent[i as usize] = g;
        i = g;
    }
    i
}

/// Bits per axis of the Morton code of [`locality_order`].
const MORTON_BITS: u32 = 21;

/// `x`'s low [`MORTON_BITS`] bits spread to every third bit.
#[inline]
fn spread3(x: u32) -> u64 {
    let mut x = u64::from(x) & 0x1f_ffff;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    (x | x << 2) & 0x1249_2492_4924_9249
}

/// A numbering of the points in which neighbours mostly lie close: by the Morton code of each
/// point's cell in a grid of 2^21 cells a side over the finite points' bounding cube
/// (non-finite points first), ties by index. Only the speed of [`propagate`] depends on it —
/// its keys and its result are those of the caller's numbering — since the random reads of
/// the forest's rounds then fall on nearby memory. Returns `(order, rank)`: `order[r]` is the
/// caller's index of the point numbered `r`, `rank` the inverse.
fn locality_order(points: &[DVec3]) -> (Vec<u32>, Vec<u32>) {
    let (lo, hi) = points
        .par_iter()
        .filter(|p| p.is_finite())
        .fold(
            || (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
        .reduce(
            || (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    // halves, so that no difference overflows
    let (lo, extent) = (lo * 0.5, (hi * 0.5 - lo * 0.5).max_element());
    let cells = ((1u32 << MORTON_BITS) - 1) as f64;
    let scale = if extent > 0.0 && (cells / extent).is_finite() {
        cells / extent
    } else {
        0.0
    };
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let code = if p.is_finite() {
                let c = ((p * 0.5 - lo) * scale).clamp(DVec3::ZERO, DVec3::splat(cells));
                spread3(c.x as u32) | spread3(c.y as u32) << 1 | spread3(c.z as u32) << 2
            } else {
                0
            };
            (code, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    let order: Vec<u32> = keyed.into_par_iter().map(|(_, i)| i).collect();
    let mut rank = vec![0u32; order.len()];
    for (r, &i) in order.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    (order, rank)
}

/// Rows per parallel task of the Borůvka sweeps.
const BLOCK_ROWS: usize = 2048;

/// The neighbour graph in the locality order as compressed rows: row `u` (the point
/// `order[u]`) is `to[off[u]..off[u] + live[u]]` with its keys; the sweeps drop an edge by
/// moving the row's last live edge into its place.
struct EdgeRows {
    /// Row starts, one more than there are rows.
    off: Vec<usize>,
    /// Live edges of each row.
    live: Vec<u32>,
    /// Other end of each edge, in the locality order.
    to: Vec<u32>,
    /// [`edge_key`] of each edge.
    key: Vec<u64>,
}

/// The table's entries `i → j` as edges from `rank[i]` to `rank[j]` keyed by [`edge_key`] of
/// `|⟨n_i, n_j⟩|` (the normals rounded to f32) and the entry's place in the table. Each entry
/// is one edge; an entry and its reverse are two parallel edges of the same weight; an entry
/// `i → i` is a loop (key 0) that the first sweep drops. The table is read in its own order
/// and each row written to its place in the locality order, so the random reads (one per
/// entry, of the other end's normal and rank) do not wait for one another.
fn edge_rows(
    table: &NeighborTable<f64>,
    order: &[u32],
    rank: &[u32],
    normals: &[DVec3],
) -> EdgeRows {
    let n = order.len();
    let lens: Vec<u32> = order
        .par_iter()
        .map(|&i| table.indices_of(i as usize).len() as u32)
        .collect();
    let mut off = Vec::with_capacity(n + 1);
    off.push(0usize);
    for &l in &lens {
        off.push(off.last().copied().unwrap_or(0) + l as usize);
    }
    // each point's normal and rank side by side: one read per entry
    let ends: Vec<(glam::Vec3, u32)> = normals
        .par_iter()
        .zip(rank)
        .map(|(n, &r)| (n.as_vec3(), r))
        .collect();
    let m = off[n];
    let to: Vec<AtomicU32> = (0..m).into_par_iter().map(|_| AtomicU32::new(0)).collect();
    let key: Vec<AtomicU64> = (0..m).into_par_iter().map(|_| AtomicU64::new(0)).collect();
    (0..n).into_par_iter().with_min_len(256).for_each(|i| {
        let (ni, ri) = ends[i];
        let (at, base) = (table.offsets()[i], off[ri as usize]);
        for (t, &j) in table.indices_of(i).iter().enumerate() {
            let (nj, rj) = ends[j as usize];
            // distinct places: every slot is written once (a plain store)
            if j as usize == i {
                to[base + t].store(ri, Relaxed);
            } else {
                to[base + t].store(rj, Relaxed);
                key[base + t].store(edge_key(ni.dot(nj).abs(), at + t), Relaxed);
            }
        }
    });
    EdgeRows {
        off,
        live: lens,
        to: to.into_iter().map(AtomicU32::into_inner).collect(),
        key: key.into_iter().map(AtomicU64::into_inner).collect(),
    }
}

/// Raises `best` to `key` if it is lower: read first — once a component's best is high most
/// of its edges lose, and a read does not contend as a write does.
#[inline]
fn offer(best: &AtomicU64, key: u64) {
    if best.load(Relaxed) < key {
        best.fetch_max(key, Relaxed);
    }
}

/// One Borůvka sweep over the rows `start..` whose edges are `to`/`key` (from `off[start]`
/// on): drops the edges inside a component (in place) and offers every other edge to the best
/// of both its components. Returns the edges kept.
fn sweep(
    start: usize,
    off: &[usize],
    live: &mut [u32],
    to: &mut [u32],
    key: &mut [u64],
    comp: &[u32],
    best: &[AtomicU64],
) -> usize {
    let base = off[start];
    let mut kept = 0;
    for (r, live) in live.iter_mut().enumerate() {
        let a = off[start + r] - base;
        let (to, key) = (
            &mut to[a..a + *live as usize],
            &mut key[a..a + *live as usize],
        );
        let cu = comp[start + r];
        let (mut len, mut e, mut top) = (to.len(), 0, 0);
        while e < len {
            let cv = comp[to[e] as usize];
            if cv == cu {
                len -= 1;
                to[e] = to[len];
                key[e] = key[len];
            } else {
                top = top.max(key[e]);
                offer(&best[cv as usize], key[e]);
                e += 1;
            }
        }
        if top != 0 {
            offer(&best[cu as usize], top);
        }
        *live = len as u32;
        kept += len;
    }
    kept
}

/// Hoppe et al.'s propagation: a maximum spanning forest of the neighbour graph (both
/// directions of every table entry) weighted by `|⟨n_i, n_j⟩|`, then every normal made to
/// agree with its parent's, from the point of largest z (ties by the smaller index) of each
/// tree, whose normal gets `n_z ≥ 0`.
///
/// The forest comes from Borůvka's algorithm: in every round each component picks its best
/// edge to another component (an atomic maximum of the edge keys, in parallel over the edges),
/// the picks are joined, and edges inside a component are dropped; every round at least
/// halves the number of components, and the edge list shrinks with them. The edge order of
/// [`edge_key`] is strict, so the forest is unique — the one Prim's algorithm grows from any
/// seed — and the result does not depend on the number of threads. The rounds run over the
/// points in a [`locality_order`], where the edge list is kept as compressed rows
/// ([`edge_rows`]) and a component's best edge and the points' components are read from
/// nearby memory; the keys, and so the forest, are those of the caller's numbering.
fn propagate(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    normals: &[DVec3],
    report: &mut dyn FnMut(f64) -> Result<()>,
) -> Result<Vec<bool>> {
    let n = points.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    if table.total() as u64 > PLACE_MASK {
        return Err(NbhdError::InvalidOption {
            name: "orientation",
            reason: format!("{} edges are too many to propagate over", table.total()),
        });
    }
    let (order, rank) = locality_order(points);
    report(0.05)?;
    let rows = edge_rows(table, &order, &rank, normals);
    report(0.1)?;
    let Forest { edges, comp } = spanning_forest(table, &rank, rows, report)?;
    let (tdeg, tadj) = adjacency(n, &edges);
    drop(edges);
    // the top point of each tree (largest z, then smallest index), in the caller's numbering
    let mut top: Vec<u32> = vec![u32::MAX; n];
    for (i, p) in points.iter().enumerate() {
        let c = comp[rank[i] as usize] as usize;
        let t = top[c];
        if t == u32::MAX || p.z > points[t as usize].z {
            top[c] = i as u32;
        }
    }
    let normal: Vec<DVec3> = order.par_iter().map(|&i| normals[i as usize]).collect();
    let seeds = top
        .into_iter()
        .filter(|&t| t != u32::MAX)
        .map(|t| rank[t as usize]);
    let keep = agree_from(seeds, &normal, &tdeg, &tadj);
    Ok(rank.par_iter().map(|&r| keep[r as usize]).collect())
}

/// A spanning forest of points in the locality order.
struct Forest {
    /// Its edges, as pairs of points.
    edges: Vec<(u32, u32)>,
    /// The component of each point, named by its smallest point.
    comp: Vec<u32>,
}

/// Borůvka's rounds over `rows` (see [`propagate`]): the edges of the maximum spanning forest
/// as pairs of points in the locality order `rank` gives, and each point's component, named by
/// its smallest point. Reports progress from 0.1 to 0.9.
fn spanning_forest(
    table: &NeighborTable<f64>,
    rank: &[u32],
    mut rows: EdgeRows,
    report: &mut dyn FnMut(f64) -> Result<()>,
) -> Result<Forest> {
    let n = rank.len();
    // the ends of the edge a key names, in the locality order: the row of a place is its
    // quotient by k when every row has k entries
    let offsets = table.offsets();
    let k = offsets.get(1).copied().unwrap_or(0);
    let uniform = k > 0 && offsets.par_iter().enumerate().all(|(i, &o)| o == i * k);
    let ends = |key: u64| {
        let place = place_of(key);
        let row = if uniform {
            place / k
        } else {
            offsets.partition_point(|&o| o <= place) - 1
        };
        (rank[row], rank[table.indices()[place] as usize])
    };
    let mut comp: Vec<u32> = (0..n as u32).collect();
    let mut parent = comp.clone();
    let mut roots = comp.clone();
    let best: Vec<AtomicU64> = (0..n).map(|_| AtomicU64::new(0)).collect();
    let mut forest: Vec<(u32, u32)> = Vec::with_capacity(n);
    while sweep_all(&mut rows, &comp, &best) > 0 {
        let picks: Vec<(u32, u32)> = roots
            .par_iter()
            .filter_map(|&c| {
                let key = best[c as usize].swap(0, Relaxed);
                (key != 0).then(|| ends(key))
            })
            .collect();
        for (a, b) in picks {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
                forest.push((a, b));
            }
        }
        // every old root straight to its new root, then the points' components in one step
        for &r in &roots {
            let f = find(&mut parent, r);
            parent[r as usize] = f;
        }
        comp.par_iter_mut().for_each(|c| *c = parent[*c as usize]);
        roots.retain(|&r| parent[r as usize] == r);
        report(0.1 + 0.8 * (1.0 - roots.len() as f64 / n as f64))?;
    }
    Ok(Forest {
        edges: forest,
        comp,
    })
}

/// One Borůvka round's [`sweep`] of every row, in parallel over blocks of rows, each with its
/// own edges; returns the edges still live (between components).
fn sweep_all(rows: &mut EdgeRows, comp: &[u32], best: &[AtomicU64]) -> usize {
    let n = comp.len();
    let EdgeRows { off, live, to, key } = rows;
    let (mut live, mut to, mut key) = (&mut live[..], &mut to[..], &mut key[..]);
    let mut blocks = Vec::with_capacity(n.div_ceil(BLOCK_ROWS));
    for start in (0..n).step_by(BLOCK_ROWS) {
        let end = (start + BLOCK_ROWS).min(n);
        let len = off[end] - off[start];
        let (l, l_rest) = std::mem::take(&mut live).split_at_mut(end - start);
        let (t, t_rest) = std::mem::take(&mut to).split_at_mut(len);
        let (k, k_rest) = std::mem::take(&mut key).split_at_mut(len);
        blocks.push((start, l, t, k));
        (live, to, key) = (l_rest, t_rest, k_rest);
    }
    let off = &off[..];
    blocks
        .into_par_iter()
        .map(|(start, l, t, k)| sweep(start, off, l, t, k, comp, best))
        .sum()
}

/// The forest of `n` points as adjacency lists: the neighbours of point `u` are
/// `tadj[tdeg[u]..tdeg[u + 1]]`.
fn adjacency(n: usize, forest: &[(u32, u32)]) -> (Vec<usize>, Vec<u32>) {
    let mut tdeg = vec![0usize; n + 1];
    for &(a, b) in forest {
        tdeg[a as usize + 1] += 1;
        tdeg[b as usize + 1] += 1;
    }
    for i in 0..n {
        tdeg[i + 1] += tdeg[i];
    }
    let mut tadj = vec![0u32; tdeg[n]];
    let mut at = tdeg.clone();
    for &(a, b) in forest {
        tadj[at[a as usize]] = b;
        at[a as usize] += 1;
        tadj[at[b as usize]] = a;
        at[b as usize] += 1;
    }
    (tdeg, tadj)
}

/// A breadth-first walk of the forest from each seed decides which normals keep their sign:
/// the seed's if `n_z ≥ 0`, then each normal agrees with its parent's, `⟨±n_parent, n⟩ ≥ 0`
/// (the sign only negates the dot product, exactly).
fn agree_from(
    seeds: impl Iterator<Item = u32>,
    normal: &[DVec3],
    tdeg: &[usize],
    tadj: &[u32],
) -> Vec<bool> {
    let n = normal.len();
    let mut keep = vec![false; n];
    let mut done = vec![false; n];
    let mut queue: Vec<u32> = Vec::with_capacity(n);
    for seed in seeds {
        let seed = seed as usize;
        keep[seed] = normal[seed].z >= 0.0;
        done[seed] = true;
        let mut head = queue.len();
        queue.push(seed as u32);
        while head < queue.len() {
            let u = queue[head] as usize;
            head += 1;
            for &v in &tadj[tdeg[u]..tdeg[u + 1]] {
                let v = v as usize;
                if !done[v] {
                    let d = normal[u].dot(normal[v]);
                    keep[v] = if keep[u] { d >= 0.0 } else { d <= 0.0 };
                    done[v] = true;
                    queue.push(v as u32);
                }
            }
        }
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::neighbors::neighbor_table;
    use crate::geometry::normals::local_frames;
    use crate::query::Neighborhood;
    use crate::shapes::{sample, Shape, Sphere, Torus};

    #[test]
    fn torus_propagation_is_consistent() {
        let torus = Torus::new(1.0, 0.35);
        let s = sample(&torus, 4000, 8);
        let table = neighbor_table(&s.points, Neighborhood::Knn { k: 10 }, true).unwrap();
        let mut frames = local_frames(&s.points, &table).unwrap();
        orient(&s.points, &table, &mut frames, Orientation::Propagate).unwrap();
        let outward = frames
            .iter()
            .zip(&s.points)
            .filter(|(f, &p)| f.normal.dot(torus.closest(p).normal) > 0.0)
            .count();
        assert_eq!(outward, 4000);
    }

    #[test]
    fn propagation_reports_progress_and_can_be_cancelled() {
        let torus = Torus::new(1.0, 0.35);
        let s = sample(&torus, 6000, 3);
        let table = neighbor_table(&s.points, Neighborhood::Knn { k: 10 }, true).unwrap();
        let frames = local_frames(&s.points, &table).unwrap();
        let mut seen = Vec::new();
        let mut f = frames.clone();
        orient_with_progress(
            &s.points,
            &table,
            &mut f,
            Orientation::Propagate,
            &mut |x| {
                seen.push(x);
                true
            },
        )
        .unwrap();
        assert!(seen.len() >= 4, "{seen:?}");
        assert!(seen.windows(2).all(|w| w[0] <= w[1]) && seen.last() == Some(&1.0));
        assert!(seen.iter().any(|&x| x > 0.1 && x < 1.0));
        // the same orientation as without a callback, for any number of threads
        let mut g = frames.clone();
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| orient(&s.points, &table, &mut g, Orientation::Propagate))
            .unwrap();
        assert_eq!(f, g);
        let mut calls = 0;
        let mut h = frames.clone();
        let r = orient_with_progress(
            &s.points,
            &table,
            &mut h,
            Orientation::Propagate,
            &mut |_| {
                calls += 1;
                calls < 3
            },
        );
        assert_eq!(r, Err(NbhdError::Cancelled));
    }

    #[test]
    fn viewpoint_orientation_is_pcls_flip_toward_the_viewpoint() {
        let s = sample(&Sphere::new(1.0), 2000, 6);
        let table = neighbor_table(&s.points, Neighborhood::Knn { k: 10 }, true).unwrap();
        let mut f = local_frames(&s.points, &table).unwrap();
        let v = DVec3::new(0.3, -4.0, 2.0);
        orient(&s.points, &table, &mut f, Orientation::TowardViewpoint(v)).unwrap();
        for (fr, &p) in f.iter().zip(&s.points) {
            assert!(fr.normal.dot(v - p) >= 0.0);
            assert!(fr.major.cross(fr.minor).dot(fr.normal) > 0.999);
        }
    }

    /// What orienting does to a frame: the normal's sign, then the right-handed tangent frame.
    fn flip_frame(f: &mut LocalFrame, want_positive: bool) {
        flip(&mut f.normal, want_positive);
        f.minor = f.normal.cross(f.major);
    }

    /// The forest of a plain Kruskal over every table entry sorted by key (the definition the
    /// Borůvka rounds must meet), then the same walk from each tree's top point.
    fn kruskal_orientation(
        points: &[DVec3],
        table: &NeighborTable<f64>,
        frames: &mut [LocalFrame],
    ) {
        let n = points.len();
        let mut edges = Vec::new();
        for i in 0..n {
            for (t, &j) in table.indices_of(i).iter().enumerate() {
                let w = frames[i]
                    .normal
                    .as_vec3()
                    .dot(frames[j as usize].normal.as_vec3());
                edges.push((edge_key(w.abs(), table.offsets()[i] + t), i as u32, j));
            }
        }
        edges.sort_unstable_by_key(|e| std::cmp::Reverse(e.0));
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut adj = vec![Vec::new(); n];
        for (_, i, j) in edges {
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            if a != b {
                parent[a as usize] = b;
                adj[i as usize].push(j as usize);
                adj[j as usize].push(i as usize);
            }
        }
        let mut top: Vec<Option<usize>> = vec![None; n];
        for i in 0..n {
            let r = find(&mut parent, i as u32) as usize;
            if top[r].is_none_or(|t| points[i].z > points[t].z) {
                top[r] = Some(i);
            }
        }
        let mut done = vec![false; n];
        for seed in top.into_iter().flatten() {
            let up = frames[seed].normal.z >= 0.0;
            flip_frame(&mut frames[seed], up);
            done[seed] = true;
            let mut stack = vec![seed];
            while let Some(i) = stack.pop() {
                for &j in &adj[i] {
                    if !done[j] {
                        let agree = frames[i].normal.dot(frames[j].normal) >= 0.0;
                        flip_frame(&mut frames[j], agree);
                        done[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
    }

    #[test]
    fn propagation_is_kruskals_forest_on_knn_and_radius_tables() {
        // two spheres far apart (two trees), a noisy plane with ties of weight 1, one lone point
        let mut points = sample(&Sphere::new(1.0), 1500, 11).points;
        points.extend(
            sample(&Sphere::new(0.5), 700, 12)
                .points
                .iter()
                .map(|p| *p + DVec3::X * 5.0),
        );
        points.extend(
            (0..400).map(|i| DVec3::new((i % 20) as f64 * 0.1, (i / 20) as f64 * 0.1, -4.0)),
        );
        points.push(DVec3::splat(40.0));
        for nbhd in [
            Neighborhood::Knn { k: 9 },
            Neighborhood::Radius {
                radius: 0.2,
                sorted: true,
            },
        ] {
            let table = neighbor_table(&points, nbhd, true).unwrap();
            let frames = local_frames(&points, &table).unwrap();
            let mut want = frames.clone();
            kruskal_orientation(&points, &table, &mut want);
            for threads in [1, 2, 3] {
                let mut got = frames.clone();
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| orient(&points, &table, &mut got, Orientation::Propagate))
                    .unwrap();
                assert_eq!(got, want, "{nbhd:?}, {threads} threads");
            }
        }
    }
}
