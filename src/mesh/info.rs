//! [`MeshInfo`]: counts, topology, size and repairs of a file-level mesh, as `meshpyr info`
//! reports them.

use super::{BuildError, BuildReport, Mesh, PolygonMesh, TextureInfo};
use serde::Serialize;

/// What `meshpyr info` reports about a mesh. Counts describe the file as given; topology
/// (loops, components, χ, genus) is measured on the mesh the builder makes of it, which for a
/// manifold file is the file itself.
#[derive(Serialize, Debug)]
pub struct MeshInfo {
    /// Vertices in the file, unreferenced ones included.
    pub vertices: usize,
    /// Triangles after fan-triangulating the file's polygons.
    pub faces: usize,
    /// Polygons as stored in the file.
    pub polygons: usize,
    /// Distinct undirected edges of those triangles.
    pub edges: usize,
    /// Holes.
    pub boundary_loops: usize,
    /// Edge-connected components.
    pub components: usize,
    /// V − E + F of the surface (referenced vertices only).
    pub euler_characteristic: i64,
    /// Σ over components of (2 − b − χ)/2; null when the file is not manifold.
    pub genus: Option<u64>,
    /// The fewest vertices a surface of this topology can be simplified to
    /// (on the repaired mesh).
    pub floor_vertices: usize,
    /// For a mesh stored in a `.pyr` file: the hierarchy's base level against that floor
    /// ([`ProgressiveMesh::describe_base`](crate::ProgressiveMesh::describe_base)); [`MeshInfo::of`]
    /// leaves it `None` for the caller to fill.
    pub pm_base: Option<String>,
    /// True when no edge has more than two triangles and no vertex is pinched.
    pub manifold: bool,
    /// Bounding-box diagonal.
    pub bbox_diagonal: f64,
    /// Mean edge length.
    pub mean_edge_length: f64,
    /// What the builder changed to make a valid half-edge mesh.
    pub repairs: BuildReport,
    /// Per-vertex attribute names, in file order.
    pub vertex_attributes: Vec<String>,
    /// Per-face attribute names, in file order.
    pub face_attributes: Vec<String>,
    /// Texture coordinates, seams, materials and the files they name; `None` for a mesh
    /// without any.
    pub texture: Option<TextureInfo>,
}

impl MeshInfo {
    /// Measures a file-level mesh (the builder's repairs happen on a copy).
    pub fn of(poly: &PolygonMesh) -> Result<MeshInfo, BuildError> {
        let built = Mesh::from_polygons(poly)?;
        let topo = built.mesh.topology();
        let manifold = built.report.input_was_manifold();
        Ok(MeshInfo {
            vertices: poly.n_vertices(),
            faces: poly.n_triangles(),
            polygons: poly.n_faces(),
            edges: count_file_edges(poly),
            boundary_loops: topo.boundary_loops,
            components: topo.components,
            euler_characteristic: topo.euler_characteristic,
            genus: if manifold { topo.genus } else { None },
            floor_vertices: topo.floor_vertices,
            pm_base: None,
            manifold,
            bbox_diagonal: built.mesh.bbox_diagonal(),
            mean_edge_length: built.mesh.mean_edge_length(),
            repairs: built.report,
            vertex_attributes: poly
                .vertex_attributes
                .iter()
                .map(|a| a.name.clone())
                .collect(),
            face_attributes: poly
                .face_attributes
                .iter()
                .map(|a| a.name.clone())
                .collect(),
            texture: TextureInfo::of(poly),
        })
    }
}

/// Distinct undirected index pairs over the fan triangles (repeated-index pairs skipped).
fn count_file_edges(poly: &PolygonMesh) -> usize {
    let mut pairs: Vec<u64> = Vec::with_capacity(poly.n_triangles() * 3);
    for f in poly.faces() {
        for k in 1..f.len().saturating_sub(1) {
            let t = [f[0], f[k], f[k + 1]];
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if a != b {
                    pairs.push(((a.min(b) as u64) << 32) | a.max(b) as u64);
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_quad_counts_as_one_polygon_two_triangles_and_five_edges_with_one_hole() {
        let mut quad = PolygonMesh::new();
        quad.positions = vec![DVec3::ZERO, DVec3::X, DVec3::X + DVec3::Y, DVec3::Y];
        quad.push_face(&[0, 1, 2, 3]);
        let info = MeshInfo::of(&quad).unwrap();
        assert_eq!(
            (info.vertices, info.polygons, info.faces, info.edges),
            (4, 1, 2, 5)
        );
        assert_eq!(
            (info.boundary_loops, info.components, info.genus),
            (1, 1, Some(0))
        );
        assert!(info.manifold && info.pm_base.is_none());
        assert_eq!(info.repairs.triangulated_polygons, 1);
    }
}
