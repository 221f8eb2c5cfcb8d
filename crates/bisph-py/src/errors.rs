//! The Python exceptions of bisph and the mapping of every Rust error onto them.

use bisph_io::RunError as IoRunError;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    bisph,
    CaseError,
    PyValueError,
    "A mistake in a case: `file` (the case file, or where the case came from), `key` (the \
     dotted key at fault, empty when the whole case is) and `message` (what was wrong and \
     what was expected). The command line reports the same errors with exit code 1."
);

pyo3::create_exception!(
    bisph,
    RunError,
    PyRuntimeError,
    "A run or a step that failed: a divergence watch tripped, a particle left the domain, a \
     state became non-finite, the time step collapsed, or the case needs more memory than \
     the machine has. `exit_code` is the code `bisph run` exits with for the same failure."
);

/// A [`CaseError`] exception carrying the case error's file, key and message.
pub fn case_error(e: &bisph_io::CaseError) -> PyErr {
    Python::attach(|py| {
        let err = CaseError::new_err(e.to_string());
        let value = err.value(py);
        let attributes = [("file", &e.file), ("key", &e.key), ("message", &e.message)];
        for (name, text) in attributes {
            if let Err(failed) = value.setattr(name, text) {
                return failed;
            }
        }
        err
    })
}

/// A [`RunError`] exception with its exit code.
pub fn run_failure(message: String, exit_code: u8) -> PyErr {
    Python::attach(|py| {
        let err = RunError::new_err(message);
        match err.value(py).setattr("exit_code", exit_code) {
            Ok(()) => err,
            Err(failed) => failed,
        }
    })
}

/// The exception of an error of a run: [`CaseError`] for a wrong case or geometry, `OSError`
/// for an output that could not be written, [`RunError`] for the rest.
pub fn run_error(e: &IoRunError) -> PyErr {
    match e {
        IoRunError::Case(c) => case_error(c),
        IoRunError::Geometry(g) => case_error(&g.0),
        IoRunError::Output(o) => PyOSError::new_err(o.to_string()),
        _ => run_failure(e.to_string(), e.exit_code()),
    }
}

/// A failed step, held without the GIL until it can be raised as a [`RunError`].
#[derive(Debug)]
pub struct Failure {
    message: String,
    exit_code: u8,
}

impl Failure {
    /// A failure with the exit code `bisph run` gives it.
    pub fn run(message: String, exit_code: u8) -> Self {
        Failure { message, exit_code }
    }

    /// The exception to raise.
    pub fn into_py(self) -> PyErr {
        run_failure(self.message, self.exit_code)
    }
}

/// A `ValueError` for an argument that is not what a function expects.
pub fn bad_argument(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
