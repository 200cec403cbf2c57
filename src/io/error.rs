//! The error of file reading and writing: it names the file and, where reading failed, the
//! line (text formats and headers) or byte offset (binary data).

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file reading failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number (text data and headers).
    Line(usize),
    /// 0-based byte offset from the start of the file (binary data).
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// What went wrong.
#[derive(Debug)]
pub enum IoErrorKind {
    /// The operating system refused to open, read or write the file.
    Io(std::io::Error),
    /// The format (or a variant of it, such as a PCD field type) is not supported.
    Unsupported(String),
    /// The file is not well-formed: the message says what was expected.
    Malformed(String),
    /// The cloud handed to a writer is inconsistent (e.g. 10 positions but 9 normals).
    InvalidCloud(String),
}

/// Error of [`read`](super::read()) and [`write`](super::write()): the file, the place in it
/// (when known) and what went wrong. Displays as `path: line 12: message`.
#[derive(Debug)]
pub struct IoError {
    /// The file read or written (`<memory>` for in-memory data).
    pub path: PathBuf,
    /// Where in the file reading failed, if it got that far.
    pub location: Option<Location>,
    /// What went wrong.
    pub kind: IoErrorKind,
}

impl IoError {
    pub(crate) fn new(path: &Path, kind: IoErrorKind) -> Self {
        Self {
            path: path.to_path_buf(),
            location: None,
            kind,
        }
    }
}

impl fmt::Display for IoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: ", self.path.display())?;
        if let Some(at) = self.location {
            write!(f, "{at}: ")?;
        }
        match &self.kind {
            IoErrorKind::Io(e) => write!(f, "{e}"),
            IoErrorKind::Unsupported(m) => write!(f, "unsupported: {m}"),
            IoErrorKind::Malformed(m) => write!(f, "{m}"),
            IoErrorKind::InvalidCloud(m) => write!(f, "invalid cloud: {m}"),
        }
    }
}

impl std::error::Error for IoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            IoErrorKind::Io(e) => Some(e),
            _ => None,
        }
    }
}

/// A failure inside a parser, before the path is attached.
#[derive(Debug)]
pub(crate) struct Fail {
    pub at: Option<Location>,
    pub kind: IoErrorKind,
}

impl Fail {
    pub fn line(line: usize, msg: impl Into<String>) -> Self {
        Self {
            at: Some(Location::Line(line)),
            kind: IoErrorKind::Malformed(msg.into()),
        }
    }
    pub fn byte(offset: usize, msg: impl Into<String>) -> Self {
        Self {
            at: Some(Location::Byte(offset as u64)),
            kind: IoErrorKind::Malformed(msg.into()),
        }
    }
    pub fn unsupported(msg: impl Into<String>) -> Self {
        Self {
            at: None,
            kind: IoErrorKind::Unsupported(msg.into()),
        }
    }
    pub fn invalid(msg: impl Into<String>) -> Self {
        Self {
            at: None,
            kind: IoErrorKind::InvalidCloud(msg.into()),
        }
    }
    /// Moves the location to the last line of `data` (for "the file ends early" errors).
    pub fn at_last_line(mut self, data: &[u8]) -> Self {
        let mut lines = data.split(|&b| b == b'\n').count();
        if data.ends_with(b"\n") {
            lines -= 1;
        }
        self.at = Some(Location::Line(lines.max(1)));
        self
    }
    pub fn with_path(self, path: &Path) -> IoError {
        IoError {
            path: path.to_path_buf(),
            location: self.at,
            kind: self.kind,
        }
    }
}

impl From<std::io::Error> for Fail {
    fn from(e: std::io::Error) -> Self {
        Self {
            at: None,
            kind: IoErrorKind::Io(e),
        }
    }
}

pub(crate) type PResult<T> = std::result::Result<T, Fail>;
