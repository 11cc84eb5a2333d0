//! The Python extension module `meshpyr._meshpyr`, re-exported by the `meshpyr` package:
//! free functions over `(V, F)` numpy arrays and classes for what has state, bound to the
//! library's front door. Every heavy call releases the GIL.

mod arrays;
mod blocks;
mod corners;
mod editor;
mod errors;
mod filters;
mod functions;
mod progressive;
mod pyramid;
mod smooth;

use pyo3::prelude::*;
use std::ffi::CString;

/// Issues a `UserWarning` with `message`, attributed to the caller's line.
pub(crate) fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    let text = CString::new(message.replace('\0', " ")).expect("no NUL left");
    PyErr::warn(py, category.as_any(), &text, 1)
}

#[pymodule]
fn _meshpyr(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("FormatError", m.py().get_type::<errors::FormatError>())?;
    m.add_function(wrap_pyfunction!(functions::read, m)?)?;
    m.add_function(wrap_pyfunction!(functions::write, m)?)?;
    m.add_function(wrap_pyfunction!(functions::info, m)?)?;
    m.add_function(wrap_pyfunction!(functions::simplify, m)?)?;
    m.add_function(wrap_pyfunction!(functions::subdivide, m)?)?;
    m.add_function(wrap_pyfunction!(functions::compare, m)?)?;
    m.add_function(wrap_pyfunction!(smooth::smooth, m)?)?;
    m.add_class::<progressive::ProgressiveMesh>()?;
    m.add_class::<pyramid::Pyramid>()?;
    m.add_class::<editor::Editor>()?;
    m.add_class::<editor::Server>()?;
    m.add_function(wrap_pyfunction!(editor::_page_html, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::_run_task, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::_run_command, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::_block_vertices_for, m)?)?;
    Ok(())
}
