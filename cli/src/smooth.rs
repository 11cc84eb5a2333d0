//! `meshpyr smooth IN -o OUT [--method adaptive|anisotropic|taubin|mcf|pyramid] [...]`: denoising that
//! keeps the input's vertices (count and order), faces and attributes; only positions change.

use super::{BarProgress, Global};
use anyhow::Context;
use meshpyr::io;
use meshpyr::pyramid::PyramidDenoise;
use meshpyr::smooth::{
    Boundary, DenoiseOptions, McfOptions, SmoothMethod, TaubinOptions, Variance, Weights,
    smooth_mesh,
};
use std::path::PathBuf;
use std::time::Instant;

/// Smoothing method. Each variant maps to one [`SmoothMethod`].
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum MethodArg {
    /// The recommended automatic method: the adaptive filter at the local scale of each
    /// face, fitted by local vertex updates, two passes (options as for adaptive).
    #[default]
    Auto,
    /// Ohtake–Belyaev–Seidel adaptive Gaussian filter of the face normals + vertex fitting.
    Adaptive,
    /// The same on anisotropic neighbourhoods that do not reach across sharp edges.
    Anisotropic,
    /// Taubin λ|μ smoothing (explicit; `--weights`, `--lambda`, `--mu`).
    Taubin,
    /// Implicit mean-curvature flow (Desbrun et al. 1999; `--time-step`).
    Mcf,
    /// Octaves of the detail pyramid attenuated by how far they stand above the noise the
    /// pyramid estimates, with the crease-keeping normal-adaptive operator (`--strength`).
    Pyramid,
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

/// Unit of the filter scales.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ScaleArg {
    /// The mean edge length of the whole mesh.
    Global,
    /// Each face's own edge length (averaged with its neighbours').
    Local,
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
                  it had to split gets the mean of its copies. auto/adaptive/anisotropic lengths \
                  are in units of the mean edge length L of the input (auto: of each face's \
                  local edge length), epsilon in L²; unset options take the method's defaults \
                  (auto: adaptive with --scale local --vertex-updates 5 --passes 2; adaptive: \
                  sigma 0.2..2.0; anisotropic: sigma 0.5..5.0 and rho). Options of another \
                  method are refused. Measure the result against a clean mesh with `meshpyr \
                  compare`."
)]
pub(crate) struct SmoothArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) input: PathBuf,
    /// Output mesh; the format follows the extension.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Smoothing method.
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    pub(crate) method: MethodArg,
    /// auto/adaptive/anisotropic: ε of the scale selection (× L²); larger smooths more.
    #[arg(long)]
    pub(crate) epsilon: Option<f64>,
    /// auto/adaptive/anisotropic: smallest filter scale σ (× L).
    #[arg(long)]
    pub(crate) sigma_min: Option<f64>,
    /// auto/adaptive/anisotropic: largest filter scale σ (× L); the work per face grows with its
    /// square.
    #[arg(long)]
    pub(crate) sigma_max: Option<f64>,
    /// auto/adaptive/anisotropic: number of scales between --sigma-min and --sigma-max (1 to 64).
    #[arg(long)]
    pub(crate) scales: Option<usize>,
    /// auto/adaptive/anisotropic: anisotropy ρ (0 = isotropic); how much normal differences
    /// lengthen distances.
    #[arg(long)]
    pub(crate) rho: Option<f64>,
    /// auto/adaptive/anisotropic: variance estimate of the scale selection.
    #[arg(long, value_enum)]
    pub(crate) variance: Option<VarianceArg>,
    /// auto/adaptive/anisotropic: what σ is measured in: the mean edge length L everywhere
    /// (`global`) or each face's local edge length (`local`, for non-uniform sampling).
    #[arg(long, value_enum)]
    pub(crate) scale: Option<ScaleArg>,
    /// auto/adaptive/anisotropic: fit the vertices with this many rounds of the local vertex
    /// update (Sun et al. 2007) instead of minimising the global energy.
    #[arg(long)]
    pub(crate) vertex_updates: Option<usize>,
    /// auto/adaptive/anisotropic: passes of filter-then-fit [default: 2 for auto, else 1].
    #[arg(long)]
    pub(crate) passes: Option<usize>,
    /// auto/adaptive/anisotropic: most conjugate-gradient iterations of the vertex fitting.
    #[arg(long)]
    pub(crate) fit_iterations: Option<usize>,
    /// auto/adaptive/anisotropic: largest move of a vertex per fitting step (× L).
    #[arg(long)]
    pub(crate) step_cap: Option<f64>,
    /// taubin/mcf: iterations (default: 10 for taubin, 1 for mcf).
    #[arg(long)]
    pub(crate) iterations: Option<usize>,
    /// taubin: edge weights [default: cotan].
    #[arg(long, value_enum)]
    pub(crate) weights: Option<WeightsArg>,
    /// taubin: shrinking factor λ, in (0, 1] [default: 0.5].
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) lambda: Option<f64>,
    /// taubin: inflating factor μ, in [-1, 0] (0: plain Laplacian smoothing) [default: -0.53].
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) mu: Option<f64>,
    /// mcf: time step in units of the squared mean edge length L² of the input [default: 1].
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) time_step: Option<f64>,
    /// taubin/mcf: what boundary vertices do [default: fixed].
    #[arg(long, value_enum)]
    pub(crate) boundary: Option<BoundaryArg>,
    /// pyramid: how much noise to assume, in units of the estimated noise power (octave gain
    /// 1 − strength / r², r the octave's details over the noise); more removes more [default: 1].
    #[arg(long)]
    pub(crate) strength: Option<f64>,
}

impl SmoothArgs {
    /// The method and options these arguments describe; an option of another method is an
    /// error rather than silently ignored.
    pub(crate) fn method(&self) -> anyhow::Result<SmoothMethod> {
        self.reject_options_of_other_methods()?;
        let boundary = match self.boundary {
            Some(BoundaryArg::Smooth) => Boundary::Smooth,
            Some(BoundaryArg::Fixed) | None => Boundary::Fixed,
        };
        Ok(match self.method {
            MethodArg::Auto if self.given_options().is_empty() => SmoothMethod::Auto,
            MethodArg::Auto | MethodArg::Adaptive | MethodArg::Anisotropic => {
                SmoothMethod::Ohtake(self.denoise_options())
            }
            MethodArg::Taubin => {
                let d = TaubinOptions::default();
                SmoothMethod::Taubin(TaubinOptions {
                    iterations: self.iterations.unwrap_or(d.iterations),
                    lambda: self.lambda.unwrap_or(d.lambda),
                    mu: self.mu.unwrap_or(d.mu),
                    weights: match self.weights {
                        Some(WeightsArg::Uniform) => Weights::Uniform,
                        Some(WeightsArg::InverseEdge) => Weights::InverseEdgeLength,
                        Some(WeightsArg::Cotan) => Weights::Cotangent,
                        None => d.weights,
                    },
                    boundary,
                })
            }
            MethodArg::Pyramid => SmoothMethod::Pyramid(PyramidDenoise {
                strength: self.strength.unwrap_or(PyramidDenoise::default().strength),
            }),
            MethodArg::Mcf => {
                let d = McfOptions::default();
                SmoothMethod::Mcf(McfOptions {
                    iterations: self.iterations.unwrap_or(d.iterations),
                    time_step: self.time_step.unwrap_or(d.time_step),
                    boundary,
                })
            }
        })
    }

    /// Every option given on the command line, with the methods it applies to.
    fn given_options(&self) -> Vec<(&'static str, &'static [MethodArg])> {
        use MethodArg::{Adaptive, Anisotropic, Auto, Mcf, Pyramid, Taubin};
        const OHTAKE: &[MethodArg] = &[Auto, Adaptive, Anisotropic];
        let given = [
            ("--epsilon", self.epsilon.is_some(), OHTAKE),
            ("--sigma-min", self.sigma_min.is_some(), OHTAKE),
            ("--sigma-max", self.sigma_max.is_some(), OHTAKE),
            ("--scales", self.scales.is_some(), OHTAKE),
            ("--rho", self.rho.is_some(), OHTAKE),
            ("--variance", self.variance.is_some(), OHTAKE),
            ("--fit-iterations", self.fit_iterations.is_some(), OHTAKE),
            ("--scale", self.scale.is_some(), OHTAKE),
            ("--vertex-updates", self.vertex_updates.is_some(), OHTAKE),
            ("--passes", self.passes.is_some(), OHTAKE),
            ("--step-cap", self.step_cap.is_some(), OHTAKE),
            ("--iterations", self.iterations.is_some(), &[Taubin, Mcf]),
            ("--weights", self.weights.is_some(), &[Taubin]),
            ("--lambda", self.lambda.is_some(), &[Taubin]),
            ("--mu", self.mu.is_some(), &[Taubin]),
            ("--time-step", self.time_step.is_some(), &[Mcf]),
            ("--boundary", self.boundary.is_some(), &[Taubin, Mcf]),
            ("--strength", self.strength.is_some(), &[Pyramid]),
        ];
        given
            .into_iter()
            .filter(|(_, set, _)| *set)
            .map(|(name, _, methods)| (name, methods))
            .collect()
    }

    fn reject_options_of_other_methods(&self) -> anyhow::Result<()> {
        for (name, methods) in self.given_options() {
            if !methods.contains(&self.method) {
                let names: Vec<String> = methods.iter().map(method_name).collect();
                anyhow::bail!(
                    "{name} does not apply to --method {} (it is an option of {})",
                    method_name(&self.method),
                    names.join(" and ")
                );
            }
        }
        Ok(())
    }

    /// The Ohtake options these arguments describe (`adaptive` presets unless the method is
    /// `anisotropic`).
    fn denoise_options(&self) -> DenoiseOptions {
        let mut o = match self.method {
            MethodArg::Anisotropic => DenoiseOptions::anisotropic(),
            MethodArg::Auto => DenoiseOptions::automatic(),
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
        o.passes = self.passes.unwrap_or(o.passes);
        o.vertex_updates = self.vertex_updates.unwrap_or(o.vertex_updates);
        o.local_scale = self.scale.map_or(o.local_scale, |s| s == ScaleArg::Local);
        o
    }
}

fn method_name(method: &MethodArg) -> String {
    use clap::ValueEnum;
    method
        .to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_string())
}

/// Runs `meshpyr smooth`.
pub(crate) fn run(args: SmoothArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let method = args.method()?;
    method.validate()?;
    let input = super::input::read_input_mesh(&args.input)?;
    let start = Instant::now();
    let bar = global.progress("smooth");
    let smoothed = smooth_mesh(&input, &method, &BarProgress(&bar))
        .with_context(|| format!("smoothing {}", args.input.display()))?;
    bar.finish_and_clear();
    if smoothed.repair.repaired_anything() {
        global.say(format_args!(
            "repaired the input for smoothing: {:?}",
            smoothed.repair
        ));
    }
    global.say(format_args!(
        "{:?}: {} faces in {:.2} s; {}",
        args.method,
        input.n_faces(),
        start.elapsed().as_secs_f64(),
        smoothed.summary
    ));
    io::write_mesh(&args.output, &smoothed.mesh)?;
    global.say(format_args!(
        "wrote {} ({} vertices, {} faces)",
        args.output.display(),
        smoothed.mesh.n_vertices(),
        smoothed.mesh.n_faces()
    ));
    Ok(())
}
