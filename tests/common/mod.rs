//! Shared helpers for the subdivision tests: a reader for the bundled test meshes (binary
//! little-endian PLY with float x/y/z and `list uchar int` faces — exactly their layout) and
//! small meshes built in code.
#![allow(dead_code)]

use glam::DVec3;
use meshpyr::mesh::Mesh;

/// Reads `tests/data/<name>.ply` into a half-edge mesh.
pub fn load(name: &str) -> Mesh {
    let path = format!("{}/tests/data/{name}.ply", env!("CARGO_MANIFEST_DIR"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let end = b"end_header\n";
    let at = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("header end")
        + end.len();
    let header = std::str::from_utf8(&bytes[..at]).expect("ascii header");
    assert!(header.contains("binary_little_endian"));
    let count = |el: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {el} ")))
            .and_then(|n| n.trim().parse().ok())
            .expect("element count")
    };
    let (nv, nf) = (count("vertex"), count("face"));
    let mut pos = at;
    let f32_at = |p: usize| f32::from_le_bytes(bytes[p..p + 4].try_into().unwrap()) as f64;
    let mut positions = Vec::with_capacity(nv);
    for _ in 0..nv {
        positions.push(DVec3::new(f32_at(pos), f32_at(pos + 4), f32_at(pos + 8)));
        pos += 12;
    }
    let mut tris = Vec::with_capacity(nf);
    for _ in 0..nf {
        let k = bytes[pos] as usize;
        pos += 1;
        let idx: Vec<u32> = (0..k)
            .map(|i| i32::from_le_bytes(bytes[pos + 4 * i..pos + 4 * i + 4].try_into().unwrap()) as u32)
            .collect();
        pos += 4 * k;
        for i in 1..k - 1 {
            tris.push([idx[0], idx[i], idx[i + 1]]);
        }
    }
    let built = Mesh::from_triangles(&positions, &tris).expect("valid mesh");
    built.mesh
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
