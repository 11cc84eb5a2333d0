//! Test meshes shared by the smoothers' unit tests.

use crate::mesh::Mesh;
use glam::DVec3;

/// An n×n grid of the unit square at height z (open, with a boundary).
pub fn grid(n: usize, z: f64) -> Mesh {
    let (p, t) = crate::mesh::shapes::grid(n, |i, j| {
        DVec3::new(i as f64 / n as f64, j as f64 / n as f64, z)
    });
    Mesh::from_triangles(&p, &t).expect("grid").mesh
}

/// The unit icosphere: an icosahedron, `levels` times split 1-to-4 with new vertices pushed
/// onto the sphere.
pub fn icosphere(levels: usize) -> Mesh {
    let (p, f) = crate::mesh::shapes::icosphere(levels);
    Mesh::from_triangles(&p, &f).expect("icosphere").mesh
}

/// `mesh` with every vertex moved by a pseudo-random vector of length up to `amplitude`.
pub fn noisy(mesh: &Mesh, amplitude: f64, seed: u64) -> Mesh {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut out = mesh.clone();
    for v in mesh.vertices() {
        let d = DVec3::new(next(), next(), next()) * (amplitude / 3f64.sqrt());
        out.set_position(v, mesh.position(v) + d);
    }
    out
}

/// Mean and standard deviation of the distance to the origin.
pub(crate) fn radial_stats(x: &[DVec3]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().map(|p| p.length()).sum::<f64>() / n;
    let var = x.iter().map(|p| (p.length() - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}
