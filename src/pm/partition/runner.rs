//! The tasks of a partitioned build run through files, as a scheduler sees them: each a
//! [`Task`] (which function, which files), run by [`run_task`] anywhere the files are seen,
//! its [`TaskOutput`] a small value. The driver hands each round's tasks to a [`TaskRunner`]:
//! [`RayonRunner`] runs them on this process's threads; another runner may send them to other
//! processes or machines (`meshpyr.dask` sends them to Dask workers, each declaring
//! `memory_estimate`), since a task depends on its files only and writes
//! the same bytes when run twice.

use super::taskfile::BlockFileError;
use super::tasks;
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// One task of a round (the functions of [`crate::pm::blocks`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Task {
    /// [`tasks::split`].
    Split {
        /// The pass file.
        pass: PathBuf,
        /// The piece to split.
        piece: PathBuf,
        /// Where its faces across cells go.
        across_out: PathBuf,
        /// Where its cells' shares go.
        routed_out: PathBuf,
    },
    /// [`tasks::concat`].
    Concat {
        /// The pieces, in order.
        pieces: Vec<PathBuf>,
        /// The joined piece.
        out: PathBuf,
    },
    /// [`tasks::gather`].
    Gather {
        /// The routed pieces, in order.
        routed: Vec<PathBuf>,
        /// The cell.
        cell: u32,
        /// The block input.
        input_out: PathBuf,
        /// The cell's pinned records.
        held_out: PathBuf,
    },
    /// [`tasks::candidates`].
    Candidates {
        /// The pass file.
        pass: PathBuf,
        /// The block input.
        input: PathBuf,
        /// Where its costs go.
        costs_out: PathBuf,
    },
    /// [`tasks::cost_histogram`].
    CostHistogram {
        /// A block's costs.
        costs: PathBuf,
        /// The high bits already resolved.
        prefix: u64,
        /// The position of the 16 bits to count.
        shift: u32,
    },
    /// [`tasks::collapse`].
    Collapse {
        /// The pass file.
        pass: PathBuf,
        /// The block input.
        input: PathBuf,
        /// The pass's cost cut.
        cut: f64,
        /// Where the result goes.
        result_out: PathBuf,
    },
    /// [`tasks::assemble`].
    Assemble {
        /// The pass's results, in cell order.
        results: Vec<PathBuf>,
        /// The input's vertex count.
        n_vertices: u64,
        /// Where the sequence goes.
        sequence_out: PathBuf,
    },
    /// [`crate::pm::blocks::patches_task`]: round 1 of the cell tasks.
    CellPatches {
        /// The streaming split's folder.
        cells: PathBuf,
        /// The cell.
        cell: u32,
        /// Where its patches (or its refusal) go.
        patches_out: PathBuf,
    },
    /// [`crate::pm::blocks::fans_task`]: round 2 of the cell tasks.
    CellFans {
        /// The streaming split's folder.
        cells: PathBuf,
        /// The cell.
        cell: u32,
        /// The driver's flips file.
        flips: PathBuf,
        /// Where its extra fans (or its refusal) go.
        fans_out: PathBuf,
    },
    /// [`crate::pm::blocks::piece_task`]: round 3 of the cell tasks.
    CellPiece {
        /// The streaming split's folder.
        cells: PathBuf,
        /// The cell.
        cell: u32,
        /// The driver's flips file.
        flips: PathBuf,
        /// The driver's copies file.
        copies: PathBuf,
        /// The weight of the boundary planes.
        boundary_weight: f64,
        /// Where its first piece (or its refusal) goes.
        piece_out: PathBuf,
    },
    /// [`tasks::finish`].
    Finish {
        /// The last pass's file.
        pass: PathBuf,
        /// The last block's input.
        input: PathBuf,
        /// Where its result goes.
        result_out: PathBuf,
    },
}

/// What a task hands back besides its files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TaskOutput {
    /// Its files are written.
    Written,
    /// A count: the candidates of [`Task::Candidates`], the collapses of [`Task::Collapse`]
    /// and [`Task::Assemble`].
    Count(u64),
    /// The bins of [`Task::CostHistogram`].
    Histogram(Vec<u64>),
}

/// Runs `task` in this process.
pub fn run_task(task: &Task) -> Result<TaskOutput, BlockFileError> {
    use TaskOutput::{Count, Histogram, Written};
    Ok(match task {
        Task::Split {
            pass,
            piece,
            across_out,
            routed_out,
        } => tasks::split(pass, piece, across_out, routed_out).map(|()| Written)?,
        Task::Concat { pieces, out } => tasks::concat(pieces, out).map(|()| Written)?,
        Task::Gather {
            routed,
            cell,
            input_out,
            held_out,
        } => tasks::gather(routed, *cell, input_out, held_out).map(|()| Written)?,
        Task::Candidates {
            pass,
            input,
            costs_out,
        } => Count(tasks::candidates(pass, input, costs_out)?),
        Task::CostHistogram {
            costs,
            prefix,
            shift,
        } => Histogram(tasks::cost_histogram(costs, *prefix, *shift)?),
        Task::Collapse {
            pass,
            input,
            cut,
            result_out,
        } => Count(tasks::collapse(pass, input, *cut, result_out)?),
        Task::Assemble {
            results,
            n_vertices,
            sequence_out,
        } => Count(tasks::assemble(results, *n_vertices, sequence_out)?),
        Task::Finish {
            pass,
            input,
            result_out,
        } => tasks::finish(pass, input, result_out).map(|()| Written)?,
        Task::CellPatches { .. } | Task::CellFans { .. } | Task::CellPiece { .. } => {
            super::stream::run_cell_task(task).expect("a cell task")?
        }
    })
}

/// Runs the tasks of one round, in any order and anywhere, and hands back their outputs in
/// the order of the tasks.
pub trait TaskRunner: Send + Sync {
    /// Runs `tasks`; the first error ends the round.
    fn run_round(&self, tasks: Vec<Task>) -> Result<Vec<TaskOutput>, BlockFileError>;
}

/// Runs a round's tasks on this process's rayon threads.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayonRunner;

impl TaskRunner for RayonRunner {
    fn run_round(&self, tasks: Vec<Task>) -> Result<Vec<TaskOutput>, BlockFileError> {
        tasks.par_iter().map(run_task).collect()
    }
}

/// A runner shared by the options of a build ([`crate::pm::PmOptions::block_runner`]); two
/// are equal when they are the same runner.
#[derive(Clone)]
pub struct SharedRunner(pub Arc<dyn TaskRunner>);

impl PartialEq for SharedRunner {
    fn eq(&self, other: &SharedRunner) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl std::fmt::Debug for SharedRunner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SharedRunner(..)")
    }
}
