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
    /// A point lies outside the box of a periodic tree: a coordinate below 0 or not below the
    /// box size `L` on a periodic axis (points must lie in `[0, L)`; queries are wrapped).
    OutsidePeriod {
        /// Caller's index of the first offending point (its position in the batch for an
        /// insertion into a growing tree).
        index: usize,
        /// Which coordinate of it.
        coordinate: usize,
        /// The coordinate's value.
        value: f64,
        /// The box size of that axis.
        size: f64,
    },
    /// A query point has a NaN or infinite coordinate.
    NonFiniteQuery {
        /// Which query of a batch (`None` for a single query).
        query: Option<usize>,
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
    /// An index subset lists the same point twice (a tree over listed indices, `build_subset`).
    DuplicateIndex {
        /// The caller's index listed twice.
        index: usize,
    },
    /// A stored-point query named a point that was skipped at build time (non-finite).
    SkippedPoint {
        /// The index given.
        index: usize,
    },
    /// An index of a dynamic tree names a point that was removed (indices are never reused).
    RemovedPoint {
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
    /// The radius is finite in the caller's type but not in the tree's scalar type, or its
    /// key overflows it (keys are compared in that type: the square for the Euclidean metric,
    /// `r^p` for a Minkowski p, `src/metric.rs`).
    RadiusOutOfRange {
        /// The radius the caller passed.
        radius: f64,
        /// The tree's scalar type (`"f32"` or `"f64"`).
        scalar: &'static str,
        /// The largest radius whose key is finite in that type.
        max: f64,
    },
    /// A size computed from the caller's description overflows the address space (for
    /// example `dim × sizeof(scalar)` or `(count − 1) × stride`).
    SizeOverflow {
        /// Which argument and how the size was computed, with the values passed.
        what: String,
    },
    /// The output does not fit in memory: an allocation of this size failed (or exceeds what
    /// the address space can hold). Nothing was changed.
    OutOfMemory {
        /// What was being allocated.
        what: &'static str,
        /// Bytes needed (saturated at `u128::MAX` never reached in practice).
        bytes: u128,
    },
    /// Every neighbourhood is degenerate: none reached 3 points (the point and two
    /// neighbours), or every normal is flagged degenerate — usually because ε is far smaller
    /// than the spacing of the points (a relative ε meant as an absolute length, or the
    /// reverse). The result would be meaningless, so it is refused.
    Degenerate {
        /// Number of points (finite points, if others were skipped).
        points: usize,
        /// Size of the largest neighbourhood `|N_i| + 1`, with the point itself.
        largest: usize,
        /// Number of normals flagged degenerate.
        flagged: usize,
        /// ε resolved to the points' units.
        epsilon: f64,
        /// The mean spacing `h` of the points (relative lengths are multiples of it).
        spacing: f64,
        /// Whether ε was given relative to `h`.
        relative: bool,
    },
    /// A saved tree (`KdTree::load`, docs/tree-file-format.md) was refused: another format,
    /// version, scalar type, dimension or byte order, or damaged data. Says what differs.
    SavedTree(SavedTreeError),
    /// Reading or writing a file or stream failed.
    Io {
        /// What was being done, e.g. "reading the saved tree from scan.nbhdtree".
        context: String,
        /// The operating system's kind of error.
        kind: std::io::ErrorKind,
        /// The operating system's message.
        message: String,
    },
    /// A query box has a NaN bound or `min > max` in some coordinate (an inverted box is
    /// refused rather than taken as empty: it is nearly always a pair of swapped corners).
    InvalidBox {
        /// Which box of a batch (`None` for a single box).
        query: Option<usize>,
        /// The first offending coordinate.
        coordinate: usize,
        /// Its lower bound.
        min: f64,
        /// Its upper bound.
        max: f64,
    },
}

/// Why a saved tree was refused; each variant names what differs from what this library reads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SavedTreeError {
    /// The input does not start with the magic bytes of a saved tree.
    NotATree {
        /// The first bytes found (at most 8).
        found: Vec<u8>,
        /// The magic expected: "NBHDTREE" (a static tree) or "NBHDFRST" (a dynamic tree).
        expected: &'static str,
    },
    /// The input is a saved nbhd tree of the other kind: a static tree where a dynamic one was
    /// asked for, or the reverse.
    OtherKind {
        /// What the input holds ("a static tree (NBHDTREE)" or "a dynamic tree (NBHDFRST)").
        file: &'static str,
        /// What was asked for.
        expected: &'static str,
    },
    /// The file was written on a machine of the other byte order.
    ByteOrder {
        /// The file's byte order ("big-endian" or "little-endian").
        file: &'static str,
        /// This machine's.
        machine: &'static str,
    },
    /// The file's format version is not the one this library reads.
    FormatVersion {
        /// The file's format version.
        file: u32,
        /// The version this library reads.
        supported: u32,
        /// The library version that wrote the file, as "MAJOR.MINOR.PATCH".
        written_by: String,
    },
    /// The file holds coordinates of another scalar type than the tree asked for.
    ScalarType {
        /// The file's type ("f32" or "f64").
        file: &'static str,
        /// The type asked for.
        expected: &'static str,
    },
    /// The file's tree has another dimension than the one asked for.
    Dimension {
        /// The file's dimension.
        file: usize,
        /// The dimension asked for.
        expected: usize,
    },
    /// The input ends before the data its header declares.
    Truncated {
        /// Bytes the header declares (header and payload).
        needed: u64,
        /// Bytes present.
        available: u64,
    },
    /// A checksum does not match: the data were changed after they were written.
    Checksum {
        /// "header" or "payload".
        part: &'static str,
        /// The CRC-32 stored in the file.
        stored: u32,
        /// The CRC-32 of the bytes read.
        computed: u32,
    },
    /// A field or the tree's structure is inconsistent (the message names which and why).
    Invalid(String),
}

impl fmt::Display for SavedTreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SavedTreeError::*;
        match self {
            NotATree { found, expected } => write!(
                f,
                "not a saved nbhd tree: it starts with {:?}, not \"{expected}\"",
                String::from_utf8_lossy(found)
            ),
            OtherKind { file, expected } => {
                write!(f, "the input holds {file}, but {expected} was asked for")
            }
            ByteOrder { file, machine } => write!(
                f,
                "the saved tree was written on a {file} machine and this one is {machine}"
            ),
            FormatVersion {
                file,
                supported,
                written_by,
            } => write!(
                f,
                "the saved tree has format version {file} (written by nbhd {written_by}); this \
                 library reads format version {supported}"
            ),
            ScalarType { file, expected } => write!(
                f,
                "the saved tree holds {file} coordinates but a tree of {expected} was asked for"
            ),
            Dimension { file, expected } => write!(
                f,
                "the saved tree has dimension {file} but dimension {expected} was asked for"
            ),
            Truncated { needed, available } => write!(
                f,
                "the saved tree is truncated: its header declares {needed} bytes but only \
                 {available} are present"
            ),
            Checksum {
                part,
                stored,
                computed,
            } => write!(
                f,
                "the saved tree's {part} is corrupted: its CRC-32 is {computed:#010x} but \
                 {stored:#010x} was stored"
            ),
            Invalid(what) => write!(f, "the saved tree is corrupted: {what}"),
        }
    }
}

/// Bytes as a short human-readable size, e.g. "7.2 GB".
fn human_bytes(b: u128) -> String {
    let v = b as f64;
    if v >= 1e12 {
        format!("{:.1} TB", v / 1e12)
    } else if v >= 1e9 {
        format!("{:.1} GB", v / 1e9)
    } else if v >= 1e6 {
        format!("{:.1} MB", v / 1e6)
    } else {
        format!("{b} bytes")
    }
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
            OutsidePeriod {
                index,
                coordinate,
                value,
                size,
            } => {
                let at = format!("coordinate {coordinate} is {value}, outside [0, {size})");
                write!(f, "point {index} lies outside the periodic box: {at}")
            }
            NonFiniteQuery { query, coordinate } => write!(
                f,
                "query point{} has a NaN or infinite coordinate (coordinate {coordinate})",
                query.map_or(String::new(), |q| format!(" {q}"))
            ),
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
            DuplicateIndex { index } => write!(
                f,
                "point index {index} is listed more than once in the index subset"
            ),
            SkippedPoint { index } => write!(
                f,
                "point {index} was skipped at build time (non-finite) and cannot be queried"
            ),
            RemovedPoint { index } => write!(
                f,
                "point {index} was removed from the dynamic tree (its index is not reused)"
            ),
            InvalidOption { name, reason } => write!(f, "option {name}: {reason}"),
            Cancelled => write!(f, "cancelled by the progress callback"),
            ThreadPool(m) => write!(f, "could not create the thread pool: {m}"),
            RadiusOutOfRange {
                radius,
                scalar,
                max,
            } => write!(
                f,
                "radius {radius:e} is too large for a tree of {scalar}: squared distances (keys \
                 of the metric) are compared in {scalar}, and radii above {max:.4e} overflow it"
            ),
            SizeOverflow { what } => write!(f, "{what} overflows the address space"),
            OutOfMemory { what, bytes } => write!(
                f,
                "out of memory: {what} needs {bytes} bytes ({}), which could not be allocated",
                human_bytes(*bytes)
            ),
            Degenerate {
                points,
                largest,
                flagged,
                epsilon,
                spacing,
                relative,
            } => write_degenerate(
                f, *points, *largest, *flagged, *epsilon, *spacing, *relative,
            ),
            SavedTree(e) => e.fmt(f),
            Io {
                context, message, ..
            } => write!(f, "{context}: {message}"),
            InvalidBox {
                query,
                coordinate,
                min,
                max,
            } => write_invalid_box(f, *query, *coordinate, *min, *max),
        }
    }
}

/// Why no normal is defined ([`NbhdError::Degenerate`]): the neighbourhood sizes, then ε as it
/// was resolved and the units it was given in, as the command line and Python spell them
/// (`src/names.rs`).
fn write_degenerate(
    f: &mut fmt::Formatter<'_>,
    points: usize,
    largest: usize,
    flagged: usize,
    epsilon: f64,
    spacing: f64,
    relative: bool,
) -> fmt::Result {
    if largest < 3 {
        write!(
            f,
            "no neighbourhood reached 3 points (the largest has {largest} with the point \
             itself), so no normal is defined"
        )?;
    } else {
        write!(
            f,
            "all {flagged} of {points} normals are degenerate (too few, collinear or \
             coincident neighbours)"
        )?;
    }
    write!(
        f,
        ": epsilon resolved to {epsilon:e} in the points' units (mean spacing h = {spacing:e})"
    )?;
    if relative {
        write!(
            f,
            "; epsilon was taken relative to h (units \"relative\"): for a length in the \
             points' units give its units as \"absolute\""
        )
    } else {
        write!(
            f,
            "; epsilon was taken in the points' units (units \"absolute\")"
        )
    }
}

/// Which bound of a box ([`NbhdError::InvalidBox`]) is wrong, and how: NaN or swapped corners.
fn write_invalid_box(
    f: &mut fmt::Formatter<'_>,
    query: Option<usize>,
    coordinate: usize,
    min: f64,
    max: f64,
) -> fmt::Result {
    match query {
        Some(q) => write!(f, "box {q}")?,
        None => write!(f, "the box")?,
    }
    write!(
        f,
        " has min {min} and max {max} in coordinate {coordinate}: "
    )?;
    if min.is_nan() || max.is_nan() {
        write!(f, "a bound is NaN")
    } else {
        write!(
            f,
            "min > max (swapped corners?); a box is closed, min <= x <= max"
        )
    }
}

impl std::error::Error for NbhdError {}

impl From<SavedTreeError> for NbhdError {
    fn from(e: SavedTreeError) -> Self {
        NbhdError::SavedTree(e)
    }
}

impl NbhdError {
    /// An I/O error while `context` (e.g. "writing the saved tree").
    pub(crate) fn io(context: impl Into<String>, e: &std::io::Error) -> Self {
        NbhdError::Io {
            context: context.into(),
            kind: e.kind(),
            message: e.to_string(),
        }
    }
}

impl NbhdError {
    /// The error of query `index` of a batch: a non-finite query names it.
    pub(crate) fn for_query(self, index: usize) -> Self {
        match self {
            NbhdError::NonFiniteQuery { coordinate, .. } => NbhdError::NonFiniteQuery {
                query: Some(index),
                coordinate,
            },
            e => e,
        }
    }
}

/// Result alias used throughout nbhd.
pub type Result<T> = std::result::Result<T, NbhdError>;
