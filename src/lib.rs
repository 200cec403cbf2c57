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
#![warn(clippy::undocumented_unsafe_blocks)]

pub mod dynamic;
pub mod error;
#[doc(hidden)]
pub mod ffi;
pub mod filter;
pub mod geometry;
pub mod handle;
pub mod index;
#[cfg(feature = "io")]
pub mod io;
pub(crate) mod linalg;
pub mod metric;
pub mod names;
pub(crate) mod packed;
pub(crate) mod parallel;
pub mod points;
pub(crate) mod prefetch;
pub(crate) mod progress;
pub mod query;
pub mod scalar;
pub(crate) mod scatter;
pub(crate) mod select;
#[cfg(any(test, feature = "shapes"))]
pub mod shapes;
pub mod simd;
pub mod smooth;
pub mod sum;
pub mod table;
pub mod tree;

pub use dynamic::DynamicKdTree;
pub use error::{NbhdError, Result};
pub use index::{IndexRows, NeighborIndex, PairWeights, Spacing};
pub use metric::Metric;
pub use packed::NonFinitePolicy;
pub use parallel::MAX_THREADS;
pub use points::{PointsView, MAX_POINTS};
pub use query::brute::BruteForce;
pub use query::pca_sweep::PcaSweep;
pub use query::{Neighbor, NeighborSearch, Neighborhood, NeighborhoodSpec, Query, QueryOptions};
pub use scalar::{Scalar, ScalarType};
pub use select::radix::{select_in_parts, DigitCounts, OrderKey, RankSearch, RankStep};
pub use sum::ExactSum;
pub use table::{NeighborTable, TableOptions};
pub use tree::{BuildOptions, KdTree, MedianAlgorithm, NodeInfo, Persist, PivotPolicy, TreeStats};

/// The Rust code blocks of README.md and docs/features.md, compiled and run as doctests (`cargo
/// test --doc`), so that what the documents show keeps to the API as it is. Built for doctests
/// only.
#[cfg(doctest)]
pub mod doc_examples {
    #[doc = include_str!("../README.md")]
    pub struct Readme;
    #[doc = include_str!("../docs/features.md")]
    pub struct Features;
}
