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
use crate::pm::seams::Seams;

/// One block's pass: its candidates collected, then collapsed under the whole mesh's cut.
pub(crate) struct Stepper {
    mesh: FlatMesh,
    quadric: Quadrics,
    /// The block's texture seams, whose wedges follow its collapses; `None` without.
    seams: Option<Seams>,
    collapses: Vec<Collapse>,
    cands: Vec<Candidate>,
    live: Vec<u32>,
}

impl Stepper {
    /// A decimation of `mesh` from the quadrics `quadric`, keeping the seams `seams`.
    pub(crate) fn new(mesh: FlatMesh, quadric: Quadrics, seams: Option<Seams>) -> Stepper {
        let live = live_triangles(&mesh);
        Stepper {
            mesh,
            quadric,
            seams,
            collapses: Vec::new(),
            cands: Vec::new(),
            live,
        }
    }

    /// Collects this pass's candidates within `max_error_sq`, the boundary planes weighted by
    /// `rim_scale`.
    pub(crate) fn collect(&mut self, rim_scale: f64, max_error_sq: f64) {
        drop_dead_triangles(&self.mesh, &mut self.live);
        self.quadric.rim_scale = rim_scale;
        collect_candidates(
            &self.mesh,
            &self.live,
            &self.quadric,
            self.seams.as_ref(),
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
        let mut state = Decimation {
            quadric: std::mem::replace(&mut self.quadric, Quadrics::new(Vec::new(), &[])),
            locked: Vec::new(),
            collapses: std::mem::take(&mut self.collapses),
            seams: self.seams.as_mut(),
        };
        let made = perform_collapses(&mut self.mesh, &mut state, &self.cands, &pass, params);
        unlock_survivors(&mut self.mesh, &mut state.locked);
        self.quadric = state.quadric;
        self.collapses = state.collapses;
        self.cands.clear();
        made
    }

    /// The collapses made, the mesh, the quadrics and the seams at the end.
    pub(crate) fn finish(self) -> (Vec<Collapse>, FlatMesh, Quadrics, Option<Seams>) {
        (self.collapses, self.mesh, self.quadric, self.seams)
    }
}

/// How many collapses a pass over a mesh of `faces` aims at: each removes about two faces, so
/// half of the faces left above `target_faces` (at least one).
pub(crate) fn pass_goal(faces: usize, target_faces: usize) -> usize {
    ((faces - target_faces.min(faces)) / 2).max(1)
}

/// A pass's cost cut from `nth`, the cost of the candidate that would meet its goal (`None`:
/// no cut, there are fewer candidates or the pass goes without one): 1.5× that cost, since
/// many candidates get locked, and never above `max_error_sq`.
pub(crate) fn cut_at(nth: Option<f64>, max_error_sq: f64) -> f64 {
    nth.map_or(f64::INFINITY, |c| 1.5 * c).min(max_error_sq)
}

/// The cut of a pass over all blocks, as the one-process decimator makes it from all
/// candidates ([`pass_goal`], [`cut_at`]), none when `use_goal` is off.
pub(crate) fn pass_cut(costs: &mut [f64], goal: usize, use_goal: bool, max_error_sq: f64) -> f64 {
    let nth = (use_goal && goal < costs.len())
        .then(|| *costs.select_nth_unstable_by(goal, f64::total_cmp).1);
    cut_at(nth, max_error_sq)
}

/// Whether the next partitioned pass takes a cost cut, and how many passes in a row found
/// nothing (after as many as there are frames, every frame's cells have had their turn).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Turns {
    pub use_goal: bool,
    pub idle: usize,
}

impl Turns {
    /// Before the first pass: with the cut, nothing idle.
    pub(crate) const START: Turns = Turns {
        use_goal: true,
        idle: 0,
    };

    /// After a pass under `cut` that `collapsed` something or not: a pass that collapses
    /// nothing is repeated without the cut, as in one process; once that finds nothing either,
    /// the next frame's cells get their turn.
    pub(crate) fn after(&mut self, collapsed: bool, cut: f64, max_error_sq: f64) {
        if collapsed {
            *self = Turns::START;
        } else if self.use_goal && cut < max_error_sq {
            self.use_goal = false;
        } else {
            self.idle += 1;
        }
    }
}
