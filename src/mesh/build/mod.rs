//! Building a half-edge [`Mesh`] from indexed polygons, repairing what would break the
//! half-edge invariants and counting every repair in a [`BuildReport`].
//!
//! The policy (never fails on topology):
//! 1. Polygons are fan-triangulated; triangles with a repeated vertex index are dropped.
//!    Zero-area triangles are kept (they are counted).
//! 2. Each undirected edge pairs at most two triangles. An edge with more (a non-manifold
//!    edge) pairs angular neighbours about the edge that run along it in opposite directions,
//!    as many as possible, preferring pairs that bound one solid (so two solids touching
//!    along an edge stay two closed surfaces); the rest become boundary along that edge.
//! 3. Orientation is made consistent per connected component by a breadth-first walk from the
//!    component's first triangle; the majority orientation wins. Where a component cannot be
//!    oriented (a Möbius band) the offending edge is cut.
//! 4. Every vertex whose triangles form more than one fan (a pinched vertex, or the endpoint of
//!    a cut edge) gets one copy per extra fan, appended after the input's vertices.
//! 5. If two distinct edges still join the same two vertices (possible around tangled
//!    non-manifold edges), one endpoint is detached: all its edges are cut, giving one copy
//!    per triangle. So the result can always be rebuilt from its own triangle list unchanged.
//!
//! Input vertices keep their slots `0..n` in input order (unreferenced ones stay, isolated);
//! faces keep the order of the triangles they come from. [`SourceMap`] maps mesh vertices and
//! faces back onto the input, so processed results can be written in the user's layout.
//!
//! One concern per file: `corners` (the corner table, which the decimator behind `meshpyr
//! simplify` reads without half-edge records), `repair` (the steps above on a corner table),
//! `assemble` (the half-edge records of a repaired corner table).

use super::halfedge::Mesh;
use super::polygon::PolygonMesh;
use glam::DVec3;
use serde::Serialize;

mod assemble;
mod corners;
mod repair;

use assemble::assemble;
pub(crate) use corners::{CornerTable, next_c, prev_c};
pub(crate) use repair::{pair_around_edge, walk_fan};

/// What the builder changed, in counts. All zero for a clean manifold triangle mesh.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BuildReport {
    /// Polygons with more than three corners that were fan-triangulated.
    pub triangulated_polygons: usize,
    /// Triangles dropped because a vertex index repeats in them.
    pub dropped_repeated_index: usize,
    /// Triangles of zero area (kept).
    pub zero_area_faces: usize,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangles form several fans although all their edges are manifold
    /// (pinched vertices).
    pub non_manifold_vertices: usize,
    /// Vertex copies added so that every vertex has a single fan.
    pub split_vertices: usize,
    /// Triangles whose orientation was flipped to agree with their neighbours.
    pub flipped_faces: usize,
    /// Edges cut because their two triangles could not be oriented consistently.
    pub orientation_cuts: usize,
    /// Vertices detached into one copy per triangle because, after fan splitting, two distinct
    /// edges still joined them to the same neighbour (a multi-edge, which a triangle list
    /// cannot express). Their copies are counted in `split_vertices` too.
    pub detached_vertices: usize,
    /// Input vertices no face refers to (kept, isolated).
    pub unreferenced_vertices: usize,
}

impl BuildReport {
    /// True when the input was already a manifold mesh (no non-manifold edge or vertex).
    pub fn input_was_manifold(&self) -> bool {
        self.non_manifold_edges == 0 && self.non_manifold_vertices == 0
    }

    /// True when the builder changed the connectivity in any way.
    pub fn repaired_anything(&self) -> bool {
        self.triangulated_polygons
            + self.dropped_repeated_index
            + self.non_manifold_edges
            + self.split_vertices
            + self.flipped_faces
            + self.orientation_cuts
            > 0
    }
}

/// Where each mesh element came from in the input.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SourceMap {
    /// Input vertex index of each mesh vertex, in mesh slot order. The first
    /// `input_vertices` entries are the identity; split copies follow.
    pub vertex_source: Vec<u32>,
    /// Input polygon index of each mesh face, in mesh slot order.
    pub face_source: Vec<u32>,
    /// Number of vertices in the input.
    pub input_vertices: usize,
}

impl SourceMap {
    /// Maps per-mesh-vertex values back onto the input's vertices. A vertex that was split
    /// gets the mean of its copies; vertices no face refers to get `fallback[i]`.
    pub(crate) fn to_input_positions(
        &self,
        mesh_values: &[DVec3],
        fallback: &[DVec3],
    ) -> Vec<DVec3> {
        let mut out = fallback.to_vec();
        self.write_input_positions(mesh_values, &mut out);
        out
    }

    /// [`SourceMap::to_input_positions`] into `out` (the input's positions, one per input
    /// vertex), in place: the caller needs no second position array. Every input vertex is
    /// a mesh vertex of its own (referenced or not), so each gets the mean of itself and its
    /// copies, summed in mesh order; only the few split vertices need a count.
    pub(crate) fn write_input_positions(&self, mesh_values: &[DVec3], out: &mut [DVec3]) {
        let n = self.input_vertices.min(out.len());
        for (o, &v) in out[..n].iter_mut().zip(mesh_values) {
            *o = DVec3::ZERO + v;
        }
        let mut copies = std::collections::BTreeMap::<u32, u32>::new();
        let split = self.vertex_source.iter().zip(mesh_values).skip(n);
        for (&src, &v) in split {
            if let Some(o) = out.get_mut(src as usize) {
                *o += v;
                *copies.entry(src).or_insert(1) += 1;
            }
        }
        for (src, count) in copies {
            out[src as usize] /= count as f64;
        }
    }
}

/// The result of building: the mesh, what was repaired, and where elements came from.
#[derive(Clone, Debug)]
pub struct Built {
    /// The half-edge mesh.
    pub mesh: Mesh,
    /// What the builder changed.
    pub report: BuildReport,
    /// Mesh → input correspondence.
    pub source: SourceMap,
}

const NONE: u32 = u32::MAX;

/// Input the builder cannot turn into a mesh.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BuildError {
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// Input vertex index.
        vertex: usize,
    },
    /// A polygon refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Input polygon index.
        face: usize,
        /// The offending index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// More than 2^32 − 1 vertices or 1.4e9 triangles.
    #[error("mesh too large for 32-bit indices")]
    TooLarge,
}

impl Mesh {
    /// Builds from a file-level polygon mesh; see the module docs for the repair policy.
    ///
    /// Fails only on geometry the mesh cannot hold: a non-finite coordinate or an index out
    /// of range (readers already reject both, so this guards programmatic input).
    pub fn from_polygons(input: &PolygonMesh) -> Result<Built, BuildError> {
        let repaired = CornerTable::from_polygons(input)?;
        let mesh = assemble(&input.positions, &repaired.corners, &repaired.source);
        Ok(Built {
            mesh,
            report: repaired.report,
            source: repaired.source,
        })
    }

    /// Builds from positions and triangles (a convenience over [`Mesh::from_polygons`]).
    pub fn from_triangles(
        positions: &[DVec3],
        triangles: &[[u32; 3]],
    ) -> Result<Built, BuildError> {
        Mesh::from_polygons(&PolygonMesh::from_triangles(positions.to_vec(), triangles))
    }
}
