//! The library's errors as Python exceptions of the `nbhd.NbhdError` hierarchy (defined in
//! `nbhd/_errors.py`), each with the library's own message.

use nbhd::io::IoError;
use nbhd::NbhdError;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception class `name` of `nbhd._errors`.
fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyType>> {
    Ok(py
        .import("nbhd._errors")?
        .getattr(name)?
        .cast_into::<PyType>()?)
}

/// A Python exception of class `name` with `message`; a plain `ValueError` if the class cannot
/// be found (the package is broken).
fn raise(name: &str, message: String) -> PyErr {
    Python::attach(|py| match class(py, name) {
        Ok(cls) => PyErr::from_type(cls, message),
        Err(_) => PyValueError::new_err(message),
    })
}

/// The exception for an error of the library.
pub fn nbhd_err(e: NbhdError) -> PyErr {
    let name = match &e {
        NbhdError::Degenerate { .. } => "DegenerateError",
        NbhdError::OutOfMemory { .. } => "NbhdMemoryError",
        NbhdError::Cancelled => "CancelledError",
        NbhdError::ThreadPool(_) => "NbhdError",
        _ => "NbhdValueError",
    };
    raise(name, e.to_string())
}

/// The exception for an error of `nbhd::io`.
pub fn io_err(e: IoError) -> PyErr {
    raise("NbhdIOError", e.to_string())
}

/// An `NbhdValueError` with a message of the binding (an argument Python passed that has no
/// Rust counterpart to check it: an unknown option name, an array of the wrong rank).
pub fn value_err(message: impl Into<String>) -> PyErr {
    raise("NbhdValueError", message.into())
}

/// Lets `?` turn the library's errors into Python exceptions.
pub trait OrRaise<T> {
    /// The value, or the Python exception for the error.
    fn or_raise(self) -> PyResult<T>;
}

impl<T> OrRaise<T> for Result<T, NbhdError> {
    fn or_raise(self) -> PyResult<T> {
        self.map_err(nbhd_err)
    }
}

impl<T> OrRaise<T> for Result<T, IoError> {
    fn or_raise(self) -> PyResult<T> {
        self.map_err(io_err)
    }
}
