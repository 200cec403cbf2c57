//! Differential geometry of point sets (thesis Section 2.1.2 and 2.2): normals from the
//! covariance of each neighbourhood (eq. 2.8–2.10; over a whole point set, [`estimate_normals`]
//! in `estimate.rs`), directional curvatures (eq. 2.20) and the Weingarten-map estimate of
//! principal curvatures and directions (eq. 2.26–2.29, 2.25); where the neighbourhoods come
//! from (`source.rs`: the call's own search, or a caller's table or tree).

mod covariance;
pub mod curvature;
mod eigen;
pub mod estimate;
pub mod neighbors;
pub mod normals;
pub mod orientation;
pub(crate) mod robust_plane;
pub mod source;

pub use curvature::{
    directional_curvature, principal_curvatures, DensityForm, PrincipalCurvatures, PrincipalFormula,
};
pub use estimate::{
    estimate_normals, estimate_normals_from, NormalEstimate, NormalOptions, NormalsResult,
};
pub use normals::{local_frame, local_frames, LocalFrame};
pub use orientation::{orient, orient_with_progress, Orientation, OrientationKind};
pub use source::{Neighbors, SearchMethod};
