//! `meshpyr smooth IN -o OUT [--method adaptive|anisotropic] [...]`: denoising.
//!
//! The output is the input with new positions: same vertex count and order, same faces and
//! attributes, so per-vertex data still lines up. Unreferenced vertices keep their positions.

use super::{BarProgress, Global};
use crate::io;
use crate::mesh::{Mesh, PolygonMesh};
use crate::smooth::normal_filter::Variance;
use crate::smooth::{DenoiseOptions, Denoised};
use anyhow::Context;
use std::path::PathBuf;
use std::time::Instant;

/// Smoothing method.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Ohtake–Belyaev–Seidel adaptive Gaussian filter of the face normals + vertex fitting.
    #[default]
    Adaptive,
    /// The same on anisotropic neighbourhoods that do not reach across sharp edges.
    Anisotropic,
}

/// Variance estimate of the scale selection.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarianceArg {
    /// Weighted variance of the normals (as reconstructed from the paper).
    Biased,
    /// With the reliability-weights correction (default; see the library docs).
    Unbiased,
}

/// Arguments of `meshpyr smooth`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Lengths are in units of the mean edge length L of the input, epsilon in L². \
                  Unset options take the method's defaults (adaptive: sigma 0.2..2.0, \
                  anisotropic: sigma 0.5..5.0 and rho; see `smooth::DenoiseOptions`)."
)]
pub struct SmoothArgs {
    /// Input mesh (.obj, .ply, .off, .stl).
    pub input: PathBuf,
    /// Output mesh: the input's vertices and faces in the same order, new positions.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Smoothing method.
    #[arg(long, value_enum, default_value_t = Method::Adaptive)]
    pub method: Method,
    /// ε of the scale selection (× L²): larger smooths more, smaller keeps more detail.
    #[arg(long)]
    pub epsilon: Option<f64>,
    /// Smallest filter scale σ (× L).
    #[arg(long)]
    pub sigma_min: Option<f64>,
    /// Largest filter scale σ (× L); the work per face grows with its square.
    #[arg(long)]
    pub sigma_max: Option<f64>,
    /// Number of scales between --sigma-min and --sigma-max (1 to 64).
    #[arg(long)]
    pub scales: Option<usize>,
    /// Anisotropy ρ (0 = isotropic); how much normal differences lengthen distances.
    #[arg(long)]
    pub rho: Option<f64>,
    /// Variance estimate of the scale selection.
    #[arg(long, value_enum)]
    pub variance: Option<VarianceArg>,
    /// Most conjugate-gradient iterations of the vertex fitting.
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Largest move of a vertex per fitting step (× L).
    #[arg(long)]
    pub step_cap: Option<f64>,
}

impl SmoothArgs {
    /// The library options these arguments describe.
    pub fn options(&self) -> DenoiseOptions {
        let mut o = match self.method {
            Method::Adaptive => DenoiseOptions::adaptive(),
            Method::Anisotropic => DenoiseOptions::anisotropic(),
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
        o.max_iterations = self.iterations.unwrap_or(o.max_iterations);
        o.step_cap = self.step_cap.unwrap_or(o.step_cap);
        o
    }
}

/// Runs `meshpyr smooth`.
pub fn run(args: SmoothArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let options = args.options();
    options.validate()?;
    let input = io::read_mesh(&args.input)?;
    let built = Mesh::from_polygons(&input)
        .with_context(|| format!("building a mesh from {}", args.input.display()))?;
    if built.report.repaired_anything() {
        global.say(format_args!(
            "repaired the input before smoothing: {:?}",
            built.report
        ));
    }
    let start = Instant::now();
    let bar = global.progress("smooth");
    let result: Denoised = crate::smooth::denoise(&built.mesh, &options, &BarProgress(&bar))
        .with_context(|| format!("smoothing {}", args.input.display()))?;
    bar.finish_and_clear();
    global.say(format_args!(
        "{:?}: {} faces in {:.2} s; mean edge {:.4e}; σ_opt histogram {:?}; fitting {} iterations, energy {:.4e} → {:.4e}",
        args.method,
        built.mesh.n_faces(),
        start.elapsed().as_secs_f64(),
        result.mean_edge,
        result.scale_histogram,
        result.fit.iterations,
        result.fit.initial_energy,
        result.fit.final_energy
    ));
    let output = PolygonMesh {
        positions: built
            .source
            .to_input_positions(&result.positions, &input.positions),
        ..input
    };
    io::write_mesh(&args.output, &output)?;
    global.say(format_args!("wrote {}", args.output.display()));
    Ok(())
}
