//! What `info` says about a textured mesh: its per-corner data and seams, its materials and
//! whether the files they name are there.

use std::collections::HashMap;

use serde::Serialize;

use super::CornerAttribute;
use super::corners::TEXCOORD;
use super::polygon::PolygonMesh;

/// The texture side of a mesh (see [`crate::mesh::corners`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TextureInfo {
    /// Per-corner attributes: name, pool rows and corners with a value.
    pub corner_attributes: Vec<(String, usize, usize)>,
    /// True when the texture coordinates are per vertex (the vertex attributes `u`, `v`, as an
    /// OBJ file's `vt` that follow its `v` one to one read): no seams then.
    pub vertex_texcoords: bool,
    /// Polygon edges whose two sides have different texture coordinates at an end.
    pub seam_edges: usize,
    /// Vertices whose corners have more than one texture coordinate.
    pub seam_vertices: usize,
    /// Material names, in the order faces index them.
    pub materials: Vec<String>,
    /// Material libraries and images, each with whether the file is there (`None`: the mesh
    /// was not read from a file, so relative names cannot be looked up).
    pub files: Vec<(String, Option<bool>)>,
    /// OBJ groups and objects.
    pub groups: usize,
    /// OBJ objects.
    pub objects: usize,
}

impl TextureInfo {
    /// The texture side of `mesh`; `None` when it has none of it.
    pub fn of(mesh: &PolygonMesh) -> Option<TextureInfo> {
        let m = &mesh.materials;
        if mesh.corner_attributes.is_empty()
            && m.is_empty()
            && mesh.group_names.is_empty()
            && mesh.object_names.is_empty()
        {
            return None;
        }
        let (seam_edges, seam_vertices) = mesh
            .corner_attribute(TEXCOORD)
            .map_or((0, 0), |uv| seams(mesh, uv));
        let names = m
            .libraries
            .iter()
            .chain(m.list.iter().filter_map(|x| x.texture.as_ref()));
        let mut files: Vec<(String, Option<bool>)> = Vec::new();
        for name in names {
            if files.iter().all(|(n, _)| n != name) {
                let found = m.folder.as_ref().map(|d| d.join(name).is_file());
                files.push((name.clone(), found));
            }
        }
        let vertex_texcoords = mesh.corner_attribute(TEXCOORD).is_none()
            && mesh.vertex_attribute("u").is_some()
            && mesh.vertex_attribute("v").is_some();
        Some(TextureInfo {
            vertex_texcoords,
            corner_attributes: mesh
                .corner_attributes
                .iter()
                .map(|a| (a.name.clone(), a.pool_len(), a.n_valued()))
                .collect(),
            seam_edges,
            seam_vertices,
            materials: m.list.iter().map(|x| x.name.clone()).collect(),
            files,
            groups: mesh.group_names.len(),
            objects: mesh.object_names.len(),
        })
    }
}

/// Seam edges and seam vertices of the corner attribute `uv`: values compared by their bits,
/// so two pool rows with equal values are no seam.
pub(crate) fn seams(mesh: &PolygonMesh, uv: &CornerAttribute) -> (usize, usize) {
    let value = |c: usize| -> Option<Vec<u64>> {
        uv.row(c).map(|r| {
            uv.columns
                .iter()
                .map(|col| col.data.get_f64(r).to_bits())
                .collect()
        })
    };
    // Per undirected edge, the values at its lower and higher vertex on each side.
    type Ends = (Option<Vec<u64>>, Option<Vec<u64>>);
    let mut edges: HashMap<(u32, u32), Vec<Ends>> = HashMap::new();
    let mut at_vertex: HashMap<u32, Vec<Option<Vec<u64>>>> = HashMap::new();
    for f in 0..mesh.n_faces() {
        let (s, e) = (
            mesh.face_starts[f] as usize,
            mesh.face_starts[f + 1] as usize,
        );
        for c in s..e {
            let d = if c + 1 == e { s } else { c + 1 };
            let (a, b) = (mesh.face_indices[c], mesh.face_indices[d]);
            let ends = if a < b {
                (value(c), value(d))
            } else {
                (value(d), value(c))
            };
            edges.entry((a.min(b), a.max(b))).or_default().push(ends);
            let seen = at_vertex.entry(a).or_default();
            let v = value(c);
            if !seen.contains(&v) {
                seen.push(v);
            }
        }
    }
    let seam_edges = edges
        .values()
        .filter(|sides| sides.iter().any(|s| *s != sides[0]))
        .count();
    let seam_vertices = at_vertex.values().filter(|v| v.len() > 1).count();
    (seam_edges, seam_vertices)
}

impl PolygonMesh {
    /// What a command that makes new faces (simplification, subdivision) cannot carry yet:
    /// one line naming the per-corner data, materials and groups, or `None` when the mesh has
    /// none of them.
    pub fn face_data_dropped(&self) -> Option<String> {
        let mut what: Vec<String> = self
            .corner_attributes
            .iter()
            .map(|a| format!("per-corner {}", a.name))
            .collect();
        if !self.materials.list.is_empty() {
            what.push(format!("{} materials", self.materials.list.len()));
        }
        if !self.group_names.is_empty() || !self.object_names.is_empty() {
            what.push("groups".into());
        }
        if !self.face_attributes.is_empty() || !self.face_lists.is_empty() {
            what.push("face properties".into());
        }
        (!what.is_empty()).then(|| {
            format!(
                "the output has new faces and does not carry the input's {}",
                what.join(", ")
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_square_cut_along_its_diagonal_in_texture_space_has_one_seam_edge_and_two_seam_vertices() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::X + DVec3::Y, DVec3::Y];
        let mut m = PolygonMesh::from_triangles(p, &[[0, 1, 2], [0, 2, 3]]);
        let u = [0.0, 1.0, 1.0, 0.5, 0.5, 0.0];
        let rows: Vec<[f32; 2]> = u.iter().map(|&u| [u, 0.0]).collect();
        m.corner_attributes.push(CornerAttribute::from_rows(
            TEXCOORD,
            ["u", "v"],
            &rows,
            vec![0, 1, 2, 3, 4, 5],
        ));
        assert_eq!(seams(&m, &m.corner_attributes[0]), (1, 2));
        let info = TextureInfo::of(&m).unwrap();
        assert_eq!(info.corner_attributes, [("texcoord".to_string(), 6, 6)]);
        assert!(
            m.face_data_dropped()
                .unwrap()
                .contains("per-corner texcoord")
        );
    }
}
