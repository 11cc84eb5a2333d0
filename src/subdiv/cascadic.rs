//! Cascadic MCM subdivision (Diewald–Morigi–Rumpf 2001, `docs/algorithms.md` §3).
//!
//! One fully implicit step of mean-curvature motion of width σ = c·h_0 (diffusion
//! coefficient α = σ²/2 over unit time) is approximated by a fixed-point iteration that
//! refines the grid on every step:
//!
//! ```text
//! M_k   := Refinement(M_{k−1})                  new vertices at edge midpoints
//! (M + α L) x_k = M · I x_0                     M, L: lumped mass and cotangent stiffness
//!                                               of M_{k−1} prolonged onto the level-k grid
//! ```
//!
//! The right-hand side is always the **initial** surface x_0, interpolated by the same
//! refinement rules — never x_{k−1}, which would apply k diffusion steps and keep shrinking.
//! Each level's system is smoothed from the prolonged x_{k−1} by `m_l` steps of damped Jacobi
//! or preconditioned CG (cascadic multigrid, `m_l = ⌈m_{l_max} β^{l_max−l}⌉`: many steps on
//! the cheap coarse levels, few on the fine ones), or solved exactly.
//!
//! Local filter width (Diewald–Morigi–Rumpf §7; `docs/algorithms.md` §3.6): with a smoothed
//! grid-size function h (initially the mean length of the edges at each vertex),
//! `α_k = (c · I h_{k−1})²/2` per vertex, averaged per triangle, and h is diffused with the
//! same matrix: `(M + L^α)[x_k, h_k] = M [I x_0, I h_0]`.
//!
//! Results are bit-for-bit reproducible on any number of threads: every sum runs in a fixed
//! order, and what runs in parallel is independent work. With quadrisection, a level's
//! half-edge connectivity (needed only by the next refinement) is built on one core while the
//! level's system is assembled and solved from flat arrays on the other; the last level's is
//! never built, since the output is its triangles.

use super::halfedge_arrays::HalfedgeArrays;
use super::refine::{
    BisectionLevel, Prolongation, QuadTopology, bisect_level, initial_marking,
    quadrisect_connectivity, quadrisection_parts, quadrisection_stiffness,
};
use super::{Refinement, Solver, SubdivError, SubdivOptions, Subdivision, compact, default_beta};
use crate::mesh::{Mesh, SlotIndex};
use crate::numerics::fem::{
    SymmetricCsr, identity_rows, mass_of, mass_rhs, stiffness_from_weights, system_matrix,
    triangle_weights,
};
use crate::numerics::solvers::{conjugate_gradient, jacobi, relative_residual, solve_exact};
use crate::progress::Progress;
use glam::DVec3;

/// What the solver did on one level.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelReport {
    /// Level, 1-based.
    pub level: usize,
    /// Vertices on this level.
    pub vertices: usize,
    /// Faces on this level.
    pub faces: usize,
    /// Smoothing or CG steps taken (0 for a direct solve).
    pub steps: usize,
    /// ‖A x − b‖ / ‖b‖ after the solve (largest over the coordinate columns).
    pub relative_residual: f64,
}

/// The cascadic schedule `m_l = ⌈m_{l_max}·β^{l_max−l}⌉` for `l = 1..=levels`, each capped
/// at `cap`.
pub(crate) fn schedule(levels: usize, finest_steps: usize, beta: f64, cap: usize) -> Vec<usize> {
    (1..=levels)
        .map(|l| {
            let m = finest_steps as f64 * beta.powi((levels - l) as i32);
            if m.is_finite() {
                // Forgive rounding: 2·(2√2)² must give 16, not 17.
                ((m * (1.0 - 1e-12)).ceil() as usize).min(cap)
            } else {
                cap
            }
        })
        .collect()
}

/// Mean length of the edges at each vertex (0 for an isolated vertex), indexed by slot.
pub(crate) fn vertex_grid_size(mesh: &Mesh) -> Vec<f64> {
    let mut h = vec![0.0; mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0)];
    for v in mesh.vertices() {
        let (s, n) = mesh
            .outgoing(v)
            .fold((0.0, 0usize), |(s, n), e| (s + mesh.edge_length(e), n + 1));
        h[v.slot()] = if n == 0 { 0.0 } else { s / n as f64 };
    }
    h
}

/// Cascadic MCM subdivision; see the module docs. Prefer [`super::subdivide`], which also
/// checks the output size.
pub fn subdivide_mcm(
    mesh: &Mesh,
    options: &SubdivOptions,
    progress: &dyn Progress,
) -> Result<Subdivision, SubdivError> {
    let input = prepare_input(mesh, options)?;
    let mut cascade = Cascade::start(&input, options)?;
    let reports = run_levels(&mut cascade, options, progress)?;
    Ok(cascade.finish(reports))
}

/// Refines and solves every level of the schedule, reporting progress weighted by the
/// levels' sizes.
fn run_levels(
    cascade: &mut Cascade,
    options: &SubdivOptions,
    progress: &dyn Progress,
) -> Result<Vec<LevelReport>, SubdivError> {
    let steps = level_steps(options);
    let growth = level_growth(options.refinement);
    let total: f64 = (1..=options.levels).map(|l| growth.powi(l as i32)).sum();
    let mut done = 0.0;
    let mut reports = Vec::with_capacity(options.levels);
    // One hand-over into rayon's pool for the whole schedule: the joins and parallel loops of
    // every level then start from a worker, which is far cheaper than each one waking the
    // pool from outside (measurable on small levels).
    rayon::scope(|_| -> Result<(), SubdivError> {
        for level in 1..=options.levels {
            let Some(report) = cascade.advance(level, steps[level - 1])? else {
                break;
            };
            reports.push(report);
            done += growth.powi(level as i32);
            progress.update(done / total);
        }
        Ok(())
    })?;
    Ok(reports)
}

/// Checks the options and the input, and gives the input with dense slots.
fn prepare_input(mesh: &Mesh, options: &SubdivOptions) -> Result<Mesh, SubdivError> {
    options.validate()?;
    if mesh.n_faces() == 0 {
        return Err(SubdivError::NoFaces);
    }
    super::check_output_size(mesh, options.levels, options.face_factor(), usize::MAX)?;
    compact(mesh)
}

/// The smoothing or CG steps of every level, by the cascadic schedule.
fn level_steps(options: &SubdivOptions) -> Vec<usize> {
    let beta = options
        .beta
        .unwrap_or_else(|| default_beta(options.solver, options.refinement));
    schedule(
        options.levels,
        options.finest_steps,
        beta,
        options.max_steps_per_level,
    )
}

/// How many times the faces multiply per level, which weighs the levels' progress.
fn level_growth(refinement: Refinement) -> f64 {
    match refinement {
        Refinement::Quadrisection => 4.0,
        Refinement::Bisection => 2.0,
    }
}

/// The current level: its positions and triangles, the connectivity the next refinement
/// reads (flat half-edge arrays for quadrisection; faces, neighbours and newest vertices for
/// bisection, which keep the triangles themselves), and what its system reads.
struct Cascade<'a> {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    connectivity: Option<Connectivity>,
    system: LevelSystem<'a>,
}

/// A refined level with its solution.
struct RefinedLevel {
    /// The connectivity the next refinement reads (none after the last quadrisection).
    next: Option<Connectivity>,
    /// The level's triangles, unless its connectivity keeps them (bisection).
    triangles: Option<Vec<[u32; 3]>>,
    faces: usize,
    solution: Result<Solved, String>,
}

/// What a level's solve gives.
struct Solved {
    steps: usize,
    residual: f64,
    positions: Vec<DVec3>,
}

impl<'a> Cascade<'a> {
    /// Level 0: the input itself.
    fn start(input: &Mesh, options: &'a SubdivOptions) -> Result<Self, SubdivError> {
        let c = options.width;
        let h0 = input.mean_edge_length();
        let h_init = vertex_grid_size(input);
        let h_cur = h_init.clone();
        let (positions, triangles) = input.to_triangles();
        let x0: Vec<DVec3> = positions.clone();
        let connectivity = Some(match options.refinement {
            Refinement::Quadrisection => Connectivity::Quad(HalfedgeArrays::from_mesh(input)),
            Refinement::Bisection => {
                Connectivity::Bisect(BisectionLevel::from_mesh(input, &initial_marking(input)?)?)
            }
        });
        Ok(Self {
            positions,
            triangles,
            connectivity,
            system: LevelSystem {
                options,
                alpha: 0.5 * (c * h0) * (c * h0),
                x0,
                h_init,
                h_cur,
            },
        })
    }

    /// Refines the current level and solves the new one's system from `m_l` steps; `None`
    /// when no connectivity is left to refine.
    fn advance(&mut self, level: usize, m_l: usize) -> Result<Option<LevelReport>, SubdivError> {
        let last = level == self.system.options.levels;
        // Only the last quadrisection level leaves no connectivity behind.
        let Some(current) = self.connectivity.take() else {
            return Ok(None);
        };
        let refined = match current {
            Connectivity::Quad(coarse) => {
                quadrisect_and_solve(coarse, &self.positions, last, &mut self.system, m_l)
            }
            Connectivity::Bisect(coarse) => {
                bisect_and_solve(coarse, &self.positions, level, &mut self.system, m_l)?
            }
        };
        let solved = check_solution(level, refined.solution)?;
        self.connectivity = refined.next;
        self.positions = solved.positions;
        if let Some(fine) = refined.triangles {
            self.triangles = fine;
        }
        Ok(Some(LevelReport {
            level,
            vertices: self.positions.len(),
            faces: refined.faces,
            steps: solved.steps,
            relative_residual: solved.residual,
        }))
    }

    /// The last level as the subdivision.
    fn finish(mut self, reports: Vec<LevelReport>) -> Subdivision {
        if let Some(Connectivity::Bisect(level)) = self.connectivity {
            self.triangles = level.triangles;
        }
        Subdivision {
            positions: self.positions,
            triangles: self.triangles,
            levels: reports,
        }
    }
}

/// Quadrisects `positions`' level; the next refinement's connectivity is built on another
/// core while this level solves, and the last level needs none.
fn quadrisect_and_solve(
    coarse: HalfedgeArrays,
    positions: &[DVec3],
    last: bool,
    system: &mut LevelSystem,
    m_l: usize,
) -> RefinedLevel {
    let (topo, prolongation, fine_positions) = quadrisection_parts(&coarse, positions);
    let (fine, solution) = rayon::join(
        || (!last).then(|| quadrisect_connectivity(&coarse, &topo)),
        || {
            system.solve(
                m_l,
                &topo.triangles,
                fine_positions,
                &prolongation,
                Some((&coarse, &topo)),
            )
        },
    );
    let faces = topo.triangles.len();
    RefinedLevel {
        next: fine.map(Connectivity::Quad),
        triangles: Some(topo.triangles),
        faces,
        solution,
    }
}

/// Bisects `positions`' level and solves the new one; the triangles stay with the level,
/// which the next bisection reads.
fn bisect_and_solve(
    coarse: BisectionLevel,
    positions: &[DVec3],
    level: usize,
    system: &mut LevelSystem,
    m_l: usize,
) -> Result<RefinedLevel, SubdivError> {
    let (fine, prolongation) = bisect_level(&coarse, positions.len()).map_err(|e| match e {
        SubdivError::NotManifold { .. } => SubdivError::NotManifold { level },
        e => e,
    })?;
    drop(coarse);
    let fine_positions = prolongation.apply(positions);
    let solution = system.solve(m_l, &fine.triangles, fine_positions, &prolongation, None);
    let faces = fine.triangles.len();
    Ok(RefinedLevel {
        next: Some(Connectivity::Bisect(fine)),
        triangles: None,
        faces,
        solution,
    })
}

/// The level's solution, or the solver's failure on it (non-finite positions included).
fn check_solution(level: usize, solution: Result<Solved, String>) -> Result<Solved, SubdivError> {
    let fail = |why: String| SubdivError::SolverFailed { level, why };
    let solved = solution.map_err(fail)?;
    if solved.positions.iter().any(|p| !p.is_finite()) {
        return Err(fail("non-finite positions".to_string()));
    }
    Ok(solved)
}

/// What every level's system reads besides its own grid: the initial surface x_0 and grid
/// size h_0, interpolated onto the current level, and the smoothed grid size.
struct LevelSystem<'a> {
    options: &'a SubdivOptions,
    /// The diffusion coefficient of the uniform width.
    alpha: f64,
    x0: Vec<DVec3>,
    h_init: Vec<f64>,
    h_cur: Vec<f64>,
}

/// The coarse mesh and layout of a quadrisection, from which its stiffness is read.
type QuadCoarse<'b> = Option<(&'b HalfedgeArrays, &'b QuadTopology)>;

impl LevelSystem<'_> {
    /// Solves a level's system from the prolonged positions by `m_l` steps; it needs only
    /// flat arrays: triangles, prolongation and positions.
    fn solve(
        &mut self,
        m_l: usize,
        triangles: &[[u32; 3]],
        positions: Vec<DVec3>,
        prolongation: &Prolongation,
        quad: QuadCoarse,
    ) -> Result<Solved, String> {
        self.x0 = prolongation.apply(&self.x0);
        if self.options.local_width {
            self.solve_local_width(m_l, triangles, &positions, prolongation, quad)
        } else {
            self.solve_uniform_width(m_l, triangles, positions, quad)
        }
    }

    /// The local filter width: the grid size is diffused with the positions.
    fn solve_local_width(
        &mut self,
        m_l: usize,
        triangles: &[[u32; 3]],
        positions: &[DVec3],
        prolongation: &Prolongation,
        quad: QuadCoarse,
    ) -> Result<Solved, String> {
        self.h_init = prolongation.apply(&self.h_init);
        self.h_cur = prolongation.apply(&self.h_cur);
        let coef = face_coefficients(triangles, &self.h_cur, self.options.width);
        let (mass, stiffness) =
            assemble_mass_and_stiffness(triangles, positions, Some(&coef), quad);
        let pinned = identity_rows(&mass);
        let a = system_matrix(&mass, stiffness, 1.0);
        let b: Vec<[f64; 4]> = (0..positions.len())
            .map(|i| {
                let w = if pinned[i] { 1.0 } else { mass[i] };
                let p = self.x0[i] * w;
                [p.x, p.y, p.z, self.h_init[i] * w]
            })
            .collect();
        let mut x: Vec<[f64; 4]> = positions
            .iter()
            .zip(&self.h_cur)
            .map(|(p, &h)| [p.x, p.y, p.z, h])
            .collect();
        let taken = run_solver(self.options, &a, &b, &mut x, m_l)?;
        let residual = relative_residual(&a, &b, &x);
        self.h_cur = x.iter().map(|v| v[3]).collect();
        Ok(Solved {
            steps: taken,
            residual,
            positions: x.iter().map(|v| DVec3::new(v[0], v[1], v[2])).collect(),
        })
    }

    /// The uniform filter width, solved in place: the prolonged positions are the start, and
    /// the solution is the level's positions (a DVec3 is three f64).
    fn solve_uniform_width(
        &self,
        m_l: usize,
        triangles: &[[u32; 3]],
        mut positions: Vec<DVec3>,
        quad: QuadCoarse,
    ) -> Result<Solved, String> {
        let (mass, stiffness) = assemble_mass_and_stiffness(triangles, &positions, None, quad);
        let a = system_matrix(&mass, stiffness, self.alpha);
        let b = mass_rhs(&mass, &self.x0);
        let x: &mut [[f64; 3]] = bytemuck::cast_slice_mut(&mut positions);
        let taken = run_solver(self.options, &a, &b, x, m_l)?;
        let residual = relative_residual(&a, &b, x);
        Ok(Solved {
            steps: taken,
            residual,
            positions,
        })
    }
}

/// Per triangle, the mean over its vertices of `α = (c·h)²/2`.
fn face_coefficients(triangles: &[[u32; 3]], h_cur: &[f64], c: f64) -> Vec<f64> {
    let alpha_v: Vec<f64> = h_cur.iter().map(|h| 0.5 * (c * h) * (c * h)).collect();
    triangles
        .iter()
        .map(|t| t.iter().map(|&v| alpha_v[v as usize]).sum::<f64>() / 3.0)
        .collect()
}

/// Mass and stiffness from one pass over the triangles; a quadrisection reads its sparsity
/// off the coarse mesh (the same bits as the general assembly).
fn assemble_mass_and_stiffness(
    triangles: &[[u32; 3]],
    positions: &[DVec3],
    coef: Option<&[f64]>,
    quad: QuadCoarse,
) -> (Vec<f64>, SymmetricCsr) {
    let tri_weights = triangle_weights(triangles, positions, coef);
    let mass = mass_of(triangles, &tri_weights, positions.len());
    let stiffness = quad
        .and_then(|(coarse, topo)| quadrisection_stiffness(coarse, topo, &tri_weights))
        .unwrap_or_else(|| stiffness_from_weights(triangles, positions.len(), &tri_weights));
    (mass, stiffness)
}

/// What the next refinement reads.
enum Connectivity {
    /// Quadrisection: the flat half-edge arrays.
    Quad(HalfedgeArrays),
    /// Bisection: the faces, their neighbours across each edge and their newest vertices.
    Bisect(BisectionLevel),
}

fn run_solver<const K: usize>(
    options: &SubdivOptions,
    a: &SymmetricCsr,
    b: &[[f64; K]],
    x: &mut [[f64; K]],
    m_l: usize,
) -> Result<usize, String> {
    match options.solver {
        Solver::Jacobi => {
            jacobi(a, b, x, m_l, options.jacobi_damping);
            Ok(m_l)
        }
        Solver::Cg => Ok(conjugate_gradient(a, b, x, m_l, options.cg_tolerance)),
        Solver::Exact => solve_exact(a, b, x, options.exact_tolerance),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_follows_the_geometric_law() {
        let s = schedule(4, 2, 2.0 * std::f64::consts::SQRT_2, 10_000);
        // ⌈2·(2√2)^3⌉ = ⌈45.25⌉, ⌈2·8⌉, ⌈2·2.83⌉, 2.
        assert_eq!(s, vec![46, 16, 6, 2]);
        assert_eq!(schedule(3, 1, 4.0, 10), vec![10, 4, 1]);
    }
}
