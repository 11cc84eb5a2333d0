//! `meshpyr.smooth`: denoising that keeps the vertices (count and order) and faces.

use crate::arrays::{self, count, positions_array};
use crate::errors::input_error;
use crate::functions::choice_error;
use meshpyr::smooth::Variance;
use meshpyr::{DenoiseOptions, NoProgress, SmoothMethod};
use numpy::PyArray2;
use pyo3::prelude::*;

/// Denoises ``(V, F)``, as ``meshpyr smooth`` (same options, same bits): ``method``
/// "adaptive" (Ohtake, Belyaev and Seidel's adaptive Gaussian filter of the face normals
/// with vertex fitting) or "anisotropic" (the same on neighbourhoods that do not reach across
/// sharp edges). Lengths are in units of the mean edge length L of the input: ``epsilon``
/// (× L², larger smooths more), ``sigma_min``/``sigma_max``/``scales`` (the filter scales),
/// ``rho`` (anisotropy, 0 = isotropic), ``variance`` ("unbiased" or "biased"),
/// ``fit_iterations`` and ``step_cap`` (× L) of the vertex fitting; unset options take the
/// method's defaults.
///
/// Returns the new positions, float64 (n, 3), the input's vertices in the same order
/// (vertices no face uses keep their positions).
#[pyfunction]
#[pyo3(signature = (v, f, /, *, method="adaptive", epsilon=None, sigma_min=None, sigma_max=None, scales=None, rho=None, variance=None, fit_iterations=None, step_cap=None))]
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
    fit_iterations: Option<i64>,
    step_cap: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let mut o = match method {
        "adaptive" => DenoiseOptions::adaptive(),
        "anisotropic" => DenoiseOptions::anisotropic(),
        other => return Err(choice_error("method", other, &["adaptive", "anisotropic"])),
    };
    o.epsilon = epsilon.unwrap_or(o.epsilon);
    o.sigma_min = sigma_min.unwrap_or(o.sigma_min);
    o.sigma_max = sigma_max.unwrap_or(o.sigma_max);
    if let Some(n) = scales {
        o.scales = count("scales", n)?;
    }
    o.rho = rho.unwrap_or(o.rho);
    o.variance = match variance {
        None => o.variance,
        Some("unbiased") => Variance::Unbiased,
        Some("biased") => Variance::Biased,
        Some(other) => return Err(choice_error("variance", other, &["unbiased", "biased"])),
    };
    if let Some(n) = fit_iterations {
        o.max_iterations = count("fit_iterations", n)?;
    }
    o.step_cap = step_cap.unwrap_or(o.step_cap);
    o.validate().map_err(input_error)?;
    let mesh = arrays::mesh(v, f)?;
    let smoothed = py
        .detach(|| meshpyr::smooth_mesh(&mesh, &SmoothMethod::Ohtake(o), &NoProgress))
        .map_err(input_error)?;
    Ok(positions_array(py, &smoothed.mesh.positions))
}
