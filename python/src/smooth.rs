//! `meshpyr.smooth`: denoising that keeps the vertices (count and order) and faces, with the
//! command line's methods and options.

use crate::arrays::{self, count, positions_array};
use crate::errors::input_error;
use meshpyr::NoProgress;
use meshpyr::choice::Choice;
use meshpyr::smooth::SmoothSettings;
use numpy::PyArray2;
use pyo3::prelude::*;

/// A named value of a keyword (`method="taubin"`), as the library names it.
fn named<T: Choice>(name: Option<&str>) -> PyResult<Option<T>> {
    name.map(T::parse).transpose().map_err(input_error)
}

/// A count keyword, negative numbers refused.
fn optional_count(name: &str, n: Option<i64>) -> PyResult<Option<usize>> {
    n.map(|n| count(name, n)).transpose()
}

/// Denoises ``(V, F)``, as ``meshpyr smooth`` (same methods, options and bits). ``method``:
///
/// - "auto" (default): the recommended method, today the adaptive filter at each face's local
///   scale with local vertex updates, two passes; it may change between versions (name a
///   method and its options to pin the result); it takes the options of "adaptive";
/// - "adaptive": Ohtake, Belyaev and Seidel's feature-preserving smoothing, face
///   normals filtered at a scale chosen per face, then the vertices fitted to them;
///   ``epsilon`` (× L², larger smooths more), ``sigma_min``, ``sigma_max`` and ``scales`` (the
///   filter scales, × L), ``rho`` (anisotropy, 0 = isotropic), ``reach`` (where
///   neighbourhoods are cut, × σ, in (0, 4]: 3 for "auto", else 4), ``variance`` ("unbiased" or
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
#[pyo3(signature = (v, f, /, *, method="auto", epsilon=None, sigma_min=None, sigma_max=None, scales=None, rho=None, reach=None, variance=None, scale=None, vertex_updates=None, passes=None, fit_iterations=None, step_cap=None, iterations=None, weights=None, lambda_=None, mu=None, time_step=None, boundary=None, strength=None))]
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
    reach: Option<f64>,
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
    let settings = SmoothSettings {
        method: named(Some(method))?.unwrap_or_default(),
        epsilon,
        sigma_min,
        sigma_max,
        scales: optional_count("scales", scales)?,
        rho,
        reach,
        variance: named(variance)?,
        scale: named(scale)?,
        vertex_updates: optional_count("vertex_updates", vertex_updates)?,
        passes: optional_count("passes", passes)?,
        fit_iterations: optional_count("fit_iterations", fit_iterations)?,
        step_cap,
        iterations: optional_count("iterations", iterations)?,
        weights: named(weights)?,
        lambda: lambda_,
        mu,
        time_step,
        boundary: named(boundary)?,
        strength,
    };
    let method = settings.method().map_err(input_error)?;
    let mesh = arrays::mesh(v, f)?;
    // The mesh is ours: smoothing writes into it rather than into a copy.
    let smoothed = py
        .detach(|| meshpyr::smooth::smooth_mesh_owned(mesh, &method, &NoProgress))
        .map_err(input_error)?;
    Ok(positions_array(py, &smoothed.mesh.positions))
}
