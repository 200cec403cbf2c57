//! # nbhd — exact neighbourhoods in point clouds, and the smoothing that needs them
//!
//! nbhd builds k-d trees over d-dimensional points with every build variant of M. Skrodzki,
//! *Neighborhood Computation of Point Set Surfaces* (pivot policies of Sections 3.2 and 5.4,
//! median algorithms of Chapter 6), answers exact k-nearest, radius and ε-k neighbourhood
//! queries (Chapter 5), and uses them for point-set smoothing (Chapter 2).
//!
//! Conventions: indices are the caller's; a radius is a plain Euclidean radius and inclusive
//! (`‖x − q‖ ≤ ε`); distances come back squared (`sq_dist`); results are ordered by
//! `(sq_dist, index)`, identical for any number of threads.
#![warn(missing_docs)]

pub mod cloud;
pub mod error;
pub mod linalg;
pub mod points;
pub mod query;
pub mod scalar;
pub mod table;

pub use cloud::NonFinitePolicy;
pub use error::{NbhdError, Result};
pub use points::{PointsView, MAX_POINTS};
pub use query::brute::BruteForce;
pub use query::{Neighbor, NeighborSearch, Neighborhood, Query};
pub use scalar::{Scalar, ScalarType};
pub use table::NeighborTable;

// Normals (eq. 2.8–2.10), directional curvatures (eq. 2.20) and principal curvatures from
// the Weingarten estimate (eq. 2.25–2.29) of point sets; the neighbourhood entry point.
pub mod geometry;
// Analytic test shapes (cube, sphere, torus, cylinder ∪ plane, catenoid for the Costa
// surface) at the sizes of Fig. 8.2, seeded noise, and the smoothing quality metrics.
pub mod shapes;
// Isotropic (eq. 2.16, 2.18) and anisotropic (eq. 2.30–2.35) smoothing with the settings of
// Section 7.3.
pub mod smooth;
