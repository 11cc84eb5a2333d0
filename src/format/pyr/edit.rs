//! Saving an edit: the same hierarchy carrying new original positions, ready to encode.

use crate::format::FormatError;
use crate::mesh::{PolygonMesh, ScalarType, SourceMap};
use crate::pm::{PmParts, ProgressiveMesh};
use glam::DVec3;

use super::internal;

/// The same hierarchy with new original positions (for saving an edit): `positions` are the
/// new positions of the input's vertices; split copies follow their source vertex. When the
/// input stores f32 positions they are rounded to f32 first, as writing a mesh file would;
/// stored normals follow them ([`PolygonMesh::refresh_normals`]).
pub(crate) fn with_positions(
    input: &PolygonMesh,
    source: &SourceMap,
    pm: &ProgressiveMesh,
    positions: Vec<DVec3>,
) -> Result<(PolygonMesh, ProgressiveMesh), FormatError> {
    if positions.len() != input.positions.len() {
        return Err(internal("position count differs from the input"));
    }
    let round = input.position_type == Some(ScalarType::F32);
    let mut new_input = input.clone();
    new_input.positions = positions
        .into_iter()
        .map(|p| if round { p.as_vec3().as_dvec3() } else { p })
        .collect();
    new_input.refresh_normals(&input.positions);
    let source = &source.vertex_source;
    let mut pm_positions = Vec::with_capacity(pm.pm_to_mesh().len());
    for &s in pm.pm_to_mesh() {
        let src = source.get(s as usize).copied().unwrap_or(s) as usize;
        let p = new_input
            .positions
            .get(src)
            .copied()
            .ok_or_else(|| internal("vertex source out of range"))?;
        pm_positions.push(p);
    }
    let new_pm = ProgressiveMesh::from_parts(PmParts {
        n_base: pm.n_base_vertices(),
        positions: pm_positions,
        pm_to_mesh: pm.pm_to_mesh().to_vec(),
        splits: pm.splits().to_vec(),
        faces: pm.finest_faces().to_vec(),
        errors: pm.split_errors().to_vec(),
        // The same splits, so the same passes: the edited hierarchy's pyramid keeps the rule.
        pins: pm.pins().cloned(),
    })
    .map_err(|e| internal(&e.to_string()))?;
    Ok((new_input, new_pm))
}
