//! Normals from the covariance of each neighbourhood (thesis eq. 2.8–2.10): the covariance
//! matrix of `N_i ∪ {p_i}` about its barycentre; the normal is the unit eigenvector of its
//! smallest eigenvalue, the two other eigenvectors span the tangent plane.

use super::covariance::OuterSum;
use crate::error::{NbhdError, Result};
use crate::table::NeighborTable;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// The orientation of these normals lives in [`super::orientation`]; re-exported here so the
/// paths `geometry::normals::{orient, orient_with_progress, Orientation}` stay valid.
pub use super::orientation::{orient, orient_with_progress, Orientation};

/// Flag: fewer than 3 points in `N_i ∪ {p_i}`; the plane is not determined.
pub const FLAG_TOO_FEW: u8 = 1;
/// Flag: the points are collinear or coincident (middle eigenvalue ≈ 0); any direction
/// perpendicular to the line fits.
pub const FLAG_COLLINEAR: u8 = 2;
/// Flag: the two smallest eigenvalues coincide (relative to the largest), so the normal is not
/// unique (e.g. an isotropic blob).
pub const FLAG_AMBIGUOUS: u8 = 4;
/// Flag: the point was skipped for a NaN or infinite coordinate (non-finite policy skip); its
/// normal and geometry are NaN.
pub const FLAG_SKIPPED: u8 = 8;

/// Relative tolerance below which an eigenvalue (or eigenvalue gap) counts as zero.
const DEGENERATE_TOL: f64 = 1e-10;

/// The principal frame of one neighbourhood.
///
/// For degenerate neighbourhoods (see the `FLAG_*` constants) the frame is still an
/// orthonormal, finite eigen-frame of the covariance matrix — for coincident points the
/// coordinate axes — and `flags` says why it should not be trusted. Never NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFrame {
    /// Unit normal: eigenvector of the smallest eigenvalue (eq. 2.10).
    pub normal: DVec3,
    /// Unit eigenvector of the largest eigenvalue (`v1` of eq. 2.27).
    pub major: DVec3,
    /// Unit eigenvector of the middle eigenvalue (`v2` of eq. 2.27).
    pub minor: DVec3,
    /// Eigenvalues of the covariance matrix `M_i` (eq. 2.8, a sum, not divided by the count),
    /// ascending: `x` belongs to `normal`, `y` to `minor`, `z` to `major`.
    pub eigenvalues: DVec3,
    /// Number of points the covariance was taken over, `|N_i| + 1`.
    pub count: u32,
    /// `FLAG_*` bits; 0 for a well-defined normal.
    pub flags: u8,
}

impl LocalFrame {
    /// `true` if no degeneracy flag is set.
    pub fn is_regular(&self) -> bool {
        self.flags == 0
    }
}

/// The covariance frame of `p` and its `neighbors` (eq. 2.8–2.10).
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::local_frame;
///
/// let p = DVec3::ZERO;
/// let around = [DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
/// let frame = local_frame(p, &around);
/// assert!(frame.is_regular());
/// assert!(frame.normal.z.abs() > 1.0 - 1e-12); // the plane z = 0
/// assert_eq!(frame.count, 6);
/// ```
pub fn local_frame(p: DVec3, neighbors: &[DVec3]) -> LocalFrame {
    frame_of(neighbors.iter().map(|&x| x - p), neighbors.len() + 1)
}

/// [`local_frame`] from the neighbours' offsets `x_j − p_i`, with the same arithmetic.
pub(crate) fn offsets_frame(offsets: &[DVec3]) -> LocalFrame {
    frame_of(offsets.iter().copied(), offsets.len() + 1)
}

/// The power of two `f` that brings the largest coordinate of `offsets` near 1 (1 if they
/// are all 0 or not finite): the covariance is taken of the offsets times `f` (thesis eq. 2.8
/// in a scaled frame), so neither the squares of tiny offsets underflow nor those of huge
/// ones overflow, over the whole finite range of f64; a power of two scales exactly.
#[inline]
pub(crate) fn unit_scale(offsets: impl Iterator<Item = DVec3>) -> f64 {
    let m = offsets.fold(0.0f64, |m, d| m.max(d.abs().max_element()));
    if m > 0.0 && m.is_finite() {
        // 2^-e with 2^e <= m < 2^(e+1), built from the exponent bits (exact, no overflow)
        let e = ((m.to_bits() >> 52) & 0x7ff) as i64 - 1023;
        let e = e.clamp(-1022, 1023);
        f64::from_bits(((1023 - e) as u64) << 52)
    } else {
        1.0
    }
}

fn frame_of(offsets: impl Iterator<Item = DVec3> + Clone, count: usize) -> LocalFrame {
    let (m, f) = scaled_covariance(offsets, count);
    let (values, vectors) = super::eigen::sym_eigen3_fast(m);
    // the normal and the eigenvalues of the closed form where it is exact, so that a frame and
    // [`NormalCovariance::normal`] agree bit for bit; the tangent vectors from the Jacobi
    // iteration, the major one made orthogonal to that normal
    let closed = super::eigen::sym_eigen3_smallest(m).and_then(|(values, normal)| {
        let major = (vectors[2] - normal * vectors[2].dot(normal)).try_normalize()?;
        Some((values, normal, major, normal.cross(major)))
    });
    let (values, normal, major, minor) =
        closed.unwrap_or((values, vectors[0], vectors[2], vectors[1]));
    let (values, flags) = checked_eigenvalues(values, count);
    let values = values / (f * f);
    LocalFrame {
        normal,
        minor,
        major,
        eigenvalues: values,
        count: count as u32,
        flags,
    }
}

/// The covariance of eq. 2.8 of the offsets scaled by [`unit_scale`], and that scale.
#[inline]
fn scaled_covariance(offsets: impl Iterator<Item = DVec3> + Clone, count: usize) -> (DMat3, f64) {
    let f = unit_scale(offsets.clone());
    (covariance(offsets.map(|d| d * f), count), f)
}

/// The covariance of a neighbourhood that normal estimation solves: eq. 2.8 in the frame scaled
/// by [`unit_scale`], the scale and the count. Its normal, eigenvalues and `FLAG_*` bits are those
/// of [`local_frame`] — the same values bit for bit — without the tangent vectors: the smallest
/// eigenvector in closed form, the Jacobi iteration only where the closed form declines (close
/// eigenvalues, which include every flagged case).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NormalCovariance {
    matrix: DMat3,
    scale: f64,
    count: usize,
}

impl NormalCovariance {
    /// The covariance of `count` points, the neighbours at `offsets` from the point.
    #[inline]
    pub(crate) fn of(offsets: impl Iterator<Item = DVec3> + Clone, count: usize) -> Self {
        let (matrix, scale) = scaled_covariance(offsets, count);
        Self {
            matrix,
            scale,
            count,
        }
    }

    /// The normal, the eigenvalues and the `FLAG_*` bits.
    #[inline]
    pub(crate) fn normal(&self) -> (DVec3, DVec3, u8) {
        self.finish(super::eigen::sym_eigen3_smallest(self.matrix))
    }

    /// [`NormalCovariance::normal`] of `N` covariances at once, the same bits: the closed forms
    /// in lanes (`eigen::sym_eigen3_smallest_lanes`), whose Newton iterations overlap where one
    /// alone waits on its divisions. A lane without a neighbourhood is best given the default
    /// (zero) covariance, which both solvers finish at once; its answer means nothing.
    pub(crate) fn normals<const N: usize>(c: &[Self; N]) -> [(DVec3, DVec3, u8); N] {
        let closed = super::eigen::sym_eigen3_smallest_lanes(&c.map(|c| c.matrix));
        std::array::from_fn(|l| c[l].finish(closed[l]))
    }

    /// The normal, the eigenvalues and the flags from the closed form's answer `closed` (the
    /// Jacobi iteration's where it declined).
    #[inline]
    fn finish(&self, closed: Option<(DVec3, DVec3)>) -> (DVec3, DVec3, u8) {
        let (values, normal) = closed.unwrap_or_else(|| {
            let (values, vectors) = super::eigen::sym_eigen3_fast(self.matrix);
            (values, vectors[0])
        });
        let (values, flags) = checked_eigenvalues(values, self.count);
        (normal, values / (self.scale * self.scale), flags)
    }
}

/// The normal (eq. 2.10), the eigenvalues and the `FLAG_*` bits of the covariance of
/// `N_i ∪ {p_i}` given the neighbours' offsets `x_j − p_i` and their sum, added in order
/// (eq. 2.8): what the smoothing needs
/// unless it reads principal curvatures. The smallest eigenvector comes in closed form, and from
/// the Jacobi iteration of [`local_frame`] whenever the closed form declines (close eigenvalues,
/// which include every flagged case), so degenerate neighbourhoods get the same finite normal and
/// the same flags as there. Allocation-free.
pub(crate) fn offsets_normal(offsets: &[DVec3], sum: DVec3) -> (DVec3, DVec3, u8) {
    let count = offsets.len() + 1;
    let f = unit_scale(offsets.iter().copied());
    let m = covariance_about(offsets.iter().map(|&d| d * f), sum * f / count as f64);
    let (values, normal) = super::eigen::sym_eigen3_smallest(m).unwrap_or_else(|| {
        let (values, vectors) = super::eigen::sym_eigen3_fast(m);
        (values, vectors[0])
    });
    let (values, flags) = checked_eigenvalues(values, count);
    (normal, values / (f * f), flags)
}

/// The covariance matrix `M_i` of eq. 2.8 (a sum over `N_i ∪ {p_i}`, not divided by the count)
/// from the offsets `x_j − p_i` of the neighbours: about the barycentre, computed relative to
/// `p_i` for accuracy far from the origin.
#[inline]
fn covariance(offsets: impl Iterator<Item = DVec3> + Clone, count: usize) -> DMat3 {
    let sum = offsets.clone().fold(DVec3::ZERO, |s, d| s + d);
    covariance_about(offsets, sum / count as f64)
}

/// The covariance of eq. 2.8 about the barycentre offset `bary`.
#[inline]
fn covariance_about(offsets: impl Iterator<Item = DVec3>, bary: DVec3) -> DMat3 {
    let mut sum = OuterSum::default();
    sum.add(-bary);
    for d in offsets {
        sum.add(d - bary);
    }
    sum.matrix()
}

/// Eigenvalues clamped at 0 (round-off can leave tiny negatives) and the degeneracy flags.
#[inline]
fn checked_eigenvalues(values: DVec3, count: usize) -> (DVec3, u8) {
    let values = values.max(DVec3::ZERO);
    let scale = values.z;
    let mut flags = 0;
    if count < 3 {
        flags |= FLAG_TOO_FEW;
    }
    if values.y <= DEGENERATE_TOL * scale || scale == 0.0 {
        flags |= FLAG_COLLINEAR;
    } else if values.y - values.x <= DEGENERATE_TOL * scale {
        flags |= FLAG_AMBIGUOUS;
    }
    (values, flags)
}

/// The frame of every point over its row of `table` (neighbours without the point itself),
/// in parallel; the result does not depend on the number of threads.
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::{local_frames, neighbors::neighbor_table};
/// use nbhd::Neighborhood;
///
/// let points: Vec<DVec3> = (0..100).map(|i| DVec3::new((i % 10) as f64, (i / 10) as f64, 0.0)).collect();
/// let table = neighbor_table(&points, Neighborhood::Knn { k: 8 }, true)?;
/// let frames = local_frames(&points, &table)?;
/// assert!(frames.iter().all(|f| f.normal.z.abs() > 1.0 - 1e-12));
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn local_frames(points: &[DVec3], table: &NeighborTable<f64>) -> Result<Vec<LocalFrame>> {
    check_table(points, table)?;
    Ok((0..points.len())
        .into_par_iter()
        .map_init(Vec::new, |buf, i| {
            buf.clear();
            buf.extend(
                table
                    .indices_of(i)
                    .iter()
                    .filter(|&&j| j as usize != i)
                    .map(|&j| points[j as usize]),
            );
            local_frame(points[i], buf)
        })
        .collect())
}

pub(crate) fn check_table(points: &[DVec3], table: &NeighborTable<f64>) -> Result<()> {
    if table.len() != points.len() || table.indices().iter().any(|&j| j as usize >= points.len()) {
        return Err(NbhdError::InvalidOption {
            name: "table",
            reason: format!(
                "neighbour table has {} rows for {} points or names a point out of range",
                table.len(),
                points.len()
            ),
        });
    }
    Ok(())
}

/// `λ0/(λ0 + λ1 + λ2)` of ascending eigenvalues, 0 when they all vanish.
pub(crate) fn quotient_of(values: DVec3) -> f64 {
    let s = values.x + values.y + values.z;
    if s > 0.0 {
        values.x / s
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::neighbors::neighbor_table;
    use crate::query::Neighborhood;
    use crate::shapes::metrics::unsigned_angle_deg;
    use crate::shapes::{sample, Sphere, Torus};

    #[test]
    fn plane_normal_and_degenerate_cases() {
        let pts: Vec<DVec3> = (0..25)
            .map(|i| DVec3::new((i % 5) as f64, (i / 5) as f64, 2.0))
            .collect();
        let f = local_frame(pts[12], &pts[..12]);
        assert!((f.normal.z.abs() - 1.0).abs() < 1e-12 && f.is_regular());
        // coincident points
        let same = [DVec3::ONE; 4];
        let f = local_frame(DVec3::ONE, &same);
        assert_eq!(f.flags & FLAG_COLLINEAR, FLAG_COLLINEAR);
        assert!((f.normal.length() - 1.0).abs() < 1e-12);
        // two points
        let f = local_frame(DVec3::ZERO, &[DVec3::X]);
        assert_eq!(f.flags, FLAG_TOO_FEW | FLAG_COLLINEAR);
        assert!(f.normal.dot(DVec3::X).abs() < 1e-12 && f.normal.is_finite());
        // collinear
        let line: Vec<DVec3> = (1..6).map(|i| DVec3::splat(i as f64)).collect();
        let f = local_frame(DVec3::ZERO, &line);
        assert_eq!(f.flags, FLAG_COLLINEAR);
        assert!(f.normal.dot(DVec3::ONE).abs() < 1e-9);
        // lone point
        let f = local_frame(DVec3::ZERO, &[]);
        assert!(f.normal.is_finite() && f.flags & FLAG_TOO_FEW != 0);
        // isotropic: octahedron vertices
        let oct = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        assert_eq!(local_frame(DVec3::ZERO, &oct).flags, FLAG_AMBIGUOUS);
    }

    /// The solves in lanes give each neighbourhood's single solve, bit for bit: regular,
    /// degenerate (the Jacobi iteration's) and the default lanes mixed.
    #[test]
    fn lanes_give_the_single_normals() {
        let grid: Vec<DVec3> = (0..25)
            .map(|i| DVec3::new((i % 5) as f64, (i / 5) as f64, 0.1 * (i % 3) as f64))
            .collect();
        let line: Vec<DVec3> = (1..6).map(|i| DVec3::splat(i as f64)).collect();
        let oct = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        let sets: [&[DVec3]; 7] = [
            &grid,
            &[DVec3::ONE; 4],
            &[DVec3::X],
            &line,
            &[],
            &oct,
            &grid[3..9],
        ];
        let mut c: Vec<NormalCovariance> = sets
            .iter()
            .map(|s| NormalCovariance::of(s.iter().copied(), s.len() + 1))
            .collect();
        c.push(NormalCovariance::default());
        let bits = |(n, v, f): (DVec3, DVec3, u8)| {
            (
                n.to_array().map(f64::to_bits),
                v.to_array().map(f64::to_bits),
                f,
            )
        };
        for start in 0..c.len() {
            let lanes: [NormalCovariance; 4] = std::array::from_fn(|l| c[(start + l) % c.len()]);
            let normals = NormalCovariance::normals(&lanes);
            for l in 0..4 {
                assert_eq!(bits(normals[l]), bits(lanes[l].normal()));
            }
        }
    }

    #[test]
    fn sphere_normals_and_orientation() {
        let sphere = Sphere::new(2.0);
        let s = sample(&sphere, 3000, 5);
        let table = neighbor_table(&s.points, Neighborhood::Knn { k: 12 }, true).unwrap();
        let mut frames = local_frames(&s.points, &table).unwrap();
        let mean_err: f64 = frames
            .iter()
            .zip(&s.normals)
            .map(|(f, &n)| unsigned_angle_deg(f.normal, n))
            .sum::<f64>()
            / 3000.0;
        assert!(mean_err < 1.5, "{mean_err}");
        for o in [Orientation::AwayFrom(DVec3::ZERO), Orientation::Propagate] {
            orient(&s.points, &table, &mut frames, o).unwrap();
            assert!(frames
                .iter()
                .zip(&s.normals)
                .all(|(f, &n)| f.normal.dot(n) > 0.0));
            assert!(frames
                .iter()
                .all(|f| f.major.cross(f.minor).dot(f.normal) > 0.999));
        }
        orient(
            &s.points,
            &table,
            &mut frames,
            Orientation::TowardViewpoint(DVec3::ZERO),
        )
        .unwrap();
        assert!(frames
            .iter()
            .zip(&s.normals)
            .all(|(f, &n)| f.normal.dot(n) < 0.0));
    }

    #[test]
    fn clean_torus_normals_are_accurate() {
        // 4,851 points (Fig. 8.2); the example `torus_normals` measures 2.0° here, 1.0° at
        // 19,404 and 0.51° at 77,616 points (k = 15)
        let torus = Torus::new(1.0, 0.4);
        let s = sample(&torus, crate::shapes::TORUS_SIZES[0], 1);
        let table = neighbor_table(&s.points, Neighborhood::Knn { k: 15 }, true).unwrap();
        let frames = local_frames(&s.points, &table).unwrap();
        let err = frames
            .iter()
            .zip(&s.normals)
            .map(|(f, &n)| unsigned_angle_deg(f.normal, n))
            .sum::<f64>()
            / s.points.len() as f64;
        assert!(err < 2.5, "{err}");
        assert!(frames.iter().all(|f| f.is_regular()));
    }
}
