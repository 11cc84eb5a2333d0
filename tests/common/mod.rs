//! Shared helpers for the subdivision tests: loading the bundled control meshes and small
//! meshes built in code.
#![allow(dead_code)]

use glam::DVec3;
use meshpyr::mesh::Mesh;

/// Reads `tests/data/<name>.ply` into a half-edge mesh.
pub fn load(name: &str) -> Mesh {
    let path = format!("{}/tests/data/{name}.ply", env!("CARGO_MANIFEST_DIR"));
    let poly = meshpyr::io::read_mesh(std::path::Path::new(&path)).expect("readable test mesh");
    Mesh::from_polygons(&poly).expect("valid mesh").mesh
}

/// The six coarse control meshes with extraordinary vertices.
pub const CONTROL_MESHES: [&str; 6] = [
    "cone20",
    "sphere_highval",
    "tripod",
    "cross",
    "torus_quad",
    "mushroom_quad",
];

/// The octahedron stretched along z used by `reference/cascadic_mcm.py`.
pub fn stretched_octahedron() -> Mesh {
    let p = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.6],
        [0.0, 0.0, -1.6],
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

/// A planar n×n grid of unit squares split into triangles (an open disk), in the z = 0 plane.
pub fn grid(n: usize) -> Mesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push(DVec3::new(i as f64, j as f64, 0.0));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh::from_triangles(&p, &t).unwrap().mesh
}

/// Bounding-box extent (max − min per axis).
pub fn extent(mesh: &Mesh) -> DVec3 {
    let b = mesh.bounding_box().unwrap();
    b.max - b.min
}

/// Signed enclosed volume (divergence theorem; meaningful for closed meshes).
pub fn volume(mesh: &Mesh) -> f64 {
    mesh.faces()
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}
