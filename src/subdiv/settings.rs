//! Subdivision as a front end asks for it: the scheme, refinement and solver by name, and the
//! solver `auto` resolved against the input's size. The command line and the Python package
//! both translate their syntax into [`SubdivSettings`], so they share the names, the defaults
//! and the mapping.

use super::{Refinement, Scheme, Solver, SubdivOptions};
use crate::choice::Choice;

impl Choice for Scheme {
    const WHAT: &'static str = "subdivision scheme";
    const ALL: &'static [Scheme] = &[Scheme::Mcm, Scheme::Loop];

    fn name(self) -> &'static str {
        match self {
            Scheme::Mcm => "mcm",
            Scheme::Loop => "loop",
        }
    }

    fn about(self) -> &'static str {
        match self {
            Scheme::Mcm => {
                "Implicit mean-curvature motion with cascadic multigrid (Diewald–Morigi–Rumpf)"
            }
            Scheme::Loop => "Loop's scheme (quadrisection only)",
        }
    }
}

impl Choice for Refinement {
    const WHAT: &'static str = "refinement";
    const ALL: &'static [Refinement] = &[Refinement::Quadrisection, Refinement::Bisection];

    fn name(self) -> &'static str {
        match self {
            Refinement::Quadrisection => "quad",
            Refinement::Bisection => "bisect",
        }
    }

    fn about(self) -> &'static str {
        match self {
            Refinement::Quadrisection => "1-to-4 split at edge midpoints (4× faces per level)",
            Refinement::Bisection => "Conforming newest-vertex bisection (2× faces per level)",
        }
    }
}

/// A [`Solver`] by name, or `auto`: chosen by [`Solver::auto`] from the output's size.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolverChoice {
    /// [`Solver::auto`].
    #[default]
    Auto,
    /// [`Solver::Jacobi`].
    Jacobi,
    /// [`Solver::Cg`].
    Cg,
    /// [`Solver::Exact`].
    Exact,
}

impl Choice for SolverChoice {
    const WHAT: &'static str = "solver";
    const ALL: &'static [SolverChoice] = &[
        SolverChoice::Auto,
        SolverChoice::Jacobi,
        SolverChoice::Cg,
        SolverChoice::Exact,
    ];

    fn name(self) -> &'static str {
        match self {
            SolverChoice::Auto => "auto",
            SolverChoice::Jacobi => "jacobi",
            SolverChoice::Cg => "cg",
            SolverChoice::Exact => "exact",
        }
    }

    fn about(self) -> &'static str {
        match self {
            SolverChoice::Auto => {
                "`exact` while the output has at most 250k vertices (where the cascadic \
                 approximation visibly oscillates on coarse inputs and the exact solve costs \
                 little), `cg` above"
            }
            SolverChoice::Jacobi => "Cascadic damped Jacobi",
            SolverChoice::Cg => "Cascadic Jacobi-preconditioned CG",
            SolverChoice::Exact => {
                "Exact per level (sparse Cholesky; CG to 1e-10 in builds without the `solver` \
                 feature)"
            }
        }
    }
}

/// The options of subdivision that front ends offer, with their defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubdivSettings {
    /// Refinement levels.
    pub levels: usize,
    /// Position rule.
    pub scheme: Scheme,
    /// Refinement rule.
    pub refinement: Refinement,
    /// Solver of the MCM levels.
    pub solver: SolverChoice,
    /// [`SubdivOptions::width`].
    pub width: f64,
    /// [`SubdivOptions::local_width`].
    pub local_width: bool,
    /// [`SubdivOptions::finest_steps`].
    pub finest_steps: usize,
    /// [`SubdivOptions::beta`].
    pub beta: Option<f64>,
}

impl Default for SubdivSettings {
    /// [`SubdivOptions::default`]'s values, the solver `auto`.
    fn default() -> Self {
        let d = SubdivOptions::default();
        SubdivSettings {
            levels: d.levels,
            scheme: d.scheme,
            refinement: d.refinement,
            solver: SolverChoice::Auto,
            width: d.width,
            local_width: d.local_width,
            finest_steps: d.finest_steps,
            beta: d.beta,
        }
    }
}

impl SubdivSettings {
    /// The options for an input of `input_vertices` vertices (`auto` picks the solver from
    /// the output's size).
    pub fn options(&self, input_vertices: usize) -> SubdivOptions {
        SubdivOptions {
            levels: self.levels,
            scheme: self.scheme,
            refinement: self.refinement,
            solver: match self.solver {
                SolverChoice::Auto => Solver::auto(input_vertices, self.levels, self.refinement),
                SolverChoice::Jacobi => Solver::Jacobi,
                SolverChoice::Cg => Solver::Cg,
                SolverChoice::Exact => Solver::Exact,
            },
            width: self.width,
            local_width: self.local_width,
            finest_steps: self.finest_steps,
            beta: self.beta,
            ..SubdivOptions::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_is_exact_on_small_outputs_and_cg_on_large_ones() {
        let settings = SubdivSettings::default();
        assert_eq!(settings.options(100).solver, Solver::Exact);
        assert_eq!(settings.options(1_000_000).solver, Solver::Cg);
        let jacobi = SubdivSettings {
            solver: SolverChoice::Jacobi,
            ..settings
        };
        assert_eq!(jacobi.options(100).solver, Solver::Jacobi);
    }
}
