//! Mesh refinement for subdivision: 1-to-4 quadrisection and conforming newest-vertex
//! bisection. Each step returns a new [`Mesh`] whose first vertices are the coarse vertices
//! (dense order) and a [`Prolongation`] saying which coarse vertices every new vertex
//! interpolates (trivial interpolation: copies and edge midpoints).
//!
//! [`bisect`] expects a mesh with dense slots (fresh from the builder, as
//! [`subdivide`](super::subdivide) guarantees); [`quadrisect`] numbers any mesh's elements by
//! slot order. Both outputs are dense. Inside [`subdivide`](super::subdivide), quadrisection
//! levels work on flat half-edge arrays (`quadrisect_connectivity`) and never build a
//! [`Mesh`].
//!
//! One scheme per file: `quadrisect` and `bisect`; this module holds what both return.

use super::SubdivError;
use crate::mesh::Mesh;
use glam::DVec3;
use std::ops::{Add, Mul};

mod bisect;
mod quadrisect;

pub(crate) use bisect::{BisectionLevel, bisect_level, initial_marking};
pub use bisect::{Marking, bisect};
pub use quadrisect::quadrisect;
pub(crate) use quadrisect::{
    QuadTopology, quad_topology, quadrisect_connectivity, quadrisection_parts,
    quadrisection_stiffness,
};

/// Trivial interpolation from a coarse to a refined mesh: fine vertex `i` takes
/// `(f[a] + f[b]) / 2` with `[a, b] = parents()[i]` (`a == b` for a copied coarse vertex).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Prolongation {
    parents: Vec<[u32; 2]>,
}

impl Prolongation {
    /// The two coarse parents of every fine vertex (equal for a copy).
    #[cfg(test)]
    pub(crate) fn parents(&self) -> &[[u32; 2]] {
        &self.parents
    }

    /// Number of fine vertices.
    #[cfg(test)]
    pub(crate) fn n_fine(&self) -> usize {
        self.parents.len()
    }

    /// Interpolates coarse values onto the fine vertices.
    pub(crate) fn apply<T>(&self, coarse: &[T]) -> Vec<T>
    where
        T: Copy + Add<Output = T> + Mul<f64, Output = T>,
    {
        self.parents
            .iter()
            .map(|&[a, b]| {
                if a == b {
                    coarse[a as usize]
                } else {
                    (coarse[a as usize] + coarse[b as usize]) * 0.5
                }
            })
            .collect()
    }
}

/// A refined mesh with its prolongation.
#[derive(Clone, Debug)]
pub struct Refined {
    /// The new mesh, vertex positions trivially interpolated from the coarse ones.
    pub mesh: Mesh,
    /// The new mesh's triangles as dense vertex indices, in face slot order.
    pub triangles: Vec<[u32; 3]>,
    /// Coarse-to-fine interpolation.
    pub prolongation: Prolongation,
}

/// Builds the half-edge mesh of a refinement; the triangles are consistently oriented and
/// manifold by construction, so the builder must not repair anything.
pub(crate) fn build(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    level: usize,
) -> Result<Mesh, SubdivError> {
    let built = Mesh::from_triangles(positions, triangles)
        .map_err(|_| SubdivError::NotManifold { level })?;
    if built.report.repaired_anything() || built.mesh.n_vertices() != positions.len() {
        return Err(SubdivError::NotManifold { level });
    }
    Ok(built.mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subdiv::halfedge_arrays::HalfedgeArrays;

    #[test]
    fn quadrisection_stiffness_is_the_general_assembly_bit_for_bit() {
        use crate::numerics::fem::{cotangent_stiffness, triangle_weights};
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        // Closed with a valence-4 vertex (octahedron), open with boundary corners (a jittered
        // grid with a hole and an isolated vertex), checked at every level, with and without
        // face coefficients, on 1 and 3 threads.
        let (mut p, t) = crate::mesh::shapes::grid(6, |i, j| {
            let h = ((i * 7 + j * 13) % 5) as f64 / 10.0;
            DVec3::new(i as f64 + 0.2 * h, j as f64 - 0.1 * h, h)
        });
        p.push(DVec3::new(50.0, 50.0, 50.0)); // an isolated vertex
        let holed: Vec<[u32; 3]> = t
            .into_iter()
            .enumerate()
            .filter(|(i, _)| *i != 31)
            .map(|(_, f)| f)
            .collect();
        let grid = Mesh::from_triangles(&p, &holed).unwrap().mesh;
        // Six octahedron levels reach 16k fine rows, past the size where rows split over
        // threads.
        for (mesh, levels) in [(octahedron(), 6), (grid, 2)] {
            let mut coarse_positions = mesh.positions();
            let mut mesh = HalfedgeArrays::from_mesh(&mesh);
            for _ in 0..levels {
                let (topo, _, positions) = quadrisection_parts(&mesh, &coarse_positions);
                let coef: Vec<f64> = (0..topo.triangles.len())
                    .map(|i| 0.5 + (i % 7) as f64)
                    .collect();
                for c in [None, Some(&coef[..])] {
                    let w = triangle_weights(&topo.triangles, &positions, c);
                    let general = cotangent_stiffness(&topo.triangles, &positions, c);
                    for threads in [1, 3] {
                        let fast = rayon::ThreadPoolBuilder::new()
                            .num_threads(threads)
                            .build()
                            .unwrap()
                            .install(|| quadrisection_stiffness(&mesh, &topo, &w))
                            .expect("covered layout");
                        assert_eq!(fast.row_start, general.row_start);
                        assert_eq!(fast.col, general.col);
                        assert_eq!(bits(&fast.val), bits(&general.val));
                    }
                }
                let fine = quadrisect_connectivity(&mesh, &topo);
                // The arrays are the mesh the general builder makes of the same triangles.
                let built = build(&positions, &topo.triangles, 1).unwrap();
                assert_eq!(
                    built.to_triangles(),
                    fine.to_mesh(&positions).to_triangles()
                );
                assert!(fine.to_mesh(&positions).validate().is_ok());
                (mesh, coarse_positions) = (fine, positions);
            }
        }
    }

    fn octahedron() -> Mesh {
        let p = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ]
        .map(DVec3::from_array);
        let f = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        Mesh::from_triangles(&p, &f).unwrap().mesh
    }

    #[test]
    fn prolongation_copies_and_averages() {
        let p = Prolongation {
            parents: vec![[0, 0], [1, 1], [0, 1]],
        };
        assert_eq!(p.apply(&[2.0, 4.0]), vec![2.0, 4.0, 3.0]);
        assert_eq!(p.n_fine(), 3);
    }

    #[test]
    fn quadrisection_puts_midpoints_and_keeps_coarse_vertices_first() {
        let m = octahedron();
        let r = quadrisect(&m).unwrap();
        assert_eq!(r.mesh.n_faces(), 32);
        assert_eq!(r.mesh.n_vertices(), 6 + 12);
        assert!(r.mesh.validate().is_ok());
        // The direct construction equals the builder's, face by face.
        let (p, t) = r.mesh.to_triangles();
        let built = Mesh::from_triangles(&p, &t).unwrap();
        assert!(!built.report.repaired_anything());
        assert_eq!(built.mesh.to_triangles(), (p, t));
        let pos = r.mesh.positions();
        for (i, &[a, b]) in r.prolongation.parents().iter().enumerate() {
            let expect = (m.positions()[a as usize] + m.positions()[b as usize]) / 2.0;
            assert_eq!(pos[i], expect);
            // Midpoints join coarse neighbours only.
            if a != b {
                assert!(m.neighbors(m.vertices().nth(a as usize).unwrap()).len() == 4);
            }
        }
    }

    #[test]
    fn bisection_marking_is_compatible_and_stays_so() {
        let mut m = octahedron();
        let mut marking = initial_marking(&m).unwrap();
        let mut faces = m.n_faces();
        for _ in 0..4 {
            let (r, next) = bisect(&m, &marking).unwrap();
            assert_eq!(r.mesh.n_faces(), 2 * faces);
            assert_eq!(r.mesh.topology().euler_characteristic, 2);
            faces = r.mesh.n_faces();
            m = r.mesh;
            marking = next;
        }
    }

    #[test]
    fn flat_bisection_levels_are_the_levels_of_the_built_meshes() {
        // Closed (octahedron) and open (a jittered grid with a hole, marked with boundary
        // edges): after each flat level, the neighbours across every face edge are those of
        // the half-edge mesh the builder makes of the same triangles, and the newest vertex is
        // the one the mesh-based step finds.
        let (p, t) = crate::mesh::shapes::grid(4, |i, j| {
            DVec3::new(i as f64 + 0.1 * ((i * j) % 3) as f64, j as f64, 0.0)
        });
        let t: Vec<[u32; 3]> = t
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| i != 12 && i != 13)
            .map(|(_, f)| f)
            .collect();
        let grid = Mesh::from_triangles(&p, &t).unwrap().mesh;
        for mut mesh in [octahedron(), grid] {
            let mut marking = initial_marking(&mesh).unwrap();
            let mut level = BisectionLevel::from_mesh(&mesh, &marking).unwrap();
            for _ in 0..5 {
                let (fine, prolongation) = bisect_level(&level, mesh.n_vertices()).unwrap();
                let (refined, next) = bisect(&mesh, &marking).unwrap();
                assert_eq!(prolongation, refined.prolongation);
                assert_eq!(fine.triangles, refined.triangles);
                let built = BisectionLevel::from_mesh(&refined.mesh, &next).unwrap();
                assert_eq!(fine.triangles, built.triangles);
                assert_eq!(fine.across, built.across);
                assert_eq!(fine.newest, built.newest);
                (mesh, marking, level) = (refined.mesh, next, fine);
            }
        }
    }

    #[test]
    fn incompatible_marking_is_rejected() {
        let m = octahedron();
        let mut marking = initial_marking(&m).unwrap();
        marking.newest[0] = (marking.newest[0] + 1) % 3;
        assert!(matches!(
            bisect(&m, &marking),
            Err(SubdivError::NoCompatibleMarking { .. })
        ));
    }

    #[test]
    fn marking_on_an_open_strip_uses_boundary_edges() {
        // Three triangles in a fan: an odd count, so one must take a boundary edge.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ]
        .map(DVec3::from_array);
        let m = Mesh::from_triangles(&p, &[[0, 1, 2], [0, 2, 3], [0, 3, 4]])
            .unwrap()
            .mesh;
        let marking = initial_marking(&m).unwrap();
        let (r, _) = bisect(&m, &marking).unwrap();
        assert_eq!(r.mesh.n_faces(), 6);
        assert!(r.mesh.validate().is_ok());
        // Direct quadrisection of an open mesh: valid, boundary loop intact, and the same
        // faces the generic builder makes.
        let q = quadrisect(&m).unwrap().mesh;
        assert!(q.validate().is_ok());
        assert_eq!(q.topology().boundary_loops, 1);
        assert_eq!(q.topology().euler_characteristic, 1);
        let (p, t) = q.to_triangles();
        assert_eq!(
            Mesh::from_triangles(&p, &t).unwrap().mesh.to_triangles(),
            (p, t)
        );
        let boundary = q.vertices().filter(|&v| q.is_boundary_vertex(v)).count();
        assert_eq!(boundary, 2 * 5);
    }
}
