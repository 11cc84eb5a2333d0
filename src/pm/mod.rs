//! The progressive mesh (PM): quadric-error half-edge collapses recorded as exact vertex
//! splits, vertices renumbered so that level `n` is the mesh on the first `n` vertices, and a
//! cursor that walks the levels up and down (`docs/algorithms.md` §4, "Progressive mesh
//! conventions").
//!
//! - `collapse`: the half-edge collapse / vertex split primitives and the legality tests.
//! - [`Legality`]: the shape rules a collapse must keep, and how a stalled decimation relaxes
//!   them ([`Relaxation`]).
//! - `quadric`: area-weighted plane quadrics.
//! - `decimate`: the greedy batched decimation loop, on a flat corner table.
//! - `partition`: the same decimation in spatial blocks with pinned borders, the cells cut
//!   differently from pass to pass ([`PmOptions::block_vertices`]; `docs/partitioned.md`);
//!   [`blocks`]: its passes' tasks as functions of files.
//! - [`ProgressiveMesh`] / [`PmCursor`]: the hierarchy and its cursor.
//! - [`FlatReplay`]: vertex splits replayed on flat arrays (reading and writing `.pyr` files).
//! - [`level_corners()`] / [`level_mesh()`]: a level of a hierarchy that keeps texture seams
//!   with the per-corner data of its faces, replayed from the finest corners.
//! - [`simplify()`]: a file-level mesh cut at a level, attributes carried along;
//!   [`simplify_to_goal`] takes the target as front ends give it, small pieces pruned first.
//! - `fuzz`: the body of the `pm_ops` fuzz target (`meshpyr::fuzzing::fuzz_operations`).

mod attribute_quadric;
pub(crate) mod collapse;
mod decimate;
#[cfg(test)]
mod decimate_reference;
pub(crate) mod fuzz;
mod goal;
mod legality;
mod level_corners;
mod partition;
mod pins;
pub mod blocks {
    //! The tasks of a partitioned build run through files (`docs/partitioned.md`, "Running
    //! the passes through files"; the files: `formats/blocks.md`), one function per task, and
    //! what runs a round of them. A scheduler that runs [`Task`]s on other processes (with
    //! [`run_task`] there) and hands their outputs back gives the same hierarchy as this
    //! process's threads. [`memory_estimate`] is the memory a task declares to such a
    //! scheduler (`meshpyr.dask`: the Dask resource `MEMORY`).
    pub use super::partition::runner::{
        RayonRunner, SharedRunner, Task, TaskOutput, TaskRunner, run_task,
    };
    pub use super::partition::stream::{
        CellEntry, CellPatches, Copies, Cut, ExtraFan, Flips, GlobalRepair, Manifest, PieceCounts,
        SplitError, SplitOptions, cell_fans, cell_patches, cell_piece, cell_pieces, fans_task,
        hierarchy_from_cells, number_copies, orient, patches_task, piece_task, split_into_cells,
    };
    pub use super::partition::task_memory::{block_vertices_for, memory_estimate};
    pub use super::partition::taskfile::BlockFileError;
    pub use super::partition::tasks::{
        HISTOGRAM_BITS, HistogramRound, assemble, candidates, collapse, concat, cost_histogram,
        finish, gather, select_cost, split,
    };
}
pub(crate) mod prefetch;
mod progressive;
pub(crate) mod quadric;
mod replay;
mod seams;
pub(crate) mod simplify;

pub use collapse::SplitError;
pub use collapse::{
    CollapseTopology, Marks, MeshRecords, half_edge_collapse, is_collapse_legal, vertex_split,
};
pub use decimate::Stop;
pub(crate) use fuzz::fuzz_operations;
pub use goal::{SimplifyGoal, simplify_to_goal};
pub use legality::Refusal;
pub use legality::{Legality, Relaxation};
pub use level_corners::{LevelFaces, SeamBreak, level_corners, level_mesh};
pub(crate) use partition::read_any as fuzz_read_block_file;
pub use partition::taskfile::BlockFileError;
pub use pins::{Pins, PinsError};
pub use progressive::SplitReplay;
pub use progressive::keeps_texture_seams;
pub(crate) use progressive::triangles_of;
pub use progressive::{
    FirstPieces, MIN_BLOCK_VERTICES, PmCursor, PmOptions, PmParts, ProgressiveMesh,
};
pub use progressive::{PmError, VertexSplit};
pub use replay::FlatReplay;
pub(crate) use replay::{FaceBuckets, canonical_sorted};
pub use simplify::SimplifyError;
pub use simplify::{Simplified, SimplifyTarget, simplify};
