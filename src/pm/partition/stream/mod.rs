//! The streaming split of a scan into cell files, and the cell tasks that turn each cell into a
//! first piece of the partitioned build through files (`docs/partitioned.md`, "Splitting a
//! scan into cell files in one pass"; the files: `formats/blocks.md`, "Cell files").
//!
//! Steps of [`split_into_cells`] (`split.rs`), one read of a PLY file:
//! 1. **vertices**: their positions streamed to `positions.f64` (for access by index), the
//!    bounding box kept and a reservoir sample drawn (`sample.rs`, seeded from the header's
//!    counts, so that the sample depends on the mesh, not on its encoding);
//! 2. **cut tree**: a k-d tree cut at the sample's medians along the first pass's frame
//!    (`tree.rs`), deep enough that a cell holds at most the block size within the sample's
//!    error;
//! 3. **labels**: each vertex located in the tree, its cell written to `cell_of.u32` and the
//!    vertex appended to its cell's `c{k}.vert`;
//! 4. **faces**: the polygons streamed, fan-triangulated as the mesh builder does (triangles
//!    with a repeated vertex dropped), each triangle appended to `c{k}.face` of every cell
//!    that holds one of its vertices, tagged with its owner (the cell of its first vertex);
//! 5. **borders**: per cell, the positions of the other cells' vertices its triangles use, in
//!    `c{k}.border`; then the manifest.
//!
//! Memory: the sample (32 bytes a point), the tree (16 bytes a cut), one write buffer per cell
//! (`SplitOptions::buffer_bytes`), a chunk of decoded rows, and in step 5 one cell's triangles
//! and border; `cell_of.u32` and `positions.f64` are read through memory maps, whose pages the
//! kernel drops when it needs the memory. Nothing is proportional to the whole mesh.
//!
//! Then the **cell tasks** (`cell.rs`), from one cell's files: the builder's repairs that are
//! local — pairing the half-edges of every edge at the cell's vertices (non-manifold edges by
//! angle, with the builder's own code) and splitting a vertex into one copy per fan — and the
//! quadrics of the cell's vertices, summed in triangle order in the whole mesh's frame, so that
//! they equal the one-process `initial_quadrics` bit for bit. Two decisions are not local and
//! take a round through the driver each: the **orientation** of each component (the builder
//! orients a whole component, the majority winning, so one flipped patch can flip faces of
//! every cell: [`cell_patches`], then [`orient`], `orient.rs`) and the **copies' numbers**
//! (numbered after the input's vertices in the order of their fans' first corners over the
//! whole mesh: [`cell_fans`], then [`number_copies`]); then [`cell_piece`]. Two repairs are
//! refused with [`SplitError::NotLocal`] rather than made differently: a component that cannot
//! be oriented (the builder cuts the edge its walk meets first) and **detaching multi-edges**
//! (a loop over the whole mesh until none is left). A refusal of any cell voids every cell's
//! piece: the caller builds such a scan from the whole mesh's first pieces.
//!
//! The rounds run as tasks of a runner (`rounds.rs`), each writing a small file the driver
//! reads back, so that a scheduler runs them where it runs the passes; the first pass then
//! takes the split's cells as they are ([`first_cells`] draws the same cells from a mesh in
//! memory, for the paths that make their first pieces from the whole mesh).

mod build;
mod cell;
mod files;
mod first;
mod orient;
mod rounds;
mod sample;
mod split;
mod tree;

#[cfg(test)]
mod tests;

pub use build::hierarchy_from_cells;
pub(crate) use build::{assemble_from_cells, decimate_from_cells};
pub use cell::{Copies, ExtraFan, PieceCounts, cell_fans, cell_piece, cell_pieces, number_copies};
pub use files::{CellEntry, Cut, Manifest};
pub(crate) use first::{InputPoints, first_cells};
pub use orient::{CellPatches, Flips, cell_patches, orient};
pub use rounds::{fans_task, patches_task, piece_task};
pub(crate) use rounds::{read_any_round, run as run_cell_task};
pub use split::{SplitOptions, split_into_cells};

use super::taskfile::BlockFileError;
use crate::io::IoError;
use std::path::PathBuf;

/// Why the streaming split or a cell task failed.
#[derive(Debug, thiserror::Error)]
pub enum SplitError {
    /// The input cannot be read: the reader's error, with the file and the byte or line.
    #[error(transparent)]
    Read(#[from] IoError),
    /// A cell file or the manifest cannot be written or read back: the file, the byte, what.
    #[error(transparent)]
    File(#[from] BlockFileError),
    /// The passes or the hierarchy's assembly failed ([`hierarchy_from_cells`]).
    #[error(transparent)]
    Build(#[from] crate::pm::PmError),
    /// The input needs a repair that a cell cannot make from its own files.
    #[error("{}: byte {offset}: {what}", path.display())]
    NotLocal {
        /// The cell file that shows it.
        path: PathBuf,
        /// The record that shows it.
        offset: u64,
        /// Which repair.
        repair: GlobalRepair,
        /// What was found, and why it is refused.
        what: String,
    },
}

/// A repair of the mesh builder that depends on more than one cell's triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlobalRepair {
    /// A component cannot be oriented (a Möbius band): the builder cuts the edge its walk
    /// meets first.
    Orientation,
    /// Two distinct edges join the same two vertices after fan splitting: the builder detaches
    /// one end in a loop over the whole mesh.
    MultiEdge,
}
