//! One pass of a partitioned build over its blocks, in step: one cost cut and one set of rules
//! for the whole mesh, as the one-process decimator's pass would have them
//! (`decimate.rs`, `decimate/passes.rs`).
//!
//! Steps: every block collects its candidates (in parallel); the cut is 1.5× the cost of the
//! candidate that would meet half the whole mesh's faces left, taken over all blocks'
//! candidates; every block collapses its candidates under the cut in cost order (in
//! parallel), a survivor locked until the pass ends.
//!
//! Locks and legality are local, so a pass over the blocks with the whole mesh's cut makes,
//! inside each block, the collapses the pass over the whole mesh makes there; only the edges
//! at pinned vertices wait, for the next pass, whose cells are cut differently.

use super::super::decimate::passes::{Stepper, pass_cut, pass_goal};
use super::super::decimate::{DecimateParams, rim_scale_at_level};
use super::block::{BlockResult, BlockTask, working_mesh};
use rayon::prelude::*;

/// The whole mesh around a pass.
pub(crate) struct Whole {
    /// Faces of the input (the rules' coarseness is measured against them).
    pub input_faces: usize,
    /// Faces of the whole mesh when the pass starts (in blocks or across them).
    pub faces: usize,
    /// Whether the pass takes the cost cut (off after a pass that collapsed nothing).
    pub use_goal: bool,
    /// The highest cut a pass may take (the seam floor's cap, `docs/seams.md`; else infinite).
    pub cap: f64,
}

/// One pass over the blocks `tasks`: their results in task order and the pass's cost cut.
pub(crate) fn pass_in_step(
    tasks: Vec<BlockTask>,
    whole: &Whole,
    params: &DecimateParams,
) -> (Vec<BlockResult>, f64) {
    let block_params = DecimateParams {
        target_vertices: 0,
        target_faces: 0,
        ..*params
    };
    let rim_scale = rim_scale_at_level(whole.faces, whole.input_faces);
    let blocks: Vec<_> = tasks
        .into_par_iter()
        .map(|t| {
            let (block, mesh, quadric, seams) = working_mesh(t);
            let mut stepper = Stepper::new(mesh, quadric, seams);
            stepper.collect(rim_scale, params.max_error_sq);
            (block, stepper)
        })
        .collect();
    let mut costs: Vec<f64> = blocks.iter().flat_map(|b| b.1.costs()).collect();
    let goal = pass_goal(whole.faces, params.target_faces);
    let cut = pass_cut(&mut costs, goal, whole.use_goal, params.max_error_sq).min(whole.cap);
    drop(costs);
    let legality = params.legality.at_level(whole.faces, whole.input_faces);
    let results = blocks
        .into_par_iter()
        .map(|(block, mut stepper)| {
            stepper.perform(cut, legality, &block_params);
            let (collapses, mesh, quadric, seams) = stepper.finish();
            block.result(collapses, &mesh, &quadric, seams.as_ref())
        })
        .collect();
    (results, cut)
}
