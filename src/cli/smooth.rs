//! `meshpyr smooth IN -o OUT [--method taubin|mcf] ...`: denoising that keeps the input's
//! vertices (count and order), faces and attributes; only positions change.

use super::{BarProgress, Global};
use crate::io;
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::smooth::{Boundary, McfOptions, TaubinOptions, Weights, implicit_mcf, taubin_smoothing};
use anyhow::Context;
use glam::DVec3;
use std::path::PathBuf;

/// Smoothing method. Each variant maps to one library function in [`run_method`].
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// Taubin λ|μ smoothing (explicit; `--weights`, `--lambda`, `--mu`).
    Taubin,
    /// Implicit mean-curvature flow (Desbrun et al. 1999; `--time-step`).
    Mcf,
}

/// Edge weights of Taubin smoothing.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeightsArg {
    /// Equal weights.
    Uniform,
    /// Inverse edge length.
    InverseEdge,
    /// Cotangent weights clamped at zero.
    Cotan,
}

/// Boundary rule.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryArg {
    /// Boundary vertices do not move.
    Fixed,
    /// Boundary vertices move (Taubin: along the boundary curve; MCF: natural boundary).
    Smooth,
}

/// Arguments of `meshpyr smooth`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "The output has the input's vertices in the same order (unreferenced ones \
                  unchanged), its faces and its attributes; only positions change. Dirty input \
                  is repaired by the builder for processing (see `meshpyr info`); a vertex it \
                  had to split gets the mean of its copies. Measure the result against a clean \
                  mesh with `meshpyr compare`."
)]
pub struct SmoothArgs {
    /// Input mesh (.obj, .ply, .off, .stl).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Smoothing method.
    #[arg(long, value_enum, default_value = "taubin")]
    pub method: MethodArg,
    /// Iterations (default: 10 for taubin, 1 for mcf).
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Taubin edge weights.
    #[arg(long, value_enum, default_value = "cotan")]
    pub weights: WeightsArg,
    /// Taubin shrinking factor λ, in (0, 1].
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub lambda: f64,
    /// Taubin inflating factor μ, in [-1, 0] (0: plain Laplacian smoothing).
    #[arg(long, default_value_t = -0.53, allow_hyphen_values = true)]
    pub mu: f64,
    /// MCF time step in units of the squared mean edge length L² of the input.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub time_step: f64,
    /// What boundary vertices do.
    #[arg(long, value_enum, default_value = "fixed")]
    pub boundary: BoundaryArg,
}

/// Runs the chosen method on `mesh`; new positions in vertex slot order.
pub fn run_method(
    mesh: &Mesh,
    args: &SmoothArgs,
    progress: &dyn Progress,
) -> anyhow::Result<Vec<DVec3>> {
    let boundary = match args.boundary {
        BoundaryArg::Fixed => Boundary::Fixed,
        BoundaryArg::Smooth => Boundary::Smooth,
    };
    Ok(match args.method {
        MethodArg::Taubin => {
            let o = TaubinOptions {
                iterations: args
                    .iterations
                    .unwrap_or(TaubinOptions::default().iterations),
                lambda: args.lambda,
                mu: args.mu,
                weights: match args.weights {
                    WeightsArg::Uniform => Weights::Uniform,
                    WeightsArg::InverseEdge => Weights::InverseEdgeLength,
                    WeightsArg::Cotan => Weights::Cotangent,
                },
                boundary,
            };
            taubin_smoothing(mesh, &o, progress)?
        }
        MethodArg::Mcf => {
            let o = McfOptions {
                iterations: args.iterations.unwrap_or(McfOptions::default().iterations),
                time_step: args.time_step,
                boundary,
            };
            implicit_mcf(mesh, &o, progress)?
        }
    })
}

/// Runs `meshpyr smooth`.
pub fn run(args: SmoothArgs, global: &Global) -> anyhow::Result<()> {
    let input = io::read_mesh(&args.input)?;
    let built = Mesh::from_polygons(&input)
        .with_context(|| format!("building a mesh from {}", args.input.display()))?;
    if built.report.repaired_anything() {
        global.say(format_args!(
            "repaired the input for smoothing: {:?}",
            built.report
        ));
    }
    let bar = global.progress("smooth");
    let positions = run_method(&built.mesh, &args, &BarProgress(&bar))
        .with_context(|| format!("smoothing {}", args.input.display()))?;
    bar.finish_and_clear();
    let mut output = input;
    output.positions = built
        .source
        .to_input_positions(&positions, &output.positions);
    io::write_mesh(&args.output, &output)?;
    global.say(format_args!(
        "wrote {} ({} vertices, {} faces)",
        args.output.display(),
        output.n_vertices(),
        output.n_faces()
    ));
    Ok(())
}
