//! The progressive mesh (PM): quadric-error half-edge collapses recorded as exact vertex
//! splits, vertices renumbered so that level `n` is the mesh on the first `n` vertices, and a
//! cursor that walks the levels up and down (`docs/algorithms.md` §4, "Progressive mesh
//! conventions").
//!
//! - [`collapse`]: the half-edge collapse / vertex split primitives and the legality tests.
//! - [`Legality`]: the shape rules a collapse must keep, and how a stalled decimation relaxes
//!   them ([`Relaxation`]).
//! - [`quadric`]: area-weighted plane quadrics.
//! - `decimate`: the greedy batched decimation loop, on a flat corner table.
//! - [`ProgressiveMesh`] / [`PmCursor`]: the hierarchy and its cursor.
//! - [`FlatReplay`]: vertex splits replayed on flat arrays (reading and writing `.pyr` files).
//! - [`simplify()`]: a file-level mesh cut at a level, attributes carried along.
//! - `fuzz`: the body of the `pm_ops` fuzz target (`meshpyr::fuzzing::fuzz_operations`).

pub mod collapse;
mod decimate;
#[cfg(test)]
mod decimate_reference;
pub(crate) mod fuzz;
mod legality;
pub(crate) mod prefetch;
mod progressive;
pub mod quadric;
mod replay;
pub mod simplify;

pub use collapse::{
    CollapseTopology, Marks, MeshRecords, SplitError, canonicalize, collapse_topology,
    half_edge_collapse, is_collapse_geometrically_legal, is_collapse_legal,
    is_collapse_topologically_legal, vertex_split,
};
pub use decimate::Stop;
pub(crate) use fuzz::fuzz_operations;
pub use legality::{Legality, Refusal, Relaxation};
pub use progressive::{
    PmCursor, PmError, PmOptions, PmParts, ProgressiveMesh, SplitReplay, VertexSplit,
};
pub use replay::{FaceBuckets, FlatReplay, canonical_sorted};
pub use simplify::{Simplified, SimplifyError, SimplifyTarget, simplify};
