//! Differential geometry of point sets (thesis Section 2.1.2 and 2.2): normals from the
//! covariance of each neighbourhood (eq. 2.8–2.10), directional curvatures (eq. 2.20) and the
//! Weingarten-map estimate of principal curvatures and directions (eq. 2.26–2.29, 2.25).

mod covariance;
pub mod curvature;
mod eigen;
pub mod neighbors;
pub mod normals;
pub mod orientation;
pub(crate) mod robust_plane;

pub use curvature::{
    directional_curvature, principal_curvatures, DensityForm, PrincipalCurvatures, PrincipalFormula,
};
pub use normals::{local_frame, local_frames, LocalFrame};
pub use orientation::{orient, orient_normals_with_progress, orient_with_progress, Orientation};
