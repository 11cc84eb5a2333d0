//! One door to every smoother: [`SmoothMethod`] names a method with its options, and
//! [`smooth_mesh`] runs it on a mesh as read from a file, so the command line, the Python
//! package and the viewer choose a method the same way and get the same bits.

use super::flat::denoise_in_place;
use super::{
    DenoiseOptions, Denoised, McfOptions, SmoothError, TaubinOptions, denoise, implicit_mcf,
    taubin_smoothing,
};
use crate::mesh::{BuildReport, Mesh, PolygonMesh};
use crate::progress::Progress;
use crate::pyramid::{PyramidDenoise, pyramid_denoise};
use crate::wording::Count;
use glam::DVec3;

/// A smoothing method with its options.
#[derive(Clone, Debug, PartialEq)]
pub enum SmoothMethod {
    /// The recommended method, which `meshpyr smooth` runs when no method is named: today
    /// [`DenoiseOptions::automatic`]. It may change between versions as better methods
    /// arrive; name the method and its options to pin the result.
    Auto,
    /// Ohtake–Belyaev–Seidel feature-preserving denoising ([`super::denoise`]): adaptive when
    /// `rho` is 0, anisotropic otherwise (see [`DenoiseOptions::adaptive`] and
    /// [`DenoiseOptions::anisotropic`]).
    Ohtake(DenoiseOptions),
    /// Taubin λ|μ smoothing ([`super::taubin_smoothing`]).
    Taubin(TaubinOptions),
    /// Implicit mean-curvature flow ([`super::implicit_mcf`]).
    Mcf(McfOptions),
    /// Per-octave attenuation on the detail pyramid with the normal-adaptive operator, the
    /// noise level estimated by the pyramid itself ([`crate::pyramid::pyramid_denoise`]).
    Pyramid(PyramidDenoise),
}

impl Default for SmoothMethod {
    /// The method `meshpyr smooth` runs when no method is named.
    fn default() -> Self {
        SmoothMethod::Auto
    }
}

impl SmoothMethod {
    /// The method's name as the command line spells it.
    pub fn name(&self) -> &'static str {
        match self {
            SmoothMethod::Auto => "auto",
            SmoothMethod::Ohtake(o) if o.rho > 0.0 => "anisotropic",
            SmoothMethod::Ohtake(_) => "adaptive",
            SmoothMethod::Taubin(_) => "taubin",
            SmoothMethod::Mcf(_) => "mcf",
            SmoothMethod::Pyramid(_) => "pyramid",
        }
    }

    /// Checks the options' ranges, so a caller can refuse bad options before reading a file.
    pub fn validate(&self) -> Result<(), SmoothError> {
        match self {
            SmoothMethod::Auto => Ok(()),
            SmoothMethod::Ohtake(o) => o.validate(),
            SmoothMethod::Taubin(o) => o.validate(),
            SmoothMethod::Mcf(o) => o.validate(),
            SmoothMethod::Pyramid(o) => o.validate(),
        }
    }
}

/// What [`smooth_mesh`] returns.
#[derive(Clone, Debug)]
pub struct Smoothed {
    /// The input with new positions: its vertices (count and order), faces and attributes
    /// unchanged but for stored normals, which follow the new surface
    /// ([`PolygonMesh::refresh_normals`]). Vertices in no face keep their positions.
    pub mesh: PolygonMesh,
    /// What the builder repaired before smoothing (a vertex it split gets the mean of its
    /// copies in [`Smoothed::mesh`]).
    pub repair: BuildReport,
    /// One line saying what the method did (scales chosen, iterations, energies).
    pub summary: String,
}

/// Smooths a mesh as read from a file: repairs it for processing as every command does, runs
/// `method`, and maps the new positions back onto the input's vertices. `progress` goes 0 → 1.
/// Fails with [`SmoothError::NoSurface`] when the input has no face to smooth.
pub fn smooth_mesh(
    input: &PolygonMesh,
    method: &SmoothMethod,
    progress: &dyn Progress,
) -> Result<Smoothed, SmoothError> {
    method.validate()?;
    input.check_surface()?;
    smooth_mesh_owned(input.clone(), method, progress)
}

/// [`smooth_mesh`] on a mesh the caller gives away: the new positions are written over its
/// own, so no second copy of the mesh is ever held (what `meshpyr smooth` uses on scans).
pub fn smooth_mesh_owned(
    mut input: PolygonMesh,
    method: &SmoothMethod,
    progress: &dyn Progress,
) -> Result<Smoothed, SmoothError> {
    method.validate()?;
    input.check_surface()?;
    let automatic;
    let method = match method {
        SmoothMethod::Auto => {
            automatic = SmoothMethod::Ohtake(DenoiseOptions::automatic());
            &automatic
        }
        chosen => chosen,
    };
    // The old positions are kept only when stored normals must follow the new ones.
    let before = input.stores_normals().then(|| input.positions.clone());
    let (repair, summary) = match method {
        SmoothMethod::Ohtake(options) => {
            let (repair, r) = denoise_in_place(&mut input, options, progress)?;
            (repair, denoise_summary(&r))
        }
        _ => {
            let built = Mesh::from_polygons(&input)?;
            let (positions, summary) = smooth_positions(&built.mesh, method, progress)?;
            drop(built.mesh);
            let source = built.source;
            source.write_input_positions(&positions, &mut input.positions);
            (built.report, summary)
        }
    };
    if let Some(before) = before {
        input.refresh_normals(&before);
    }
    Ok(Smoothed {
        mesh: input,
        repair,
        summary,
    })
}

/// Runs `method` on a half-edge mesh: new positions in vertex slot order, and a line saying
/// what was done.
pub fn smooth_positions(
    mesh: &Mesh,
    method: &SmoothMethod,
    progress: &dyn Progress,
) -> Result<(Vec<DVec3>, String), SmoothError> {
    Ok(match method {
        SmoothMethod::Auto => {
            let automatic = SmoothMethod::Ohtake(DenoiseOptions::automatic());
            return smooth_positions(mesh, &automatic, progress);
        }
        SmoothMethod::Ohtake(options) => {
            let r = denoise(mesh, options, progress)?;
            let summary = denoise_summary(&r);
            (r.positions, summary)
        }
        SmoothMethod::Taubin(options) => (
            taubin_smoothing(mesh, options, progress)?,
            iterations(options.iterations),
        ),
        SmoothMethod::Mcf(options) => (
            implicit_mcf(mesh, options, progress)?,
            iterations(options.iterations),
        ),
        SmoothMethod::Pyramid(options) => {
            let r = pyramid_denoise(mesh, options, progress)?;
            let gains: Vec<String> = r.gains.iter().map(|g| format!("{g:.2}")).collect();
            let summary = format!(
                "noise {:.3e} along the normal; octave gains, finest first: {}",
                r.noise,
                gains.join(" ")
            );
            (r.positions, summary)
        }
    })
}

/// The line saying what the denoiser did.
fn denoise_summary(r: &Denoised) -> String {
    format!(
        "mean edge {:.4e}; σ_opt histogram {:?}; fitting {}, energy {:.4e} → {:.4e}",
        r.mean_edge,
        r.scale_histogram,
        iterations(r.fit.iterations),
        r.fit.initial_energy,
        r.fit.final_energy
    )
}

fn iterations(n: usize) -> String {
    Count(n, "iteration", "iterations").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn a_point_cloud_is_refused_as_no_surface() {
        let cloud = PolygonMesh::from_triangles(vec![DVec3::ZERO, DVec3::X, DVec3::Y], &[]);
        let r = smooth_mesh(&cloud, &SmoothMethod::Auto, &NoProgress);
        assert!(matches!(r, Err(SmoothError::NoSurface(_))), "{r:?}");
    }

    #[test]
    fn auto_is_the_automatic_preset_and_keeps_the_layout() {
        let (p, t) = crate::mesh::shapes::icosphere(2);
        let wobble = |i: usize| 1.0 + 0.05 * ((i * 7919) as f64).sin();
        let p: Vec<DVec3> = p.iter().enumerate().map(|(i, &x)| x * wobble(i)).collect();
        let input = PolygonMesh::from_triangles(p, &t);
        let auto = smooth_mesh(&input, &SmoothMethod::Auto, &NoProgress).expect("smooths");
        let preset = SmoothMethod::Ohtake(DenoiseOptions::automatic());
        let explicit = smooth_mesh(&input, &preset, &NoProgress).expect("smooths");
        assert_eq!(auto.mesh, explicit.mesh);
        assert_eq!(auto.mesh.face_indices, input.face_indices);
        assert_ne!(auto.mesh.positions, input.positions);
        assert_eq!(SmoothMethod::default().name(), "auto");
    }
}
