//! One task of a partitioned build: one block decimated with its border pinned, for one pass
//! (`lockstep.rs`) or, for the last block, to the base.
//!
//! A task reads only its [`BlockTask`] — its triangles, the positions, quadrics and pinned
//! flags of their vertices, its rules and, for a textured scan, its corners' wedges with their
//! texture coordinates and attribute quadrics ([`BlockSeams`]) — and returns a
//! [`BlockResult`]: its collapses, its triangles (and their corners' wedges) afterwards and the
//! quadrics its collapses changed. Everything is in the input's
//! vertex numbering, so results of different tasks can be put together without knowing how
//! each task numbered its working mesh; a task run twice gives the same result.
//!
//! Steps:
//! 1. number the block's vertices by input index and build its corner table (half-edges
//!    paired by sorting; a half-edge whose twin is in another block becomes a boundary
//!    half-edge of the block, and both its ends are pinned);
//! 2. pin the border, start the quadrics from the given ones (not from the block's faces: a
//!    border edge is no hole rim, and a vertex's quadric sums the planes of its whole star);
//!    number the block's wedges by their whole-mesh number, so that the one-process seam rule
//!    and attribute cost (`super::super::seams`) decide its collapses. A free vertex has its
//!    whole star, so all its corners and wedges, in the block, and the rule and the cost read
//!    only the corners of the collapse's two ends, both free;
//! 3. decimate: one pass under the whole mesh's cut (`lockstep.rs`), or, for the last block,
//!    which holds the whole mesh and pins nothing, to the end (`decimate_from`), relaxing the
//!    rules where nothing else moves, as the one-process build ends;
//! 4. map the collapses and the triangles back to input indices.

use super::super::Stop;
use super::super::attribute_quadric::AttributeQuadric;
use super::super::decimate::{Collapse, DecimateParams, FlatMesh, Run, SeamFloor, decimate_from};
use super::super::quadric::{Quadric, Quadrics};
use super::super::seams::Seams;
use crate::mesh::build::next_c;
use crate::progress::NoProgress;
use glam::{DVec2, DVec3};

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
    /// A textured scan's seams in the block; `None` decimates without them.
    pub seams: Option<BlockSeams>,
    /// The dearest collapse the passes before made under a cost cut, which caps the last
    /// block's passes without one when it keeps seams, as in one process.
    pub seam_floor: SeamFloor,
}

/// A block's texture seams: the wedge of each corner of its faces and what the seam rule and
/// the attribute cost read of each wedge.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BlockSeams {
    /// Per face of the task, the wedges of its corners (the whole mesh's wedge numbers).
    pub wedges: Vec<[u32; 3]>,
    /// The wedges `wedges` names, ascending.
    pub ids: Vec<u32>,
    /// Per wedge of `ids`: its texture coordinates and attribute quadric (both empty without
    /// texture coordinates or weight).
    pub uv: Vec<DVec2>,
    pub quadrics: Vec<AttributeQuadric>,
    /// `(uv_weight · extent)²`, as the whole build's.
    pub scale: f64,
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
    /// With seams: per triangle of `faces`, its corners' wedges (else empty).
    pub wedges: Vec<[u32; 3]>,
    /// With seams: the attribute quadrics of the wedges at surviving free vertices (the only
    /// ones a collapse changes), ascending by wedge.
    pub wedge_quadrics: Vec<(u32, AttributeQuadric)>,
}

/// Runs one block task to its end; also says why it stopped.
pub(crate) fn decimate_block(task: BlockTask) -> (BlockResult, Stop) {
    let run = Run {
        input_faces: task.input_faces,
        relax: task.last,
        seam_floor: task.seam_floor,
    };
    let params = task.params;
    let (block, mesh, quadric, mut seams) = working_mesh(task);
    let (collapses, mesh, outcome, quadric) =
        decimate_from(mesh, quadric, run, &params, seams.as_mut(), &NoProgress);
    (
        block.result(collapses, &mesh, &quadric, seams.as_ref()),
        outcome.stop,
    )
}

/// What a block keeps while its working mesh is decimated: its vertices (local index →
/// input index), which are pinned, and its wedges (local number → whole-mesh number).
pub(crate) struct Block {
    vertices: Vec<u32>,
    pinned: Vec<bool>,
    wedges: Vec<u32>,
}

/// The working mesh, quadrics and seams of a task (steps 1 and 2), its vertices pinned.
pub(crate) fn working_mesh(task: BlockTask) -> (Block, FlatMesh, Quadrics, Option<Seams>) {
    let BlockTask {
        faces,
        vertices,
        positions,
        quadrics,
        pinned,
        seams,
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
    let (seams, wedges) = match seams {
        Some(s) => {
            let local = |w: u32| s.ids.binary_search(&w).map_or(NONE, |i| i as u32);
            let wedge = s.wedges.iter().flatten().map(|&w| local(w)).collect();
            let seams = Seams::of_block(wedge, s.uv, s.quadrics, s.scale);
            (Some(seams), s.ids)
        }
        None => (None, Vec::new()),
    };
    (
        Block {
            vertices,
            pinned,
            wedges,
        },
        mesh,
        Quadrics::new(planes, &rims),
        seams,
    )
}

impl Block {
    /// The task's result from its decimation (step 4).
    pub(crate) fn result(
        &self,
        collapses: Vec<Collapse>,
        mesh: &FlatMesh,
        quadric: &Quadrics,
        seams: Option<&Seams>,
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
        let triangles = mesh.triangles();
        let (wedges, wedge_quadrics) = match seams {
            Some(s) => self.wedges_after(s, mesh, &triangles),
            None => (Vec::new(), Vec::new()),
        };
        BlockResult {
            collapses,
            faces: triangles.into_iter().map(|t| t.map(global)).collect(),
            quadrics,
            wedges,
            wedge_quadrics,
        }
    }

    /// The wedges of the live `triangles` of `mesh` in whole-mesh numbers, and the attribute
    /// quadrics of the wedges at their free vertices.
    fn wedges_after(
        &self,
        seams: &Seams,
        mesh: &FlatMesh,
        triangles: &[[u32; 3]],
    ) -> (Vec<[u32; 3]>, Vec<(u32, AttributeQuadric)>) {
        let local = seams.live_wedges(mesh);
        let mut free: Vec<u32> = triangles
            .iter()
            .zip(&local)
            .flat_map(|(t, w)| {
                (0..3)
                    .filter(|&k| !self.pinned[t[k] as usize])
                    .map(|k| w[k])
            })
            .collect();
        free.sort_unstable();
        free.dedup();
        let quadrics = free
            .into_iter()
            .filter_map(|w| seams.quadric(w).map(|q| (self.wedges[w as usize], *q)))
            .collect();
        let wedges = local
            .into_iter()
            .map(|w| w.map(|w| self.wedges[w as usize]))
            .collect();
        (wedges, quadrics)
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
