//! Orientation of the sign-free covariance normals (thesis eq. 2.10 gives a normal only up to
//! its sign): toward a viewpoint, away from a centre, or propagated consistently over the
//! neighbour graph (Hoppe et al. 1992).

use super::normals::{check_table, LocalFrame};
use crate::error::{NbhdError, Result};
use crate::table::NeighborTable;
use glam::DVec3;
use rayon::prelude::*;

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

/// Flips normals in place as `orientation` asks. Only the sign of `frame.normal` changes (the
/// tangent frame keeps `major × minor` parallel to the normal after the call).
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
/// frames are then partly flipped). Only [`Orientation::Propagate`] takes long enough to
/// report in between.
pub fn orient_with_progress(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    frames: &mut [LocalFrame],
    orientation: Orientation,
    progress: &mut dyn FnMut(f64) -> bool,
) -> Result<()> {
    check_table(points, table)?;
    if frames.len() != points.len() {
        return Err(NbhdError::InvalidOption {
            name: "frames",
            reason: "one frame per point is needed".into(),
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
            frames.par_iter_mut().zip(points).for_each(|(f, &p)| {
                flip(f, f.normal.dot(v - p) >= 0.0);
            });
        }
        Orientation::AwayFrom(c) => {
            frames.par_iter_mut().zip(points).for_each(|(f, &p)| {
                flip(f, f.normal.dot(p - c) >= 0.0);
            });
        }
        Orientation::Propagate => propagate(points, table, frames, &mut report)?,
    }
    report(1.0)
}

/// Keeps the normal's sign if `want_positive`, flips it otherwise, and keeps the tangent frame
/// right-handed.
#[inline]
fn flip(f: &mut LocalFrame, want_positive: bool) {
    if !want_positive {
        f.normal = -f.normal;
    }
    f.minor = f.normal.cross(f.major);
}

/// Bits of an edge's place in the live edge list inside a [`propagate`] key.
const PLACE_BITS: u32 = 40;
/// Mask of the place bits.
const PLACE_MASK: u64 = (1 << PLACE_BITS) - 1;

/// The key of the edge at `place` with weight `w` in `[0, 1]`: larger weights first (quantised
/// to 24 bits), ties by the earlier place; the largest key is the preferred edge. Keys are
/// distinct, so the maximum spanning forest is unique and does not depend on the threads.
#[inline]
fn edge_key(w: f32, place: usize) -> u64 {
    let q = (w.clamp(0.0, 1.0) * ((1 << 24) - 1) as f32) as u64;
    (q << PLACE_BITS) | (PLACE_MASK - place as u64)
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
/// seed — and the result does not depend on the number of threads.
fn propagate(
    points: &[DVec3],
    table: &NeighborTable<f64>,
    frames: &mut [LocalFrame],
    report: &mut dyn FnMut(f64) -> Result<()>,
) -> Result<()> {
    use std::sync::atomic::{AtomicU64, Ordering as AtomicOrdering};
    let n = points.len();
    if n == 0 {
        return Ok(());
    }
    if table.total() as u64 > PLACE_MASK {
        return Err(NbhdError::InvalidOption {
            name: "orientation",
            reason: format!("{} edges are too many to propagate over", table.total()),
        });
    }
    // blocks of rows for the passes over the table
    const BLOCK: usize = 4096;
    let blocks: Vec<std::ops::Range<usize>> = (0..n)
        .step_by(BLOCK)
        .map(|a| a..(a + BLOCK).min(n))
        .collect();
    // the normals alone, compact: the weights read them at random
    let unit: Vec<glam::Vec3> = frames.par_iter().map(|f| f.normal.as_vec3()).collect();
    let weight = |i: usize, j: u32| unit[i].dot(unit[j as usize]).abs();
    let mut comp: Vec<u32> = (0..n as u32).collect();
    let mut parent: Vec<u32> = comp.clone();
    let best: Vec<AtomicU64> = (0..n).map(|_| AtomicU64::new(0)).collect();
    let mut tree: Vec<(u32, u32)> = Vec::with_capacity(n);
    let mut components = n;
    report(0.1)?;
    // Offers an edge to the best of both its components: read first — once a component's
    // best is high most of its edges lose, and a read does not contend as a write does.
    let offer = |best: &[AtomicU64], ci: u32, cj: u32, key: u64| {
        for c in [ci, cj] {
            let b = &best[c as usize];
            if b.load(AtomicOrdering::Relaxed) < key {
                b.fetch_max(key, AtomicOrdering::Relaxed);
            }
        }
    };
    // The first round reads the table itself (every point is its own component); an edge's
    // place is its position in the table.
    blocks.par_iter().for_each(|r| {
        for i in r.clone() {
            let at = table.offsets()[i];
            for (t, &j) in table.indices_of(i).iter().enumerate() {
                if j as usize != i {
                    offer(&best, i as u32, j, edge_key(weight(i, j), at + t));
                }
            }
        }
    });
    let join = |best: &[AtomicU64],
                parent: &mut [u32],
                tree: &mut Vec<(u32, u32)>,
                edge: &dyn Fn(usize) -> (u32, u32)| {
        let mut added = 0;
        for b in best {
            let key = b.swap(0, AtomicOrdering::Relaxed);
            if key == 0 {
                continue;
            }
            let (i, j) = edge((PLACE_MASK - (key & PLACE_MASK)) as usize);
            let (a, c) = (find(parent, i), find(parent, j));
            if a != c {
                parent[a.max(c) as usize] = a.min(c);
                tree.push((i, j));
                added += 1;
            }
        }
        added
    };
    let row_of_place = |p: usize| -> (u32, u32) {
        let i = table.offsets().partition_point(|&o| o <= p) - 1;
        (i as u32, table.indices()[p])
    };
    components -= join(&best, &mut parent, &mut tree, &row_of_place);
    for c in comp.iter_mut() {
        *c = find(&mut parent, *c);
    }
    // the edges between components, in table order, with their weights
    let mut live: Vec<(u32, u32, f32)> = {
        let comp = &comp;
        let parts: Vec<Vec<(u32, u32, f32)>> = blocks
            .par_iter()
            .map(|r| {
                let mut v = Vec::new();
                for i in r.clone() {
                    for &j in table.indices_of(i) {
                        if comp[i] != comp[j as usize] {
                            v.push((i as u32, j, weight(i, j)));
                        }
                    }
                }
                v
            })
            .collect();
        parts.concat()
    };
    report(0.1 + 0.8 * (1.0 - components as f64 / n as f64))?;
    while !live.is_empty() {
        {
            let comp = &comp;
            let best = &best;
            live.par_iter().enumerate().for_each(|(place, &(i, j, w))| {
                let (ci, cj) = (comp[i as usize], comp[j as usize]);
                if ci != cj {
                    offer(best, ci, cj, edge_key(w, place));
                }
            });
        }
        let edge = |p: usize| (live[p].0, live[p].1);
        let added = join(&best, &mut parent, &mut tree, &edge);
        if added == 0 {
            break;
        }
        for c in comp.iter_mut() {
            *c = find(&mut parent, *c);
        }
        components -= added;
        let comp = &comp;
        live = live
            .par_iter()
            .copied()
            .filter(|&(i, j, _)| comp[i as usize] != comp[j as usize])
            .collect();
        report(0.1 + 0.8 * (1.0 - components as f64 / n as f64))?;
    }
    drop(live);
    drop(best);
    // the forest as adjacency lists
    let mut tdeg = vec![0usize; n + 1];
    for &(a, b) in &tree {
        tdeg[a as usize + 1] += 1;
        tdeg[b as usize + 1] += 1;
    }
    for i in 0..n {
        tdeg[i + 1] += tdeg[i];
    }
    let mut tadj = vec![0u32; tdeg[n]];
    let mut at = tdeg.clone();
    for &(a, b) in &tree {
        tadj[at[a as usize]] = b;
        at[a as usize] += 1;
        tadj[at[b as usize]] = a;
        at[b as usize] += 1;
    }
    drop(at);
    // the top point of each tree (largest z, then smallest index), then a breadth-first walk
    let mut top: Vec<u32> = vec![u32::MAX; n];
    for i in 0..n {
        let c = comp[i] as usize;
        let t = top[c];
        if t == u32::MAX || points[i].z > points[t as usize].z {
            top[c] = i as u32;
        }
    }
    let mut done = vec![false; n];
    let mut queue = std::collections::VecDeque::new();
    for seed in top.into_iter().filter(|&t| t != u32::MAX) {
        let seed = seed as usize;
        let up = frames[seed].normal.z >= 0.0;
        flip(&mut frames[seed], up);
        done[seed] = true;
        queue.push_back(seed);
        while let Some(i) = queue.pop_front() {
            for &j in &tadj[tdeg[i]..tdeg[i + 1]] {
                let j = j as usize;
                if !done[j] {
                    let agree = frames[i].normal.dot(frames[j].normal) >= 0.0;
                    flip(&mut frames[j], agree);
                    done[j] = true;
                    queue.push_back(j);
                }
            }
        }
    }
    Ok(())
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
}
