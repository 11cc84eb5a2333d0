//! Loop subdivision (Loop 1987) with the usual boundary rules (Hoppe et al. 1994): the
//! baseline the cascadic MCM scheme is compared against.
//!
//! - New edge vertex, interior edge `ab` with opposite vertices `c, d`:
//!   `3/8 (a + b) + 1/8 (c + d)`; boundary edge: the midpoint.
//! - Old interior vertex of valence `n`: `(1 − nβ) v + β Σ neighbours`, with Loop's
//!   `β = (5/8 − (3/8 + 1/4 cos(2π/n))²) / n`; old boundary vertex with boundary neighbours
//!   `b0, b1`: `3/4 v + 1/8 (b0 + b1)` (the cubic B-spline rule along the boundary curve).
//! - Isolated vertices stay where they are.

use super::halfedge_arrays::HalfedgeArrays;
use super::refine::{QuadTopology, quad_topology, quadrisect_connectivity};
use super::{LevelReport, SubdivError, Subdivision};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;

/// Loop's weight β for an interior vertex of valence `n`.
pub(crate) fn loop_beta(n: usize) -> f64 {
    let n = n as f64;
    let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n).cos();
    (0.625 - c * c) / n
}

/// One level of Loop subdivision. The output's first vertices are the input's (slot order),
/// then one vertex per edge in [`Mesh::edges`] order — the same layout as
/// [`quadrisect`](super::refine::quadrisect).
pub fn loop_step(mesh: &Mesh) -> Result<Mesh, SubdivError> {
    let coarse = HalfedgeArrays::from_mesh(mesh);
    let (topo, positions) = loop_level(&coarse, &mesh.positions());
    Ok(quadrisect_connectivity(&coarse, &topo).to_mesh(&positions))
}

/// The quadrisection of `mesh` (vertex positions `positions`) and Loop's positions for its
/// vertices.
fn loop_level(mesh: &HalfedgeArrays, positions: &[DVec3]) -> (QuadTopology, Vec<DVec3>) {
    let (topo, _) = quad_topology(mesh);
    let at = |v: u32| positions[v as usize];
    let mut fine = Vec::with_capacity(topo.n_coarse + topo.edges.len());
    for (v, &p) in (0..).zip(positions) {
        let out = mesh.vertex_halfedge[v as usize];
        let new = if out == super::halfedge_arrays::NONE {
            p
        } else if mesh.is_boundary(out) {
            // The stored out-edge of a boundary vertex runs along the boundary; the boundary
            // edge arriving at v is its predecessor in the boundary loop.
            let b1 = at(mesh.get(out).to);
            let b0 = at(mesh.from(mesh.get(out).prev));
            0.75 * p + 0.125 * (b0 + b1)
        } else {
            let (sum, n) = mesh.outgoing(v).fold((DVec3::ZERO, 0usize), |(s, n), h| {
                (s + at(mesh.get(h).to), n + 1)
            });
            let beta = loop_beta(n);
            (1.0 - n as f64 * beta) * p + beta * sum
        };
        fine.push(new);
    }
    for &h in &topo.edges {
        let e = mesh.get(h);
        let (a, b) = (at(mesh.from(h)), at(e.to));
        let p = if mesh.is_boundary(h) || mesh.is_boundary(e.twin) {
            0.5 * (a + b)
        } else {
            let c = at(mesh.get(e.next).to);
            let d = at(mesh.get(mesh.get(e.twin).next).to);
            0.375 * (a + b) + 0.125 * (c + d)
        };
        fine.push(p);
    }
    (topo, fine)
}

/// `levels` levels of Loop subdivision (the input is compacted first). Each level's report
/// has its counts, 0 steps and a zero residual: the stencils are explicit, nothing is solved.
pub fn subdivide_loop(
    mesh: &Mesh,
    levels: usize,
    progress: &dyn Progress,
) -> Result<Subdivision, SubdivError> {
    let quadrisection = super::SubdivOptions {
        levels,
        refinement: super::Refinement::Quadrisection,
        ..Default::default()
    };
    super::check_output_size(mesh, levels, quadrisection.face_factor(), usize::MAX)?;
    let input = super::compact(mesh)?;
    let (mut positions, mut triangles) = input.to_triangles();
    let mut connectivity = HalfedgeArrays::from_mesh(&input);
    drop(input);
    let total: f64 = (1..=levels).map(|l| 4f64.powi(l as i32)).sum();
    let mut done = 0.0;
    let mut reports = Vec::with_capacity(levels);
    for level in 1..=levels {
        let (topo, fine) = loop_level(&connectivity, &positions);
        // The last level's half-edges are never read: the output is its triangles.
        if level < levels {
            connectivity = quadrisect_connectivity(&connectivity, &topo);
        }
        positions = fine;
        triangles = topo.triangles;
        reports.push(LevelReport {
            level,
            vertices: positions.len(),
            faces: triangles.len(),
            steps: 0,
            relative_residual: 0.0,
        });
        done += 4f64.powi(level as i32);
        progress.update(done / total);
    }
    Ok(Subdivision {
        positions,
        triangles,
        levels: reports,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::SlotIndex;

    #[test]
    fn beta_matches_the_regular_stencil() {
        assert!((loop_beta(6) - 1.0 / 16.0).abs() < 1e-15);
        assert!((loop_beta(3) - 3.0 / 16.0).abs() < 1e-15);
    }

    #[test]
    fn planar_grid_stays_planar_and_interior_linear_functions_are_reproduced() {
        let n = 4;
        let (p, t) = crate::mesh::shapes::grid(n, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let m = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let fine = loop_step(&m).unwrap();
        assert_eq!(fine.n_faces(), 4 * m.n_faces());
        for v in fine.vertices() {
            assert_eq!(fine.position(v).z, 0.0);
        }
        // The centre vertex (regular, valence 6) stays put: Loop reproduces linear data on a
        // regular grid and the grid coordinates are linear.
        let c = id(2, 2) as usize;
        let v = fine.vertices().find(|v| v.slot() == c).unwrap();
        assert!((fine.position(v) - p[c]).length() < 1e-12);
        // Boundary corners move along the boundary rule (3/4 v + 1/8 neighbours).
        let corner = fine.vertices().next().unwrap();
        let q = fine.position(corner);
        assert!(q.x > 0.0 && q.y > 0.0 && q.x < 0.3);
    }
}
