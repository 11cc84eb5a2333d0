//! Feature-preserving denoising by Ohtake, Belyaev and Seidel, "Mesh smoothing by adaptive and
//! anisotropic Gaussian filter applied to mesh normals" (VMV 2002): one pass of
//!
//! 1. the adaptive Gaussian filter of the face normals with per-face scale selection
//!    ([`super::normal_filter`]), on isotropic or anisotropic dual geodesic balls
//!    ([`super::dual`]), then
//! 2. moving the vertices so the face normals fit the filtered field ([`super::fitting`]).
//!
//! The paper warns that iterating oversmooths, so the paper's presets
//! ([`DenoiseOptions::adaptive`], [`DenoiseOptions::anisotropic`]) run the pass once. Every
//! constant the source garbles is a field of [`DenoiseOptions`], in units of the mean edge
//! length L of the input.
//!
//! Scans with uneven sampling need three changes (`docs/algorithms.md` §2.7), which
//! [`DenoiseOptions::automatic`] switches on: σ in units of each face's local edge length,
//! the local vertex update instead of the global energy, and a second pass.

use super::SmoothError;
use super::dual::DualGraph;
use super::fitting::{FitOptions, FitReport, Fitting};
use super::normal_filter::{FilteredNormals, MAX_SCALES, ScaleGrid, Variance, filter_normals};
use super::surface::FlatSurface;
use crate::mesh::{BoundingBox, Mesh, SlotIndex};
use crate::progress::Progress;
use glam::DVec3;

/// Parameters of [`denoise`]. Lengths are in units of the mean edge length L, ε in L².
#[derive(Clone, Debug, PartialEq)]
pub struct DenoiseOptions {
    /// Smallest σ of the scale grid (× L).
    pub sigma_min: f64,
    /// Largest σ of the scale grid (× L); the neighbourhoods reach `reach` · σ_max.
    pub sigma_max: f64,
    /// Number of σ values, evenly spaced from `sigma_min` to `sigma_max` (1 to 64).
    pub scales: usize,
    /// ε of the scale selection rule `argmin V_σ + ε/σ²` (× L²). Larger values favour larger
    /// σ (smoother results); smaller ones keep more detail.
    pub epsilon: f64,
    /// ρ of the anisotropic metric; 0 gives the isotropic ("adaptive") filter.
    pub rho: f64,
    /// Where each face's neighbourhood is cut, in units of σ (greater than 0, at most 4, the
    /// kernel's support). The work per face grows with its square; beyond 3σ the kernel's
    /// quartic tail holds 0.5 % of its weight on a plane.
    pub reach: f64,
    /// The variance estimate of the scale selection rule.
    pub variance: Variance,
    /// Most conjugate-gradient iterations of the vertex fitting.
    pub max_iterations: usize,
    /// The fitting stops when an iteration lowers the energy by less than this fraction.
    pub tolerance: f64,
    /// Largest move of a vertex in one fitting step (× L).
    pub step_cap: f64,
    /// Measure σ in units of each face's *local* edge length instead of the mean L, so that
    /// on a non-uniformly sampled scan small triangles are filtered at their own scale.
    pub local_scale: bool,
    /// Fit the vertices with this many rounds of the local vertex update instead of
    /// minimising the global energy (0: the energy).
    pub vertex_updates: usize,
    /// Passes of filter-then-fit, each on the previous one's result (at least 1).
    pub passes: usize,
}

impl DenoiseOptions {
    /// The isotropic adaptive filter: σ ∈ {0.2L, 0.4L, …, 2.0L} (the paper's legible grid),
    /// ρ = 0, the unbiased variance and ε = 0.03 L² (calibrated on the noisy bunny, fandisk
    /// and OpenMesh cube; the paper's garbled "0.0?L²" reads as 0.01–0.09).
    pub fn adaptive() -> DenoiseOptions {
        DenoiseOptions {
            sigma_min: 0.2,
            sigma_max: 2.0,
            scales: 10,
            epsilon: 0.03,
            rho: 0.0,
            reach: 4.0,
            variance: Variance::Unbiased,
            max_iterations: 200,
            tolerance: 1e-6,
            step_cap: 0.1,
            local_scale: false,
            vertex_updates: 0,
            passes: 1,
        }
    }

    /// The anisotropic filter: the wider grid σ ∈ {0.5L, …, 5.0L} (the metric stretches
    /// distances by 1 + ρ/2 · (normal spread), so the same σ covers less surface), ρ = 5 and
    /// ε = 1 L². Calibrated: the metric is built from the *noisy* normals, and with ρ = 20 (the
    /// paper's likely value) noise of 0.1–0.2 L stretches every distance five- to tenfold, so
    /// the filter barely smooths; ρ = 5 still cuts neighbourhoods at sharp edges. The large ε
    /// lets the metric, not the scale rule, decide where to stop.
    pub fn anisotropic() -> DenoiseOptions {
        DenoiseOptions {
            sigma_min: 0.5,
            sigma_max: 5.0,
            scales: 10,
            epsilon: 1.0,
            rho: 5.0,
            ..DenoiseOptions::adaptive()
        }
    }

    /// The automatic default of `meshpyr smooth`: the adaptive filter with σ in units of the
    /// local edge length (non-uniform sampling), the local vertex update for the fitting
    /// (5 rounds), two passes, and neighbourhoods cut at 3σ instead of the kernel's 4σ (balls
    /// of about half the faces). See `docs/performance.md` for how it compares.
    pub fn automatic() -> DenoiseOptions {
        DenoiseOptions {
            local_scale: true,
            vertex_updates: 5,
            passes: 2,
            reach: 3.0,
            ..DenoiseOptions::adaptive()
        }
    }

    /// The σ grid in units of L.
    pub(crate) fn sigmas(&self) -> Vec<f64> {
        if self.scales <= 1 {
            return vec![self.sigma_max];
        }
        let step = (self.sigma_max - self.sigma_min) / (self.scales - 1) as f64;
        (0..self.scales)
            .map(|i| self.sigma_min + step * i as f64)
            .collect()
    }

    /// Checks the options; the error says which field is wrong.
    pub fn validate(&self) -> Result<(), SmoothError> {
        let bad = |what: &str| {
            Err(SmoothError::InvalidParameter(format!(
                "invalid smoothing options: {what}"
            )))
        };
        let finite_pos = |x: f64| x.is_finite() && x > 0.0;
        if !finite_pos(self.sigma_min) || !finite_pos(self.sigma_max) {
            return bad("sigma_min and sigma_max must be positive and finite");
        }
        if self.sigma_min > self.sigma_max {
            return bad("sigma_min must not exceed sigma_max");
        }
        if self.scales == 0 || self.scales > MAX_SCALES {
            return bad("scales must be between 1 and 64");
        }
        if !(self.epsilon.is_finite() && self.epsilon >= 0.0) {
            return bad("epsilon must be finite and not negative");
        }
        if !(self.reach > 0.0 && self.reach <= 4.0) {
            return bad("reach must be greater than 0 and at most 4");
        }
        if !(self.rho.is_finite() && self.rho >= 0.0) {
            return bad("rho must be finite and not negative");
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return bad("tolerance must be finite and not negative");
        }
        if !finite_pos(self.step_cap) {
            return bad("step_cap must be positive and finite");
        }
        if self.passes == 0 {
            return bad("passes must be at least 1");
        }
        Ok(())
    }
}

impl Default for DenoiseOptions {
    fn default() -> Self {
        DenoiseOptions::adaptive()
    }
}

/// The result of [`denoise`].
#[derive(Clone, Debug, PartialEq)]
pub struct Denoised {
    /// New positions indexed by vertex slot (length: one more than the largest slot). Vertices
    /// in no triangle keep their positions; slots without a vertex hold zero.
    pub positions: Vec<DVec3>,
    /// The mean edge length L the options were scaled by.
    pub mean_edge: f64,
    /// Number of faces at each scale of the grid (σ_opt histogram).
    pub scale_histogram: Vec<usize>,
    /// Faces left out of the fitting (no defined smoothed normal).
    pub unfiltered_faces: usize,
    /// What the vertex fitting did.
    pub fit: FitReport,
}

/// Denoises `mesh` with one pass of the adaptive (or, with `rho > 0`, anisotropic) normal
/// filter and vertex fitting. `progress` goes 0 → 1 (filtering is the first 70%).
///
/// Never panics on degenerate input: zero-area faces get no weight, faces without a defined
/// smoothed normal are left out of the fitting, boundaries and components are not crossed, and
/// a mesh without faces or edges of positive length is returned unchanged.
pub fn denoise(
    mesh: &Mesh,
    options: &DenoiseOptions,
    progress: &dyn Progress,
) -> Result<Denoised, SmoothError> {
    options.validate()?;
    let surface = FlatSurface::new(mesh);
    let mut input = vec![DVec3::ZERO; surface.vertex_slots];
    for v in mesh.vertices() {
        let p = mesh.position(v);
        if !p.is_finite() {
            return Err(SmoothError::NonFinite(v.slot()));
        }
        input[v.slot()] = p;
    }
    Ok(denoise_surface(surface, &|i| input[i], options, progress))
}

/// [`denoise`] on a flat surface whose vertex slot `i` sits at `input(i)` (finite; zero for
/// an empty slot), for callers that never make the half-edge mesh. Does not validate
/// `options`.
pub(crate) fn denoise_surface(
    mut surface: FlatSurface,
    input: &dyn Fn(usize) -> DVec3,
    options: &DenoiseOptions,
    progress: &dyn Progress,
) -> Denoised {
    let slots = surface.vertex_slots;
    // Everything below runs relative to the bounding-box centre: the fitting's energy is a sum
    // of tiny differences and the scale selection a discrete choice, so in the absolute
    // coordinates of a scan far from the origin (georeferenced units) rounding would decide
    // them (1e6 units away, results differed by a quarter of the displacement). An exactly
    // translated input now gives exactly translated output.
    let origin = BoundingBox::of((0..slots).map(input)).map_or(DVec3::ZERO, |b| b.centre());
    let positions: Vec<DVec3> = (0..slots).map(|i| input(i) - origin).collect();
    let l = surface.mean_edge_length(&positions);
    let mut result = Denoised {
        positions,
        mean_edge: l,
        scale_histogram: vec![0; options.scales],
        unfiltered_faces: 0,
        fit: FitReport::default(),
    };
    if !(l > 0.0 && l.is_finite()) {
        progress.update(1.0);
        result.positions = (0..slots).map(input).collect();
        return result;
    }
    surface.reorder_spatially(&result.positions);
    let passes = options.passes.max(1);
    for pass in 0..passes {
        let share = |x: f64| progress.update((pass as f64 + x) / passes as f64);
        run_pass(&surface, &mut result, options, l, &share);
    }
    // Back to the input's coordinates; vertices the fitting did not move (those in no face,
    // and empty slots) keep their exact input bits. Nothing changed the positions before the
    // fitting, so a vertex it left alone still holds exactly `q - origin`.
    for (i, p) in result.positions.iter_mut().enumerate() {
        let q = input(i);
        *p = if *p == q - origin { q } else { *p + origin };
    }
    result
}

/// One pass: filter the face normals of `result.positions`, then fit the vertices to them.
fn run_pass(
    surface: &FlatSurface,
    result: &mut Denoised,
    options: &DenoiseOptions,
    l: f64,
    progress: &dyn Progress,
) {
    let filtered = filter_pass(surface, &result.positions, options, l, progress);
    result.scale_histogram.fill(0);
    result.unfiltered_faces = 0;
    for &s in &filtered.scale {
        match result.scale_histogram.get_mut(s as usize) {
            Some(c) => *c += 1,
            None => result.unfiltered_faces += 1,
        }
    }
    let fitting = Fitting::new(surface, &filtered.normals);
    if options.vertex_updates > 0 {
        let initial_energy = fitting.energy(&result.positions);
        fitting.project(&mut result.positions, options.vertex_updates);
        result.fit = FitReport {
            iterations: options.vertex_updates,
            initial_energy,
            final_energy: fitting.energy(&result.positions),
            rejected_flips: 0,
        };
    } else {
        let fit_options = FitOptions {
            max_iterations: options.max_iterations,
            tolerance: options.tolerance,
            step_cap: options.step_cap * l,
            ..FitOptions::default()
        };
        result.fit = fitting.minimise(&mut result.positions, &fit_options, &|x: f64| {
            progress.update(0.7 + 0.3 * x)
        });
    }
    progress.update(1.0);
}

/// The filtered normals of the faces at `positions`. The face normals, the dual graph and the
/// local scales are dropped on return, before the fitting makes its own arrays.
fn filter_pass(
    surface: &FlatSurface,
    positions: &[DVec3],
    options: &DenoiseOptions,
    l: f64,
    progress: &dyn Progress,
) -> FilteredNormals {
    let frames = surface.face_frames(positions);
    let graph = DualGraph::new(surface, positions);
    let grid = ScaleGrid {
        sigmas: options.sigmas().iter().map(|s| s * l).collect(),
        epsilon: options.epsilon * l * l,
        rho: options.rho,
        reach: options.reach,
        variance: options.variance,
        local: if options.local_scale {
            surface.local_length_factors(positions, l)
        } else {
            Vec::new()
        },
    };
    filter_normals(&graph, &frames.normals, &frames.areas, &grid, &|x: f64| {
        progress.update(0.7 * x)
    })
}
