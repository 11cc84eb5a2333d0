//! How much memory a task holds at its peak, estimated before it runs from the sizes of what
//! it reads, so that a scheduler can declare it: `meshpyr.dask` submits every task with this
//! figure as the Dask resource `MEMORY`, and a worker started with `MEMORY=3e9` never runs
//! tasks that together declare more. A Rust heap is invisible to Dask's own memory manager, so
//! the declaration is what keeps a worker inside its memory.
//!
//! The figures are upper bounds measured per task kind (`docs/performance.md`, "Block tasks on
//! Dask"): a task's peak is a multiple of the bytes it reads, plus the process's fixed part.

use super::contents;
use super::runner::Task;
use std::path::{Path, PathBuf};

/// What every task holds besides its data: buffers, the thread pool's stacks.
const FIXED: u64 = 16 << 20;

/// A decimation task (candidates, collapse, the last block) per byte of its block input: the
/// records and faces read, the working mesh, the quadrics, the candidate heap and the result.
const DECIMATION_PER_BYTE: u64 = 5;

/// A task that reads records and faces, sorts them and writes them (split, concat, gather,
/// assemble), per byte read: what was read, what it is sorted into, the bytes being written.
const COPY_PER_BYTE: u64 = 3;

/// A cell task per byte of its cell's files (32 B a record): the records, the half-edges and
/// their mates, the quadrics and the encoded piece.
const CELL_PER_BYTE: u64 = 6;

/// A block input's bytes per vertex: a record (120 B), two faces (24 B) and a share of the
/// pinned and boundary records.
const INPUT_BYTES_PER_VERTEX: u64 = 150;

/// The bytes `task` holds at its peak, estimated from the files it reads (a file that is
/// missing counts nothing: the task will fail on it anyway).
pub fn memory_estimate(task: &Task) -> u64 {
    let data = match task {
        Task::Split { pass, piece, .. } => COPY_PER_BYTE * (size(pass) + size(piece)),
        Task::Concat { pieces, .. } => COPY_PER_BYTE * sizes(pieces),
        Task::Gather { routed, cell, .. } => {
            let share: u64 = routed.iter().map(|r| share_size(r, *cell)).sum();
            COPY_PER_BYTE * share
        }
        Task::Candidates { input, .. }
        | Task::Collapse { input, .. }
        | Task::Finish { input, .. } => DECIMATION_PER_BYTE * size(input),
        // The costs read and the bins.
        Task::CostHistogram { costs, .. } => size(costs) + (8 << super::tasks::HISTOGRAM_BITS),
        Task::Assemble { results, .. } => COPY_PER_BYTE * sizes(results),
        Task::CellPatches { cells, cell, .. } | Task::CellFans { cells, cell, .. } => {
            CELL_PER_BYTE * cell_size(cells, *cell)
        }
        Task::CellPiece {
            cells,
            cell,
            copies,
            ..
        } => CELL_PER_BYTE * cell_size(cells, *cell) + COPY_PER_BYTE * size(copies),
    };
    FIXED.saturating_add(data)
}

/// The largest block (in vertices) whose decimation tasks are estimated to fit `memory`
/// bytes, at least [`crate::pm::MIN_BLOCK_VERTICES`]: the block size to build with on workers
/// of that memory.
pub fn block_vertices_for(memory: u64) -> usize {
    let per_vertex = DECIMATION_PER_BYTE * INPUT_BYTES_PER_VERTEX;
    let n = memory.saturating_sub(FIXED) / per_vertex;
    (n as usize).max(crate::pm::MIN_BLOCK_VERTICES)
}

fn size(path: &Path) -> u64 {
    std::fs::metadata(path).map_or(0, |m| m.len())
}

/// The bytes of cell `cell`'s files in the split's folder `cells`.
fn cell_size(cells: &Path, cell: u32) -> u64 {
    let name = |ext: &str| cells.join(format!("c{cell}.{ext}"));
    size(&name("vert")) + size(&name("face")) + size(&name("border"))
}

fn sizes(paths: &[PathBuf]) -> u64 {
    paths.iter().map(|p| size(p)).sum()
}

/// The bytes of `cell`'s share of the routed piece `path`, from its section table (the whole
/// file when the table cannot be read).
fn share_size(path: &Path, cell: u32) -> u64 {
    contents::share_len(path, cell).unwrap_or_else(|_| size(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_decimation_task_is_estimated_by_its_input_and_a_block_size_fits_its_estimate() {
        let dir = std::env::temp_dir().join(format!("meshpyr-task-memory-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("input");
        std::fs::write(&input, vec![0u8; 150_000]).unwrap();
        let collapse = Task::Collapse {
            pass: dir.join("pass"),
            input: input.clone(),
            cut: 1.0,
            result_out: dir.join("result"),
        };
        assert_eq!(memory_estimate(&collapse), FIXED + 5 * 150_000);
        let missing = Task::Candidates {
            pass: dir.join("pass"),
            input: dir.join("missing"),
            costs_out: dir.join("costs"),
        };
        assert_eq!(memory_estimate(&missing), FIXED);
        // A block of the size chosen for 3 GB is estimated within 3 GB.
        let n = block_vertices_for(3_000_000_000) as u64;
        assert!(FIXED + DECIMATION_PER_BYTE * INPUT_BYTES_PER_VERTEX * n <= 3_000_000_000);
        assert!(n > 1_000_000, "{n}");
        assert_eq!(block_vertices_for(0), crate::pm::MIN_BLOCK_VERTICES);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
