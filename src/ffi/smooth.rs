//! Normals, curvatures and point-set smoothing (thesis Chapter 2) for C: an options struct
//! with a defaults initializer, a progress callback that can cancel, and outputs in caller
//! buffers. Each export converts its arguments and calls [`crate::smooth::smooth_with_progress`];
//! nothing is computed here. What the smoothing exports share is in [`super::smoothing_io`].

use std::ffi::c_void;

use super::enums::{nbhd_feature_criterion, nbhd_non_finite_policy, nbhd_orientation};
use super::enums::{nbhd_units, nbhd_weighting};
use super::fields::{c_field, CStruct};
use super::smoothing_io::{nbhd_point_geometry, nbhd_progress_fn, nbhd_smooth_summary};
use super::smoothing_io::{read_points, Outputs, Progress};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::types::nbhd_points;
use crate::smooth::{self, Neighbors, SmoothOptions};

/// The `interior_threshold` C shows while `constrain_interior` is off (the core has none
/// then), so that switching it on alone gives a usable threshold.
const INTERIOR_THRESHOLD: f64 = 0.01;

/// Options of nbhd_smooth and nbhd_estimate_curvatures (nbhd_estimate_normals has its own,
/// nbhd_normal_options). Start from nbhd_smooth_options_default() and change what you need.
///
/// UNITS: `epsilon`, `lambda` and a curvature `feature_threshold` are RELATIVE by default —
/// multiples of the mean spacing h of the points (or of 1/h) — not lengths in the points'
/// units. `epsilon = 0.01` means 0.01 h, far below any neighbour, and is refused with
/// NBHD_STATUS_DEGENERATE; for 1 cm in metre coordinates set `epsilon = 0.01` AND
/// `epsilon_units = NBHD_UNITS_ABSOLUTE`. nbhd_smooth_summary reports h and ε resolved.
///
/// Neighbourhoods are the thesis' ε-k-neighbourhoods (Section 2.1.1): the `k` nearest other
/// points within `epsilon`, computed once on the input and cached (Section 2.1.3) unless
/// `update_neighbors` is set. One step moves every point at once by
/// `p_i += tau * (1/|N_i|) Σ_j g_ij (x_j − p_i)` (eq. 2.16, 2.18, 2.30).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_smooth_options {
    /// Maximum valence k (>= 1). Default 15.
    pub k: usize,
    /// Influence radius ε (> 0), plain (not squared), inclusive. Default 6 (relative: 6h).
    pub epsilon: f64,
    /// Units of `epsilon`. Default relative.
    pub epsilon_units: nbhd_units,
    /// Number of smoothing steps (0 only analyses). Default 3.
    pub steps: usize,
    /// Step size τ = λ·∂t of eq. 2.18 (finite, >= 0). Default 0.5.
    pub tau: f64,
    /// The weights g_ij. Default NBHD_WEIGHTING_SHARP.
    pub weighting: nbhd_weighting,
    /// Curvature threshold λ of g_sharp / g_cont (> 0). Default 0.2 (relative: 0.2/h).
    pub lambda: f64,
    /// Units of `lambda`. Default relative.
    pub lambda_units: nbhd_units,
    /// Which points are smoothed anisotropically. Default all points.
    pub feature: nbhd_feature_criterion,
    /// Threshold of the feature criterion: the quotient Q (a plain number) for
    /// EDGE_QUOTIENT, a curvature for PRINCIPAL_CURVATURE and DIRECTIONAL_CURVATURE.
    /// Ignored for ALL_POINTS. Default 0.5.
    pub feature_threshold: f64,
    /// Units of a curvature `feature_threshold`. Default relative.
    pub feature_units: nbhd_units,
    /// 'Constrain interior' (thesis Section 7.3): points whose covariance quotient
    /// λ0/(λ0 + λ1 + λ2) is below `interior_threshold` are held fixed. Default false.
    pub constrain_interior: bool,
    /// The covariance-quotient threshold of `constrain_interior` (finite). Default 0.01.
    pub interior_threshold: f64,
    /// 'Update Neighbors' (Section 7.3): recompute the neighbourhoods before every step.
    /// Default false.
    pub update_neighbors: bool,
    /// Orientation of the normals written to the outputs (smoothing itself uses |κ| and does
    /// not depend on it). Default unoriented.
    pub orientation: nbhd_orientation,
    /// The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite). Default
    /// (0, 0, 0).
    pub orientation_point: [f64; 3],
    /// Worker threads: 0 the shared pool with a thread per core, n >= 1 a pool of n threads
    /// made for this call (at most NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results
    /// are identical for every value. Default 0.
    pub threads: usize,
    /// Called with the progress of the run; NULL for none. Default NULL.
    pub progress: nbhd_progress_fn,
    /// Passed to `progress` unchanged. Default NULL.
    pub progress_user_data: *mut c_void,
    /// Points with a NaN or infinite coordinate (the holes of organized scans), as in
    /// nbhd_build_options: REJECT (the default) refuses the input with NON_FINITE; SKIP
    /// computes on the finite points only, and a skipped point keeps its index, is left
    /// unmoved (its coordinates are copied to `out_coords` as they are) and gets NaN geometry
    /// with `normal_flags` 8. Default REJECT.
    pub non_finite: nbhd_non_finite_policy,
}

/// The C form of the core's options, with no progress callback.
impl From<SmoothOptions> for nbhd_smooth_options {
    fn from(d: SmoothOptions) -> Self {
        let (epsilon_units, epsilon) = nbhd_units::of_length(d.epsilon);
        let (lambda_units, lambda) = nbhd_units::of_curvature(d.lambda);
        let (feature, feature_threshold, feature_units) =
            nbhd_feature_criterion::of_core(d.feature);
        let (orientation, orientation_point) = nbhd_orientation::of_core(d.orientation);
        Self {
            k: d.k,
            epsilon,
            epsilon_units,
            steps: d.steps,
            tau: d.tau,
            weighting: d.weighting.into(),
            lambda,
            lambda_units,
            feature,
            feature_threshold,
            feature_units,
            constrain_interior: d.constrain_interior.is_some(),
            interior_threshold: d.constrain_interior.unwrap_or(INTERIOR_THRESHOLD),
            update_neighbors: d.update_neighbors,
            orientation,
            orientation_point,
            threads: d.threads,
            progress: None,
            progress_user_data: std::ptr::null_mut(),
            non_finite: d.non_finite.into(),
        }
    }
}

/// The default smoothing options: the thesis' anisotropic flow with g_sharp at λ = 0.2/h on
/// all points, 3 steps of τ = 0.5, the 15 nearest other points within 6h, no progress
/// callback, the shared thread pool.
#[no_mangle]
pub extern "C" fn nbhd_smooth_options_default() -> nbhd_smooth_options {
    let d = || SmoothOptions::default().into();
    guard_value("nbhd_smooth_options_default", d(), d)
}

/// Reads `*options` field by field into the core's options and the call's progress callback
/// (NULL gives the defaults).
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_smooth_options`.
pub(super) unsafe fn read_options(
    options: *const nbhd_smooth_options,
) -> Result<(SmoothOptions, Progress), FfiError> {
    let defaults = SmoothOptions::default().into();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    let feature_units = c_field!(o.feature_units as enum)?;
    let core = SmoothOptions {
        k: c_field!(o.k),
        epsilon: c_field!(o.epsilon_units as enum)?.length(c_field!(o.epsilon)),
        steps: c_field!(o.steps),
        tau: c_field!(o.tau),
        weighting: c_field!(o.weighting as enum)?.into(),
        lambda: c_field!(o.lambda_units as enum)?.curvature(c_field!(o.lambda)),
        feature: c_field!(o.feature as enum)?.to_core(c_field!(o.feature_threshold), feature_units),
        constrain_interior: c_field!(o.constrain_interior as bool)
            .then(|| c_field!(o.interior_threshold)),
        update_neighbors: c_field!(o.update_neighbors as bool),
        orientation: c_field!(o.orientation as enum)?.to_core(c_field!(o.orientation_point))?,
        non_finite: c_field!(o.non_finite as enum)?.into(),
        threads: c_field!(o.threads),
        ..SmoothOptions::default()
    };
    let progress = Progress::new(c_field!(o.progress), c_field!(o.progress_user_data));
    Ok((core, progress))
}

/// Smooths 3-D points (thesis Chapter 2) and writes the smoothed coordinates to `out_coords`.
///
/// `out_coords` is laid out like the input: `points->count` points `points->stride` bytes
/// apart (a stride of 0 means packed), three coordinates of `points->scalar_type` each; only
/// the coordinates are written, other bytes in a strided layout are left alone. It may be
/// `points->data` itself, to smooth in place (the input is read completely first).
/// `out_geometry` (`points->count` elements) receives the per-point geometry of the smoothed
/// points and `out_summary` the spacing and thresholds used; either may be NULL, and leaving
/// `out_geometry` NULL skips that work. `options` may be NULL for the defaults.
///
/// Nothing is written unless the call succeeds. Results are identical for any number of
/// threads.
///
/// Errors: NULL_POINTER (`points`, `points->data`, `out_coords`), MISALIGNED_POINTER,
/// INVALID_ARGUMENT (dimension other than 3, `points->scalar_type` out of range, a buffer
/// size that overflows), ZERO_DIMENSION (dimension 0), EMPTY_INPUT (also: no finite point
/// left to SKIP), STRIDE_TOO_SMALL, TOO_MANY_POINTS, NON_FINITE (with `non_finite` REJECT;
/// the message names the point), INVALID_K, INVALID_OPTION (an enum field of `options` out of
/// range, ε or λ not > 0, τ negative, relative units on a set without two distinct points,
/// more than NBHD_MAX_THREADS threads, ...), DEGENERATE (no neighbourhood reached 3 points: ε
/// far below the spacing — check `epsilon_units`; the message gives ε in the points' units),
/// OUT_OF_MEMORY (the neighbourhoods of `k` do not fit in memory, e.g. k = SIZE_MAX on a
/// large set), THREAD_POOL, CANCELLED (the progress callback returned false).
///
/// # Safety
/// `points` must describe readable memory (see nbhd_points); `out_coords` must be writable
/// with the same layout; `out_geometry` and `out_summary` must be NULL or writable for
/// `points->count` elements / one element; `options` must be NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth(
    points: *const nbhd_points,
    options: *const nbhd_smooth_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth", || {
        // SAFETY: forwarded from the caller.
        let (arg, pts) = unsafe { read_points(points) }?;
        let out = Outputs::smoothing(out_coords, out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        let (mut opts, mut progress) = unsafe { read_options(options) }?;
        opts.outputs = out.wants_geometry();
        let result = smooth::smooth_with_progress(&pts, &opts, &mut |f, s| progress.report(f, s))?;
        // SAFETY: the outputs are writable with the input's layout / for `count` elements
        // (caller); the input view was dropped in `read_points`, so smoothing in place
        // overlaps no live borrow.
        unsafe { out.write(&result, arg.scalar, arg.stride) };
        Ok(())
    })
}

/// Estimates normals and curvatures of every point without moving it: the normal, the
/// principal curvatures and directions of the Weingarten estimate (thesis eq. 2.26–2.29 with
/// 2.25) and the other per-point values of nbhd_point_geometry, over the ε-k-neighbourhoods
/// of `options`. `out_geometry` receives `points->count` elements; `out_summary` (may be NULL)
/// the spacing and thresholds used.
///
/// Errors: as nbhd_smooth; DEGENERATE also when every normal is flagged degenerate.
///
/// # Safety
/// `points` must describe readable memory; `out_geometry` must be writable for
/// `points->count` elements; `out_summary` NULL or writable; `options` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn nbhd_estimate_curvatures(
    points: *const nbhd_points,
    options: *const nbhd_smooth_options,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_estimate_curvatures", || {
        // SAFETY: forwarded from the caller.
        let (arg, pts) = unsafe { read_points(points) }?;
        let out = Outputs::curvatures(out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        let (opts, mut progress) = unsafe { read_options(options) }?;
        let result =
            smooth::analyze_with_progress(&pts, Neighbors::default(), &opts, &mut |f, s| {
                progress.report(f, s)
            })?;
        // SAFETY: the outputs are writable for `count` elements / one element (caller).
        unsafe { out.write(&result, arg.scalar, arg.stride) };
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffi::{nbhd_scalar_type, nbhd_stage};
    use crate::shapes::{sample, Sphere};
    use glam::DVec3;

    fn sphere_points() -> Vec<f32> {
        sample(&Sphere::new(1.0), 600, 3)
            .points
            .iter()
            .flat_map(|p| p.as_vec3().to_array())
            .collect()
    }

    fn desc(data: &[f32]) -> nbhd_points {
        nbhd_points {
            data: data.as_ptr().cast(),
            count: data.len() / 3,
            dim: 3,
            stride: 12,
            scalar_type: nbhd_scalar_type::F32,
        }
    }

    #[test]
    fn defaults_mirror_the_core() {
        // SAFETY: NULL asks for the defaults.
        let (core, progress) = unsafe { read_options(std::ptr::null()) }.unwrap();
        assert_eq!(core, SmoothOptions::default());
        assert!(progress.is_none());
        let c = nbhd_smooth_options_default();
        // SAFETY: a live, initialised options struct.
        let (core, _) = unsafe { read_options(&c) }.unwrap();
        assert_eq!(core, SmoothOptions::default());
        assert_eq!(core.threads, 0);
    }

    unsafe extern "C" fn record_pool_size(_: f64, _: nbhd_stage, seen: *mut c_void) -> bool {
        // SAFETY: the test passes a pointer to its usize.
        unsafe { *seen.cast::<usize>() = rayon::current_num_threads() };
        true
    }

    #[test]
    fn the_threads_option_reaches_the_core_and_changes_no_bit() {
        let data = sphere_points();
        let run = |threads: usize| {
            let mut o = nbhd_smooth_options_default();
            let mut pool = 0usize;
            o.threads = threads;
            o.progress = Some(record_pool_size);
            o.progress_user_data = (&mut pool as *mut usize).cast();
            let mut out = vec![0f32; data.len()];
            // SAFETY: the descriptor matches `data`; `out` has its layout; `pool` outlives
            // the call.
            let s = unsafe {
                nbhd_smooth(
                    &desc(&data),
                    &o,
                    out.as_mut_ptr().cast(),
                    std::ptr::null_mut(),
                    std::ptr::null_mut(),
                )
            };
            assert_eq!(s, nbhd_status::Ok);
            (out, pool)
        };
        let (one, pool1) = run(1);
        let (three, pool3) = run(3);
        assert_eq!((pool1, pool3), (1, 3));
        assert_eq!(one, three);
    }

    #[test]
    fn smoothing_through_the_abi_equals_the_core() {
        let data = sphere_points();
        let pts: Vec<DVec3> = data
            .chunks(3)
            .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect();
        let core = smooth::smooth(&pts, &SmoothOptions::default()).unwrap();
        let mut out = vec![0f32; data.len()];
        let mut geo = vec![nbhd_point_geometry::default(); pts.len()];
        let mut summary = nbhd_smooth_summary::default();
        // SAFETY: the descriptor matches `data`; the outputs hold `count` elements.
        let s = unsafe {
            nbhd_smooth(
                &desc(&data),
                std::ptr::null(),
                out.as_mut_ptr().cast(),
                geo.as_mut_ptr(),
                &mut summary,
            )
        };
        assert_eq!(s, nbhd_status::Ok);
        for (i, p) in core.points.iter().enumerate() {
            assert_eq!(&out[3 * i..3 * i + 3], &p.as_vec3().to_array());
            assert_eq!(geo[i], nbhd_point_geometry::from(&core.outputs[i]));
        }
        assert_eq!(summary, nbhd_smooth_summary::from(&core));
    }

    unsafe extern "C" fn stop_at_half(f: f64, _: nbhd_stage, seen: *mut c_void) -> bool {
        // SAFETY: the test passes a pointer to its usize counter.
        unsafe { *seen.cast::<usize>() += 1 };
        f < 0.5
    }

    #[test]
    fn a_callback_that_returns_false_cancels_and_writes_nothing() {
        let data = sphere_points();
        let mut seen = 0usize;
        let mut o = nbhd_smooth_options_default();
        o.progress = Some(stop_at_half);
        o.progress_user_data = (&mut seen as *mut usize).cast();
        let mut out = vec![7f32; data.len()];
        // SAFETY: the descriptor matches `data`; `out` has its layout; `seen` outlives the call.
        let s = unsafe {
            nbhd_smooth(
                &desc(&data),
                &o,
                out.as_mut_ptr().cast(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(s, nbhd_status::Cancelled);
        assert!(seen >= 2);
        assert!(out.iter().all(|&v| v == 7.0));
    }

    #[test]
    fn bad_options_are_named() {
        let data = sphere_points();
        let mut geo = vec![nbhd_point_geometry::default(); data.len() / 3];
        let mut o = nbhd_smooth_options_default();
        o.k = 0;
        // SAFETY: the descriptor matches `data`; `geo` holds one element per point.
        let s = unsafe {
            nbhd_estimate_curvatures(&desc(&data), &o, geo.as_mut_ptr(), std::ptr::null_mut())
        };
        assert_eq!(s, nbhd_status::InvalidK);
        let mut o = nbhd_smooth_options_default();
        // SAFETY: writes an int into the int-sized enum field, as C may.
        unsafe {
            std::ptr::addr_of_mut!(o.weighting)
                .cast::<std::ffi::c_int>()
                .write(9)
        };
        // SAFETY: as above.
        let s = unsafe {
            nbhd_estimate_curvatures(&desc(&data), &o, geo.as_mut_ptr(), std::ptr::null_mut())
        };
        // an enum field of an options struct out of range is an option out of range
        assert_eq!(s, nbhd_status::InvalidOption);
    }
}
