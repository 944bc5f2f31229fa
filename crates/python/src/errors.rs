//! The package's exceptions. `InputError` (a `ValueError`) is bad input, with the CLI's
//! messages naming the pose, vertex, face or part; `Error` (a `RuntimeError`) is a
//! failure while computing or writing.
//!
//! **Invariant:** nothing else reaches Python from this crate. Every entry point runs
//! inside [`guard`], so a Rust panic (a bug, or a crate that panics on hostile input)
//! is an `Error` naming the call, never PyO3's `PanicException`, which derives from
//! `BaseException` and so escapes `except Exception`.

use std::panic::{AssertUnwindSafe, catch_unwind};

use desal_io::IoError;
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::{PyErr, PyResult};

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

/// A stage's error: bad input when the chain holds an error the input caused (a rig
/// desal cannot read or pose, a mesh or file it refuses, a saliency setting that does
/// not fit the pose set), else a failure.
pub fn classify(error: anyhow::Error) -> PyErr {
    let caused_by_input = error.chain().any(|c| {
        c.is::<desal_rig::RigError>()
            || c.is::<desal_mesh::MeshError>()
            || c.downcast_ref::<IoError>().is_some_and(is_input_io)
            || c.downcast_ref::<desal_saliency::SaliencyError>().is_some_and(|e| {
                use desal_saliency::SaliencyError as S;
                matches!(e, S::UnknownPose { .. } | S::NoPosesLeft { .. } | S::BadOption { .. })
            })
    });
    if caused_by_input { input(error) } else { failed(error) }
}

/// A read or write of a path the user gave that desal refuses or cannot parse: the
/// path's fault, not desal's. (`Io` itself, a disk that is full or a file that vanished,
/// stays a failure, except a path that does not exist.)
fn is_input_io(error: &IoError) -> bool {
    match error {
        IoError::Io { cause, .. } => cause.kind() == std::io::ErrorKind::NotFound,
        IoError::NotAFile { .. }
        | IoError::NotWritable { .. }
        | IoError::Confined { .. }
        | IoError::NotText { .. }
        | IoError::UnsupportedFormat { .. }
        | IoError::BadMesh { .. }
        | IoError::InvalidMesh { .. }
        | IoError::BadLine { .. } => true,
        _ => false,
    }
}

/// A desal-io read or write of a path the user named: [`classify`]'s rule.
pub fn io(error: IoError) -> PyErr {
    classify(error.into())
}

/// Runs the body of the entry point `call`, turning a Rust panic into `desal.Error`.
/// The panic has already been printed by the panic hook (with a backtrace when
/// `RUST_BACKTRACE` is set), so the message only names the call and the panic's text.
pub fn guard<T>(call: &str, body: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or_else(|payload| {
        let text = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".to_owned());
        Err(Error::new_err(format!(
            "{call}: internal error (a Rust panic: {text}); this is a bug in desal, please report it with the input"
        )))
    })
}
