//! What the normals, curvature and smoothing exports share: the caller's 3-D points read in
//! double, the progress callback as the core's progress closure, and the outputs — the
//! coordinates written back in the input's layout, the per-point geometry and the summary.

use std::ffi::c_void;

use glam::DVec3;

use super::args::{check_aligned, check_optional, check_ptr};
use super::enums::nbhd_stage;
use super::status::FfiError;
use super::types::{nbhd_points, PointsArg};
use crate::error::NbhdError;
use crate::points::PointsView;
use crate::scalar::ScalarType;
use crate::smooth::{PointOutput, SmoothResult, Stage};

/// A progress callback: `fraction` grows from 0 to 1 over the run; return `true` to go on,
/// `false` to stop the run, which then returns NBHD_STATUS_CANCELLED and writes no output.
/// It is called from the thread that runs the computation (the calling thread when
/// `threads` is 0, otherwise a worker of the call's own pool), never from two threads at
/// once, and must return normally (no longjmp, no C++ exception).
pub type nbhd_progress_fn =
    Option<unsafe extern "C" fn(fraction: f64, stage: nbhd_stage, user_data: *mut c_void) -> bool>;

/// The C progress callback of one call with its user data: [`Progress::report`] is the core's
/// progress closure.
pub(super) struct Progress {
    callback: nbhd_progress_fn,
    user_data: *mut c_void,
}

// SAFETY: the callback and its user data are the caller's; the header tells C that the
// callback may run on a worker thread of the call's pool (never on two threads at once),
// which is all that moving them to that thread needs.
unsafe impl Send for Progress {}

impl Progress {
    /// The callback (NULL for none) and the user data it is called with.
    pub(super) fn new(callback: nbhd_progress_fn, user_data: *mut c_void) -> Self {
        Self {
            callback,
            user_data,
        }
    }

    /// Whether there is no callback.
    #[cfg(test)]
    pub(super) fn is_none(&self) -> bool {
        self.callback.is_none()
    }

    /// Calls the callback, if any; `false` asks the core to stop.
    pub(super) fn report(&mut self, fraction: f64, stage: Stage) -> bool {
        match self.callback {
            // SAFETY: a C function pointer the caller gave for this purpose, called with the
            // user data it gave and plain values.
            Some(f) => unsafe { f(fraction, stage.into(), self.user_data) },
            None => true,
        }
    }
}

/// The per-point geometry the thesis' program colours by (Section 7.3), on the final points.
/// Curvatures are signed relative to the reported normal.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_point_geometry {
    /// Unit normal (eq. 2.10), oriented as the options ask.
    pub normal: [f64; 3],
    /// Larger principal curvature k1 (Weingarten estimate, eq. 2.25–2.29).
    pub k1: f64,
    /// Smaller principal curvature k2.
    pub k2: f64,
    /// Unit principal direction of k1.
    pub dir1: [f64; 3],
    /// Unit principal direction of k2.
    pub dir2: [f64; 3],
    /// 'Mean': (k1 + k2) / 2.
    pub mean_curvature: f64,
    /// 'Max Princ': max(|k1|, |k2|).
    pub max_principal_curvature: f64,
    /// 'CovQuotient': λ0/(λ0 + λ1 + λ2) of the covariance (0 flat, at most 1/3).
    pub covariance_quotient: f64,
    /// 'MeanAni': Σ g κ / Σ g over the neighbours, with the chosen weights (0 if all vanish).
    pub anisotropic_mean_curvature: f64,
    /// 'PrincQuotient': min(|k1|,|k2|) / max(|k1|,|k2|) in [0, 1].
    pub principal_curvature_quotient: f64,
    /// 'MaxCov': the largest covariance eigenvalue over the neighbourhood size.
    pub max_covariance: f64,
    /// Why the normal is not to be trusted, 0 if it is: 1 fewer than 3 points, 2 collinear or
    /// coincident points, 4 the normal is not unique (isotropic neighbourhood), 8 the point
    /// was skipped for a NaN or infinite coordinate (everything else is NaN then).
    pub normal_flags: u8,
    /// Whether the feature criterion selects the point.
    pub feature: bool,
    /// Whether 'constrain interior' holds the point fixed.
    pub interior: bool,
}

/// Scalars a run resolved: the spacing estimate and the absolute thresholds it used.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct nbhd_smooth_summary {
    /// Mean nearest-neighbour spacing h of the input.
    pub spacing: f64,
    /// The absolute ε used.
    pub epsilon: f64,
    /// The absolute λ used.
    pub lambda: f64,
    /// 'Min Neighbors': the smallest neighbourhood size |N_i| of the input.
    pub min_neighbors: usize,
}

/// Reads the caller's points into 3-D double positions (the smoothing computes in double).
///
/// # Safety
/// `points` must be NULL or describe readable memory (see nbhd_points).
pub(super) unsafe fn read_points(
    points: *const nbhd_points,
) -> Result<(PointsArg, Vec<DVec3>), FfiError> {
    // SAFETY: forwarded from the caller.
    let arg = unsafe { PointsArg::read(points, "points") }?;
    // SAFETY: the caller's description of the point memory is true (contract above); the
    // view is dropped before this function returns, so later writes to an aliasing output
    // buffer never overlap a live borrow.
    let view: PointsView<'_> = unsafe { arg.view() }?;
    if view.dim() != 3 {
        return Err(FfiError::InvalidArgument(format!(
            "points->dim is {}; normals, curvatures and smoothing need 3-D points",
            view.dim()
        )));
    }
    let mut xyz = [0.0f64; 3];
    let pts = (0..view.len())
        .map(|i| {
            view.read_point(i, &mut xyz);
            DVec3::from_array(xyz)
        })
        .collect();
    Ok((arg, pts))
}

/// One strided output array of a caller's (coordinates, normals, curvatures): where, how far
/// apart, in which scalar type. The one writer of values into a caller's strided layout, the
/// output twin of [`PointsView`], which reads one.
pub(super) struct Strided {
    at: *mut u8,
    stride: usize,
    scalar: ScalarType,
}

impl Strided {
    /// Checks a strided array of `count` points of `width` values named `what`: the stride
    /// (0 = packed) holds one point's values and the span does not overflow.
    pub(super) fn new(
        at: *mut c_void,
        stride: usize,
        scalar: ScalarType,
        width: usize,
        count: usize,
        what: &str,
    ) -> Result<Self, FfiError> {
        let size = width * scalar.size();
        let stride = if stride == 0 { size } else { stride };
        if stride < size {
            return Err(FfiError::InvalidArgument(format!(
                "out->{what}_stride {stride} is smaller than {width} value(s) of {} bytes",
                scalar.size()
            )));
        }
        if (count.max(1) - 1)
            .checked_mul(stride)
            .and_then(|b| b.checked_add(size))
            .is_none_or(|b| b > isize::MAX as usize)
        {
            return Err(NbhdError::SizeOverflow {
                what: format!("out->{what} with {count} points and stride {stride}"),
            }
            .into());
        }
        Ok(Self {
            at: at.cast(),
            stride,
            scalar,
        })
    }

    /// The layout of a caller's points, already checked as a [`PointsView`] of them (`stride`
    /// resolved, the span in the address space): where smoothed coordinates go back.
    pub(super) fn of_points(at: *mut c_void, stride: usize, scalar: ScalarType) -> Self {
        Self {
            at: at.cast(),
            stride,
            scalar,
        }
    }

    /// Writes the values of point `i`, unaligned.
    ///
    /// # Safety
    /// The array must be writable for point `i` in the layout checked by [`Strided::new`], and
    /// no Rust borrow of it may be live.
    pub(super) unsafe fn write(&self, i: usize, values: &[f64]) {
        let size = self.scalar.size();
        for (c, &v) in values.iter().enumerate() {
            // SAFETY: inside point i's values of the caller's writable array (caller); the
            // offset cannot overflow (checked in `new`); unaligned writes.
            unsafe {
                let p = self.at.add(i * self.stride + c * size);
                match self.scalar {
                    ScalarType::F32 => p.cast::<f32>().write_unaligned(v as f32),
                    ScalarType::F64 => p.cast::<f64>().write_unaligned(v),
                }
            }
        }
    }
}

impl From<&PointOutput> for nbhd_point_geometry {
    fn from(o: &PointOutput) -> Self {
        Self {
            normal: o.normal.to_array(),
            k1: o.principal.k1,
            k2: o.principal.k2,
            dir1: o.principal.dir1.to_array(),
            dir2: o.principal.dir2.to_array(),
            mean_curvature: o.mean_curvature,
            max_principal_curvature: o.max_principal_curvature,
            covariance_quotient: o.covariance_quotient,
            anisotropic_mean_curvature: o.anisotropic_mean_curvature,
            principal_curvature_quotient: o.principal_curvature_quotient,
            max_covariance: o.max_covariance,
            normal_flags: o.normal_flags,
            feature: o.feature,
            interior: o.interior,
        }
    }
}

impl From<&SmoothResult> for nbhd_smooth_summary {
    fn from(r: &SmoothResult) -> Self {
        Self {
            spacing: r.spacing,
            epsilon: r.epsilon,
            lambda: r.lambda,
            min_neighbors: r.min_neighbors,
        }
    }
}

/// Writes `values` to `out[0..values.len()]`.
///
/// # Safety
/// `out` must be non-NULL, aligned and point to `values.len()` writable `T`s.
unsafe fn write_all<T: Copy>(out: *mut T, values: &[T]) {
    // SAFETY: `out` is non-NULL, aligned and holds `values.len()` writable elements (caller);
    // it cannot overlap `values`, which is nbhd's own memory.
    unsafe { std::ptr::copy_nonoverlapping(values.as_ptr(), out, values.len()) };
}

/// The output pointers of a smoothing or curvature export, checked for NULL and alignment
/// before anything is computed.
pub(super) struct Outputs {
    /// NULL for a curvature export.
    coords: *mut c_void,
    geometry: *mut nbhd_point_geometry,
    summary: *mut nbhd_smooth_summary,
}

impl Outputs {
    /// A smoothing export's outputs: `coords` is required (written unaligned, so only NULL is
    /// refused), `geometry` and `summary` may be NULL.
    pub(super) fn smoothing(
        coords: *mut c_void,
        geometry: *mut nbhd_point_geometry,
        summary: *mut nbhd_smooth_summary,
    ) -> Result<Self, FfiError> {
        check_aligned(coords.cast_const(), 1, "out_coords")?;
        check_optional(geometry.cast_const(), "out_geometry")?;
        check_optional(summary.cast_const(), "out_summary")?;
        Ok(Self {
            coords,
            geometry,
            summary,
        })
    }

    /// A curvature export's outputs: `geometry` is required, `summary` may be NULL.
    pub(super) fn curvatures(
        geometry: *mut nbhd_point_geometry,
        summary: *mut nbhd_smooth_summary,
    ) -> Result<Self, FfiError> {
        check_ptr(geometry.cast_const(), "out_geometry")?;
        check_optional(summary.cast_const(), "out_summary")?;
        Ok(Self {
            coords: std::ptr::null_mut(),
            geometry,
            summary,
        })
    }

    /// Whether the per-point geometry is asked for (leaving it NULL skips that work).
    pub(super) fn wants_geometry(&self) -> bool {
        !self.geometry.is_null()
    }

    /// Writes the result: the coordinates (if asked) in the layout `scalar`/`stride` (the
    /// input points' layout, [`Strided::of_points`]), the geometry and the summary (if asked).
    ///
    /// # Safety
    /// Each non-NULL pointer must be writable for `result.points.len()` points in that layout
    /// / `result.outputs.len()` elements / one element, and no Rust borrow of that memory may
    /// be live (the input view is dropped in [`read_points`]).
    pub(super) unsafe fn write(&self, result: &SmoothResult, scalar: ScalarType, stride: usize) {
        if !self.coords.is_null() {
            let out = Strided::of_points(self.coords, stride, scalar);
            for (i, p) in result.points.iter().enumerate() {
                // SAFETY: point `i` of the caller's layout, writable (caller).
                unsafe { out.write(i, &p.to_array()) };
            }
        }
        if !self.geometry.is_null() {
            // straight into the caller's array: a copy of a million elements first would be
            // another 150 MB to allocate and write
            for (i, o) in result.outputs.iter().enumerate() {
                // SAFETY: element `i` of the caller's array, non-NULL and aligned (checked by
                // the constructors) and writable for `result.outputs.len()` elements (caller).
                unsafe { self.geometry.add(i).write(o.into()) };
            }
        }
        if !self.summary.is_null() {
            // SAFETY: as above.
            unsafe { write_all(self.summary, &[nbhd_smooth_summary::from(result)]) };
        }
    }
}
