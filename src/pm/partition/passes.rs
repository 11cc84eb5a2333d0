//! One pass of the decimator on one block, so that the blocks of a partitioned build can take
//! their passes in step with one cost cut for the whole mesh (`partition/lockstep.rs`): a
//! child of `decimate.rs`, whose pass steps it reuses.
//!
//! One pass of the one-process decimator collects every live edge's cost, cuts them at 1.5×
//! the cost of the candidate that would meet the pass's share of the target, and collapses
//! the rest in cost order, a survivor locked until the pass ends. Locks and legality are local,
//! so a pass over several blocks with the same cut makes, inside each block, the collapses
//! the pass over the whole mesh makes there; only near the pinned borders do they differ.

use super::{
    Candidate, Collapse, DecimateParams, Decimation, FlatMesh, Legality, Pass, collect_candidates,
    drop_dead_triangles, live_triangles, perform_collapses, rank_candidates, unlock_survivors,
};
use crate::pm::quadric::Quadrics;

/// One block's pass: its candidates collected, then collapsed under the whole mesh's cut.
pub(crate) struct Stepper {
    mesh: FlatMesh,
    state: Decimation<'static>,
    cands: Vec<Candidate>,
    live: Vec<u32>,
}

impl Stepper {
    /// A decimation of `mesh` from the quadrics `quadric`.
    pub(crate) fn new(mesh: FlatMesh, quadric: Quadrics) -> Stepper {
        let live = live_triangles(&mesh);
        Stepper {
            mesh,
            state: Decimation {
                quadric,
                locked: Vec::new(),
                collapses: Vec::new(),
                seams: None,
            },
            cands: Vec::new(),
            live,
        }
    }

    /// Collects this pass's candidates within `max_error_sq`, the boundary planes weighted by
    /// `rim_scale`.
    pub(crate) fn collect(&mut self, rim_scale: f64, max_error_sq: f64) {
        drop_dead_triangles(&self.mesh, &mut self.live);
        self.state.quadric.rim_scale = rim_scale;
        let quadric = &self.state.quadric;
        collect_candidates(
            &self.mesh,
            &self.live,
            quadric,
            None,
            max_error_sq,
            &mut self.cands,
        );
    }

    /// The costs of this pass's candidates.
    pub(crate) fn costs(&self) -> impl Iterator<Item = f64> + '_ {
        self.cands.iter().map(|c| c.cost)
    }

    /// Collapses this pass's candidates within `error_cut` in cost order under `legality`;
    /// returns how many.
    pub(crate) fn perform(
        &mut self,
        error_cut: f64,
        legality: Legality,
        params: &DecimateParams,
    ) -> usize {
        if error_cut < f64::INFINITY {
            self.cands.retain(|c| c.cost <= error_cut);
        }
        rank_candidates(&mut self.cands);
        let pass = Pass {
            error_cut,
            legality,
            budget: usize::MAX,
        };
        let made = perform_collapses(&mut self.mesh, &mut self.state, &self.cands, &pass, params);
        unlock_survivors(&mut self.mesh, &mut self.state.locked);
        self.cands.clear();
        made
    }

    /// The collapses made, the mesh and the quadrics at the end.
    pub(crate) fn finish(self) -> (Vec<Collapse>, FlatMesh, Quadrics) {
        (self.state.collapses, self.mesh, self.state.quadric)
    }
}

/// The cut of a pass over all blocks, as the one-process decimator makes it from all
/// candidates: 1.5× the cost of the candidate that would meet the pass's share of the target
/// (`faces_left / 2` collapses), none when `use_goal` is off, never above `max_error_sq`.
pub(crate) fn pass_cut(
    costs: &mut [f64],
    faces_left: usize,
    use_goal: bool,
    max_error_sq: f64,
) -> f64 {
    let goal = (faces_left / 2).max(1);
    let cut = if use_goal && goal < costs.len() {
        let (_, nth, _) = costs.select_nth_unstable_by(goal, f64::total_cmp);
        1.5 * *nth
    } else {
        f64::INFINITY
    };
    cut.min(max_error_sq)
}
