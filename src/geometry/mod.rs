//! Differential geometry of point sets (thesis Section 2.1.2 and 2.2): normals from the
//! covariance of each neighbourhood (eq. 2.8–2.10), directional curvatures (eq. 2.20) and the
//! Weingarten-map estimate of principal curvatures and directions (eq. 2.26–2.29, 2.25).

pub mod neighbors;
