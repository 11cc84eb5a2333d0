//! `meshpyr smooth IN -o OUT [--method adaptive|anisotropic|taubin|mcf] [...]`: denoising that
//! keeps the input's vertices (count and order), faces and attributes; only positions change.

use super::{BarProgress, Global};
use crate::io;
use crate::mesh::{Mesh, PolygonMesh};
use crate::progress::Progress;
use crate::smooth::normal_filter::Variance;
use crate::smooth::{
    Boundary, DenoiseOptions, McfOptions, TaubinOptions, Weights, implicit_mcf, taubin_smoothing,
};
use anyhow::Context;
use glam::DVec3;
use std::path::PathBuf;
use std::time::Instant;

/// Smoothing method. Each variant maps to one library function in [`run_method`].
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum MethodArg {
    /// Ohtake–Belyaev–Seidel adaptive Gaussian filter of the face normals + vertex fitting.
    #[default]
    Adaptive,
    /// The same on anisotropic neighbourhoods that do not reach across sharp edges.
    Anisotropic,
    /// Taubin λ|μ smoothing (explicit; `--weights`, `--lambda`, `--mu`).
    Taubin,
    /// Implicit mean-curvature flow (Desbrun et al. 1999; `--time-step`).
    Mcf,
}

/// Edge weights of Taubin smoothing.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum WeightsArg {
    /// Equal weights.
    Uniform,
    /// Inverse edge length.
    InverseEdge,
    /// Cotangent weights clamped at zero.
    Cotan,
}

/// Boundary rule of the baselines.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BoundaryArg {
    /// Boundary vertices do not move.
    Fixed,
    /// Boundary vertices move (Taubin: along the boundary curve; MCF: natural boundary).
    Smooth,
}

/// Variance estimate of the scale selection.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum VarianceArg {
    /// Weighted variance of the normals (as reconstructed from the paper).
    Biased,
    /// With the reliability-weights correction (default; see the library docs).
    Unbiased,
}

/// Arguments of `meshpyr smooth`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "The output has the input's vertices in the same order (unreferenced \
                  ones unchanged), its faces and its attributes; only positions change. Dirty \
                  input is repaired by the builder for processing (see `meshpyr info`); a vertex \
                  it had to split gets the mean of its copies. adaptive/anisotropic lengths are \
                  in units of the mean edge length L of the input, epsilon in L²; unset options \
                  take the method's defaults (adaptive: sigma 0.2..2.0, anisotropic: sigma \
                  0.5..5.0 and rho). Measure the result against a clean mesh with `meshpyr \
                  compare`."
)]
pub(crate) struct SmoothArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) input: PathBuf,
    /// Output mesh; the format follows the extension.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Smoothing method.
    #[arg(long, value_enum, default_value_t = MethodArg::Adaptive)]
    pub(crate) method: MethodArg,
    /// adaptive/anisotropic: ε of the scale selection (× L²); larger smooths more.
    #[arg(long)]
    pub(crate) epsilon: Option<f64>,
    /// adaptive/anisotropic: smallest filter scale σ (× L).
    #[arg(long)]
    pub(crate) sigma_min: Option<f64>,
    /// adaptive/anisotropic: largest filter scale σ (× L); the work per face grows with its
    /// square.
    #[arg(long)]
    pub(crate) sigma_max: Option<f64>,
    /// adaptive/anisotropic: number of scales between --sigma-min and --sigma-max (1 to 64).
    #[arg(long)]
    pub(crate) scales: Option<usize>,
    /// adaptive/anisotropic: anisotropy ρ (0 = isotropic); how much normal differences
    /// lengthen distances.
    #[arg(long)]
    pub(crate) rho: Option<f64>,
    /// adaptive/anisotropic: variance estimate of the scale selection.
    #[arg(long, value_enum)]
    pub(crate) variance: Option<VarianceArg>,
    /// adaptive/anisotropic: most conjugate-gradient iterations of the vertex fitting.
    #[arg(long)]
    pub(crate) fit_iterations: Option<usize>,
    /// adaptive/anisotropic: largest move of a vertex per fitting step (× L).
    #[arg(long)]
    pub(crate) step_cap: Option<f64>,
    /// taubin/mcf: iterations (default: 10 for taubin, 1 for mcf).
    #[arg(long)]
    pub(crate) iterations: Option<usize>,
    /// taubin: edge weights.
    #[arg(long, value_enum, default_value = "cotan")]
    pub(crate) weights: WeightsArg,
    /// taubin: shrinking factor λ, in (0, 1].
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub(crate) lambda: f64,
    /// taubin: inflating factor μ, in [-1, 0] (0: plain Laplacian smoothing).
    #[arg(long, default_value_t = -0.53, allow_hyphen_values = true)]
    pub(crate) mu: f64,
    /// mcf: time step in units of the squared mean edge length L² of the input.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub(crate) time_step: f64,
    /// taubin/mcf: what boundary vertices do.
    #[arg(long, value_enum, default_value = "fixed")]
    pub(crate) boundary: BoundaryArg,
}

impl SmoothArgs {
    /// The Ohtake options these arguments describe (`adaptive` presets unless the method is
    /// `anisotropic`).
    pub(crate) fn denoise_options(&self) -> DenoiseOptions {
        let mut o = match self.method {
            MethodArg::Anisotropic => DenoiseOptions::anisotropic(),
            _ => DenoiseOptions::adaptive(),
        };
        o.epsilon = self.epsilon.unwrap_or(o.epsilon);
        o.sigma_min = self.sigma_min.unwrap_or(o.sigma_min);
        o.sigma_max = self.sigma_max.unwrap_or(o.sigma_max);
        o.scales = self.scales.unwrap_or(o.scales);
        o.rho = self.rho.unwrap_or(o.rho);
        o.variance = match self.variance {
            Some(VarianceArg::Biased) => Variance::Biased,
            Some(VarianceArg::Unbiased) => Variance::Unbiased,
            None => o.variance,
        };
        o.max_iterations = self.fit_iterations.unwrap_or(o.max_iterations);
        o.step_cap = self.step_cap.unwrap_or(o.step_cap);
        o
    }
}

/// Runs the chosen method on `mesh`; new positions in vertex slot order, and a line saying
/// what was done.
pub(crate) fn run_method(
    mesh: &Mesh,
    args: &SmoothArgs,
    progress: &dyn Progress,
) -> anyhow::Result<(Vec<DVec3>, String)> {
    let boundary = match args.boundary {
        BoundaryArg::Fixed => Boundary::Fixed,
        BoundaryArg::Smooth => Boundary::Smooth,
    };
    Ok(match args.method {
        MethodArg::Adaptive | MethodArg::Anisotropic => {
            let options = args.denoise_options();
            let r = crate::smooth::denoise(mesh, &options, progress)?;
            let what = format!(
                "mean edge {:.4e}; σ_opt histogram {:?}; fitting {} iterations, energy {:.4e} → {:.4e}",
                r.mean_edge,
                r.scale_histogram,
                r.fit.iterations,
                r.fit.initial_energy,
                r.fit.final_energy
            );
            (r.positions, what)
        }
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
            let what = format!("{} iterations", o.iterations);
            (taubin_smoothing(mesh, &o, progress)?, what)
        }
        MethodArg::Mcf => {
            let o = McfOptions {
                iterations: args.iterations.unwrap_or(McfOptions::default().iterations),
                time_step: args.time_step,
                boundary,
            };
            let what = format!("{} iterations", o.iterations);
            (implicit_mcf(mesh, &o, progress)?, what)
        }
    })
}

/// Runs `meshpyr smooth`.
pub(crate) fn run(args: SmoothArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    if matches!(args.method, MethodArg::Adaptive | MethodArg::Anisotropic) {
        args.denoise_options().validate()?;
    }
    let input = super::input::read_input_mesh(&args.input)?;
    let built = Mesh::from_polygons(&input)
        .with_context(|| format!("building a mesh from {}", args.input.display()))?;
    if built.report.repaired_anything() {
        global.say(format_args!(
            "repaired the input for smoothing: {:?}",
            built.report
        ));
    }
    let start = Instant::now();
    let bar = global.progress("smooth");
    let (positions, what) = run_method(&built.mesh, &args, &BarProgress(&bar))
        .with_context(|| format!("smoothing {}", args.input.display()))?;
    bar.finish_and_clear();
    global.say(format_args!(
        "{:?}: {} faces in {:.2} s; {what}",
        args.method,
        built.mesh.n_faces(),
        start.elapsed().as_secs_f64()
    ));
    let output = PolygonMesh {
        positions: built
            .source
            .to_input_positions(&positions, &input.positions),
        ..input
    };
    io::write_mesh(&args.output, &output)?;
    global.say(format_args!(
        "wrote {} ({} vertices, {} faces)",
        args.output.display(),
        output.n_vertices(),
        output.n_faces()
    ));
    Ok(())
}
