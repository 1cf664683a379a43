//! Errors as Python exceptions: `ValueError` for bad input and for what the library refuses
//! (its message kept), `MemoryError` when the size estimate exceeds the available memory.

use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::PyErr;

/// An error raised where the GIL is released (plain data, `Send`), turned into the Python
/// exception on return.
#[derive(Debug)]
pub enum Error {
    /// Bad input (shape, values): `ValueError`.
    Value(String),
    /// The library refused the extraction: `ValueError` with its message.
    Library(String),
    /// Not enough memory for the estimated need: `MemoryError`.
    Memory(String),
}

impl From<Error> for PyErr {
    fn from(e: Error) -> Self {
        match e {
            Error::Value(m) | Error::Library(m) => PyValueError::new_err(m),
            Error::Memory(m) => PyMemoryError::new_err(m),
        }
    }
}

/// The library's error as a `ValueError` carrying its message.
pub fn extract_error(e: rmt_extract::ExtractError) -> PyErr {
    PyValueError::new_err(e.to_string())
}
