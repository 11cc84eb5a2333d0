//! `meshpyr subdivide IN -o OUT --levels K`: cascadic MCM subdivision (or Loop).

use super::{BarProgress, Global};
use crate::choices::named;
use anyhow::Context;
use meshpyr::choice::Choice;
use meshpyr::io;
use meshpyr::mesh::{Mesh, PolygonMesh};
use meshpyr::subdiv::{self, Refinement, Scheme, Solver, SolverChoice, SubdivSettings};
use meshpyr::wording::Count;
use std::path::PathBuf;

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
    #[arg(long, default_value_t = SubdivSettings::default().levels)]
    pub(crate) levels: usize,
    /// Position rule.
    #[arg(long, value_parser = named::<Scheme>(), default_value = SubdivSettings::default().scheme.name())]
    pub(crate) scheme: Scheme,
    /// Refinement rule.
    #[arg(long, value_parser = named::<Refinement>(), default_value = SubdivSettings::default().refinement.name())]
    pub(crate) refine: Refinement,
    /// Solver for MCM levels (`exact` gives the true fixed point; `cg`/`jacobi` are the
    /// faster cascadic approximations, linear in the output size).
    #[arg(long, value_parser = named::<SolverChoice>(), default_value = SubdivSettings::default().solver.name())]
    pub(crate) solver: SolverChoice,
    /// Filter-width constant c (σ = c · mean edge length of the input). Larger values
    /// smooth and shrink more; coarse meshes collapse above about 0.4.
    #[arg(long, default_value_t = SubdivSettings::default().width)]
    pub(crate) width: f64,
    /// Let the filter width follow the local edge length (for meshes with very uneven edges).
    #[arg(long)]
    pub(crate) local_width: bool,
    /// Cascadic steps on the finest level (m_lmax).
    #[arg(long, default_value_t = SubdivSettings::default().finest_steps)]
    pub(crate) finest_steps: usize,
    /// Growth factor of the cascadic schedule (default: 2√2 for CG, 4 for Jacobi; quad).
    #[arg(long)]
    pub(crate) beta: Option<f64>,
}

/// Runs `meshpyr subdivide`.
pub(crate) fn run(args: SubdivideArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let input = read_input(&args)?;
    let built = Mesh::from_polygons(&input)
        .with_context(|| format!("building a mesh from {}", args.input.display()))?;
    if built.report.repaired_anything() {
        global.say(format_args!(
            "repaired the input before subdividing: {:?}",
            built.report
        ));
    }
    let settings = SubdivSettings {
        levels: args.levels,
        scheme: args.scheme,
        refinement: args.refine,
        solver: args.solver,
        width: args.width,
        local_width: args.local_width,
        finest_steps: args.finest_steps,
        beta: args.beta,
    };
    let options = settings.options(built.mesh.n_vertices());
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
    super::input::warn_face_data_dropped(&args.input, &input, &output);
    global.say(format_args!(
        "wrote {} ({}, {})",
        args.output.display(),
        Count(output.n_vertices(), "vertex", "vertices"),
        Count(output.n_faces(), "face", "faces")
    ));
    Ok(())
}

/// The input, first checked for memory ([`super::input::read_input_mesh_for`]) unless the
/// output would exceed the library's own face limit, whose error says it better.
fn read_input(args: &SubdivideArgs) -> anyhow::Result<PolygonMesh> {
    let limit = meshpyr::SubdivOptions::default().max_output_faces as u64;
    let growth = 4u64.saturating_pow(args.levels.min(32) as u32);
    let size = meshpyr::memory::input_size(&args.input);
    let beyond_limit = size.is_some_and(|s| {
        s.faces
            .max(s.vertices.saturating_mul(2))
            .saturating_mul(growth)
            > limit
    });
    if beyond_limit {
        return super::input::read_input_mesh(&args.input);
    }
    // The solver `auto` picks, as the library will for the repaired mesh (whose vertex count
    // the header's approaches).
    let exact_solver = args.scheme == Scheme::Mcm
        && match args.solver {
            SolverChoice::Exact => true,
            SolverChoice::Auto => size.is_some_and(|s| {
                Solver::auto(s.scale() as usize, args.levels, args.refine) == Solver::Exact
            }),
            _ => false,
        };
    let job = meshpyr::memory::Job::Subdivide {
        levels: args.levels,
        refinement: args.refine,
        exact_solver,
    };
    super::input::read_input_mesh_for(&args.input, job)
}
