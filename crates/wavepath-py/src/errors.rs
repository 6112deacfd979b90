//! Engine errors as Python exceptions: the command line's one-line message, under the
//! exception a Python user expects for it.

use pyo3::PyErr;
use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyPermissionError, PyValueError};

/// The message the command line prints after `error: `, on one line.
pub fn one_line(e: &anyhow::Error) -> String {
    format!("{e:#}").replace('\n', " ")
}

/// A missing file is `FileNotFoundError`, another I/O failure `OSError`, an interrupted
/// render `KeyboardInterrupt`, anything else about the input `ValueError`.
pub fn to_py(e: anyhow::Error) -> PyErr {
    let msg = one_line(&e);
    if let Some(io) = e.chain().find_map(|c| c.downcast_ref::<std::io::Error>()) {
        return match io.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
            _ => PyOSError::new_err(msg),
        };
    }
    if e.chain().any(|c| c.downcast_ref::<wavepath::Interrupted>().is_some()) {
        return PyKeyboardInterrupt::new_err(msg);
    }
    PyValueError::new_err(msg)
}

pub fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}
