//! The one error type of the command-line tool. Every command returns [`Result`]; `main` prints
//! the error as `nbhd: error: …` on standard error and exits with status 1.

use std::fmt;

/// Why a command failed. Its text is what the user reads after `nbhd: error: `.
#[derive(Debug)]
pub enum Error {
    /// A sentence for the user: a refused option, an empty input, a missing field.
    Message(String),
    /// An error of the nbhd library (bad options, empty point set, …).
    Nbhd(nbhd::NbhdError),
    /// A file nbhd could not read or write; the error names the file itself.
    File(nbhd::io::IoError),
    /// An operating-system error (creating a folder, writing a report or picture).
    Io(std::io::Error),
    /// A worker thread pool that could not be created.
    Threads(rayon::ThreadPoolBuildError),
    /// `source`, about `context` (a file, a shape): shown as `context: source`.
    Context {
        /// What the error is about.
        context: String,
        /// The error itself.
        source: Box<Error>,
    },
}

/// The result of a command and of its parts.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An error whose text is `message`.
    pub fn msg(message: impl Into<String>) -> Self {
        Error::Message(message.into())
    }

    /// An error of a foreign library (a plotting or encoding error) about `context`.
    pub fn about(context: impl fmt::Display, error: impl fmt::Display) -> Self {
        Error::msg(error.to_string()).within(context)
    }

    /// This error, about `context`: shown as `context: self`.
    pub fn within(self, context: impl fmt::Display) -> Self {
        Error::Context {
            context: context.to_string(),
            source: Box::new(self),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Message(m) => f.write_str(m),
            Error::Nbhd(e) => write!(f, "{e}"),
            Error::File(e) => write!(f, "{e}"),
            Error::Io(e) => write!(f, "{e}"),
            Error::Threads(e) => write!(f, "{e}"),
            Error::Context { context, source } => write!(f, "{context}: {source}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Message(_) => None,
            Error::Nbhd(e) => Some(e),
            Error::File(e) => Some(e),
            Error::Io(e) => Some(e),
            Error::Threads(e) => Some(e),
            Error::Context { source, .. } => Some(source.as_ref()),
        }
    }
}

impl From<String> for Error {
    fn from(m: String) -> Self {
        Error::Message(m)
    }
}

impl From<&str> for Error {
    fn from(m: &str) -> Self {
        Error::Message(m.to_string())
    }
}

impl From<nbhd::NbhdError> for Error {
    fn from(e: nbhd::NbhdError) -> Self {
        Error::Nbhd(e)
    }
}

impl From<nbhd::io::IoError> for Error {
    fn from(e: nbhd::io::IoError) -> Self {
        Error::File(e)
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Io(e)
    }
}

impl From<rayon::ThreadPoolBuildError> for Error {
    fn from(e: rayon::ThreadPoolBuildError) -> Self {
        Error::Threads(e)
    }
}

/// Puts a context before the error of a result: `.context(path.display())?`.
pub trait Context<T> {
    /// The error, if any, about `context`: shown as `context: error`.
    fn context(self, context: impl fmt::Display) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn context(self, context: impl fmt::Display) -> Result<T> {
        self.map_err(|e| e.into().within(context))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn context_reads_before_the_error() {
        let e: Result<()> = Err(std::io::Error::other("disk full")).context("out/report.md");
        assert_eq!(e.unwrap_err().to_string(), "out/report.md: disk full");
        let e: Result<()> = Err(nbhd::NbhdError::EmptyInput).context("cube");
        assert_eq!(
            e.unwrap_err().to_string(),
            format!("cube: {}", nbhd::NbhdError::EmptyInput)
        );
        assert_eq!(Error::from("plain").to_string(), "plain");
    }
}
