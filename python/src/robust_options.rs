//! The robust mode's keyword arguments (`nbhd::smooth::RobustOptions`), written once: the
//! [`robust_keywords!`] list below makes both `smooth_robust`'s signature and that of
//! `RobustOptions`, the options object the tiled run's `RobustRun` and `RobustTile` take, so the
//! two cannot drift apart (names, types, defaults).

use nbhd::smooth::RobustOptions;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::options;

/// Makes, from one list of `name: type = default` keywords: the struct of their values
/// (`RobustKeywords`), the class `RobustOptions` built from them, and the function
/// `smooth_robust` taking them (and `non_finite`, `threads`) after its points.
macro_rules! robust_keywords {
    ($($name:ident: $ty:ty = $default:tt),* $(,)?) => {
        /// The keywords of the robust mode as the caller gave them.
        struct RobustKeywords<'a> {
            $($name: $ty,)*
        }

        impl RobustKeywords<'_> {
            /// The keywords as a dict (what `RobustOptions` is pickled as).
            fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
                let d = PyDict::new(py);
                $(d.set_item(stringify!($name), self.$name)?;)*
                Ok(d)
            }
        }

        #[pymethods]
        impl PyRobustOptions {
            /// The options of `smooth_robust` (without `non_finite` and `threads`), checked.
            #[new]
            #[pyo3(signature = (*, $($name = $default),*))]
            #[allow(clippy::too_many_arguments)]
            fn new<'a>(py: Python<'_>, $($name: $ty),*) -> PyResult<Self> {
                let keywords = RobustKeywords { $($name),* };
                Ok(Self {
                    options: keywords.options("reject", 0)?,
                    keywords: keywords.to_dict(py)?.unbind(),
                })
            }

            /// The keywords `RobustOptions(**keywords)` is made again from (pickling).
            fn __getnewargs_ex__<'py>(
                &self,
                py: Python<'py>,
            ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
                Ok((PyTuple::empty(py), self.keywords.bind(py).copy()?))
            }

            fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
                let mut parts = Vec::new();
                for (key, value) in self.keywords.bind(py).iter() {
                    parts.push(format!("{key}={}", value.repr()?));
                }
                Ok(format!("RobustOptions({})", parts.join(", ")))
            }
        }

        /// Smooths an (n, 3) point array with the robust mode (`nbhd.smooth.robust`): normals
        /// chosen among shifted neighbourhoods' planes, weights from distances to the
        /// neighbours' tangent planes scaled by the estimated noise σ̂, and a stopping rule;
        /// one default setting for every shape and noise level.
        ///
        /// `noise_scale` (None: the library's default, on) widens the neighbourhoods while the
        /// cloud reads as a ball of noise (noise of about two spacings or more).
        ///
        /// Returns the dict of `smooth()` plus `normals` (the robust normals of the last
        /// step), `noise` (σ̂ of each iteration's input, in h), `moved` (RMS displacement per
        /// iteration, in h), `dimension` (the local dimension of each check of the noise
        /// scale: 2 a surface, 3 a ball of noise) and `wide_iterations` (the iterations that
        /// used the wide neighbourhoods).
        #[pyfunction]
        #[pyo3(signature = (points, *, $($name = $default,)* non_finite = "reject",
                            threads = 0))]
        #[allow(clippy::too_many_arguments)]
        pub fn smooth_robust<'py, 'a>(
            py: Python<'py>,
            points: &Bound<'py, PyAny>,
            $($name: $ty,)*
            non_finite: &str,
            threads: usize,
        ) -> PyResult<Bound<'py, PyDict>> {
            let options = RobustKeywords { $($name),* }.options(non_finite, threads)?;
            crate::geometry::smooth_robust_dict(py, points, &options)
        }
    };
}

robust_keywords! {
    k: usize = 24,
    k_plane: usize = 48,
    epsilon: f64 = 12.0,
    epsilon_units: &'a str = "relative",
    max_iterations: usize = 10,
    tolerance: f64 = 0.05,
    inlier_width: f64 = 5.0,
    feature_angle: f64 = 20.0,
    tau: f64 = 1.0,
    noise_scale: Option<bool> = None,
    orientation: &'a str = "unoriented",
    orientation_point: [f64; 3] = [0.0, 0.0, 0.0],
    outputs: bool = false,
}

impl RobustKeywords<'_> {
    /// The library's options from the keywords, with the non-finite policy and thread count.
    fn options(&self, non_finite: &str, threads: usize) -> PyResult<RobustOptions> {
        let defaults = RobustOptions::default();
        Ok(RobustOptions {
            k: self.k,
            k_plane: self.k_plane,
            epsilon: options::length(self.epsilon, self.epsilon_units)?,
            max_iterations: self.max_iterations,
            tolerance: self.tolerance,
            inlier_width: self.inlier_width,
            feature_angle: self.feature_angle,
            tau: self.tau,
            noise_scale: self.noise_scale.unwrap_or(defaults.noise_scale),
            orientation: options::orientation(self.orientation, self.orientation_point)?,
            outputs: self.outputs,
            non_finite: options::non_finite(non_finite)?,
            threads,
        })
    }
}

/// The options of a robust run, made with the keywords of `smooth_robust` (but `non_finite`
/// and `threads`: a tiled run takes finite points and each tile runs on one worker thread):
/// what `RobustRun` and `RobustTile` take. Picklable.
#[pyclass(module = "nbhd._nbhd", name = "RobustOptions", frozen)]
pub struct PyRobustOptions {
    pub(crate) options: RobustOptions,
    keywords: Py<PyDict>,
}
