//! The tasks of a hierarchy built in blocks through task files, for `meshpyr.dask`: a task as
//! a small picklable dict (what to run, which files, and the memory it is estimated to hold),
//! run anywhere the files are seen by `_run_task`, and the commands `build`, `filter` and
//! `edit` run by `_run_command` with each round's tasks handed to a Python callable, which
//! may send them to other processes and returns when all are done.

use crate::errors::{FormatError, value_error};
use meshpyr::pm::blocks::{
    BlockFileError, SharedRunner, Task, TaskOutput, TaskRunner, memory_estimate, run_task,
};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::ffi::OsString;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// `task` as a dict: `kind` and the task's fields by name (paths as str, lists of paths as
/// lists), and `memory`, the bytes it is estimated to hold at its peak.
fn describe<'py>(py: Python<'py>, task: &Task) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let path = |p: &PathBuf| p.as_os_str().to_os_string();
    let paths = |ps: &[PathBuf]| ps.iter().map(path).collect::<Vec<_>>();
    match task {
        Task::Split {
            pass,
            piece,
            across_out,
            routed_out,
        } => {
            d.set_item("kind", "split")?;
            d.set_item("pass", path(pass))?;
            d.set_item("piece", path(piece))?;
            d.set_item("across_out", path(across_out))?;
            d.set_item("routed_out", path(routed_out))?;
        }
        Task::Concat { pieces, out } => {
            d.set_item("kind", "concat")?;
            d.set_item("pieces", paths(pieces))?;
            d.set_item("out", path(out))?;
        }
        Task::Gather {
            routed,
            cell,
            input_out,
            held_out,
        } => {
            d.set_item("kind", "gather")?;
            d.set_item("routed", paths(routed))?;
            d.set_item("cell", cell)?;
            d.set_item("input_out", path(input_out))?;
            d.set_item("held_out", path(held_out))?;
        }
        Task::Candidates {
            pass,
            input,
            costs_out,
        } => {
            d.set_item("kind", "candidates")?;
            d.set_item("pass", path(pass))?;
            d.set_item("input", path(input))?;
            d.set_item("costs_out", path(costs_out))?;
        }
        Task::CostHistogram {
            costs,
            prefix,
            shift,
        } => {
            d.set_item("kind", "cost_histogram")?;
            d.set_item("costs", path(costs))?;
            d.set_item("prefix", prefix)?;
            d.set_item("shift", shift)?;
        }
        Task::Collapse {
            pass,
            input,
            cut,
            result_out,
        } => {
            d.set_item("kind", "collapse")?;
            d.set_item("pass", path(pass))?;
            d.set_item("input", path(input))?;
            d.set_item("cut", cut)?;
            d.set_item("result_out", path(result_out))?;
        }
        Task::Assemble {
            results,
            n_vertices,
            sequence_out,
        } => {
            d.set_item("kind", "assemble")?;
            d.set_item("results", paths(results))?;
            d.set_item("n_vertices", n_vertices)?;
            d.set_item("sequence_out", path(sequence_out))?;
        }
        Task::Finish {
            pass,
            input,
            result_out,
        } => {
            d.set_item("kind", "finish")?;
            d.set_item("pass", path(pass))?;
            d.set_item("input", path(input))?;
            d.set_item("result_out", path(result_out))?;
        }
        Task::CellPatches {
            cells,
            cell,
            patches_out,
        } => {
            d.set_item("kind", "cell_patches")?;
            d.set_item("cells", path(cells))?;
            d.set_item("cell", cell)?;
            d.set_item("patches_out", path(patches_out))?;
        }
        Task::CellFans {
            cells,
            cell,
            flips,
            fans_out,
        } => {
            d.set_item("kind", "cell_fans")?;
            d.set_item("cells", path(cells))?;
            d.set_item("cell", cell)?;
            d.set_item("flips", path(flips))?;
            d.set_item("fans_out", path(fans_out))?;
        }
        Task::CellPiece {
            cells,
            cell,
            flips,
            copies,
            boundary_weight,
            piece_out,
        } => {
            d.set_item("kind", "cell_piece")?;
            d.set_item("cells", path(cells))?;
            d.set_item("cell", cell)?;
            d.set_item("flips", path(flips))?;
            d.set_item("copies", path(copies))?;
            d.set_item("boundary_weight", boundary_weight)?;
            d.set_item("piece_out", path(piece_out))?;
        }
    }
    d.set_item("memory", memory_estimate(task))?;
    Ok(d)
}

/// The task a dict of [`describe`] names.
fn task_of(d: &Bound<'_, PyDict>) -> PyResult<Task> {
    let get = |key: &str| {
        d.get_item(key)?
            .ok_or_else(|| value_error(format!("a task description without {key:?}")))
    };
    let path = |key: &str| get(key)?.extract::<PathBuf>();
    let kind: String = get("kind")?.extract()?;
    Ok(match kind.as_str() {
        "split" => Task::Split {
            pass: path("pass")?,
            piece: path("piece")?,
            across_out: path("across_out")?,
            routed_out: path("routed_out")?,
        },
        "concat" => Task::Concat {
            pieces: get("pieces")?.extract()?,
            out: path("out")?,
        },
        "gather" => Task::Gather {
            routed: get("routed")?.extract()?,
            cell: get("cell")?.extract()?,
            input_out: path("input_out")?,
            held_out: path("held_out")?,
        },
        "candidates" => Task::Candidates {
            pass: path("pass")?,
            input: path("input")?,
            costs_out: path("costs_out")?,
        },
        "cost_histogram" => Task::CostHistogram {
            costs: path("costs")?,
            prefix: get("prefix")?.extract()?,
            shift: get("shift")?.extract()?,
        },
        "collapse" => Task::Collapse {
            pass: path("pass")?,
            input: path("input")?,
            cut: get("cut")?.extract()?,
            result_out: path("result_out")?,
        },
        "assemble" => Task::Assemble {
            results: get("results")?.extract()?,
            n_vertices: get("n_vertices")?.extract()?,
            sequence_out: path("sequence_out")?,
        },
        "finish" => Task::Finish {
            pass: path("pass")?,
            input: path("input")?,
            result_out: path("result_out")?,
        },
        "cell_patches" => Task::CellPatches {
            cells: path("cells")?,
            cell: get("cell")?.extract()?,
            patches_out: path("patches_out")?,
        },
        "cell_fans" => Task::CellFans {
            cells: path("cells")?,
            cell: get("cell")?.extract()?,
            flips: path("flips")?,
            fans_out: path("fans_out")?,
        },
        "cell_piece" => Task::CellPiece {
            cells: path("cells")?,
            cell: get("cell")?.extract()?,
            flips: path("flips")?,
            copies: path("copies")?,
            boundary_weight: get("boundary_weight")?.extract()?,
            piece_out: path("piece_out")?,
        },
        other => return Err(value_error(format!("unknown task kind {other:?}"))),
    })
}

/// A task's output as Python: `None` (its files are written), a count, or a histogram's bins
/// as little-endian u64 bytes (512 KB, where a list would be 65536 objects).
fn output_to_py(py: Python<'_>, output: TaskOutput) -> PyResult<Py<PyAny>> {
    Ok(match output {
        TaskOutput::Written => py.None(),
        TaskOutput::Count(n) => n.into_pyobject(py)?.into_any().unbind(),
        TaskOutput::Histogram(bins) => {
            let bytes: Vec<u8> = bins.iter().flat_map(|b| b.to_le_bytes()).collect();
            PyBytes::new(py, &bytes).into_any().unbind()
        }
    })
}

/// The inverse of [`output_to_py`].
fn output_of(value: &Bound<'_, PyAny>) -> PyResult<TaskOutput> {
    if value.is_none() {
        return Ok(TaskOutput::Written);
    }
    if let Ok(bytes) = value.cast::<PyBytes>() {
        let bins = bytes.as_bytes().chunks_exact(8);
        let bins = bins.map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")));
        return Ok(TaskOutput::Histogram(bins.collect()));
    }
    Ok(TaskOutput::Count(value.extract()?))
}

/// A task file that could not be read or written, as Python: OSError when the file could not
/// be opened, read or written, FormatError when its content is damaged.
fn block_file_error(e: BlockFileError) -> PyErr {
    if e.what.starts_with("cannot ") {
        PyOSError::new_err(e.to_string())
    } else {
        FormatError::new_err(e.to_string())
    }
}

/// Runs one task described by a dict of a round (as the callable of `_run_command` receives
/// them) in this process, the GIL released; returns None, a count, or a histogram as bytes.
#[pyfunction]
pub(crate) fn _run_task(py: Python<'_>, task: &Bound<'_, PyDict>) -> PyResult<Py<PyAny>> {
    let task = task_of(task)?;
    let output = py.detach(|| run_task(&task)).map_err(block_file_error)?;
    output_to_py(py, output)
}

/// A runner whose rounds go to a Python callable: a list of task dicts in, a list of their
/// outputs in the same order back. The first Python exception is kept, to be raised as it
/// was once the driver has stopped.
struct PythonRunner {
    round: Py<PyAny>,
    error: Mutex<Option<PyErr>>,
}

impl PythonRunner {
    fn call(&self, py: Python<'_>, tasks: &[Task]) -> PyResult<Vec<TaskOutput>> {
        let described = (tasks.iter())
            .map(|t| describe(py, t))
            .collect::<PyResult<Vec<_>>>()?;
        let outputs = self.round.call1(py, (PyList::new(py, described)?,))?;
        let outputs = outputs.bind(py);
        let n = outputs.len()?;
        if n != tasks.len() {
            return Err(value_error(format!(
                "the task runner returned {n} outputs for {} tasks",
                tasks.len()
            )));
        }
        (outputs.try_iter()?)
            .map(|o| output_of(&o?))
            .collect::<PyResult<Vec<_>>>()
    }
}

impl TaskRunner for PythonRunner {
    fn run_round(&self, tasks: Vec<Task>) -> Result<Vec<TaskOutput>, BlockFileError> {
        Python::attach(|py| self.call(py, &tasks)).map_err(|e| {
            let what = format!("a round of tasks failed: {e}");
            let mut kept = self.error.lock().unwrap_or_else(|p| p.into_inner());
            kept.get_or_insert(e);
            BlockFileError {
                path: PathBuf::new(),
                offset: 0,
                what,
            }
        })
    }
}

/// Runs the command `meshpyr ARGS` (`args`: what follows the program's name) in this process,
/// the GIL released, with each round of block tasks handed to `round` (a callable from a list
/// of task dicts to the list of their outputs; it runs them anywhere, each with `_run_task`).
/// Raises the callable's own exception when it raised one, OSError when an input or output
/// could not be read or written, else ValueError; the message is the command line's one line.
#[pyfunction]
pub(crate) fn _run_command(py: Python<'_>, args: Vec<OsString>, round: Py<PyAny>) -> PyResult<()> {
    let runner = Arc::new(PythonRunner {
        round,
        error: Mutex::new(None),
    });
    let shared = SharedRunner(runner.clone());
    let done = py.detach(|| meshpyr_cli::run_with_block_runner(args, shared));
    let kept = runner
        .error
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .take();
    if let Some(e) = kept {
        return Err(e);
    }
    done.map_err(|e| {
        let message = format!("{e:#}");
        if e.chain().any(|c| c.is::<std::io::Error>()) {
            PyOSError::new_err(message)
        } else {
            value_error(message)
        }
    })
}

/// The largest block (in vertices) whose decimation tasks are estimated to fit `memory` bytes.
#[pyfunction]
pub(crate) fn _block_vertices_for(memory: u64) -> usize {
    meshpyr::pm::blocks::block_vertices_for(memory)
}
