//! Loop subdivision (Loop 1987) with the usual boundary rules (Hoppe et al. 1994): the
//! baseline the cascadic MCM scheme is compared against.
//!
//! - New edge vertex, interior edge `ab` with opposite vertices `c, d`:
//!   `3/8 (a + b) + 1/8 (c + d)`; boundary edge: the midpoint.
//! - Old interior vertex of valence `n`: `(1 − nβ) v + β Σ neighbours`, with Loop's
//!   `β = (5/8 − (3/8 + 1/4 cos(2π/n))²) / n`; old boundary vertex with boundary neighbours
//!   `b0, b1`: `3/4 v + 1/8 (b0 + b1)` (the cubic B-spline rule along the boundary curve).
//! - Isolated vertices stay where they are.

use super::SubdivError;
use super::refine::{build_quadrisection, quad_topology};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;

/// Loop's weight β for an interior vertex of valence `n`.
pub fn loop_beta(n: usize) -> f64 {
    let n = n as f64;
    let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n).cos();
    (0.625 - c * c) / n
}

/// One level of Loop subdivision. The output's first vertices are the input's (slot order),
/// then one vertex per edge in [`Mesh::edges`] order — the same layout as
/// [`quadrisect`](super::refine::quadrisect).
pub fn loop_step(mesh: &Mesh) -> Result<Mesh, SubdivError> {
    let topo = quad_topology(mesh);
    let mut positions = Vec::with_capacity(topo.parents.len());
    for &v in &topo.coarse {
        let p = mesh.position(v);
        let new = match mesh.vertex_halfedge(v) {
            None => p,
            Some(out) if mesh.is_boundary_halfedge(out) => {
                // The stored out-edge of a boundary vertex runs along the boundary; the
                // boundary edge arriving at v is its predecessor in the boundary loop.
                let b1 = mesh.position(mesh.to_vertex(out));
                let b0 = mesh.position(mesh.from_vertex(mesh.prev(out)));
                0.75 * p + 0.125 * (b0 + b1)
            }
            Some(_) => {
                let (sum, n) = mesh.outgoing(v).fold((DVec3::ZERO, 0usize), |(s, n), h| {
                    (s + mesh.position(mesh.to_vertex(h)), n + 1)
                });
                let beta = loop_beta(n);
                (1.0 - n as f64 * beta) * p + beta * sum
            }
        };
        positions.push(new);
    }
    for &h in &topo.edges {
        let a = mesh.position(mesh.from_vertex(h));
        let b = mesh.position(mesh.to_vertex(h));
        let t = mesh.twin(h);
        let p = if mesh.is_boundary_halfedge(h) || mesh.is_boundary_halfedge(t) {
            0.5 * (a + b)
        } else {
            let c = mesh.position(mesh.to_vertex(mesh.next(h)));
            let d = mesh.position(mesh.to_vertex(mesh.next(t)));
            0.375 * (a + b) + 0.125 * (c + d)
        };
        positions.push(p);
    }
    build_quadrisection(mesh, &topo, &positions)
}

/// `levels` levels of Loop subdivision (the input is compacted first).
pub fn subdivide_loop(
    mesh: &Mesh,
    levels: usize,
    progress: &dyn Progress,
) -> Result<Mesh, SubdivError> {
    let mut current = super::compact(mesh)?;
    let total: f64 = (1..=levels).map(|l| 4f64.powi(l as i32)).sum();
    let mut done = 0.0;
    for level in 1..=levels {
        current = loop_step(&current).map_err(|e| match e {
            SubdivError::NotManifold { .. } => SubdivError::NotManifold { level },
            e => e,
        })?;
        done += 4f64.powi(level as i32);
        progress.update(done / total);
    }
    Ok(current)
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
