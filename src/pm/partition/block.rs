//! One task of a partitioned build: one block decimated with its border pinned, for one pass
//! (`lockstep.rs`) or, for the last block, to the base.
//!
//! A task reads only its [`BlockTask`] — its triangles, the positions, quadrics and pinned
//! flags of their vertices, its rules — and returns a [`BlockResult`]: its collapses, its
//! triangles afterwards and the quadrics its collapses changed. Everything is in the input's
//! vertex numbering, so results of different tasks can be put together without knowing how
//! each task numbered its working mesh; a task run twice gives the same result.
//!
//! Steps:
//! 1. number the block's vertices by input index and build its corner table (half-edges
//!    paired by sorting; a half-edge whose twin is in another block becomes a boundary
//!    half-edge of the block, and both its ends are pinned);
//! 2. pin the border, start the quadrics from the given ones (not from the block's faces: a
//!    border edge is no hole rim, and a vertex's quadric sums the planes of its whole star);
//! 3. decimate: one pass under the whole mesh's cut (`lockstep.rs`), or, for the last block,
//!    which holds the whole mesh and pins nothing, to the end (`decimate_from`), relaxing the
//!    rules where nothing else moves, as the one-process build ends;
//! 4. map the collapses and the triangles back to input indices.

use super::super::Stop;
use super::super::decimate::{Collapse, DecimateParams, FlatMesh, Run, decimate_from};
use super::super::quadric::{Quadric, Quadrics};
use crate::mesh::build::next_c;
use crate::progress::NoProgress;
use glam::DVec3;

const NONE: u32 = u32::MAX;

/// A vertex's quadric: the planes of its faces (with the point regulariser) and of its
/// boundary edges, which the decimator weighs by level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct VertexQuadric {
    pub planes: Quadric,
    pub rim: Option<Quadric>,
}

/// What one block task reads.
#[derive(Clone, Debug)]
pub(crate) struct BlockTask {
    /// The block's triangles, in input vertex indices.
    pub faces: Vec<[u32; 3]>,
    /// The vertices of `faces`, ascending.
    pub vertices: Vec<u32>,
    /// Per vertex of `vertices`: position (in the build's frame), quadric, whether pinned.
    pub positions: Vec<DVec3>,
    pub quadrics: Vec<VertexQuadric>,
    pub pinned: Vec<bool>,
    /// The input faces the block covers (the rules' coarseness is measured against them).
    pub input_faces: usize,
    /// The decimator's targets, bound and rules for this block.
    pub params: DecimateParams,
    /// Whether this is the last block (the whole mesh once it fits one): it may relax the rules.
    pub last: bool,
}

/// What one block task returns.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BlockResult {
    /// The collapses in the order made, in input vertex indices.
    pub collapses: Vec<Collapse>,
    /// The block's triangles afterwards, in input vertex indices.
    pub faces: Vec<[u32; 3]>,
    /// The quadrics of the surviving free vertices (the only ones a collapse changes).
    pub quadrics: Vec<(u32, VertexQuadric)>,
}

/// Runs one block task to its end; also says why it stopped.
pub(crate) fn decimate_block(task: BlockTask) -> (BlockResult, Stop) {
    let run = Run {
        input_faces: task.input_faces,
        relax: task.last,
    };
    let params = task.params;
    let (block, mesh, quadric) = working_mesh(task);
    let (collapses, mesh, outcome, quadric) =
        decimate_from(mesh, quadric, run, &params, None, &NoProgress);
    (block.result(collapses, &mesh, &quadric), outcome.stop)
}

/// What a block keeps while its working mesh is decimated: its vertices (local index →
/// input index) and which are pinned.
pub(crate) struct Block {
    vertices: Vec<u32>,
    pinned: Vec<bool>,
}

/// The working mesh and quadrics of a task (steps 1 and 2), its vertices pinned.
pub(crate) fn working_mesh(task: BlockTask) -> (Block, FlatMesh, Quadrics) {
    let BlockTask {
        faces,
        vertices,
        positions,
        quadrics,
        pinned,
        ..
    } = task;
    let local = |v: u32| vertices.binary_search(&v).map_or(NONE, |i| i as u32);
    let corner_vertex: Vec<u32> = faces.iter().flatten().map(|&v| local(v)).collect();
    drop(faces);
    let twin = pair_half_edges(&corner_vertex);
    let mut mesh = FlatMesh::at_positions(positions, &corner_vertex, twin, None);
    for (i, _) in pinned.iter().enumerate().filter(|(_, p)| **p) {
        mesh.pin(i as u32);
    }
    let rims: Vec<(u32, Quadric)> = (0..quadrics.len() as u32)
        .filter_map(|v| quadrics[v as usize].rim.map(|r| (v, r)))
        .collect();
    let planes = quadrics.iter().map(|q| q.planes).collect();
    (
        Block { vertices, pinned },
        mesh,
        Quadrics::new(planes, &rims),
    )
}

impl Block {
    /// The task's result from its decimation (step 4).
    pub(crate) fn result(
        &self,
        collapses: Vec<Collapse>,
        mesh: &FlatMesh,
        quadric: &Quadrics,
    ) -> BlockResult {
        let global = |v: u32| {
            if v == NONE {
                NONE
            } else {
                self.vertices[v as usize]
            }
        };
        let collapses = collapses
            .into_iter()
            .map(|c| Collapse {
                from: global(c.from),
                to: global(c.to),
                left: global(c.left),
                right: global(c.right),
                error_sq: c.error_sq,
            })
            .collect();
        let quadrics = mesh
            .survivors()
            .into_iter()
            .filter(|&v| !self.pinned[v as usize])
            .map(|v| {
                let q = VertexQuadric {
                    planes: quadric.faces[v as usize],
                    rim: quadric.rim(v).copied(),
                };
                (global(v), q)
            })
            .collect();
        BlockResult {
            collapses,
            faces: mesh
                .triangles()
                .into_iter()
                .map(|t| t.map(global))
                .collect(),
            quadrics,
        }
    }
}

/// The twin of every half-edge of the triangles `corner_vertex` (half-edge `c` runs from
/// corner `c` to the next corner of its triangle), boundary half-edges numbered after the
/// corners in the order of their corners, as [`FlatMesh::at_positions`] takes them.
fn pair_half_edges(corner_vertex: &[u32]) -> Vec<u32> {
    let nh = corner_vertex.len() as u32;
    let ends = |c: u32| (corner_vertex[c as usize], corner_vertex[next_c(c) as usize]);
    let mut by_ends: Vec<u32> = (0..nh).collect();
    by_ends.sort_unstable_by_key(|&c| ends(c));
    let mut twin = vec![NONE; nh as usize];
    for c in 0..nh {
        let (a, b) = ends(c);
        if let Ok(i) = by_ends.binary_search_by_key(&(b, a), |&x| ends(x)) {
            twin[c as usize] = by_ends[i];
        }
    }
    for c in 0..nh {
        if twin[c as usize] == NONE {
            twin[c as usize] = twin.len() as u32;
            twin.push(c);
        }
    }
    twin
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_edges_pair_across_shared_edges_and_open_ones_get_boundary_twins() {
        // Two triangles sharing the edge 1-2.
        let twin = pair_half_edges(&[0, 1, 2, 2, 1, 3]);
        assert_eq!(twin.len(), 6 + 4);
        assert_eq!(twin[1], 3); // 1→2 pairs with 2→1
        assert_eq!(twin[3], 1);
        for c in [0, 2, 4, 5] {
            let b = twin[c] as usize;
            assert!(b >= 6);
            assert_eq!(twin[b], c as u32);
        }
    }
}
