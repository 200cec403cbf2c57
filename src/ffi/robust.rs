//! The robust smoothing mode for C ([`crate::smooth::robust`]): thresholds adapted to the
//! estimated noise and a stopping rule, so it needs no tuning per scan. The export converts
//! its arguments and calls [`crate::smooth::smooth_robust_with_progress`].

use std::ffi::c_void;

use super::enums::{nbhd_non_finite_policy, nbhd_orientation, nbhd_units};
use super::fields::{c_field, CStruct};
use super::smoothing_io::{nbhd_point_geometry, nbhd_progress_fn, nbhd_smooth_summary};
use super::smoothing_io::{read_points, Outputs, Progress};
use super::status::{guard, guard_value, nbhd_status, FfiError};
use super::types::nbhd_points;
use crate::smooth::{self, RobustOptions};

/// Options of nbhd_smooth_robust. Start from nbhd_robust_options_default(); the defaults are
/// one setting meant for every shape and noise level (all thresholds are multiples of the
/// estimated noise or dimensionless).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct nbhd_robust_options {
    /// Size k of the umbrella neighbourhood (>= 1). Default 24.
    pub k: usize,
    /// Size of the wider neighbourhood the candidate planes are fitted and scored on
    /// (>= k). Default 48.
    pub k_plane: usize,
    /// Influence radius ε (> 0) that cuts both neighbourhoods. Default 12 (relative: 12h).
    pub epsilon: f64,
    /// Units of `epsilon`. Default relative.
    pub epsilon_units: nbhd_units,
    /// Upper bound on the number of iterations. Default 10.
    pub max_iterations: usize,
    /// Stopping rule: stop once an iteration lowered the noise estimate by less than this
    /// fraction (finite, >= 0; 0 runs max_iterations unless the estimate rises). Default 0.05.
    pub tolerance: f64,
    /// Width of the biweight of plane distances, in units of the estimated noise (> 0).
    /// Default 5.
    pub inlier_width: f64,
    /// Angle in degrees at which a neighbour counts as across a feature (> 0). Default 20.
    pub feature_angle: f64,
    /// Step size τ in (0, 1]. Default 1.
    pub tau: f64,
    /// Orientation of the normals written to the outputs. Default unoriented.
    pub orientation: nbhd_orientation,
    /// The point of NBHD_ORIENTATION_TOWARD_POINT / _AWAY_FROM_POINT (finite). Default
    /// (0, 0, 0).
    pub orientation_point: [f64; 3],
    /// Worker threads: 0 the shared pool, n >= 1 a pool of n threads for this call (at most
    /// NBHD_MAX_THREADS, else NBHD_STATUS_INVALID_OPTION). Results are identical for every
    /// value. Default 0.
    pub threads: usize,
    /// Called with the progress of the run; NULL for none. Default NULL.
    pub progress: nbhd_progress_fn,
    /// Passed to `progress` unchanged. Default NULL.
    pub progress_user_data: *mut c_void,
    /// Points with a NaN or infinite coordinate: REJECT (the default) or SKIP (left unmoved,
    /// NaN geometry with `normal_flags` 8), as nbhd_smooth_options.non_finite.
    pub non_finite: nbhd_non_finite_policy,
    /// Scale from the noise: while the cloud's neighbourhoods read as balls of noise (noise of
    /// about two spacings or more), iterate with k and k_plane tripled. Clouds with noise up to
    /// about 1.5 spacings are smoothed as without it. Default true.
    pub noise_scale: bool,
}

/// The C form of the core's options, with no progress callback.
impl From<RobustOptions> for nbhd_robust_options {
    fn from(d: RobustOptions) -> Self {
        let (epsilon_units, epsilon) = nbhd_units::of_length(d.epsilon);
        let (orientation, orientation_point) = nbhd_orientation::of_core(d.orientation);
        Self {
            k: d.k,
            k_plane: d.k_plane,
            epsilon,
            epsilon_units,
            max_iterations: d.max_iterations,
            tolerance: d.tolerance,
            inlier_width: d.inlier_width,
            feature_angle: d.feature_angle,
            tau: d.tau,
            orientation,
            orientation_point,
            threads: d.threads,
            progress: None,
            progress_user_data: std::ptr::null_mut(),
            non_finite: d.non_finite.into(),
            noise_scale: d.noise_scale,
        }
    }
}

/// The default robust options: 24 neighbours within 12h, planes scored on 48, at most 10
/// iterations stopped when the noise estimate falls by less than 5 %, no callback.
#[no_mangle]
pub extern "C" fn nbhd_robust_options_default() -> nbhd_robust_options {
    let d = || RobustOptions::default().into();
    guard_value("nbhd_robust_options_default", d(), d)
}

/// Reads `*options` field by field into the core's options and the call's progress callback
/// (NULL gives the defaults).
///
/// # Safety
/// `options` must be NULL or point to a readable `nbhd_robust_options`.
pub(super) unsafe fn read_options(
    options: *const nbhd_robust_options,
) -> Result<(RobustOptions, Progress), FfiError> {
    let defaults = RobustOptions::default().into();
    // SAFETY: forwarded from the caller.
    let o = unsafe { CStruct::options(options, &defaults) }?;
    let core = RobustOptions {
        k: c_field!(o.k),
        k_plane: c_field!(o.k_plane),
        epsilon: c_field!(o.epsilon_units as enum)?.length(c_field!(o.epsilon)),
        max_iterations: c_field!(o.max_iterations),
        tolerance: c_field!(o.tolerance),
        inlier_width: c_field!(o.inlier_width),
        feature_angle: c_field!(o.feature_angle),
        tau: c_field!(o.tau),
        orientation: c_field!(o.orientation as enum)?.to_core(c_field!(o.orientation_point))?,
        non_finite: c_field!(o.non_finite as enum)?.into(),
        threads: c_field!(o.threads),
        noise_scale: c_field!(o.noise_scale as bool),
        ..RobustOptions::default()
    };
    let progress = Progress::new(c_field!(o.progress), c_field!(o.progress_user_data));
    Ok((core, progress))
}

/// Smooths 3-D points with the robust mode and writes the smoothed coordinates to
/// `out_coords`, laid out like the input (it may be `points->data` itself, to smooth in
/// place). `out_geometry` (`points->count` elements, computed with the robust normals) and
/// `out_summary` (its `lambda` is the noise-adapted threshold of the first iteration) may be
/// NULL. `options` may be NULL for the defaults. Nothing is written unless the call succeeds;
/// results are identical for any number of threads.
///
/// Slower than nbhd_smooth (each iteration searches the wider neighbourhood and fits
/// candidate planes) but keeps sharp edges at noise of about one spacing, where the faithful
/// method cannot tell noise from features.
///
/// Errors: as nbhd_smooth; INVALID_OPTION also for k_plane < k, a tolerance < 0, a width or
/// angle not > 0, τ outside (0, 1].
///
/// # Safety
/// As nbhd_smooth.
#[no_mangle]
pub unsafe extern "C" fn nbhd_smooth_robust(
    points: *const nbhd_points,
    options: *const nbhd_robust_options,
    out_coords: *mut c_void,
    out_geometry: *mut nbhd_point_geometry,
    out_summary: *mut nbhd_smooth_summary,
) -> nbhd_status {
    guard("nbhd_smooth_robust", || {
        // SAFETY: forwarded from the caller.
        let (arg, pts) = unsafe { read_points(points) }?;
        let out = Outputs::smoothing(out_coords, out_geometry, out_summary)?;
        // SAFETY: forwarded from the caller.
        let (mut opts, mut progress) = unsafe { read_options(options) }?;
        opts.outputs = out.wants_geometry();
        let result =
            smooth::smooth_robust_with_progress(&pts, &opts, &mut |f, s| progress.report(f, s))?;
        // SAFETY: the outputs are writable with the input's layout / for `count` elements
        // (caller); the input view was dropped in `read_points`.
        unsafe { out.write(&result, arg.scalar, arg.stride) };
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffi::nbhd_scalar_type;
    use crate::shapes::{add_noise, sample, NoiseKind, Sphere};
    use glam::DVec3;

    #[test]
    fn defaults_mirror_the_core() {
        // SAFETY: NULL asks for the defaults.
        let (core, progress) = unsafe { read_options(std::ptr::null()) }.unwrap();
        assert_eq!(core, RobustOptions::default());
        assert_eq!(core.threads, 0);
        assert!(progress.is_none());
        let c = nbhd_robust_options_default();
        // SAFETY: a live, initialised options struct.
        let (core, ..) = unsafe { read_options(&c) }.unwrap();
        assert_eq!(core, RobustOptions::default());
    }

    #[test]
    fn robust_smoothing_through_the_abi_equals_the_core() {
        let s = sample(&Sphere::new(1.0), 800, 5);
        let pts = add_noise(&s, 0.5, 0.07, NoiseKind::Gaussian, 6).unwrap();
        let core = smooth::smooth_robust(&pts, &RobustOptions::default()).unwrap();
        let flat: Vec<f64> = pts.iter().flat_map(|p| p.to_array()).collect();
        let desc = nbhd_points {
            data: flat.as_ptr().cast(),
            count: pts.len(),
            dim: 3,
            stride: 0,
            scalar_type: nbhd_scalar_type::F64,
        };
        let mut out = vec![0f64; flat.len()];
        let mut geo = vec![nbhd_point_geometry::default(); pts.len()];
        // SAFETY: the descriptor matches `flat`; the outputs hold `count` elements.
        let status = unsafe {
            nbhd_smooth_robust(
                &desc,
                std::ptr::null(),
                out.as_mut_ptr().cast(),
                geo.as_mut_ptr(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(status, nbhd_status::Ok);
        let got: Vec<DVec3> = out.chunks(3).map(DVec3::from_slice).collect();
        assert_eq!(got, core.points);
        assert_eq!(geo[7], nbhd_point_geometry::from(&core.outputs[7]));
    }

    #[test]
    fn bad_robust_options_are_named() {
        let flat = [
            0.0f64, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.5,
        ];
        let desc = nbhd_points {
            data: flat.as_ptr().cast(),
            count: 4,
            dim: 3,
            stride: 0,
            scalar_type: nbhd_scalar_type::F64,
        };
        let mut out = [0f64; 12];
        let mut o = nbhd_robust_options_default();
        o.k_plane = 3;
        o.k = 4;
        // SAFETY: the descriptor matches `flat`; `out` has its layout.
        let status = unsafe {
            nbhd_smooth_robust(
                &desc,
                &o,
                out.as_mut_ptr().cast(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(status, nbhd_status::InvalidOption);
        assert!(out.iter().all(|&v| v == 0.0));
    }
}
