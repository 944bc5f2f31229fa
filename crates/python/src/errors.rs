//! The package's exceptions. `InputError` (a `ValueError`) is bad input, with the CLI's
//! messages naming the pose, vertex, face or part; `Error` (a `RuntimeError`) is a
//! failure while computing or writing.

use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};

create_exception!(
    desal,
    InputError,
    PyValueError,
    "Bad input: the message names the argument and the pose, vertex, face or part."
);
create_exception!(desal, Error, PyRuntimeError, "A failure while computing, reading or writing.");

/// An error chain as one message, the way the CLI prints it (`a: b: c`).
fn message(error: &anyhow::Error) -> String {
    format!("{error:#}")
}

/// Bad input.
pub fn input(error: anyhow::Error) -> PyErr {
    InputError::new_err(message(&error))
}

/// A failure while computing.
pub fn failed(error: anyhow::Error) -> PyErr {
    Error::new_err(message(&error))
}
