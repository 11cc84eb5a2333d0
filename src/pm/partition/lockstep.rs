//! The blocks of one merge-tree level below the root decimated in step: pass by pass, each
//! pass with one cost cut and one set of rules for the whole mesh, as the one-process
//! decimator's pass would have them (`decimate/passes.rs`).
//!
//! Steps of a pass: every block collects its candidates (in parallel); the cut is 1.5× the
//! cost of the candidate that would meet half the whole mesh's faces left, taken over all
//! blocks' candidates; every block collapses its candidates under the cut (in parallel). A
//! pass that collapses nothing is repeated without the cut, as in one process; the level ends
//! after the pass that brings the whole mesh to the level's vertex target, or when nothing
//! is left to collapse (a block never relaxes the rules: only the root does).
//!
//! Why in step: each block decimated by itself to its own target follows its own pass
//! schedule, which makes a different hierarchy from the one-process one everywhere; in step,
//! the blocks' interiors collapse what one process collapses there, and the hierarchies
//! differ near the borders.

use super::super::Stop;
use super::super::decimate::passes::{Stepper, pass_cut};
use super::super::decimate::{DecimateParams, rim_scale_at_level};
use super::block::{BlockResult, BlockTask, working_mesh};
use rayon::prelude::*;

/// The whole mesh around a level: what is outside its blocks and where the level ends.
pub(crate) struct Level {
    /// Faces of the input (the rules' coarseness is measured against them).
    pub input_faces: usize,
    /// Faces not in any block of the level (they join above it).
    pub pending_faces: usize,
    /// Vertices of the whole mesh left when the level starts.
    pub vertices: usize,
    /// The level ends once at most this many are left.
    pub target_vertices: usize,
}

/// Decimates the level's `tasks` in step; their results in task order.
pub(crate) fn decimate_in_step(
    tasks: Vec<BlockTask>,
    level: &Level,
    params: &DecimateParams,
) -> Vec<BlockResult> {
    let block_params = DecimateParams {
        target_vertices: 0,
        target_faces: 0,
        ..*params
    };
    let mut blocks: Vec<_> = tasks
        .into_par_iter()
        .map(|t| {
            let (block, mesh, quadric) = working_mesh(t);
            (block, Stepper::new(mesh, quadric))
        })
        .collect();
    let mut vertices = level.vertices;
    let mut use_goal = true;
    let mut costs: Vec<f64> = Vec::new();
    while vertices > level.target_vertices {
        let faces = level.pending_faces + blocks.iter().map(|b| b.1.n_faces()).sum::<usize>();
        let rim_scale = rim_scale_at_level(faces, level.input_faces);
        blocks
            .par_iter_mut()
            .for_each(|b| b.1.collect(rim_scale, params.max_error_sq));
        costs.clear();
        costs.extend(blocks.iter().flat_map(|b| b.1.costs()));
        if costs.is_empty() {
            break;
        }
        let faces_left = faces - params.target_faces.min(faces);
        let cut = pass_cut(&mut costs, faces_left, use_goal, params.max_error_sq);
        let legality = params.legality.at_level(faces, level.input_faces);
        let made: usize = blocks
            .par_iter_mut()
            .map(|b| b.1.perform(cut, legality, &block_params))
            .sum();
        vertices -= made;
        if made == 0 {
            if use_goal && cut < params.max_error_sq {
                use_goal = false;
                continue;
            }
            break;
        }
        use_goal = true;
    }
    blocks
        .into_par_iter()
        .map(|(block, stepper)| {
            let (collapses, mesh, quadric) = stepper.finish();
            let stop = Stop::NoLegalCollapse(Vec::new());
            block.result(collapses, &mesh, &quadric, stop)
        })
        .collect()
}
