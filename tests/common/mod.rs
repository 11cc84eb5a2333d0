//! Helpers shared by the integration tests: test data paths, io round trips, and small meshes
//! built in code. The command line's tests (`cli/tests/common`) include this file too.
#![allow(dead_code)]

use std::path::PathBuf;

use glam::DVec3;
use meshpyr::io::{MeshFormat, PlyEncoding, WriteOptions};
use meshpyr::mesh::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, Mesh, PolygonMesh,
    ScalarType,
};

/// Runs `f` on a rayon pool of `threads` threads (for tests that results do not depend on the
/// thread count).
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
        .install(f)
}

/// The library's folder, which holds `tests/data` and `fuzz`, seen from the crate being tested
/// (the library, or the command line in `cli/`).
pub fn library_dir() -> PathBuf {
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if env!("CARGO_PKG_NAME") == "meshpyr" {
        crate_dir
    } else {
        crate_dir.join("..")
    }
}

/// Path of a file in `tests/data`.
pub fn data(name: &str) -> PathBuf {
    library_dir().join("tests/data").join(name)
}

/// A fresh-per-process scratch file `name` in a temporary folder named after `test`.
pub fn scratch(test: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshpyr-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Bytes of a file in `tests/data`.
pub fn data_bytes(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

/// Options for a PLY encoding.
pub fn ply(enc: PlyEncoding) -> WriteOptions {
    WriteOptions {
        ply_encoding: enc,
        ..Default::default()
    }
}

/// All PLY encodings.
pub const ENCODINGS: [PlyEncoding; 3] = [
    PlyEncoding::Ascii,
    PlyEncoding::BinaryLittleEndian,
    PlyEncoding::BinaryBigEndian,
];

/// Positions compared bit for bit.
pub fn position_bits(m: &PolygonMesh) -> Vec<[u64; 3]> {
    m.positions
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

/// write → read → write: asserts the two writes are byte-identical; returns the re-read mesh.
pub fn trip(m: &PolygonMesh, format: MeshFormat, opts: &WriteOptions) -> PolygonMesh {
    let a = meshpyr::io::write_mesh_bytes(m, format, opts).unwrap();
    let r = meshpyr::io::read_mesh_bytes(&a, format)
        .unwrap_or_else(|e| panic!("re-read failed: {e}\n{}", String::from_utf8_lossy(&a)));
    let b = meshpyr::io::write_mesh_bytes(&r, format, opts).unwrap();
    assert!(a == b, "write → read → write differs for {format} {opts:?}");
    r
}

/// A small mesh exercising everything PLY can hold: f32 positions with awkward values, mixed
/// polygons, an unreferenced vertex, typed vertex and face attributes, an extra element with a
/// scalar and a list property, and comments.
pub fn rich_mesh() -> PolygonMesh {
    let mut m = PolygonMesh::new();
    m.positions = vec![
        DVec3::new(0.1f32 as f64, -0.0, 1e-30f32 as f64),
        DVec3::new(3.4e38f32 as f64, 1.0, 2.0),
        DVec3::new(-1.5, 1.17e-38f32 as f64, 123456.79f32 as f64),
        DVec3::new(7.0, 8.0, 9.0), // unreferenced
        DVec3::new(0.3f32 as f64, 0.7f32 as f64, -2.25),
    ];
    m.position_type = Some(ScalarType::F32);
    m.push_face(&[0, 1, 2]);
    m.push_face(&[4, 2, 1, 0]);
    m.push_face(&[0, 4, 1, 2, 0]);
    m.vertex_attributes = vec![
        Attribute {
            name: "red".into(),
            data: AttributeData::U8(vec![255, 0, 7, 1, 128]),
        },
        Attribute {
            name: "quality".into(),
            data: AttributeData::F32(vec![0.5, -1e-7, 3.0, f32::MAX, 0.1]),
        },
        Attribute {
            name: "id".into(),
            data: AttributeData::I32(vec![-1, i32::MIN, i32::MAX, 0, 42]),
        },
        Attribute {
            name: "w64".into(),
            data: AttributeData::F64(vec![0.1, 1e300, -5e-324, 2.0, 0.0]),
        },
    ];
    m.face_attributes = vec![
        Attribute {
            name: "flags".into(),
            data: AttributeData::U32(vec![0, u32::MAX, 5]),
        },
        Attribute {
            name: "s".into(),
            data: AttributeData::I16(vec![-3, 300, i16::MIN]),
        },
        Attribute {
            name: "c".into(),
            data: AttributeData::I8(vec![-128, 0, 127]),
        },
        Attribute {
            name: "us".into(),
            data: AttributeData::U16(vec![65535, 1, 2]),
        },
    ];
    m.extra_elements = vec![
        ExtraElement {
            name: "edge".into(),
            rows: 2,
            properties: vec![
                ElementProperty::Scalar(Attribute {
                    name: "vertex1".into(),
                    data: AttributeData::I32(vec![0, 1]),
                }),
                ElementProperty::List(ListProperty {
                    name: "weights".into(),
                    count_type: ScalarType::U8,
                    item_type: ScalarType::F32,
                    starts: vec![0, 2, 2],
                    items: vec![0.5, 0.1f32 as f64],
                }),
            ],
        },
        ExtraElement {
            name: "material".into(),
            rows: 1,
            properties: vec![ElementProperty::List(ListProperty {
                name: "ids".into(),
                count_type: ScalarType::I32,
                item_type: ScalarType::I16,
                starts: vec![0, 3],
                items: vec![-1.0, 2.0, 300.0],
            })],
        },
    ];
    m.comments = vec!["made by a test".into(), "".into(), "  indented".into()];
    m
}

/// Reads `tests/data/<name>.ply` into a half-edge mesh.
pub fn load(name: &str) -> meshpyr::mesh::Mesh {
    let poly = meshpyr::io::read_mesh(data(&format!("{name}.ply")))
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    meshpyr::mesh::Mesh::from_polygons(&poly)
        .expect("valid mesh")
        .mesh
}

/// `mesh` with its coordinates snapped to multiples of 2^-20 and then moved by `offset` along
/// every axis, both exactly for offsets up to 2^20 or so: the same scan near and far from the
/// origin, which only the arithmetic can tell apart.
pub fn snapped_and_moved(mesh: &Mesh, offset: f64) -> Mesh {
    let snap = |x: f64| (x * f64::from(1u32 << 20)).round() / f64::from(1u32 << 20);
    let mut m = mesh.clone();
    let vertices: Vec<_> = m.vertices().collect();
    for v in vertices {
        let p = m.position(v);
        m.set_position(v, DVec3::new(snap(p.x), snap(p.y), snap(p.z)) + offset);
    }
    m
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

/// The octahedron stretched along z used by `docs/reference/cascadic_mcm.py`.
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
    let (p, t) = meshpyr::mesh::shapes::grid(n, |i, j| DVec3::new(i as f64, j as f64, 0.0));
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

/// Calls `run` on every file of `fuzz/corpus/<target>` and `fuzz/regressions/<target>`, in
/// name order, and returns how many there were.
pub fn replay_fuzz_corpus(target: &str, run: impl Fn(&[u8])) -> usize {
    let root = library_dir().join("fuzz");
    let mut n = 0;
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) else {
            continue;
        };
        let mut files: Vec<_> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        files.sort();
        for f in files {
            run(&std::fs::read(&f).unwrap());
            n += 1;
        }
    }
    n
}

/// `n` fixed pseudo-random byte strings of `len` bytes (a multiplicative hash of the index),
/// for running fuzz harnesses without a corpus.
pub fn byte_patterns(n: u32, len: u32) -> impl Iterator<Item = Vec<u8>> {
    (0..n).map(move |seed| {
        (0..len)
            .map(|i| (i.wrapping_mul(2654435761).wrapping_add(seed * 97) >> 7) as u8)
            .collect()
    })
}

/// How far unit gains may land from the analysed signal: `√3/2` of the pyramid's detail step
/// (details are quantised in a closed loop, docs/algorithms.md §1f), plus rounding.
pub fn closed_loop_bound(p: &meshpyr::pyramid::DetailPyramid) -> f64 {
    0.5 * 3f64.sqrt() * p.detail_step() + 1e-12 * p.bbox_diagonal()
}

/// A Möbius band of `2n` vertices: a strip of `n` quads (two triangles each) whose ends are
/// glued with a half twist, so that no orientation of its triangles agrees along every edge
/// (the builder cuts the edge its walk meets first).
pub fn mobius_band(n: u32) -> PolygonMesh {
    let positions = (0..2 * n)
        .map(|i| {
            let (k, side) = ((i % n) as f64, (i / n) as f64 - 0.5);
            let a = k / n as f64 * std::f64::consts::TAU;
            let r = 3.0 + side * (a / 2.0).cos();
            DVec3::new(r * a.cos(), r * a.sin(), side * (a / 2.0).sin())
        })
        .collect();
    let mut band = PolygonMesh::from_triangles(positions, &[]);
    for k in 0..n {
        let (a, b) = (k, n + k);
        let (c, d) = if k + 1 == n {
            (n, 0)
        } else {
            (k + 1, n + k + 1)
        };
        band.push_face(&[a, c, d]);
        band.push_face(&[a, d, b]);
    }
    band
}
