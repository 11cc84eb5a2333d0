//! `meshpyr smooth IN -o OUT [--method adaptive|anisotropic|taubin|mcf|pyramid] [...]`: denoising that
//! keeps the input's vertices (count and order), faces and attributes; only positions change.

use super::{BarProgress, Global};
use crate::choices::named;
use anyhow::Context;
use meshpyr::choice::Choice;
use meshpyr::smooth::{
    Boundary, FilterScale, SmoothKind, SmoothSettings, Variance, Weights, smooth_mesh_owned,
};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `meshpyr smooth`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "The output has the input's vertices in the same order (unreferenced \
                  ones unchanged), its faces and its attributes; only positions change. Dirty \
                  input is repaired by the builder for processing (see `meshpyr info`); a vertex \
                  it had to split gets the mean of its copies. auto/adaptive/anisotropic lengths \
                  are in units of the mean edge length L of the input (auto: of each face's \
                  local edge length), epsilon in L²; unset options take the method's defaults \
                  (auto: adaptive with --scale local --vertex-updates 5 --passes 2 --reach 3; adaptive: \
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
    #[arg(long, value_parser = named::<SmoothKind>(), default_value = SmoothKind::default().name())]
    pub(crate) method: SmoothKind,
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
    /// auto/adaptive/anisotropic: where neighbourhoods are cut, in units of σ, in (0, 4]
    /// [default: 3 for auto, else 4, the kernel's support]; the time grows with its square.
    #[arg(long)]
    pub(crate) reach: Option<f64>,
    /// auto/adaptive/anisotropic: variance estimate of the scale selection.
    #[arg(long, value_parser = named::<Variance>())]
    pub(crate) variance: Option<Variance>,
    /// auto/adaptive/anisotropic: what σ is measured in: the mean edge length L everywhere
    /// (`global`) or each face's local edge length (`local`, for non-uniform sampling).
    #[arg(long, value_parser = named::<FilterScale>())]
    pub(crate) scale: Option<FilterScale>,
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
    #[arg(long, value_parser = named::<Weights>())]
    pub(crate) weights: Option<Weights>,
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
    #[arg(long, value_parser = named::<Boundary>())]
    pub(crate) boundary: Option<Boundary>,
    /// pyramid: how much noise to assume, in units of the estimated noise power (octave gain
    /// 1 − strength / r², r the octave's details over the noise); more removes more [default: 1].
    #[arg(long)]
    pub(crate) strength: Option<f64>,
}

impl SmoothArgs {
    /// The library's settings these arguments spell.
    fn settings(&self) -> SmoothSettings {
        SmoothSettings {
            method: self.method,
            epsilon: self.epsilon,
            sigma_min: self.sigma_min,
            sigma_max: self.sigma_max,
            scales: self.scales,
            rho: self.rho,
            reach: self.reach,
            variance: self.variance,
            scale: self.scale,
            vertex_updates: self.vertex_updates,
            passes: self.passes,
            fit_iterations: self.fit_iterations,
            step_cap: self.step_cap,
            iterations: self.iterations,
            weights: self.weights,
            lambda: self.lambda,
            mu: self.mu,
            time_step: self.time_step,
            boundary: self.boundary,
            strength: self.strength,
        }
    }
}

/// Runs `meshpyr smooth`.
pub(crate) fn run(args: SmoothArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let method = args.settings().method()?;
    let input = super::input::read_input_mesh_for(&args.input, meshpyr::memory::Job::Smooth)?;
    let start = Instant::now();
    let bar = global.progress("smooth");
    let faces = input.n_faces();
    // The input is given away: its positions are replaced in place, so a scan is held once.
    let smoothed = smooth_mesh_owned(input, &method, &BarProgress(&bar))
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
        faces,
        start.elapsed().as_secs_f64(),
        smoothed.summary
    ));
    super::output::write_mesh_output(&args.output, &smoothed.mesh, &Default::default())?;
    global.say(format_args!(
        "wrote {} ({} vertices, {} faces)",
        args.output.display(),
        smoothed.mesh.n_vertices(),
        smoothed.mesh.n_faces()
    ));
    Ok(())
}
