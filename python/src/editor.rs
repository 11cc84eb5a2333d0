//! The editor of `meshpyr view` for Python: `_Editor` answers the page's requests in-process
//! (the notebook widget carries them as widget messages), `_Server` is the HTTP server of
//! `meshpyr view` on a thread. The `meshpyr.Viewer` class (meshpyr/_viewer.py) wraps both.

use crate::arrays::positions_array;
use crate::errors::value_error;
use crate::pyramid::Pyramid;
use meshpyr_cli::view::{self, Stopper, ViewServer};
use numpy::PyArray2;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::sync::{Mutex, MutexGuard};
use std::thread::JoinHandle;

fn check_budget(budget: usize) -> PyResult<()> {
    view::limits::check_budget(budget).map_err(value_error)
}

/// The editor's state and handlers for one pyramid (see ``meshpyr.Viewer``). States are the
/// JSON bodies of ``POST /api/edit`` (docs/view-api.md).
#[pyclass(module = "meshpyr._meshpyr", name = "_Editor", frozen)]
pub(crate) struct Editor {
    inner: Mutex<view::Editor>,
}

impl Editor {
    fn lock(&self) -> MutexGuard<'_, view::Editor> {
        // A panic inside a handler is caught there; the state stays usable.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[pymethods]
impl Editor {
    #[new]
    #[pyo3(signature = (pyramid, /, *, name="mesh", budget=view::DEFAULT_BUDGET))]
    fn new(pyramid: &Pyramid, name: &str, budget: usize) -> PyResult<Self> {
        check_budget(budget)?;
        let editor = view::Editor::new(pyramid.shared())
            .with_name(name)
            .with_budget(budget);
        Ok(Editor {
            inner: Mutex::new(editor),
        })
    }

    /// The equalizer's octaves as ``(from, to)`` levels.
    #[getter]
    fn octaves(&self) -> Vec<(usize, usize)> {
        self.lock().octaves().to_vec()
    }

    /// One ``/api`` request: ``(status, content_type, headers, body)``.
    fn request<'py>(
        &self,
        py: Python<'py>,
        method: &str,
        target: &str,
        body: &[u8],
    ) -> (u16, String, Vec<(String, String)>, Bound<'py, PyBytes>) {
        let answer = py.detach(|| self.lock().request(method, target, body));
        let bytes = PyBytes::new(py, &answer.body);
        (answer.status, answer.content_type, answer.headers, bytes)
    }

    /// Raises ValueError when the state is refused.
    fn check_state(&self, state: &[u8]) -> PyResult<()> {
        self.lock().check_state(state).map_err(value_error)
    }

    /// The exact full-resolution result of ``state``, float64 (n, 3), input order.
    fn positions<'py>(&self, py: Python<'py>, state: &[u8]) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let positions = py
            .detach(|| self.lock().positions(state))
            .map_err(value_error)?;
        Ok(positions_array(py, &positions))
    }

    /// The self-contained page of ``state``'s result.
    fn snapshot_html(&self, py: Python<'_>, state: &[u8]) -> PyResult<String> {
        py.detach(|| self.lock().snapshot_html(state))
            .map_err(value_error)
    }
}

/// The page with ``script`` run before the editor's own (see ``view::page_html``).
#[pyfunction]
pub(crate) fn _page_html(script: &str) -> PyResult<String> {
    if script.contains("</script") {
        return Err(value_error("the script must not contain </script"));
    }
    Ok(view::page_html(script))
}

/// ``meshpyr view``'s HTTP server on 127.0.0.1, serving on its own thread until ``stop()``.
#[pyclass(module = "meshpyr._meshpyr", name = "_Server", frozen)]
pub(crate) struct Server {
    url: String,
    stopper: Stopper,
    thread: Mutex<Option<JoinHandle<Result<(), view::ViewError>>>>,
}

#[pymethods]
impl Server {
    #[new]
    #[pyo3(signature = (pyramid, /, *, name="mesh", budget=view::DEFAULT_BUDGET, port=0))]
    fn new(pyramid: &Pyramid, name: &str, budget: usize, port: u16) -> PyResult<Self> {
        check_budget(budget)?;
        let server = ViewServer::bind(pyramid.shared(), port)
            .map_err(|e| PyOSError::new_err(e.to_string()))?
            .with_name(name)
            .with_budget(budget);
        let (url, stopper) = (server.url(), server.stopper());
        let thread = std::thread::spawn(move || server.run());
        Ok(Server {
            url,
            stopper,
            thread: Mutex::new(Some(thread)),
        })
    }

    /// The page's address with its token.
    #[getter]
    fn url(&self) -> &str {
        &self.url
    }

    /// Stops serving and waits for the server's thread; stopping twice does nothing.
    fn stop(&self, py: Python<'_>) {
        self.stopper.stop();
        let thread = self.thread.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(thread) = thread {
            py.detach(|| {
                let _ = thread.join();
            });
        }
    }

    /// Whether it still serves.
    #[getter]
    fn running(&self) -> bool {
        self.thread
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .is_some_and(|t| !t.is_finished())
    }
}
