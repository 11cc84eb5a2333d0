//! `meshpyr subdivide IN -o OUT --levels K`: cascadic MCM subdivision (or Loop).

use super::{BarProgress, Global};
use anyhow::Context;
use meshpyr::io;
use meshpyr::mesh::{Mesh, PolygonMesh};
use meshpyr::subdiv::{self, Refinement, Scheme, Solver, SubdivOptions};
use meshpyr::wording::Count;
use std::path::PathBuf;

/// Subdivision rule.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum SchemeArg {
    /// Implicit mean-curvature motion with cascadic multigrid (Diewald–Morigi–Rumpf).
    Mcm,
    /// Loop's scheme (quadrisection only).
    Loop,
}

/// Refinement rule.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum RefineArg {
    /// 1-to-4 split at edge midpoints (4× faces per level).
    Quad,
    /// Conforming newest-vertex bisection (2× faces per level).
    Bisect,
}

/// Linear solver of each MCM level.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum SolverArg {
    /// `exact` while the output has at most 250k vertices (where the cascadic approximation
    /// visibly oscillates on coarse inputs and the exact solve costs little), `cg` above.
    Auto,
    /// Cascadic damped Jacobi.
    Jacobi,
    /// Cascadic Jacobi-preconditioned CG.
    Cg,
    /// Exact per level (sparse Cholesky; CG to 1e-10 in builds without the `solver` feature).
    Exact,
}

/// Arguments of `meshpyr subdivide`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "The output is a new triangle mesh: the input's vertices first (same order), new \
                  vertices after. Vertex and face attributes of the input are not carried over. \
                  Dirty input is repaired by the builder first (see `meshpyr info`)."
)]
pub(crate) struct SubdivideArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) input: PathBuf,
    /// Output mesh; the format follows the extension.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Refinement levels.
    #[arg(long, default_value_t = 3)]
    pub(crate) levels: usize,
    /// Position rule.
    #[arg(long, value_enum, default_value = "mcm")]
    pub(crate) scheme: SchemeArg,
    /// Refinement rule.
    #[arg(long, value_enum, default_value = "quad")]
    pub(crate) refine: RefineArg,
    /// Solver for MCM levels (`exact` gives the true fixed point; `cg`/`jacobi` are the
    /// faster cascadic approximations, linear in the output size).
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) solver: SolverArg,
    /// Filter-width constant c (σ = c · mean edge length of the input). Larger values
    /// smooth and shrink more; coarse meshes collapse above about 0.4.
    #[arg(long, default_value_t = 0.25)]
    pub(crate) width: f64,
    /// Let the filter width follow the local edge length (for meshes with very uneven edges).
    #[arg(long)]
    pub(crate) local_width: bool,
    /// Cascadic steps on the finest level (m_lmax).
    #[arg(long, default_value_t = 2)]
    pub(crate) finest_steps: usize,
    /// Growth factor of the cascadic schedule (default: 2√2 for CG, 4 for Jacobi; quad).
    #[arg(long)]
    pub(crate) beta: Option<f64>,
}

/// Runs `meshpyr subdivide`.
pub(crate) fn run(args: SubdivideArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let input = super::input::read_input_mesh(&args.input)?;
    let built = Mesh::from_polygons(&input)
        .with_context(|| format!("building a mesh from {}", args.input.display()))?;
    if built.report.repaired_anything() {
        global.say(format_args!(
            "repaired the input before subdividing: {:?}",
            built.report
        ));
    }
    let options = SubdivOptions {
        levels: args.levels,
        scheme: match args.scheme {
            SchemeArg::Mcm => Scheme::Mcm,
            SchemeArg::Loop => Scheme::Loop,
        },
        refinement: match args.refine {
            RefineArg::Quad => Refinement::Quadrisection,
            RefineArg::Bisect => Refinement::Bisection,
        },
        solver: match args.solver {
            SolverArg::Auto => Solver::auto(
                built.mesh.n_vertices(),
                args.levels,
                match args.refine {
                    RefineArg::Quad => Refinement::Quadrisection,
                    RefineArg::Bisect => Refinement::Bisection,
                },
            ),
            SolverArg::Jacobi => Solver::Jacobi,
            SolverArg::Cg => Solver::Cg,
            SolverArg::Exact => Solver::Exact,
        },
        width: args.width,
        local_width: args.local_width,
        finest_steps: args.finest_steps,
        beta: args.beta,
        ..SubdivOptions::default()
    };
    let bar = global.progress("subdivide");
    let result = subdiv::subdivide(&built.mesh, &options, &BarProgress(&bar))
        .with_context(|| format!("subdividing {}", args.input.display()))?;
    bar.finish_and_clear();
    for l in &result.levels {
        let solve = match options.scheme {
            Scheme::Mcm => format!(
                ", {}, relative residual {:.1e}",
                Count(l.steps, "step", "steps"),
                l.relative_residual
            ),
            Scheme::Loop => String::new(),
        };
        global.say(format_args!(
            "level {}: {}, {}{solve}",
            l.level,
            Count(l.vertices, "vertex", "vertices"),
            Count(l.faces, "face", "faces")
        ));
    }
    let output = PolygonMesh::from_triangle_vec(result.positions, result.triangles);
    io::write_mesh(&args.output, &output)?;
    global.say(format_args!(
        "wrote {} ({}, {})",
        args.output.display(),
        Count(output.n_vertices(), "vertex", "vertices"),
        Count(output.n_faces(), "face", "faces")
    ));
    Ok(())
}
