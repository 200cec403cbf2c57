//! The one error type of the library. Every fallible function returns it; nothing panics on bad
//! input.

use std::fmt;

/// Why an operation was refused. Each variant names the offending argument or point.
#[derive(Clone, Debug, PartialEq)]
pub enum NbhdError {
    /// The point set has no points (or none left after skipping non-finite ones).
    EmptyInput,
    /// The dimension of the points is 0.
    ZeroDimension,
    /// The stride between points is smaller than one point (`dim * scalar size`).
    StrideTooSmall {
        /// The stride given, in bytes.
        stride: usize,
        /// The size of one point, in bytes.
        point_bytes: usize,
    },
    /// A buffer is shorter than its description requires.
    BufferTooSmall {
        /// Which buffer.
        what: &'static str,
        /// Its length (in bytes or elements, as `what` says).
        len: usize,
        /// The length required.
        needed: usize,
    },
    /// A coordinate is NaN or infinite.
    NonFinite {
        /// Caller's index of the first offending point.
        index: usize,
        /// Which coordinate of it.
        coordinate: usize,
    },
    /// A query point has a NaN or infinite coordinate.
    NonFiniteQuery {
        /// Which coordinate.
        coordinate: usize,
    },
    /// More points than the index type (`u32`) can address.
    TooManyPoints {
        /// Number of points given.
        count: usize,
        /// The largest number supported.
        max: usize,
    },
    /// `k` was 0 for a k-nearest query.
    ZeroK,
    /// The radius is negative, NaN or infinite.
    InvalidRadius(f64),
    /// A query point has a different dimension from the tree.
    DimensionMismatch {
        /// The tree's dimension.
        expected: usize,
        /// The query's dimension.
        got: usize,
    },
    /// A stored-point query named an index that the tree does not hold.
    IndexOutOfRange {
        /// The index given.
        index: usize,
        /// Number of points the caller passed in.
        count: usize,
    },
    /// A stored-point query named a point that was skipped at build time (non-finite).
    SkippedPoint {
        /// The index given.
        index: usize,
    },
    /// An option has a value outside its range.
    InvalidOption {
        /// Which option.
        name: &'static str,
        /// Why it is refused.
        reason: String,
    },
    /// The operation was stopped by the caller's progress callback.
    Cancelled,
    /// A worker thread pool could not be created.
    ThreadPool(String),
}

impl fmt::Display for NbhdError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use NbhdError::*;
        match self {
            EmptyInput => write!(f, "the point set is empty (no finite points)"),
            ZeroDimension => write!(f, "the dimension of the points is 0"),
            StrideTooSmall {
                stride,
                point_bytes,
            } => write!(
                f,
                "stride {stride} bytes is smaller than one point ({point_bytes} bytes)"
            ),
            BufferTooSmall { what, len, needed } => {
                write!(f, "{what} holds {len} but {needed} are needed")
            }
            NonFinite { index, coordinate } => write!(
                f,
                "point {index} has a NaN or infinite coordinate (coordinate {coordinate})"
            ),
            NonFiniteQuery { coordinate } => {
                write!(
                    f,
                    "query point has a NaN or infinite coordinate ({coordinate})"
                )
            }
            TooManyPoints { count, max } => {
                write!(f, "{count} points exceed the supported maximum of {max}")
            }
            ZeroK => write!(f, "k must be at least 1"),
            InvalidRadius(r) => write!(f, "radius {r} is not a finite number >= 0"),
            DimensionMismatch { expected, got } => write!(
                f,
                "query point has dimension {got} but the tree has dimension {expected}"
            ),
            IndexOutOfRange { index, count } => {
                write!(
                    f,
                    "point index {index} is out of range (the set has {count} points)"
                )
            }
            SkippedPoint { index } => write!(
                f,
                "point {index} was skipped at build time (non-finite) and cannot be queried"
            ),
            InvalidOption { name, reason } => write!(f, "option {name}: {reason}"),
            Cancelled => write!(f, "cancelled by the progress callback"),
            ThreadPool(m) => write!(f, "could not create the thread pool: {m}"),
        }
    }
}

impl std::error::Error for NbhdError {}

/// Result alias used throughout nbhd.
pub type Result<T> = std::result::Result<T, NbhdError>;
