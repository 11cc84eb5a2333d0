//! `meshpyr.smooth`: denoising that keeps the vertices (count and order) and faces, with the
//! command line's methods and options.

use crate::arrays::{self, count, positions_array};
use crate::errors::{input_error, value_error};
use crate::functions::choice_error;
use meshpyr::smooth::{Boundary, McfOptions, TaubinOptions, Variance, Weights};
use meshpyr::{DenoiseOptions, NoProgress, PyramidDenoise, SmoothMethod};
use numpy::PyArray2;
use pyo3::prelude::*;

const METHODS: [&str; 6] = [
    "auto",
    "adaptive",
    "anisotropic",
    "taubin",
    "mcf",
    "pyramid",
];
const OHTAKE: &[&str] = &["auto", "adaptive", "anisotropic"];

/// The keywords of `smooth` as given (`None`: not given).
struct SmoothArgs<'a> {
    method: &'a str,
    epsilon: Option<f64>,
    sigma_min: Option<f64>,
    sigma_max: Option<f64>,
    scales: Option<i64>,
    rho: Option<f64>,
    variance: Option<&'a str>,
    scale: Option<&'a str>,
    vertex_updates: Option<i64>,
    passes: Option<i64>,
    fit_iterations: Option<i64>,
    step_cap: Option<f64>,
    iterations: Option<i64>,
    weights: Option<&'a str>,
    lambda: Option<f64>,
    mu: Option<f64>,
    time_step: Option<f64>,
    boundary: Option<&'a str>,
    strength: Option<f64>,
}

impl SmoothArgs<'_> {
    /// The method these keywords describe; a keyword of another method is a `ValueError`
    /// rather than silently ignored, as on the command line.
    fn method(&self) -> PyResult<SmoothMethod> {
        if !METHODS.contains(&self.method) {
            return Err(choice_error("method", self.method, &METHODS));
        }
        self.reject_keywords_of_other_methods()?;
        match self.method {
            // Named without options, the recommended method as the library defines it.
            "auto" if self.given().is_empty() => Ok(SmoothMethod::Auto),
            "taubin" => self.taubin(),
            "mcf" => self.mcf(),
            "pyramid" => Ok(SmoothMethod::Pyramid(PyramidDenoise {
                strength: self.strength.unwrap_or(PyramidDenoise::default().strength),
            })),
            _ => self.ohtake(),
        }
    }

    /// Every keyword given, with the methods it applies to.
    fn given(&self) -> Vec<(&'static str, &'static [&'static str])> {
        [
            ("epsilon", self.epsilon.is_some(), OHTAKE),
            ("sigma_min", self.sigma_min.is_some(), OHTAKE),
            ("sigma_max", self.sigma_max.is_some(), OHTAKE),
            ("scales", self.scales.is_some(), OHTAKE),
            ("rho", self.rho.is_some(), OHTAKE),
            ("variance", self.variance.is_some(), OHTAKE),
            ("scale", self.scale.is_some(), OHTAKE),
            ("vertex_updates", self.vertex_updates.is_some(), OHTAKE),
            ("passes", self.passes.is_some(), OHTAKE),
            ("fit_iterations", self.fit_iterations.is_some(), OHTAKE),
            ("step_cap", self.step_cap.is_some(), OHTAKE),
            ("iterations", self.iterations.is_some(), &["taubin", "mcf"]),
            ("weights", self.weights.is_some(), &["taubin"]),
            ("lambda_", self.lambda.is_some(), &["taubin"]),
            ("mu", self.mu.is_some(), &["taubin"]),
            ("time_step", self.time_step.is_some(), &["mcf"]),
            ("boundary", self.boundary.is_some(), &["taubin", "mcf"]),
            ("strength", self.strength.is_some(), &["pyramid"]),
        ]
        .into_iter()
        .filter(|&(_, set, _)| set)
        .map(|(name, _, methods)| (name, methods))
        .collect()
    }

    fn reject_keywords_of_other_methods(&self) -> PyResult<()> {
        for (name, methods) in self.given() {
            if !methods.contains(&self.method) {
                return Err(value_error(format!(
                    "{name}= does not apply to method={:?} (it is an option of {})",
                    self.method,
                    methods.join(" and ")
                )));
            }
        }
        Ok(())
    }

    fn ohtake(&self) -> PyResult<SmoothMethod> {
        let mut o = match self.method {
            "anisotropic" => DenoiseOptions::anisotropic(),
            "auto" => DenoiseOptions::automatic(),
            _ => DenoiseOptions::adaptive(),
        };
        o.epsilon = self.epsilon.unwrap_or(o.epsilon);
        o.sigma_min = self.sigma_min.unwrap_or(o.sigma_min);
        o.sigma_max = self.sigma_max.unwrap_or(o.sigma_max);
        if let Some(n) = self.scales {
            o.scales = count("scales", n)?;
        }
        o.rho = self.rho.unwrap_or(o.rho);
        o.variance = match self.variance {
            None => o.variance,
            Some("unbiased") => Variance::Unbiased,
            Some("biased") => Variance::Biased,
            Some(other) => return Err(choice_error("variance", other, &["unbiased", "biased"])),
        };
        if let Some(n) = self.fit_iterations {
            o.max_iterations = count("fit_iterations", n)?;
        }
        o.step_cap = self.step_cap.unwrap_or(o.step_cap);
        if let Some(n) = self.passes {
            o.passes = count("passes", n)?;
        }
        if let Some(n) = self.vertex_updates {
            o.vertex_updates = count("vertex_updates", n)?;
        }
        o.local_scale = match self.scale {
            None => o.local_scale,
            Some("global") => false,
            Some("local") => true,
            Some(other) => return Err(choice_error("scale", other, &["global", "local"])),
        };
        Ok(SmoothMethod::Ohtake(o))
    }

    fn boundary(&self) -> PyResult<Boundary> {
        match self.boundary {
            None | Some("fixed") => Ok(Boundary::Fixed),
            Some("smooth") => Ok(Boundary::Smooth),
            Some(other) => Err(choice_error("boundary", other, &["fixed", "smooth"])),
        }
    }

    fn taubin(&self) -> PyResult<SmoothMethod> {
        let d = TaubinOptions::default();
        Ok(SmoothMethod::Taubin(TaubinOptions {
            iterations: match self.iterations {
                Some(n) => count("iterations", n)?,
                None => d.iterations,
            },
            lambda: self.lambda.unwrap_or(d.lambda),
            mu: self.mu.unwrap_or(d.mu),
            weights: match self.weights {
                None => d.weights,
                Some("uniform") => Weights::Uniform,
                Some("inverse-edge") => Weights::InverseEdgeLength,
                Some("cotan") => Weights::Cotangent,
                Some(other) => {
                    return Err(choice_error(
                        "weights",
                        other,
                        &["uniform", "inverse-edge", "cotan"],
                    ));
                }
            },
            boundary: self.boundary()?,
        }))
    }

    fn mcf(&self) -> PyResult<SmoothMethod> {
        let d = McfOptions::default();
        Ok(SmoothMethod::Mcf(McfOptions {
            iterations: match self.iterations {
                Some(n) => count("iterations", n)?,
                None => d.iterations,
            },
            time_step: self.time_step.unwrap_or(d.time_step),
            boundary: self.boundary()?,
        }))
    }
}

/// Denoises ``(V, F)``, as ``meshpyr smooth`` (same methods, options and bits). ``method``:
///
/// - "auto" (default): the recommended method, today the adaptive filter at each face's local
///   scale with local vertex updates, two passes; it may change between versions (name a
///   method and its options to pin the result); it takes the options of "adaptive";
/// - "adaptive": Ohtake, Belyaev and Seidel's feature-preserving smoothing, face
///   normals filtered at a scale chosen per face, then the vertices fitted to them;
///   ``epsilon`` (× L², larger smooths more), ``sigma_min``, ``sigma_max`` and ``scales`` (the
///   filter scales, × L), ``rho`` (anisotropy, 0 = isotropic), ``variance`` ("unbiased" or
///   "biased"), ``scale`` ("global": σ in units of the mean edge length L; "local": of each
///   face's own), ``passes`` of filter-then-fit, ``vertex_updates`` (rounds of local vertex
///   updates instead of the global fit, 0 for the global fit), ``fit_iterations`` and
///   ``step_cap`` (× L) of the vertex fitting;
/// - "anisotropic": the same on neighbourhoods that do not reach across sharp edges;
/// - "taubin": Taubin's λ|μ smoothing; ``iterations`` (10), ``lambda_`` (0.5), ``mu``
///   (-0.53), ``weights`` ("cotan", "uniform" or "inverse-edge"), ``boundary``;
/// - "mcf": implicit mean-curvature flow; ``iterations`` (1), ``time_step`` (× L², 1),
///   ``boundary`` ("fixed" keeps rim vertices in place, "smooth" moves them);
/// - "pyramid": the detail pyramid with the crease-keeping "normal" operator, each octave of
///   levels attenuated by how far its details stand above the noise the pyramid estimates;
///   ``strength`` (1; more removes more, 0 nothing).
///
/// Unset options take the method's defaults; an option of another method is a ValueError.
/// Returns the new positions, float64 (n, 3), the input's vertices in the same order
/// (vertices no face uses keep their positions).
#[pyfunction]
#[pyo3(signature = (v, f, /, *, method="auto", epsilon=None, sigma_min=None, sigma_max=None, scales=None, rho=None, variance=None, scale=None, vertex_updates=None, passes=None, fit_iterations=None, step_cap=None, iterations=None, weights=None, lambda_=None, mu=None, time_step=None, boundary=None, strength=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn smooth<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    method: &str,
    epsilon: Option<f64>,
    sigma_min: Option<f64>,
    sigma_max: Option<f64>,
    scales: Option<i64>,
    rho: Option<f64>,
    variance: Option<&str>,
    scale: Option<&str>,
    vertex_updates: Option<i64>,
    passes: Option<i64>,
    fit_iterations: Option<i64>,
    step_cap: Option<f64>,
    iterations: Option<i64>,
    weights: Option<&str>,
    lambda_: Option<f64>,
    mu: Option<f64>,
    time_step: Option<f64>,
    boundary: Option<&str>,
    strength: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let method = SmoothArgs {
        method,
        epsilon,
        sigma_min,
        sigma_max,
        scales,
        rho,
        variance,
        scale,
        vertex_updates,
        passes,
        fit_iterations,
        step_cap,
        iterations,
        weights,
        lambda: lambda_,
        mu,
        time_step,
        boundary,
        strength,
    }
    .method()?;
    method.validate().map_err(input_error)?;
    let mesh = arrays::mesh(v, f)?;
    let smoothed = py
        .detach(|| meshpyr::smooth_mesh(&mesh, &method, &NoProgress))
        .map_err(input_error)?;
    Ok(positions_array(py, &smoothed.mesh.positions))
}
