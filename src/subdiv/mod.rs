//! Subdivision of triangle meshes: implicit mean-curvature motion with cascadic multigrid
//! (Diewald–Morigi–Rumpf 2001), and Loop subdivision as the baseline.
//!
//! One algorithm per file:
//! - [`refine`]: 1-to-4 quadrisection and conforming newest-vertex bisection, each giving a new
//!   [`Mesh`] plus the [`Prolongation`] (which coarse vertices every new vertex interpolates);
//!   the level loops run quadrisection on flat half-edge arrays (`halfedge_arrays`) instead;
//! - `loop_scheme`: Loop's scheme with the usual boundary rules;
//! - `cascadic`: the level loop `(M + αL) x_k = M · I x_0` with damped Jacobi, CG or exact
//!   solves, the cascadic schedule and the local filter-width expansion; the lumped mass,
//!   cotangent stiffness (on the prolonged surface) and solvers are [`crate::numerics`].
//!
//! One Jacobi update of the implicit MCM system, as a relaxation for the detail pyramid, is
//! [`crate::relax::MeanCurvatureStep`].
//!
//! The output is a *new* mesh: the coarse vertices come first (same order as the input's
//! vertex slots), new vertices follow. No attributes are carried over.

pub(crate) mod cascadic;
mod halfedge_arrays;
pub(crate) mod loop_scheme;
pub mod refine;
mod settings;

pub use cascadic::LevelReport;
pub use cascadic::subdivide_mcm;
pub use loop_scheme::{loop_step, subdivide_loop};
pub use refine::Prolongation;
pub use refine::{Marking, Refined};
pub use settings::{SolverChoice, SubdivSettings};

use crate::mesh::{Mesh, PolygonMesh};
use crate::progress::Progress;
use glam::DVec3;

/// Which subdivision rule computes the new positions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scheme {
    /// Implicit mean-curvature motion of the refined surface (Diewald–Morigi–Rumpf).
    #[default]
    Mcm,
    /// Loop's approximating scheme (quadrisection only).
    Loop,
}

/// How the triangles are split on each level.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Refinement {
    /// 1-to-4 split at the edge midpoints: 4× faces per level.
    #[default]
    Quadrisection,
    /// Newest-vertex bisection with a compatible (conforming) marking: 2× faces per level.
    Bisection,
}

/// How the per-level linear system `(M + αL) x = M · I x_0` is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Solver {
    /// Cascadic damped Jacobi: `m_l` smoothing steps on level `l`.
    Jacobi,
    /// Cascadic Jacobi-preconditioned conjugate gradients: `m_l` steps on level `l`.
    #[default]
    Cg,
    /// Exact solve per level: sparse Cholesky (faer, cargo feature `solver`); without that
    /// feature, preconditioned CG to [`SubdivOptions::exact_tolerance`].
    Exact,
}

impl Solver {
    /// Largest output, in vertices, for which [`Solver::auto`] picks the exact solve.
    pub const AUTO_EXACT_MAX_VERTICES: f64 = 250_000.0;

    /// The solver `meshpyr subdivide --solver auto` uses for a mesh of `input_vertices`
    /// (after the builder's repairs): [`Solver::Exact`] while the output has at most
    /// [`Self::AUTO_EXACT_MAX_VERTICES`] vertices, where the cascadic approximation visibly
    /// oscillates on coarse inputs and the exact solve costs little, [`Solver::Cg`] above.
    pub fn auto(input_vertices: usize, levels: usize, refinement: Refinement) -> Solver {
        // Each quadrisection level multiplies the vertex count by about 4, a bisection level
        // by 2.
        let growth: f64 = match refinement {
            Refinement::Quadrisection => 4.0,
            Refinement::Bisection => 2.0,
        };
        let output_vertices = input_vertices as f64 * growth.powi(levels.min(64) as i32);
        if output_vertices <= Self::AUTO_EXACT_MAX_VERTICES {
            Solver::Exact
        } else {
            Solver::Cg
        }
    }
}

/// Options of [`subdivide`]. Every constant of the method is here, with its default.
#[derive(Clone, Debug, PartialEq)]
pub struct SubdivOptions {
    /// Number of refinement levels `l_max` (default 3).
    pub levels: usize,
    /// Position rule (default [`Scheme::Mcm`]).
    pub scheme: Scheme,
    /// Refinement rule (default [`Refinement::Quadrisection`]).
    pub refinement: Refinement,
    /// Linear solver for MCM (default [`Solver::Cg`], the cascadic multigrid).
    pub solver: Solver,
    /// Filter-width constant `c`: the filter width is `σ = c·h_0` (h_0 = mean edge length of
    /// the input, or the local grid-size function with [`Self::local_width`]), and the
    /// diffusion coefficient is `α = σ²/2`. Dimensionless, default 0.25. One implicit step
    /// keeps a sphere of radius r only if α ≤ r²/8, so `c·h_0` must stay well below the
    /// feature size; larger values shrink the surface more (see the README table).
    pub width: f64,
    /// Local filter-width expansion (Diewald–Morigi–Rumpf §7; `docs/algorithms.md` §3.6): `α`
    /// follows a smoothed local grid size that is diffused with the surface (default false).
    pub local_width: bool,
    /// Smoothing steps on the finest level, `m_{l_max}` (default 2).
    pub finest_steps: usize,
    /// Growth factor `β` of the cascadic schedule `m_l = ⌈m_{l_max}·β^{l_max−l}⌉`; `None`
    /// picks `default_beta` (2√2 for CG with quadrisection).
    pub beta: Option<f64>,
    /// Upper bound on `m_l` for any level, so that huge `levels` cannot ask for an absurd
    /// number of coarse-level steps (default 10 000).
    pub max_steps_per_level: usize,
    /// Damping `ω` of the Jacobi smoother (default 2/3, the classic smoothing-optimal value;
    /// any ω < 2/λ_max(D⁻¹A) converges).
    pub jacobi_damping: f64,
    /// Cascadic CG stops a column early when its residual falls below this fraction of the
    /// right-hand side (default 1e-12; guards the division by zero after exact convergence).
    pub cg_tolerance: f64,
    /// Relative residual of the CG used for [`Solver::Exact`] without the `solver` feature,
    /// and the acceptance check of the Cholesky solve (default 1e-10).
    pub exact_tolerance: f64,
    /// Refuse to produce more faces than this (default 20 000 000, about 4 GB of half-edge
    /// mesh): `levels` is a user input and 4^levels grows fast.
    pub max_output_faces: usize,
}

impl Default for SubdivOptions {
    fn default() -> Self {
        SubdivOptions {
            levels: 3,
            scheme: Scheme::Mcm,
            refinement: Refinement::Quadrisection,
            solver: Solver::Cg,
            width: 0.25,
            local_width: false,
            finest_steps: 2,
            beta: None,
            max_steps_per_level: 10_000,
            jacobi_damping: 2.0 / 3.0,
            cg_tolerance: 1e-12,
            exact_tolerance: 1e-10,
            max_output_faces: 20_000_000,
        }
    }
}

/// The default growth factor `β` of the cascadic schedule (`docs/algorithms.md` §3.5, from the
/// Bornemann–Deuflhard bounds with mesh-size ratio κ): CG is optimal for κ⁻¹ < β < κ⁻² and
/// takes the geometric mean; Jacobi takes β = κ⁻² ("nearly optimal", O(N log N)).
///
/// | | quadrisection (κ = ½) | bisection (κ = 1/√2) |
/// |---|---|---|
/// | CG | 2√2 | 2^¾ |
/// | Jacobi | 4 | 2 |
///
/// The exact solver has no schedule; it returns the CG value.
pub(crate) fn default_beta(solver: Solver, refinement: Refinement) -> f64 {
    match (solver, refinement) {
        (Solver::Jacobi, Refinement::Quadrisection) => 4.0,
        (Solver::Jacobi, Refinement::Bisection) => 2.0,
        (_, Refinement::Quadrisection) => 2.0 * std::f64::consts::SQRT_2,
        (_, Refinement::Bisection) => 2f64.powf(0.75),
    }
}

/// The result of [`subdivide`].
#[derive(Clone, Debug)]
pub struct Subdivision {
    /// Vertex positions of the refined mesh: the input's vertices first (in slot order), then
    /// the new vertices, level by level (one per edge of the level before, in
    /// [`Mesh::edges`] order, for quadrisection).
    pub positions: Vec<DVec3>,
    /// Triangles of the refined mesh, indexing `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// One entry per level: counts, solver steps and residuals (0 and 0 for Loop).
    pub levels: Vec<LevelReport>,
}

impl Subdivision {
    /// The refined surface as a half-edge [`Mesh`] (vertex and face slots in the order of
    /// `positions` and `triangles`).
    ///
    /// Built on request because the result itself is flat: at a million vertices the
    /// half-edge mesh takes about 400 MB, which callers that only write or measure the
    /// surface do not need. Fails with [`SubdivError::NotManifold`] when the triangles are
    /// not a manifold the builder takes without repair, which happens only for degenerate
    /// inputs: a two-triangle "pillow" refines into triangles with four faces on an edge.
    pub fn mesh(&self) -> Result<Mesh, SubdivError> {
        refine::build(&self.positions, &self.triangles, self.levels.len())
    }
}

/// Why a subdivision could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SubdivError {
    /// The input cannot be turned into a half-edge mesh.
    #[error(transparent)]
    Build(#[from] crate::mesh::BuildError),
    /// The input has no triangle.
    #[error("the mesh has no triangles to subdivide")]
    NoFaces,
    /// The output would exceed [`SubdivOptions::max_output_faces`] (or the 32-bit index range,
    /// whichever is smaller).
    #[error(
        "{levels} levels would make {} faces, above the limit of {limit} ({}): use fewer levels",
        FaceCount(*faces),
        limit_source(*limit)
    )]
    TooLarge {
        /// Requested levels.
        levels: usize,
        /// Faces the output would have (saturating: `usize::MAX` stands for more).
        faces: usize,
        /// The limit.
        limit: usize,
    },
    /// An option is out of its valid range.
    #[error("invalid option {name}: {why}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// What is wrong with it.
        why: String,
    },
    /// Loop's rules are defined for quadrisection only.
    #[error("Loop subdivision needs quadrisection refinement (bisection has no Loop rules)")]
    LoopNeedsQuadrisection,
    /// No conforming bisection marking exists: some triangle can be paired neither with a
    /// neighbour across a shared refinement edge nor with a boundary edge.
    #[error(
        "bisection: face {face} cannot be given a compatible refinement edge (no perfect pairing of the triangles exists)"
    )]
    NoCompatibleMarking {
        /// Face index (slot order) that stayed unpaired.
        face: usize,
    },
    /// Bisection would join the midpoint of a refinement edge to the same apex from both
    /// sides: the two triangles across that edge share all three vertices (a closed
    /// two-triangle component, often what repairing duplicated faces leaves), and no manifold
    /// bisection of it exists. Quadrisection handles it.
    #[error(
        "bisection: face {face} and the face across its refinement edge share all three vertices (a closed two-triangle component); use --refine quad, or remove that component"
    )]
    FoldedPair {
        /// Face index (slot order) of one of the two triangles.
        face: usize,
    },
    /// A refinement produced a mesh the half-edge builder had to repair, which means the
    /// input mesh violated an invariant.
    #[error("refinement produced a non-manifold mesh at level {level}")]
    NotManifold {
        /// Level (1-based).
        level: usize,
    },
    /// The sparse solver failed (for example a matrix that is not positive definite because
    /// of degenerate triangles).
    #[error("linear solve failed on level {level}: {why}")]
    SolverFailed {
        /// Level (1-based).
        level: usize,
        /// Reason.
        why: String,
    },
}

impl SubdivOptions {
    /// Checks ranges; called by [`subdivide`].
    pub fn validate(&self) -> Result<(), SubdivError> {
        let bad = |name, why: &str| {
            Err(SubdivError::InvalidOption {
                name,
                why: why.to_string(),
            })
        };
        if !(self.width.is_finite() && self.width >= 0.0) {
            return bad("width", "must be a finite number ≥ 0");
        }
        if let Some(b) = self.beta
            && !(b.is_finite() && b >= 1.0)
        {
            return bad("beta", "must be a finite number ≥ 1");
        }
        if !(self.jacobi_damping > 0.0 && self.jacobi_damping < 2.0) {
            return bad("jacobi_damping", "must lie in (0, 2)");
        }
        if !(self.cg_tolerance.is_finite() && self.cg_tolerance > 0.0) {
            return bad("cg_tolerance", "must be a positive number");
        }
        if !(self.exact_tolerance.is_finite() && self.exact_tolerance > 0.0) {
            return bad("exact_tolerance", "must be a positive number");
        }
        if self.scheme == Scheme::Loop && self.refinement != Refinement::Quadrisection {
            return Err(SubdivError::LoopNeedsQuadrisection);
        }
        Ok(())
    }

    /// Faces per input face after all levels (4^levels or 2^levels), saturating.
    pub(crate) fn face_factor(&self) -> usize {
        let per_level: usize = match self.refinement {
            Refinement::Quadrisection => 4,
            Refinement::Bisection => 2,
        };
        (0..self.levels).fold(1usize, |f, _| f.saturating_mul(per_level))
    }
}

/// Subdivides `mesh` by `options.levels` levels with the chosen scheme, refinement and solver.
///
/// The input is compacted first (slot order kept), so meshes with deleted elements work.
/// Isolated vertices are copied through unchanged.
pub fn subdivide(
    mesh: &Mesh,
    options: &SubdivOptions,
    progress: &dyn Progress,
) -> Result<Subdivision, SubdivError> {
    options.validate()?;
    if mesh.n_faces() == 0 {
        return Err(SubdivError::NoFaces);
    }
    check_output_size(
        mesh,
        options.levels,
        options.face_factor(),
        options.max_output_faces,
    )?;
    match options.scheme {
        Scheme::Loop => subdivide_loop(mesh, options.levels, progress),
        Scheme::Mcm => subdivide_mcm(mesh, options, progress),
    }
}

/// [`subdivide`] on a mesh as read from a file (repaired first, as every command does): the
/// subdivided triangle mesh. Progress is not reported; call [`subdivide`] for that and for the
/// per-level statistics.
pub fn subdivide_mesh(
    input: &PolygonMesh,
    options: &SubdivOptions,
) -> Result<PolygonMesh, SubdivError> {
    let built = Mesh::from_polygons(input)?;
    let result = subdivide(&built.mesh, options, &crate::progress::NoProgress)?;
    Ok(PolygonMesh::from_triangle_vec(
        result.positions,
        result.triangles,
    ))
}

/// A face count for messages; a saturated count reads as "more than" the largest one.
struct FaceCount(usize);

impl std::fmt::Display for FaceCount {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 == usize::MAX {
            write!(f, "more than {:.1e}", usize::MAX as f64)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// What sets a face limit, for [`SubdivError::TooLarge`]: the 32-bit indices or the option
/// (which the command line leaves at its default).
fn limit_source(limit: usize) -> &'static str {
    if limit == INDEX_FACE_LIMIT {
        "32-bit element indices"
    } else {
        "SubdivOptions::max_output_faces, about 4 GB of mesh; the command line has no option for it"
    }
}

/// Faces beyond which refinement's `u32` element indices could overflow (a quadrisection
/// level makes up to 8 half-edges per coarse face). No memory this side of 100 GB reaches it.
const INDEX_FACE_LIMIT: usize = (u32::MAX / 8) as usize;

/// [`SubdivError::TooLarge`] if `levels` levels multiplying the faces by `face_factor` would
/// give more than `limit` faces (or more than the index range allows).
pub(crate) fn check_output_size(
    mesh: &Mesh,
    levels: usize,
    face_factor: usize,
    limit: usize,
) -> Result<(), SubdivError> {
    let limit = limit.min(INDEX_FACE_LIMIT);
    let faces = mesh.n_faces().saturating_mul(face_factor);
    if faces > limit {
        return Err(SubdivError::TooLarge {
            levels,
            faces,
            limit,
        });
    }
    Ok(())
}

/// The mesh with its vertex and face slots made dense (`0..n` in slot order). Returns the
/// input unchanged (cloned) when it is already dense.
pub(crate) fn compact(mesh: &Mesh) -> Result<Mesh, SubdivError> {
    use crate::mesh::SlotIndex;
    let dense = mesh.vertices().enumerate().all(|(i, v)| v.slot() == i)
        && mesh.faces().enumerate().all(|(i, f)| f.slot() == i)
        && mesh.halfedges().enumerate().all(|(i, h)| h.slot() == i);
    if dense {
        return Ok(mesh.clone());
    }
    let (p, t) = mesh.to_triangles();
    let built = Mesh::from_triangles(&p, &t).map_err(|_| SubdivError::NotManifold { level: 0 })?;
    if built.report.repaired_anything() {
        return Err(SubdivError::NotManifold { level: 0 });
    }
    Ok(built.mesh)
}
