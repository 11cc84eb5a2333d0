//! Ohtake–Belyaev–Seidel denoising of a file's mesh on the builder's corner table, the
//! path of `meshpyr smooth` for `auto`, `adaptive` and `anisotropic`.
//!
//! The half-edge [`crate::mesh::Mesh`] is never made: the builder's repairs run on a corner
//! table ([`crate::mesh::CornerTable`]), whose arrays become the denoiser's flat surface, and
//! the new positions are written over the input's own (a vertex the builder split gets the
//! mean of its copies), so the output is the input with new positions and no second copy of
//! it exists. The surface is the one the half-edge mesh would give, so the result is the same
//! bit for bit (`docs/performance.md` has the memory and time this saves).

use super::{DenoiseOptions, Denoised, SmoothError};
use crate::fairing::ohtake::denoise_surface;
use crate::fairing::surface::FlatSurface;
use crate::mesh::{BuildReport, CornerTable, PolygonMesh};
use crate::progress::Progress;

/// Denoises `input` in place with `options` (validated): its positions become the smoothed
/// ones, everything else stays. Returns what the builder repaired and the denoiser's report
/// (whose positions are left empty: they are in `input`).
pub(crate) fn denoise_in_place(
    input: &mut PolygonMesh,
    options: &DenoiseOptions,
    progress: &dyn Progress,
) -> Result<(BuildReport, Denoised), SmoothError> {
    let repaired = CornerTable::from_polygons(input)?;
    let source = repaired.source;
    let vertex_source = &source.vertex_source;
    let surface = FlatSurface::from_corners(repaired.corners, vertex_source.len());
    let original = &input.positions;
    let at = |i: usize| original[vertex_source[i] as usize];
    let mut denoised = denoise_surface(surface, &at, options, progress);
    source.write_input_positions(&denoised.positions, &mut input.positions);
    denoised.positions = Vec::new();
    Ok((repaired.report, denoised))
}
