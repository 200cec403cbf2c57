//! Status codes, the per-thread last error message, and the panic guard every export runs in.

use std::any::Any;
use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr, CString};
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::error::{NbhdError, SavedTreeError};

/// What a fallible nbhd function returns. NBHD_STATUS_OK is 0; every other value is an
/// error, described in words for the calling thread by nbhd_last_error_message().
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum nbhd_status {
    /// Success.
    Ok = 0,
    /// A required pointer argument is NULL (the message names it).
    NullPointer = 1,
    /// A pointer argument is not aligned for the type it points to (the message names it).
    MisalignedPointer = 2,
    /// An argument has a value outside its range: an enum field of an argument struct
    /// (nbhd_points, nbhd_neighborhood_spec, nbhd_normals_output) holding no value of its
    /// enum, a row or index beyond its range, or a points description whose byte size
    /// overflows the address space (`dim * sizeof(scalar)` or `(count - 1) * stride`; the
    /// message names the argument and the values passed).
    InvalidArgument = 3,
    /// The point set is empty: count 0, or no finite point left after skipping.
    EmptyInput = 4,
    /// The dimension of the points is 0.
    ZeroDimension = 5,
    /// The stride between points is smaller than one point (`dim * sizeof(scalar)`).
    StrideTooSmall = 6,
    /// A caller's buffer is too small; for query results the needed size is in `*count`.
    BufferTooSmall = 7,
    /// A point has a NaN or infinite coordinate (the message names the point's index and
    /// the coordinate).
    NonFinite = 8,
    /// A query point has a NaN or infinite coordinate.
    NonFiniteQuery = 9,
    /// More points than `uint32_t` indices address (UINT32_MAX at most).
    TooManyPoints = 10,
    /// k is 0.
    InvalidK = 11,
    /// The radius is negative, NaN or infinite, or too large for the tree's scalar type: its
    /// square must be finite there (for a float tree, at most about 1.8e19; the message gives
    /// the value passed and the limit).
    InvalidRadius = 12,
    /// Query points have a different dimension from the tree.
    DimensionMismatch = 13,
    /// A query by stored index names an index the tree was not given.
    IndexOutOfRange = 14,
    /// A query by stored index names a point skipped at build time (non-finite).
    SkippedPoint = 15,
    /// A field of an options struct (nbhd_*_options) is out of range, an enum field holding
    /// no value of its enum included (the message names the option and the value).
    InvalidOption = 16,
    /// A pool of worker threads could not be created.
    ThreadPool = 17,
    /// The operation was cancelled by the caller.
    Cancelled = 18,
    /// A bug in nbhd: a Rust panic was caught at the ABI boundary (the message has its text).
    /// The objects passed to the call are unchanged and may still be used and freed.
    Internal = 19,
    /// Every neighbourhood is degenerate, so the normals (and curvatures) would be
    /// meaningless: no neighbourhood reached 3 points (the point and two neighbours), or every
    /// normal is flagged degenerate. The usual cause is an ε far below the spacing of the
    /// points — for example `epsilon = 0.01` meant as 1 cm but left in the default RELATIVE
    /// units (0.01 × the mean spacing). The message gives ε resolved to the points' units and
    /// the mean spacing h. Nothing is written.
    Degenerate = 20,
    /// The result does not fit in memory: an allocation whose size comes from the input
    /// (a table with very many neighbours, a huge k) failed. The message says how many bytes
    /// were needed. Nothing is written and the process is unharmed.
    OutOfMemory = 21,
    /// A file could not be opened, read or written (the message names the file and gives
    /// the operating system's reason).
    IoError = 22,
    /// The bytes are not a saved tree this library reads: not a saved nbhd tree at all, or one
    /// of another format version or byte order (the message names what differs: the file's
    /// value and this library's).
    FormatMismatch = 23,
    /// A saved tree is damaged: truncated, followed by other bytes, a checksum that does not
    /// match, or a field or node structure that is inconsistent (the message says which).
    CorruptData = 24,
    /// An index passed to a dynamic tree names a point already removed (indices are never
    /// reused), or is named twice in one removal.
    RemovedPoint = 25,
    /// A query box has a NaN bound or min > max in some coordinate (boxes are closed,
    /// min <= x <= max; infinite bounds are allowed). The message names the box and the
    /// coordinate.
    InvalidBox = 26,
    /// A point lies outside the box of a periodic tree (nbhd_tree_build_periodic,
    /// nbhd_dynamic_new_periodic): on a periodic axis of size L its coordinate is below 0 or
    /// not below L. The message names the point, the coordinate, its value and L.
    OutsidePeriod = 27,
}

impl nbhd_status {
    const ALL: [nbhd_status; 28] = [
        nbhd_status::Ok,
        nbhd_status::NullPointer,
        nbhd_status::MisalignedPointer,
        nbhd_status::InvalidArgument,
        nbhd_status::EmptyInput,
        nbhd_status::ZeroDimension,
        nbhd_status::StrideTooSmall,
        nbhd_status::BufferTooSmall,
        nbhd_status::NonFinite,
        nbhd_status::NonFiniteQuery,
        nbhd_status::TooManyPoints,
        nbhd_status::InvalidK,
        nbhd_status::InvalidRadius,
        nbhd_status::DimensionMismatch,
        nbhd_status::IndexOutOfRange,
        nbhd_status::SkippedPoint,
        nbhd_status::InvalidOption,
        nbhd_status::ThreadPool,
        nbhd_status::Cancelled,
        nbhd_status::Internal,
        nbhd_status::Degenerate,
        nbhd_status::OutOfMemory,
        nbhd_status::IoError,
        nbhd_status::FormatMismatch,
        nbhd_status::CorruptData,
        nbhd_status::RemovedPoint,
        nbhd_status::InvalidBox,
        nbhd_status::OutsidePeriod,
    ];

    /// A short, static description.
    fn description(self) -> &'static CStr {
        use nbhd_status::*;
        match self {
            Ok => c"success",
            NullPointer => c"a required pointer argument is NULL",
            MisalignedPointer => c"a pointer argument is not aligned for its type",
            InvalidArgument => c"an argument is out of range",
            EmptyInput => c"the point set is empty",
            ZeroDimension => c"the dimension of the points is 0",
            StrideTooSmall => c"the stride is smaller than one point",
            BufferTooSmall => c"a buffer is too small",
            NonFinite => c"a point has a NaN or infinite coordinate",
            NonFiniteQuery => c"the query point has a NaN or infinite coordinate",
            TooManyPoints => c"more points than 32-bit indices address",
            InvalidK => c"k must be at least 1",
            InvalidRadius => c"the radius is negative, NaN or infinite",
            DimensionMismatch => c"the dimensions of the query and the tree differ",
            IndexOutOfRange => c"the point index is out of range",
            SkippedPoint => c"the point was skipped at build time",
            InvalidOption => c"an option is out of range",
            ThreadPool => c"a thread pool could not be created",
            Cancelled => c"cancelled",
            Internal => c"internal error in nbhd (a bug; please report it)",
            Degenerate => c"every neighbourhood is degenerate (is epsilon in the right units?)",
            OutOfMemory => c"out of memory",
            IoError => c"a file could not be read or written",
            FormatMismatch => c"not a saved tree of this format version and byte order",
            CorruptData => c"the saved tree is damaged (truncated or corrupted)",
            RemovedPoint => c"the point was removed from the dynamic tree",
            InvalidBox => c"a query box has a NaN bound or min > max",
            OutsidePeriod => c"a point lies outside the periodic box",
        }
    }
}

/// Why an export failed: an error of the core, or one of the ABI's own argument checks.
#[derive(Debug)]
pub(crate) enum FfiError {
    /// The core refused the call.
    Core(NbhdError),
    /// A required pointer is NULL; names the argument.
    Null(String),
    /// A pointer is not aligned for its type.
    Misaligned {
        /// The argument.
        what: String,
        /// Its address.
        addr: usize,
        /// The alignment it needs.
        align: usize,
    },
    /// An argument is out of range (the full message).
    InvalidArgument(String),
}

impl From<NbhdError> for FfiError {
    fn from(e: NbhdError) -> Self {
        FfiError::Core(e)
    }
}

impl FfiError {
    /// The status code C sees.
    pub(crate) fn status(&self) -> nbhd_status {
        use nbhd_status as S;
        match self {
            FfiError::Null(_) => S::NullPointer,
            FfiError::Misaligned { .. } => S::MisalignedPointer,
            FfiError::InvalidArgument(_) => S::InvalidArgument,
            FfiError::Core(e) => match e {
                NbhdError::EmptyInput => S::EmptyInput,
                NbhdError::ZeroDimension => S::ZeroDimension,
                NbhdError::StrideTooSmall { .. } => S::StrideTooSmall,
                NbhdError::BufferTooSmall { .. } => S::BufferTooSmall,
                NbhdError::NonFinite { .. } => S::NonFinite,
                NbhdError::NonFiniteQuery { .. } => S::NonFiniteQuery,
                NbhdError::TooManyPoints { .. } => S::TooManyPoints,
                NbhdError::ZeroK => S::InvalidK,
                NbhdError::InvalidRadius(_) => S::InvalidRadius,
                NbhdError::DimensionMismatch { .. } => S::DimensionMismatch,
                NbhdError::IndexOutOfRange { .. } => S::IndexOutOfRange,
                NbhdError::SkippedPoint { .. } => S::SkippedPoint,
                NbhdError::DuplicateIndex { .. } => S::InvalidArgument,
                NbhdError::RemovedPoint { .. } => S::RemovedPoint,
                NbhdError::InvalidOption { .. } => S::InvalidOption,
                NbhdError::Cancelled => S::Cancelled,
                NbhdError::ThreadPool(_) => S::ThreadPool,
                NbhdError::RadiusOutOfRange { .. } => S::InvalidRadius,
                NbhdError::SizeOverflow { .. } => S::InvalidArgument,
                NbhdError::OutOfMemory { .. } => S::OutOfMemory,
                NbhdError::Degenerate { .. } => S::Degenerate,
                NbhdError::Io { .. } => S::IoError,
                NbhdError::SavedTree(e) => match e {
                    SavedTreeError::NotATree { .. }
                    | SavedTreeError::OtherKind { .. }
                    | SavedTreeError::ByteOrder { .. }
                    | SavedTreeError::FormatVersion { .. }
                    | SavedTreeError::ScalarType { .. } => S::FormatMismatch,
                    SavedTreeError::Dimension { .. } => S::DimensionMismatch,
                    SavedTreeError::Truncated { .. }
                    | SavedTreeError::Checksum { .. }
                    | SavedTreeError::Invalid(_) => S::CorruptData,
                },
                NbhdError::InvalidBox { .. } => S::InvalidBox,
                NbhdError::OutsidePeriod { .. } => S::OutsidePeriod,
            },
        }
    }
}

impl fmt::Display for FfiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            // the core names units as Rust and Python spell them; C users set an enum
            FfiError::Core(e @ NbhdError::Degenerate { relative, .. }) => {
                let units = if *relative { "RELATIVE" } else { "ABSOLUTE" };
                write!(f, "{e} (epsilon_units NBHD_UNITS_{units}")?;
                if *relative {
                    f.write_str("; set NBHD_UNITS_ABSOLUTE for a length in the points' units")?;
                }
                f.write_str(")")
            }
            FfiError::Core(e) => e.fmt(f),
            FfiError::Null(what) => write!(f, "argument {what} is NULL"),
            FfiError::Misaligned { what, addr, align } => write!(
                f,
                "argument {what} ({addr:#x}) is not aligned to {align} bytes"
            ),
            FfiError::InvalidArgument(m) => f.write_str(m),
        }
    }
}

thread_local! {
    /// The message of the last failed call on this thread ("" after a success).
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// Records `message` as this thread's last error, prefixed with the function's name.
fn set_last_error(func: &str, message: &str) {
    let text = format!("{func}: {message}").replace('\0', "\\0");
    let text = CString::new(text).unwrap_or_default();
    // A thread being torn down has no storage left; the status code still reports the error.
    let _ = LAST_ERROR.try_with(|e| {
        if let Ok(mut e) = e.try_borrow_mut() {
            *e = text;
        }
    });
}

/// Clears this thread's last error after a successful call.
fn clear_last_error() {
    let _ = LAST_ERROR.try_with(|e| {
        if let Ok(mut e) = e.try_borrow_mut() {
            if !e.as_bytes().is_empty() {
                *e = CString::default();
            }
        }
    });
}

/// The text of a panic payload.
fn panic_message(payload: &(dyn Any + Send)) -> &str {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s
    } else {
        "(a panic without a message)"
    }
}

/// Runs the body of a status-returning export named `func`: `Ok` clears the thread's last
/// error, an error records its message, and a panic is caught and becomes
/// `NBHD_STATUS_INTERNAL` with the panic's message. Nothing unwinds past this function.
pub(crate) fn guard(func: &str, body: impl FnOnce() -> Result<(), FfiError>) -> nbhd_status {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => {
            clear_last_error();
            nbhd_status::Ok
        }
        Ok(Err(e)) => {
            set_last_error(func, &e.to_string());
            e.status()
        }
        Err(payload) => {
            let message = format!("internal error: Rust panic: {}", panic_message(&*payload));
            // Dropping the payload could panic in turn; keep it from unwinding.
            let _ = catch_unwind(AssertUnwindSafe(move || drop(payload)));
            set_last_error(func, &message);
            nbhd_status::Internal
        }
    }
}

/// Runs the body of an export that returns a value rather than a status: a panic is caught,
/// recorded as the thread's last error, and `fallback` is returned. The last error is
/// otherwise left alone.
pub(crate) fn guard_value<R>(func: &str, fallback: R, body: impl FnOnce() -> R) -> R {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(r) => r,
        Err(payload) => {
            let message = format!("internal error: Rust panic: {}", panic_message(&*payload));
            let _ = catch_unwind(AssertUnwindSafe(move || drop(payload)));
            set_last_error(func, &message);
            fallback
        }
    }
}

/// An nbhd_status passed by value from C: the `int` C passes (a status of a later release, or
/// any integer, must be answered safely; a Rust enum holding it would be undefined
/// behaviour). cbindgen.toml names it `nbhd_status` in the header, so C sees the enum's type.
pub(crate) type StatusArg = c_int;

/// A static, human-readable description of a status code, such as "k must be at least 1".
/// Never NULL, never to be freed. Any value is answered safely: one that is no nbhd_status
/// (a status of a later release, `(nbhd_status)-1`) gives "unknown status".
#[no_mangle]
pub extern "C" fn nbhd_status_string(status: StatusArg) -> *const c_char {
    guard_value("nbhd_status_string", c"unknown status".as_ptr(), || {
        nbhd_status::ALL
            .iter()
            .find(|s| **s as c_int == status)
            .map_or(c"unknown status", |s| s.description())
            .as_ptr()
    })
}

/// The reason the last failed nbhd call on the calling thread failed, in words that name the
/// argument, option or point index at fault, e.g. "nbhd_tree_build: point 7 has a NaN or
/// infinite coordinate (coordinate 2)"; "" if the last status-returning call on this thread
/// succeeded or none was made. Never NULL. Each thread has its own message.
///
/// The string belongs to nbhd: do not free it. It stays valid until the next nbhd call on the
/// same thread; copy it to keep it.
#[no_mangle]
pub extern "C" fn nbhd_last_error_message() -> *const c_char {
    guard_value("nbhd_last_error_message", c"".as_ptr(), || {
        LAST_ERROR
            .try_with(|e| e.borrow().as_ptr())
            .unwrap_or(c"".as_ptr())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn last_error() -> String {
        // SAFETY: nbhd_last_error_message returns a valid NUL-terminated string that lives
        // until the next nbhd call on this thread; it is copied at once.
        unsafe { CStr::from_ptr(nbhd_last_error_message()) }
            .to_str()
            .unwrap()
            .to_owned()
    }

    #[test]
    fn a_panic_becomes_internal_with_its_message() {
        let status = guard("nbhd_test", || panic!("index {} out of bounds", 7));
        assert_eq!(status, nbhd_status::Internal);
        assert_eq!(
            last_error(),
            "nbhd_test: internal error: Rust panic: index 7 out of bounds"
        );
        let status = guard("nbhd_test", || panic!("static text"));
        assert_eq!(status, nbhd_status::Internal);
        assert!(last_error().ends_with("Rust panic: static text"));
    }

    #[test]
    fn a_panic_without_a_message_still_becomes_internal() {
        let status = guard("nbhd_test", || std::panic::panic_any(42_u8));
        assert_eq!(status, nbhd_status::Internal);
        assert!(last_error().contains("a panic without a message"));
    }

    #[test]
    fn a_panic_in_a_value_export_gives_the_fallback() {
        let v = guard_value("nbhd_test_value", 0_usize, || panic!("boom"));
        assert_eq!(v, 0);
        assert_eq!(
            last_error(),
            "nbhd_test_value: internal error: Rust panic: boom"
        );
    }

    #[test]
    fn a_panic_on_a_worker_thread_reaches_the_guard() {
        let status = guard("nbhd_test", || {
            crate::parallel::with_threads(2, || {
                rayon::join(|| (), || panic!("in a worker"));
            })?;
            Ok(())
        });
        assert_eq!(status, nbhd_status::Internal);
        assert!(last_error().ends_with("in a worker"), "{}", last_error());
    }

    #[test]
    fn errors_are_recorded_and_success_clears_them() {
        let status = guard("nbhd_test", || Err(NbhdError::ZeroK.into()));
        assert_eq!(status, nbhd_status::InvalidK);
        assert_eq!(last_error(), "nbhd_test: k must be at least 1");
        assert_eq!(guard("nbhd_test", || Ok(())), nbhd_status::Ok);
        assert_eq!(last_error(), "");
    }

    #[test]
    fn the_last_error_is_per_thread() {
        let _ = guard("nbhd_main", || Err(NbhdError::EmptyInput.into()));
        std::thread::spawn(|| {
            assert_eq!(last_error(), "");
            let _ = guard("nbhd_other", || Err(NbhdError::ZeroK.into()));
            assert!(last_error().starts_with("nbhd_other"));
        })
        .join()
        .unwrap();
        assert!(last_error().starts_with("nbhd_main"));
    }

    #[test]
    fn every_status_has_a_string_and_unknown_values_are_answered() {
        for s in nbhd_status::ALL {
            // SAFETY: static NUL-terminated strings.
            let text = unsafe { CStr::from_ptr(nbhd_status_string(s as c_int)) };
            assert!(!text.to_bytes().is_empty());
        }
        // the first value past the last status, whatever statuses a release adds
        let past_last = nbhd_status::ALL.len() as c_int;
        for bad in [-1, past_last, c_int::MAX, c_int::MIN] {
            // SAFETY: as above.
            let text = unsafe { CStr::from_ptr(nbhd_status_string(bad)) };
            assert_eq!(text.to_str().unwrap(), "unknown status");
        }
    }
}
