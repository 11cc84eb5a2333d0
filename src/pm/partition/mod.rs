//! The partitioned build of the progressive mesh: the same half-edge collapses, decided in
//! spatial blocks with their borders pinned and merged pairwise up a tree until one block
//! holds the base (`docs/partitioned.md`). The systems that scale mesh simplification work
//! this way (Nexus's `nxsbuild`, meshoptimizer's clusterlod); Hoppe's view-dependent
//! refinement (SIGGRAPH 1998) builds a large terrain's progressive mesh as a hierarchy of
//! such block refinements.
//!
//! Steps ([`decimate_in_blocks`]):
//! 1. the whole mesh's quadrics, once (a vertex's quadric sums its whole star's planes);
//! 2. the vertices cut into `2^depth` cells of at most the block size (`cells.rs`), the
//!    leaves of a complete binary merge tree (`tree.rs`);
//! 3. level by level from the leaves, every node's block decimated with its border pinned
//!    (`block.rs`); a node's block is what its two children left plus the input faces across
//!    their border, whose vertices are free now. Below the root the blocks of a level take
//!    their passes in step, one cost cut per pass for the whole mesh (`lockstep.rs`), down to
//!    `2^-(j+1)` of the input's vertices at level `j`; the root decimates alone to the base;
//! 4. each level's collapses interleaved by cost (`order.rs`) and the levels concatenated:
//!    one collapse sequence of the whole mesh, put into PM order like the one-process
//!    build's.
//!
//! Each level of the merge tree is a level of detail of the whole mesh, and a block holds
//! about the block size at every level. A block below the root never relaxes the shape
//! rules; only the root, whose result is the base, does, as the one-process build does at
//! its end.
//!
//! Results depend on the input and the block size only: each task is a function of its
//! inputs, tasks of a level are collected in node order, and the merge breaks ties by node.

mod block;
mod cells;
mod lockstep;
mod order;
mod tree;

use super::PmError;
use super::decimate::{DecimateParams, FlatMesh, initial_quadrics};
use super::progressive::Decimated;
use crate::progress::Progress;
use block::{BlockResult, BlockTask, VertexQuadric, decimate_block};
use glam::DVec3;
use lockstep::Level;
use rayon::prelude::*;
use tree::MergeTree;

/// Decimates `flat` in blocks of at most `max_block` vertices (see the module docs).
pub(crate) fn decimate_in_blocks(
    flat: FlatMesh,
    params: &DecimateParams,
    max_block: usize,
    progress: &dyn Progress,
) -> Result<Decimated, PmError> {
    let quadric = initial_quadrics(&flat, params.boundary_weight);
    let positions = flat.positions();
    let faces = flat.triangles();
    let referenced = flat.survivors();
    drop(flat);
    let mut quadrics: Vec<VertexQuadric> = (0..positions.len())
        .map(|v| VertexQuadric {
            planes: quadric.faces[v],
            rim: quadric.rim(v as u32).copied(),
        })
        .collect();
    drop(quadric);
    let totals = (referenced.len(), faces.len());
    let cells = cells::split_cells(&positions, referenced, max_block);
    let tree = MergeTree::new(&cells.cell_of, cells.depth, &faces);
    drop(cells);
    let input = Input {
        positions: &positions,
        faces: &faces,
        tree: &tree,
        params,
    };
    let mut below: Vec<Vec<[u32; 3]>> = Vec::new();
    let mut collapses = Vec::new();
    let mut vertices = totals.0;
    for j in 0..=tree.depth {
        let tasks = (0..tree.nodes_at(j)).into_par_iter();
        let tasks: Vec<BlockTask> = tasks.map(|k| input.task(j, k, &below, &quadrics)).collect();
        // The input faces outside every block of the level join above it, untouched.
        let pending_faces = totals.1 - tasks.iter().map(|t| t.input_faces).sum::<usize>();
        let results: Vec<BlockResult> = if j == tree.depth {
            tasks.into_iter().map(decimate_block).collect()
        } else {
            let level = Level {
                input_faces: totals.1,
                pending_faces,
                vertices,
                target_vertices: (totals.0 >> (j + 1)).max(params.target_vertices),
            };
            lockstep::decimate_in_step(tasks, &level, params)
        };
        vertices -= results.iter().map(|r| r.collapses.len()).sum::<usize>();
        let mut level = Vec::with_capacity(results.len());
        below = Vec::with_capacity(results.len());
        for r in results {
            for &(v, q) in &r.quadrics {
                quadrics[v as usize] = q;
            }
            level.push(r.collapses);
            below.push(r.faces);
            if j == tree.depth {
                let base = below.pop().unwrap_or_default();
                collapses.extend(order::merge_by_cost(level));
                progress.update(1.0);
                return Ok(Decimated {
                    collapses,
                    survivors: vertices_of(&base),
                    n_base_faces: base.len(),
                    stop: r.stop,
                });
            }
        }
        collapses.extend(order::merge_by_cost(level));
        progress.update(f64::from(j + 1) / f64::from(tree.depth + 1));
    }
    Err(PmError::Internal("the merge tree has no root".into()))
}

/// What every task of a build reads from.
struct Input<'a> {
    positions: &'a [DVec3],
    faces: &'a [[u32; 3]],
    tree: &'a MergeTree,
    params: &'a DecimateParams,
}

impl Input<'_> {
    /// The task of node `k` at level `j`: its children's triangles (`below`, the previous
    /// level's results) and the input faces that join here.
    fn task(
        &self,
        j: u32,
        k: usize,
        below: &[Vec<[u32; 3]>],
        quadrics: &[VertexQuadric],
    ) -> BlockTask {
        let mut faces: Vec<[u32; 3]> = Vec::new();
        if j > 0 {
            faces.extend_from_slice(&below[2 * k]);
            faces.extend_from_slice(&below[2 * k + 1]);
        }
        let joined = self.tree.joined(j, k).iter();
        faces.extend(joined.map(|&t| self.faces[t as usize]));
        let vertices = vertices_of(&faces);
        BlockTask {
            positions: vertices
                .iter()
                .map(|&v| self.positions[v as usize])
                .collect(),
            quadrics: vertices.iter().map(|&v| quadrics[v as usize]).collect(),
            pinned: vertices
                .iter()
                .map(|&v| self.tree.is_pinned(j, k, v))
                .collect(),
            faces,
            vertices,
            input_faces: self.tree.faces_in(j, k),
            params: *self.params,
            last: j == self.tree.depth,
        }
    }
}

/// The vertices of `faces`, ascending.
fn vertices_of(faces: &[[u32; 3]]) -> Vec<u32> {
    let mut v: Vec<u32> = faces.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    v
}
