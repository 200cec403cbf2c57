//! Triangle meshes as ground truth for the denoising protocol of the point-cloud literature
//! (ScoreDenoise, Luo & Hu, ICCV 2021, and its successors): meshes normalised to the unit
//! sphere, Poisson-disk samples, and the exact metrics — the Chamfer distance between two point
//! sets and the point-to-mesh distance, each the mean *squared* distance taken both ways.
//!
//! Sampling: [`TriangleMesh::sample_poisson_disk`] draws five times the wanted count uniformly
//! by area and thins them by *sample elimination* (Yuksel, "Sample Elimination for Generating
//! Poisson Disk Sample Sets", Eurographics 2015): every sample is weighted by how closely its
//! neighbours crowd it, and the most crowded is removed until the count is reached. Seeded, so a
//! (mesh, count, seed) triple gives the same points on every platform and thread count.
//!
//! Distances are exact: point-to-triangle by the closest-point regions of the triangle (Ericson,
//! "Real-Time Collision Detection", §5.1.5), searched through a bounding-volume hierarchy; the
//! distance from a triangle to the nearest point of a set through a k-d tree of the set.

use super::Rng;
use crate::error::{NbhdError, Result};
use crate::index::NeighborIndex;
use crate::points::PointsView;
use crate::query::{Neighbor, Neighborhood, Query};
use crate::table::TableOptions;
use crate::tree::{BuildOptions, KdTree};
use glam::DVec3;
use rayon::prelude::*;
use std::collections::BinaryHeap;

/// A triangle mesh: vertices and triangles as vertex indices.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Triangles, three vertex indices each.
    pub triangles: Vec<[u32; 3]>,
}

fn bad(reason: String) -> NbhdError {
    NbhdError::InvalidOption {
        name: "mesh",
        reason,
    }
}

impl TriangleMesh {
    /// A mesh from vertices and triangles; every index must name a vertex and every vertex be
    /// finite.
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        if vertices.iter().any(|v| !v.is_finite()) {
            return Err(bad("a vertex is not finite".into()));
        }
        if triangles
            .iter()
            .flatten()
            .any(|&i| i as usize >= vertices.len())
        {
            return Err(bad("a triangle names a vertex that does not exist".into()));
        }
        if triangles.is_empty() {
            return Err(bad("no triangle".into()));
        }
        Ok(Self {
            vertices,
            triangles,
        })
    }

    /// Parses an OFF file (`OFF`, counts, vertices, faces; `#` comments); polygons are split
    /// into triangle fans.
    pub fn from_off(text: &str) -> Result<Self> {
        let mut tokens = text
            .lines()
            .map(|l| l.split('#').next().unwrap_or(""))
            .flat_map(str::split_whitespace);
        let mut next = |what: &str| tokens.next().ok_or_else(|| bad(format!("OFF: no {what}")));
        let head = next("header")?;
        if !head.ends_with("OFF") {
            return Err(bad(format!("OFF: header '{head}'")));
        }
        let mut count = |what: &str| -> Result<usize> {
            let t = next(what)?;
            t.parse().map_err(|_| bad(format!("OFF: {what} '{t}'")))
        };
        let (nv, nf, _) = (
            count("vertex count")?,
            count("face count")?,
            count("edges")?,
        );
        let mut next = |what: &str| tokens.next().ok_or_else(|| bad(format!("OFF: no {what}")));
        let mut vertices = Vec::with_capacity(nv.min(1 << 24));
        for _ in 0..nv {
            let mut c = [0.0; 3];
            for x in &mut c {
                let t = next("coordinate")?;
                *x = t
                    .parse()
                    .map_err(|_| bad(format!("OFF: coordinate '{t}'")))?;
            }
            vertices.push(DVec3::from_array(c));
        }
        let mut triangles = Vec::with_capacity(nf.min(1 << 24));
        for _ in 0..nf {
            let t = next("face size")?;
            let size: usize = t
                .parse()
                .map_err(|_| bad(format!("OFF: face size '{t}'")))?;
            let mut face = Vec::with_capacity(size.min(64));
            for _ in 0..size {
                let t = next("face index")?;
                face.push(t.parse().map_err(|_| bad(format!("OFF: index '{t}'")))?);
            }
            for i in 2..face.len() {
                triangles.push([face[0], face[i - 1], face[i]]);
            }
        }
        Self::new(vertices, triangles)
    }

    /// The cube [−1, 1]³ in twelve triangles (its analytic surface exactly).
    pub fn cube() -> Self {
        let vertices = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64) * 2.0 - 1.0)
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Self {
            vertices,
            triangles,
        }
    }

    /// The torus of major radius `big` and tube radius `small` around the z axis, `around` ×
    /// `across` quadrilaterals split in two (its surface to within the chord error
    /// `(big + small)(1 − cos(π/around))`).
    pub fn torus(big: f64, small: f64, around: u32, across: u32) -> Self {
        let tau = std::f64::consts::TAU;
        let vertices = (0..around * across)
            .map(|i| {
                let (u, v) = (
                    tau * (i / across) as f64 / around as f64,
                    tau * (i % across) as f64 / across as f64,
                );
                let r = big + small * v.cos();
                DVec3::new(r * u.cos(), r * u.sin(), small * v.sin())
            })
            .collect();
        let at = |a: u32, b: u32| (a % around) * across + b % across;
        let triangles = (0..around)
            .flat_map(|a| (0..across).map(move |b| (a, b)))
            .flat_map(|(a, b)| {
                let q = [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)];
                [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
            })
            .collect();
        Self {
            vertices,
            triangles,
        }
    }

    /// The mesh moved and scaled into the unit sphere as the protocol does: the centre of the
    /// bounding box to the origin, the farthest vertex at distance 1.
    pub fn normalized(&self) -> Self {
        let (lo, hi) = self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let c = (lo + hi) / 2.0;
        let r = self
            .vertices
            .iter()
            .map(|&v| v.distance(c))
            .fold(0.0, f64::max);
        let s = if r > 0.0 { 1.0 / r } else { 1.0 };
        Self {
            vertices: self.vertices.iter().map(|&v| (v - c) * s).collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// The corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| tri_area(self.corners(t)))
            .sum()
    }

    /// `n` points drawn uniformly by area (triangle by its area, then a uniform point in it).
    pub fn sample_uniform(&self, n: usize, rng: &mut Rng) -> Vec<DVec3> {
        let mut cumulative = Vec::with_capacity(self.triangles.len());
        let mut total = 0.0;
        for t in 0..self.triangles.len() {
            total += tri_area(self.corners(t));
            cumulative.push(total);
        }
        (0..n)
            .map(|_| {
                let u = rng.unit() * total;
                let t = cumulative
                    .partition_point(|&c| c <= u)
                    .min(cumulative.len() - 1);
                let [a, b, c] = self.corners(t);
                let (mut r1, mut r2) = (rng.unit(), rng.unit());
                if r1 + r2 > 1.0 {
                    (r1, r2) = (1.0 - r1, 1.0 - r2);
                }
                a + (b - a) * r1 + (c - a) * r2
            })
            .collect()
    }

    /// `n` points with Poisson-disk spacing by sample elimination from `5n` uniform ones (see
    /// the module documentation), seeded by `seed`.
    pub fn sample_poisson_disk(&self, n: usize, seed: u64) -> Result<Vec<DVec3>> {
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut rng = Rng::new(seed);
        let candidates = self.sample_uniform(5 * n, &mut rng);
        // Yuksel's r_max for a surface: the radius of n disks packing the area hexagonally
        let r_max = (self.area() / (2.0 * 3f64.sqrt() * n as f64)).sqrt();
        let keep = eliminate(&candidates, n, 2.0 * r_max)?;
        Ok(keep.into_iter().map(|i| candidates[i]).collect())
    }
}

fn tri_area([a, b, c]: [DVec3; 3]) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}

/// A heap entry of the sample elimination: a sample's weight (as ordered bits: weights are
/// non-negative), then the larger index first so that ties break the same way everywhere.
#[derive(PartialEq, Eq, PartialOrd, Ord)]
struct Crowding(u64, u32);

/// The indices of the `n` samples sample elimination keeps (in index order), with the weight
/// `(1 − d/(2 r_max))⁸` of every pair closer than `2 r_max` (Yuksel's α = 8).
fn eliminate(points: &[DVec3], n: usize, radius: f64) -> Result<Vec<usize>> {
    let table = points_tree(points)?.neighborhoods(
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
        &TableOptions {
            exclude_self: true,
            threads: 0,
            ..Default::default()
        },
    )?;
    let weight_of = |d2: f64| (1.0 - d2.sqrt() / radius).max(0.0).powi(8);
    let mut weight: Vec<f64> = (0..points.len())
        .map(|i| table.sq_dists_of(i).iter().map(|&d| weight_of(d)).sum())
        .collect();
    let mut heap: BinaryHeap<Crowding> = (0..points.len())
        .map(|i| Crowding(weight[i].to_bits(), i as u32))
        .collect();
    let mut removed = vec![false; points.len()];
    let mut left = points.len();
    while left > n {
        let Some(Crowding(bits, i)) = heap.pop() else {
            break;
        };
        let i = i as usize;
        if removed[i] || bits != weight[i].to_bits() {
            continue; // stale entry
        }
        removed[i] = true;
        left -= 1;
        for (&j, &d) in table.indices_of(i).iter().zip(table.sq_dists_of(i)) {
            let j = j as usize;
            if !removed[j] {
                weight[j] = (weight[j] - weight_of(d)).max(0.0);
                heap.push(Crowding(weight[j].to_bits(), j as u32));
            }
        }
    }
    Ok((0..points.len()).filter(|&i| !removed[i]).collect())
}

fn points_tree(points: &[DVec3]) -> Result<KdTree<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    KdTree::build(&PointsView::from_flat(&flat, 3)?, &BuildOptions::default())
}

/// Squared distance from `p` to the triangle `[a, b, c]` (closest-point regions; Ericson
/// §5.1.5).
pub fn point_triangle_sq_dist(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length_squared();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (ap - ab * v).length_squared();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (ap - ac * w).length_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (bp - (c - b) * w).length_squared();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (ap - ab * v - ac * w).length_squared()
}

/// A node of [`MeshDistance`]'s hierarchy: a box and either two children or a range of
/// triangles.
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// The children's nodes if `count == 0`.
    children: [u32; 2],
    /// The first of `count` triangles of `order` (a leaf), or 0.
    first: u32,
    count: u32,
}

/// Exact distances to a mesh's surface through a bounding-volume hierarchy (boxes split at the
/// median of the longest axis, leaves of at most four triangles).
pub struct MeshDistance<'a> {
    mesh: &'a TriangleMesh,
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl<'a> MeshDistance<'a> {
    /// The hierarchy of `mesh`.
    pub fn new(mesh: &'a TriangleMesh) -> Self {
        let centre: Vec<DVec3> = (0..mesh.triangles.len())
            .map(|t| mesh.corners(t).iter().sum::<DVec3>() / 3.0)
            .collect();
        let mut order: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
        let mut nodes = Vec::new();
        build(mesh, &mut order, 0, &centre, &mut nodes);
        Self { mesh, order, nodes }
    }

    /// Squared distance from `p` to the nearest triangle.
    pub fn sq_dist(&self, p: DVec3) -> f64 {
        let box_d2 = |n: &Node| {
            let d = (n.lo - p).max(DVec3::ZERO).max(p - n.hi);
            d.length_squared()
        };
        let mut best = f64::INFINITY;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i];
            if box_d2(n) >= best {
                continue;
            }
            if n.count > 0 {
                let range = n.first as usize..(n.first + n.count) as usize;
                for &t in &self.order[range] {
                    best = best.min(point_triangle_sq_dist(p, self.mesh.corners(t as usize)));
                }
                continue;
            }
            let [a, b] = n.children.map(|c| c as usize);
            let (da, db) = (box_d2(&self.nodes[a]), box_d2(&self.nodes[b]));
            // the nearer child last, so that it is searched first
            if da < db {
                stack.extend([b, a]);
            } else {
                stack.extend([a, b]);
            }
        }
        best
    }
}

/// Builds the subtree over `order` (the triangles from `first` of the whole order) into
/// `nodes`; returns its root.
fn build(
    mesh: &TriangleMesh,
    order: &mut [u32],
    first: usize,
    centre: &[DVec3],
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &t in order.iter() {
        for v in mesh.corners(t as usize) {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
    }
    let me = nodes.len();
    nodes.push(Node {
        lo,
        hi,
        children: [0; 2],
        first: first as u32,
        count: order.len() as u32,
    });
    if order.len() > 4 {
        let e = hi - lo;
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |&a, &b| {
            centre[a as usize][axis]
                .total_cmp(&centre[b as usize][axis])
                .then(a.cmp(&b))
        });
        let (a, b) = order.split_at_mut(mid);
        let left = build(mesh, a, first, centre, nodes);
        let right = build(mesh, b, first + mid, centre, nodes);
        nodes[me].children = [left, right];
        nodes[me].count = 0;
    }
    me as u32
}

/// Mean squared distance from each point of `a` to the nearest point of `b`.
fn mean_nearest_sq(a: &[DVec3], b_tree: &KdTree<f64>) -> Result<f64> {
    let d: Vec<f64> = a
        .par_iter()
        .map_init(Vec::new, |out: &mut Vec<Neighbor<f64>>, p| {
            b_tree
                .knn(Query::point(&p.to_array()), 1, out)
                .map(|_| out[0].sq_dist)
        })
        .collect::<Result<_>>()?;
    Ok(d.iter().sum::<f64>() / d.len() as f64)
}

/// The Chamfer distance of the protocol: the mean squared distance from each point of `a` to
/// the nearest of `b` plus the same from `b` to `a`.
pub fn chamfer(a: &[DVec3], b: &[DVec3]) -> Result<f64> {
    if a.is_empty() || b.is_empty() {
        return Err(NbhdError::EmptyInput);
    }
    Ok(mean_nearest_sq(a, &points_tree(b)?)? + mean_nearest_sq(b, &points_tree(a)?)?)
}

/// The point-to-mesh distance of the protocol: the mean squared distance from each point to
/// the nearest triangle plus the mean over triangles of the squared distance from the triangle
/// to the nearest point.
pub fn point_to_mesh(points: &[DVec3], mesh: &TriangleMesh) -> Result<f64> {
    if points.is_empty() {
        return Err(NbhdError::EmptyInput);
    }
    let bvh = MeshDistance::new(mesh);
    let to_mesh: f64 = points.par_iter().map(|&p| bvh.sq_dist(p)).sum::<f64>();
    let tree = points_tree(points)?;
    let from_mesh: Vec<f64> = (0..mesh.triangles.len())
        .into_par_iter()
        .map_init(Vec::new, |out, t| {
            triangle_to_points(mesh.corners(t), &tree, out)
        })
        .collect::<Result<_>>()?;
    Ok(to_mesh / points.len() as f64 + from_mesh.iter().sum::<f64>() / from_mesh.len() as f64)
}

/// Squared distance from a triangle to the nearest point of the tree: the nearest point to its
/// centroid bounds it, and every point nearer the triangle lies within that bound plus the
/// triangle's radius about the centroid.
fn triangle_to_points(
    tri: [DVec3; 3],
    tree: &KdTree<f64>,
    out: &mut Vec<Neighbor<f64>>,
) -> Result<f64> {
    let c = tri.iter().sum::<DVec3>() / 3.0;
    let radius = tri.iter().map(|v| v.distance(c)).fold(0.0, f64::max);
    tree.knn(Query::point(&c.to_array()), 1, out)?;
    let first = out[0].index;
    let at = |i: u32| DVec3::from_slice(tree.point(i).expect("an index of the tree"));
    let mut best = point_triangle_sq_dist(at(first), tri);
    tree.radius(Query::point(&c.to_array()), best.sqrt() + radius, out)?;
    for n in out.iter() {
        best = best.min(point_triangle_sq_dist(at(n.index), tri));
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> TriangleMesh {
        TriangleMesh::cube()
    }

    #[test]
    fn analytic_meshes_lie_on_their_surfaces() {
        let t = TriangleMesh::torus(1.0, 0.4, 64, 32);
        let area = 4.0 * std::f64::consts::PI.powi(2) * 0.4;
        assert!((t.area() / area - 1.0).abs() < 0.01);
        assert!((TriangleMesh::cube().area() - 24.0).abs() < 1e-12);
    }

    #[test]
    fn off_parse_normalise_and_distances() {
        let off = "OFF\n# a square\n4 1 0\n0 0 0\n2 0 0\n2 2 0\n0 2 0\n4 0 1 2 3\n";
        let m = TriangleMesh::from_off(off).unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert!((m.area() - 4.0).abs() < 1e-12);
        let n = m.normalized();
        let far = n.vertices.iter().map(|v| v.length()).fold(0.0, f64::max);
        assert!((far - 1.0).abs() < 1e-12);
        assert!(TriangleMesh::from_off("OFF\n1 1 0\n0 0 0\n3 0 1 2\n").is_err());
        let c = cube();
        let d = MeshDistance::new(&c);
        for (p, want) in [
            (DVec3::new(0.0, 0.0, 3.0), 4.0),
            (DVec3::new(2.0, 2.0, 0.0), 2.0),
            (DVec3::new(0.5, 0.0, 0.0), 0.25),
            (DVec3::new(2.0, 2.0, 2.0), 3.0),
        ] {
            assert!((d.sq_dist(p) - want).abs() < 1e-12, "{p}");
            let brute = (0..12)
                .map(|t| point_triangle_sq_dist(p, c.corners(t)))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d.sq_dist(p), brute);
        }
    }

    #[test]
    fn poisson_disk_samples_are_spread_and_on_the_surface() {
        let c = cube();
        let s = c.sample_poisson_disk(2000, 3).unwrap();
        assert_eq!(s.len(), 2000);
        assert_eq!(s, c.sample_poisson_disk(2000, 3).unwrap());
        assert!(point_to_mesh(&s, &c).unwrap() < 0.01);
        let d = MeshDistance::new(&c);
        assert!(s.iter().all(|&p| d.sq_dist(p) < 1e-24));
        // closer to a lattice than uniform draws: the smallest spacing is far from zero
        let mut rng = Rng::new(3);
        let u = c.sample_uniform(2000, &mut rng);
        let min_spacing = |p: &[DVec3]| {
            let t = crate::geometry::neighbors::neighbor_table(p, Neighborhood::Knn { k: 1 }, true)
                .unwrap();
            (0..p.len())
                .map(|i| t.sq_dists_of(i)[0])
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        };
        assert!(min_spacing(&s) > 5.0 * min_spacing(&u));
        assert!(chamfer(&s, &s).unwrap() == 0.0);
        assert!(chamfer(&s, &u).unwrap() > 0.0);
    }
}
