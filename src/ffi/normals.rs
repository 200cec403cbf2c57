//! Normals for C: their own options struct (the neighbourhood, the orientation and the
//! non-finite policy — nothing of smoothing) and an output description with strides, so that
//! the normals (and PCL's curvature, the surface variation) are written straight into a
//! caller's point type such as `pcl::Normal` or `pcl::PointNormal`. The export converts its
//! arguments and calls [`crate::geometry::estimate_normals_from`] (normals, surface variation and
//! flags, nothing else); nothing is computed here.

use std::ffi::c_void;

use super::args::{check_aligned, check_optional};
use super::enums::{nbhd_non_finite_policy, nbhd_orientation, nbhd_scalar_type, nbhd_units};
use super::fields::{c_field, CStruct};
use super::smoothing_io::{nbhd_progress_fn, read_points, Progress, Strided};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::types::nbhd_points;
use crate::geometry::{estimate_normals_from, Neighbors, NormalEstimate, NormalOptions};
use crate::scalar::ScalarType;

/// Options of nbhd_estimate_normals. Start from nbhd_normal_options_default() and change
/// what you need.
///
/// The neighbourhood of a point is the thesis' ε-k-neighbourhood (Section 2.1.1): its `k`
/// nearest other points within `epsilon`; the normal is the eigenvector of the smallest
/// eigenvalue of the covariance of the point and its neighbourhood (eq. 2.8–2.10), as PCL's
/// NormalEstimation computes it.
///
/// UNITS: `epsilon` is RELATIVE by default — a multiple of the mean spacing h of the points
/// (the mean distance of a point to its nearest other point), NOT a length in the points'
/// units. The default `epsilon = 6` means 6 h. For a radius in the points' units (say 1 cm in
/// metre coordinates) set BOTH `epsilon = 0.01` and `epsilon_units = NBHD_UNITS_ABSOLUTE`;
/// a relative `epsilon = 0.01` (0.01 h, below any neighbour) is refused with
/// NBHD_STATUS_DEGENERATE, whose message gives ε resolved to the points' units.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_normal_options {
    /// Maximum valence k (>= 1): at most the k nearest other points. Default 15.
    pub k: usize,
    /// Influence radius ε (> 0), plain (not squared), inclusive; in `epsilon_units`.
    /// Default 6 (relative: 6 h).
    pub epsilon: f64,
    /// Units of `epsilon`: NBHD_UNITS_RELATIVE (multiples of h, the default) or
    /// NBHD_UNITS_ABSOLUTE (the points' own units).
    pub epsilon_units: nbhd_units,
    /// Orientation of the normals. Default unoriented. NBHD_ORIENTATION_TOWARD_POINT with the
    /// sensor position is PCL's flipNormalTowardsViewpoint: dot(viewpoint − p, n) >= 0.
    pub orientation: nbhd_orientation,
    /// The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite). Default
    /// (0, 0, 0).
    pub orientation_point: [f64; 3],
    /// Points with a NaN or infinite coordinate: REJECT (the default) refuses the input with
    /// NON_FINITE; SKIP leaves them out — they keep their index and get a NaN normal (and
    /// curvature) and flag 8.
    pub non_finite: nbhd_non_finite_policy,
    /// Worker threads: 0 the shared pool, n >= 1 a pool of n threads made for this call (at
    /// most NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results are identical for
    /// every value. Default 0.
    pub threads: usize,
    /// Called with the progress of the run; NULL for none. Default NULL.
    pub progress: nbhd_progress_fn,
    /// Passed to `progress` unchanged. Default NULL.
    pub progress_user_data: *mut c_void,
}

/// Where nbhd_estimate_normals writes, in the caller's layout: point i's normal (x, y, z) at
/// byte `i * normals_stride` from `normals`, its curvature at byte `i * curvature_stride`
/// from `curvature`, all of `scalar_type`; only these values are written, other bytes of a
/// strided layout are left alone. Strides of 0 mean packed (3 values, 1 value).
///
/// For `pcl::PointCloud<pcl::Normal> cloud` (float normal_x/y/z, then curvature, 32 bytes):
/// `{&cloud[0].normal_x, sizeof(pcl::Normal), NBHD_SCALAR_TYPE_F32, &cloud[0].curvature,
/// sizeof(pcl::Normal), NULL}`; for `pcl::PointNormal` use `&cloud[0].normal_x`,
/// `&cloud[0].curvature` and `sizeof(pcl::PointNormal)`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_normals_output {
    /// First byte of point 0's normal. Must not be NULL.
    pub normals: *mut c_void,
    /// Bytes from one point's normal to the next: 0 (packed) or at least 3 values.
    pub normals_stride: usize,
    /// Type of every value written (normals and curvature).
    pub scalar_type: nbhd_scalar_type,
    /// First byte of point 0's curvature, or NULL for none. The curvature is PCL's: the
    /// surface variation λ0 / (λ0 + λ1 + λ2) of the covariance eigenvalues (0 on a plane, at
    /// most 1/3), as pcl::NormalEstimation writes to `curvature`.
    pub curvature: *mut c_void,
    /// Bytes from one point's curvature to the next: 0 (packed) or at least one value.
    pub curvature_stride: usize,
    /// `points->count` bytes (packed), or NULL: 0 for a well-defined normal, otherwise the
    /// bits of nbhd_point_geometry.normal_flags (8: the point was skipped).
    pub flags: *mut u8,
}

/// The C form of the core's options, with no progress callback.
impl From<NormalOptions> for nbhd_normal_options {
    fn from(d: NormalOptions) -> Self {
        let (epsilon_units, epsilon) = nbhd_units::of_length(d.epsilon);
        let (orientation, orientation_point) = nbhd_orientation::of_core(d.orientation);
        Self {
            k: d.k,
            epsilon,
            epsilon_units,
            orientation,
            orientation_point,
            non_finite: d.non_finite.into(),
            threads: d.threads,
            progress: None,
            progress_user_data: std::ptr::null_mut(),
        }
    }
}

/// The default normal options: the 15 nearest other points within 6 h (RELATIVE units: h is
/// the mean spacing), unoriented, non-finite points rejected, the shared thread pool, no
/// progress callback.
#[no_mangle]
pub extern "C" fn nbhd_normal_options_default() -> nbhd_normal_options {
    let d = || NormalOptions::default().into();
    guard_value("nbhd_normal_options_default", d(), d)
}

/// Reads `*options` field by field (NULL gives the defaults) into the core's options, and the
/// call's progress callback.
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_normal_options`.
unsafe fn read_options(
    options: *const nbhd_normal_options,
) -> Result<(NormalOptions, Progress), FfiError> {
    let defaults = NormalOptions::default().into();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    let core = NormalOptions {
        k: c_field!(o.k),
        epsilon: c_field!(o.epsilon_units as enum)?.length(c_field!(o.epsilon)),
        orientation: c_field!(o.orientation as enum)?.to_core(c_field!(o.orientation_point))?,
        non_finite: c_field!(o.non_finite as enum)?.into(),
        threads: c_field!(o.threads),
    };
    let progress = Progress::new(c_field!(o.progress), c_field!(o.progress_user_data));
    Ok((core, progress))
}

/// The caller's nbhd_normals_output, read and checked for `count` points.
struct NormalsOut {
    normals: Strided,
    curvature: Option<Strided>,
    flags: *mut u8,
}

impl NormalsOut {
    /// Reads `*out` field by field and checks its pointers, strides and spans.
    ///
    /// # Safety
    /// `out` must be NULL or point to a readable nbhd_normals_output.
    unsafe fn read(out: *const nbhd_normals_output, count: usize) -> Result<Self, FfiError> {
        // SAFETY: forwarded from the caller.
        let o = unsafe { CStruct::argument(out, "out") }?;
        let (normals, curvature, flags) = (
            c_field!(o.normals),
            c_field!(o.curvature),
            c_field!(o.flags),
        );
        let scalar = ScalarType::from(c_field!(o.scalar_type as enum)?);
        check_aligned(normals.cast_const(), 1, "out->normals")?;
        check_optional(flags.cast_const(), "out->flags")?;
        let stride = c_field!(o.normals_stride);
        let normals = Strided::new(normals, stride, scalar, 3, count, "normals")?;
        let curvature = match curvature.is_null() {
            true => None,
            false => {
                let stride = c_field!(o.curvature_stride);
                Some(Strided::new(
                    curvature,
                    stride,
                    scalar,
                    1,
                    count,
                    "curvature",
                )?)
            }
        };
        Ok(Self {
            normals,
            curvature,
            flags,
        })
    }

    /// Writes the normal, curvature and flags of every point.
    ///
    /// # Safety
    /// The arrays must be writable for `outputs.len()` points in the layouts checked by
    /// [`NormalsOut::read`], and no Rust borrow of them may be live.
    unsafe fn write(&self, outputs: &[NormalEstimate]) {
        for (i, o) in outputs.iter().enumerate() {
            // SAFETY: forwarded from the caller.
            unsafe {
                self.normals.write(i, &o.normal.to_array());
                if let Some(c) = &self.curvature {
                    c.write(i, &[o.surface_variation]);
                }
            }
        }
        if !self.flags.is_null() {
            let f: Vec<u8> = outputs.iter().map(|o| o.flags).collect();
            // SAFETY: `flags` is non-NULL and writable for the points' bytes (caller); it
            // cannot overlap `f`, nbhd's own memory.
            unsafe { std::ptr::copy_nonoverlapping(f.as_ptr(), self.flags, f.len()) };
        }
    }
}

/// Estimates the normal of every point (thesis eq. 2.8–2.10: the eigenvector of the smallest
/// eigenvalue of the covariance of the point and its ε-k-neighbourhood), oriented as
/// `options->orientation` asks, and writes it into the caller's layout `*out` (see
/// nbhd_normals_output: a packed `double[3 * count]`, or the fields of `pcl::Normal` /
/// `pcl::PointNormal` in place), with PCL's curvature (the surface variation) and the
/// degeneracy flags if asked. Degenerate neighbourhoods give a finite unit vector and a flag,
/// never NaN; skipped points (NBHD_NON_FINITE_POLICY_SKIP) a NaN normal and curvature.
/// `options` may be NULL for the defaults (NOTE: ε is then 6 × the mean spacing, RELATIVE
/// units). Nothing is written unless the call succeeds.
///
/// Errors: NULL_POINTER (`points`, `points->data`, `out`, `out->normals`),
/// MISALIGNED_POINTER, INVALID_ARGUMENT (dimension other than 3, `out->scalar_type` out of
/// range, an output stride smaller than its values or one that overflows), ZERO_DIMENSION
/// (dimension 0), EMPTY_INPUT, STRIDE_TOO_SMALL, TOO_MANY_POINTS, NON_FINITE (non_finite
/// REJECT), INVALID_K, INVALID_OPTION (an enum field of `options` out of range, ε not > 0,
/// relative units on a set without two distinct points, a non-finite orientation point,
/// more than NBHD_MAX_THREADS threads), DEGENERATE (no neighbourhood reached 3 points, or
/// every normal is flagged: usually ε far too small — check `epsilon_units`; the message
/// gives ε in the points' units), OUT_OF_MEMORY, THREAD_POOL, CANCELLED.
///
/// # Safety
/// `points` must describe readable memory; `out` must point to a readable
/// nbhd_normals_output whose arrays are writable for `points->count` points in the layout it
/// describes; `options` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_estimate_normals(
    points: *const nbhd_points,
    options: *const nbhd_normal_options,
    out: *const nbhd_normals_output,
) -> nbhd_status {
    guard("nbhd_estimate_normals", || {
        // SAFETY: forwarded from the caller.
        let (_, pts) = unsafe { read_points(points) }?;
        // SAFETY: forwarded from the caller.
        let out = unsafe { NormalsOut::read(out, pts.len()) }?;
        // SAFETY: forwarded from the caller.
        let (opts, mut progress) = unsafe { read_options(options) }?;
        let report = &mut |f, s| progress.report(f, s);
        let result = estimate_normals_from(&pts, Neighbors::default(), &opts, report)?;
        // SAFETY: the arrays are writable for the points in the checked layouts (caller); the
        // input view was dropped in `read_points`, so nothing borrowed overlaps.
        unsafe { out.write(&result.normals) };
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{sample, Sphere};

    #[test]
    fn defaults_mirror_the_core() {
        // SAFETY: NULL asks for the defaults.
        let (a, _) = unsafe { read_options(std::ptr::null()) }.unwrap();
        let d = NormalOptions::default();
        assert_eq!((a.k, a.epsilon, a.threads), (d.k, d.epsilon, d.threads));
        assert_eq!(a.non_finite, d.non_finite);
        let c = nbhd_normal_options_default();
        // SAFETY: a live, initialised options struct.
        let (b, _) = unsafe { read_options(&c) }.unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn normals_into_a_strided_float_layout_equal_the_core() {
        let s = sample(&Sphere::new(1.0), 500, 4);
        let data: Vec<f64> = s.points.iter().flat_map(|p| p.to_array()).collect();
        let pts = nbhd_points {
            data: data.as_ptr().cast(),
            count: s.points.len(),
            dim: 3,
            stride: 0,
            scalar_type: nbhd_scalar_type::F64,
        };
        // a PCL-like record: 4 floats of normal, then curvature and 3 floats of padding
        let mut rec = vec![[7f32; 8]; s.points.len()];
        let out = nbhd_normals_output {
            normals: rec.as_mut_ptr().cast(),
            normals_stride: 32,
            scalar_type: nbhd_scalar_type::F32,
            curvature: rec[0][4..].as_mut_ptr().cast(),
            curvature_stride: 32,
            flags: std::ptr::null_mut(),
        };
        // SAFETY: the descriptors match `data` and `rec`.
        let st = unsafe { nbhd_estimate_normals(&pts, std::ptr::null(), &out) };
        assert_eq!(st, nbhd_status::Ok);
        let core = crate::smooth::analyze(&s.points, &crate::smooth::SmoothOptions::default());
        let core = core.unwrap();
        for (r, o) in rec.iter().zip(&core.outputs) {
            assert_eq!(&r[..3], &o.normal.as_vec3().to_array());
            assert_eq!(r[3], 7.0);
            assert_eq!(r[4], o.covariance_quotient as f32);
            assert_eq!(&r[5..], &[7.0; 3]);
        }
    }
}
