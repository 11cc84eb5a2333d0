//! What a mesh must hold before anything can work on it: something at all, and for the surface
//! operations (pyramids, simplification, subdivision, smoothing) a triangle.
//!
//! A file that is not a mesh (a text file named `.obj`) reads as an empty mesh, and a point
//! cloud reads as vertices without faces; both are valid [`PolygonMesh`]es, so the readers
//! accept them and the operations that need more say so here, before they run.

use super::PolygonMesh;
use crate::wording::Count;

/// Why a mesh cannot be worked on.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MissingSurface {
    /// No vertices and no faces (an empty file, or a file that holds no mesh data).
    #[error("no mesh in it: no vertices and no faces")]
    Empty,
    /// Vertices but no faces: a point cloud.
    #[error(
        "{} and no faces (a point cloud), but a surface is needed",
        Count(*vertices, "vertex", "vertices")
    )]
    PointCloud {
        /// Number of vertices.
        vertices: usize,
    },
    /// Faces, but every one repeats a vertex, so no triangle survives the builder's repair.
    #[error(
        "{}, each repeating a vertex, so no triangle: a surface is needed",
        Count(*faces, "face", "faces")
    )]
    NoTriangle {
        /// Number of faces.
        faces: usize,
    },
}

impl PolygonMesh {
    /// Fails when the mesh holds nothing at all (no vertices and no faces). A point cloud
    /// passes: it is something to inspect or convert.
    pub fn check_not_empty(&self) -> Result<(), MissingSurface> {
        if self.positions.is_empty() && self.n_faces() == 0 {
            return Err(MissingSurface::Empty);
        }
        Ok(())
    }

    /// Fails unless at least one face has three distinct vertices, the least the surface
    /// operations ([`crate::Pyramid`], [`crate::simplify()`], subdivision, smoothing) need.
    pub fn check_surface(&self) -> Result<(), MissingSurface> {
        self.check_not_empty()?;
        if self.n_faces() == 0 {
            return Err(MissingSurface::PointCloud {
                vertices: self.n_vertices(),
            });
        }
        if !self.faces().any(has_three_distinct) {
            return Err(MissingSurface::NoTriangle {
                faces: self.n_faces(),
            });
        }
        Ok(())
    }
}

/// True when a fan triangle of `face` keeps three distinct corners (the builder drops the
/// triangles that repeat a vertex).
fn has_three_distinct(face: &[u32]) -> bool {
    let Some((&first, rest)) = face.split_first() else {
        return false;
    };
    rest.windows(2)
        .any(|w| w[0] != first && w[1] != first && w[0] != w[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn an_empty_mesh_is_neither_something_nor_a_surface() {
        let m = PolygonMesh::new();
        assert_eq!(m.check_not_empty(), Err(MissingSurface::Empty));
        assert_eq!(m.check_surface(), Err(MissingSurface::Empty));
    }

    #[test]
    fn a_point_cloud_is_something_but_not_a_surface() {
        let m = PolygonMesh::from_triangles(vec![DVec3::ZERO, DVec3::X], &[]);
        assert_eq!(m.check_not_empty(), Ok(()));
        assert_eq!(
            m.check_surface(),
            Err(MissingSurface::PointCloud { vertices: 2 })
        );
    }

    #[test]
    fn faces_that_all_repeat_a_vertex_are_not_a_surface() {
        let mut m = PolygonMesh::from_triangles(vec![DVec3::ZERO, DVec3::X], &[[0, 1, 1]]);
        m.push_face(&[0, 0, 1, 1]);
        assert_eq!(
            m.check_surface(),
            Err(MissingSurface::NoTriangle { faces: 2 })
        );
    }

    #[test]
    fn one_proper_polygon_makes_a_surface() {
        let mut m = PolygonMesh::from_triangles(vec![DVec3::ZERO, DVec3::X, DVec3::Y], &[]);
        m.push_face(&[0, 0, 1, 2]);
        assert_eq!(m.check_surface(), Ok(()));
    }
}
