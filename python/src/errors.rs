//! The library's errors as Python exceptions: `ValueError` for bad arrays and options, `OSError`
//! (and its subclasses, such as `FileNotFoundError`) for files, `meshpyr.FormatError` for files
//! whose content is damaged or not what their name says.

use meshpyr::PyrFileError;
use meshpyr::io::IoError;
use meshpyr::pyramid::PyramidError;
use pyo3::PyErr;
use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIsADirectoryError, PyNotADirectoryError, PyOSError,
    PyPermissionError, PyRuntimeError, PyValueError,
};
use std::io::ErrorKind;
use std::path::Path;

pyo3::create_exception!(
    meshpyr,
    FormatError,
    PyValueError,
    "A mesh or .pyr file (or .pyr bytes) whose content is damaged, truncated or not in the format its name says. A subclass of ValueError."
);

/// A `ValueError` with `message`.
pub(crate) fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// An operating-system error on `path`, as the matching `OSError` subclass with `errno`,
/// `strerror` and `filename` set, as Python's own `open` raises it.
pub(crate) fn os_error(path: &Path, error: &std::io::Error) -> PyErr {
    let filename = path.display().to_string();
    let strerror = error.to_string();
    let args = (error.raw_os_error().unwrap_or(0), strerror, filename);
    match error.kind() {
        ErrorKind::NotFound => PyFileNotFoundError::new_err(args),
        ErrorKind::PermissionDenied => PyPermissionError::new_err(args),
        ErrorKind::AlreadyExists => PyFileExistsError::new_err(args),
        ErrorKind::IsADirectory => PyIsADirectoryError::new_err(args),
        ErrorKind::NotADirectory => PyNotADirectoryError::new_err(args),
        _ => PyOSError::new_err(args),
    }
}

/// Reading or writing a mesh file.
pub(crate) fn io_error(error: IoError) -> PyErr {
    match &error {
        IoError::Io { path, error } => os_error(path, error),
        IoError::Parse { .. } => FormatError::new_err(error.to_string()),
        // An extension we cannot read or write, or a mesh the format cannot hold: the caller's
        // arguments are wrong, not the file.
        IoError::UnknownFormat { .. } | IoError::InvalidMesh { .. } => {
            value_error(error.to_string())
        }
    }
}

/// Saving or opening a `.pyr` file or its bytes.
pub(crate) fn pyr_error(error: PyrFileError) -> PyErr {
    match error {
        PyrFileError::Io(io) => io_error(io),
        // A hierarchy that decodes but cannot be rebuilt is as damaged as a bad checksum.
        PyrFileError::Format { .. } | PyrFileError::Pyramid { .. } => {
            FormatError::new_err(error.to_string())
        }
    }
}

/// Building or using a pyramid from the caller's arrays.
pub(crate) fn pyramid_error(error: PyramidError) -> PyErr {
    match error {
        PyramidError::Internal(_) => PyRuntimeError::new_err(error.to_string()),
        _ => value_error(error.to_string()),
    }
}

/// Any other library error caused by the caller's arrays or options.
pub(crate) fn input_error(error: impl std::fmt::Display) -> PyErr {
    value_error(error.to_string())
}
