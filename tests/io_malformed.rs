//! Malformed input: never a panic, always a one-line error naming the place, bounded memory.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use common::*;
use glam::DVec3;
use meshpyr::fuzzing::fuzz_read;
use meshpyr::io::{
    IoError, Location, MeshFormat, PlyEncoding, WriteOptions, read_mesh, read_mesh_bytes,
    write_mesh_bytes,
};
use meshpyr::mesh::PolygonMesh;

/// Counts the bytes each thread asks the allocator for, so a test can check that a parser rejects
/// an absurd header count *before* allocating for it (other tests run on other threads and do
/// not disturb the count).
struct CountingAllocator;

thread_local! {
    static ALLOCATED: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards every call to `System`; the counter is a const-initialised thread local, so
// touching it never allocates (no re-entry).
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATED.try_with(|a| a.set(a.get() + layout.size()));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATED.try_with(|a| a.set(a.get() + new_size));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn bytes_allocated_by_this_thread() -> usize {
    ALLOCATED.with(Cell::get)
}

fn err(bytes: &[u8], f: MeshFormat) -> IoError {
    match read_mesh_bytes(bytes, f) {
        Ok(m) => panic!(
            "expected an error, got a mesh with {} vertices",
            m.n_vertices()
        ),
        Err(e) => {
            let s = e.to_string();
            assert!(!s.contains('\n'), "multi-line error: {s}");
            e
        }
    }
}

fn assert_err(bytes: &[u8], f: MeshFormat, loc: Location, contains: &str) {
    let e = err(bytes, f);
    assert_eq!(e.location(), Some(loc), "{e}");
    assert!(
        e.to_string().contains(contains),
        "{e:?} does not mention {contains:?}"
    );
}

/// Every prefix of `bytes` gives an error or a valid mesh, never a panic.
fn every_prefix(bytes: &[u8], f: MeshFormat) {
    let mut ok = 0;
    for n in 0..bytes.len() {
        match read_mesh_bytes(&bytes[..n], f) {
            Ok(m) => {
                m.check().unwrap();
                ok += 1;
            }
            Err(e) => assert!(!e.to_string().contains('\n')),
        }
        fuzz_read(f, &bytes[..n]);
    }
    // Full file must read.
    read_mesh_bytes(bytes, f).unwrap();
    assert!(ok < bytes.len(), "truncation is never detected for {f}");
}

#[test]
fn truncated_at_every_byte() {
    let tet = read_mesh(data("tetrahedron.ply")).unwrap();
    every_prefix(&data_bytes("tetrahedron.ply"), MeshFormat::Ply);
    for enc in ENCODINGS {
        let b = write_mesh_bytes(&rich_mesh(), MeshFormat::Ply, &ply(enc)).unwrap();
        every_prefix(&b, MeshFormat::Ply);
    }
    every_prefix(&data_bytes("cube_quad.off"), MeshFormat::Off);
    every_prefix(&data_bytes("cube_degenerate_om.obj"), MeshFormat::Obj);
    every_prefix(&data_bytes("back_to_back_scad.stl"), MeshFormat::Stl);
    let stl = write_mesh_bytes(&tet, MeshFormat::Stl, &WriteOptions::default()).unwrap();
    every_prefix(&stl, MeshFormat::Stl);
    // Binary PLY truncated inside the body reports a byte offset.
    let b = data_bytes("tetrahedron.ply");
    let e = err(&b[..b.len() - 3], MeshFormat::Ply);
    assert!(matches!(e.location(), Some(Location::Byte(_))), "{e}");
}

#[test]
fn absurd_counts_fail_fast_without_allocating() {
    let before = bytes_allocated_by_this_thread();
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
        property float x\nproperty float y\nproperty float z\nend_header\n"
        .to_vec();
    b.resize(150, 0); // the smallest such binary header is 125 bytes
    let body = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    assert_err(
        &b,
        MeshFormat::Ply,
        Location::Byte(body as u64),
        "4000000000",
    );
    // Counts beyond u32 and beyond usize are errors too.
    let huge = String::from_utf8(b.clone())
        .unwrap()
        .replace("4000000000", "18446744073709551615");
    err(huge.as_bytes(), MeshFormat::Ply);
    // ASCII as well.
    let a = b"ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n\
        property float y\nproperty float z\nend_header\n0 0 0\n";
    assert_err(a, MeshFormat::Ply, Location::Line(3), "4000000000 rows");
    // Face count and a single absurd list length.
    let f = b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n\
        property float y\nproperty float z\nelement face 1\n\
        property list int int vertex_indices\nend_header\n\xff\xff\xff\x7f";
    let e = err(f, MeshFormat::Ply);
    assert!(e.to_string().contains("2147483647 indices"), "{e}");
    // Extra element with a huge list.
    let x = b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
        property float z\nelement stuff 1\nproperty list uint float v\nend_header\n4000000000 1 2\n";
    assert_err(x, MeshFormat::Ply, Location::Line(10), "4000000000 items");
    // OFF and STL.
    assert_err(
        b"OFF\n4000000000 4000000000 0\n0 0 0\n",
        MeshFormat::Off,
        Location::Line(2),
        "4000000000 vertices",
    );
    let mut s = vec![b' '; 80];
    s.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    s.extend_from_slice(&[0; 50]);
    assert_err(
        &s,
        MeshFormat::Stl,
        Location::Byte(80),
        "4000000000 triangles",
    );
    // Every header above claims gigabytes; all of them together may allocate only the small
    // buffers of error messages and header parsing.
    let allocated = bytes_allocated_by_this_thread() - before;
    assert!(allocated < 1 << 20, "{allocated} bytes allocated");
}

#[test]
fn non_finite_coordinates_are_rejected_with_the_vertex() {
    let ply_ascii = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
        property float y\nproperty float z\nend_header\n0 0 0\n1 nan 0\n";
    assert_err(
        ply_ascii,
        MeshFormat::Ply,
        Location::Line(9),
        "vertex 1 has a non-finite",
    );
    let inf = String::from_utf8_lossy(ply_ascii).replace("nan", "-inf");
    assert_err(
        inf.as_bytes(),
        MeshFormat::Ply,
        Location::Line(9),
        "vertex 1",
    );

    let mut m = read_mesh(data("tetrahedron.ply")).unwrap();
    let mut b = write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap();
    let body = b.len() - (4 * 12 + 4 * 13);
    b[body + 12 * 2 + 4..body + 12 * 2 + 8].copy_from_slice(&f32::INFINITY.to_le_bytes());
    assert_err(
        &b,
        MeshFormat::Ply,
        Location::Byte((body + 28) as u64),
        "vertex 2",
    );

    assert_err(
        b"v 0 0 0\nv 1 inf 0\n",
        MeshFormat::Obj,
        Location::Line(2),
        "vertex 2",
    );
    assert_err(
        b"OFF\n1 0 0\n0 NaN 0\n",
        MeshFormat::Off,
        Location::Line(3),
        "vertex 0 has a non-finite",
    );
    let stl = b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
        vertex 0 nan 0\nendloop\nendfacet\nendsolid\n";
    assert_err(stl, MeshFormat::Stl, Location::Line(6), "facet 0");
    let mut bs = write_mesh_bytes(&m, MeshFormat::Stl, &Default::default()).unwrap();
    bs[84 + 50 + 16..84 + 50 + 20].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_err(
        &bs,
        MeshFormat::Stl,
        Location::Byte(84 + 50 + 16),
        "triangle 1",
    );

    // Writers refuse non-finite positions too.
    m.positions[0] = DVec3::new(f64::NAN, 0.0, 0.0);
    for f in [
        MeshFormat::Ply,
        MeshFormat::Obj,
        MeshFormat::Off,
        MeshFormat::Stl,
    ] {
        let e = write_mesh_bytes(&m, f, &Default::default()).unwrap_err();
        assert!(e.to_string().contains("vertex 0"), "{e}");
    }
}

#[test]
fn bad_indices_are_rejected_with_their_place() {
    // Binary PLY: index 40000 in a 4-vertex file, at its byte offset.
    let m = read_mesh(data("tetrahedron.ply")).unwrap();
    let mut b = write_mesh_bytes(&m, MeshFormat::Ply, &Default::default()).unwrap();
    let faces = b.len() - 4 * 13;
    let at = faces + 13 + 1 + 4; // face 1, second index
    b[at..at + 4].copy_from_slice(&40000i32.to_le_bytes());
    assert_err(
        &b,
        MeshFormat::Ply,
        Location::Byte(at as u64),
        "face 1 has index 40000 but the file has 4 vertices",
    );
    b[at..at + 4].copy_from_slice(&(-1i32).to_le_bytes());
    assert_err(
        &b,
        MeshFormat::Ply,
        Location::Byte(at as u64),
        "face 1 has negative index -1",
    );
    // Same via the generic (big-endian) path.
    let mut be = write_mesh_bytes(&m, MeshFormat::Ply, &ply(PlyEncoding::BinaryBigEndian)).unwrap();
    let at = be.len() - 4 * 13 + 13 + 1 + 4;
    be[at..at + 4].copy_from_slice(&4i32.to_be_bytes());
    assert_err(
        &be,
        MeshFormat::Ply,
        Location::Byte(at as u64),
        "index 4 but the file has 4",
    );
    let a = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n";
    assert_err(a, MeshFormat::Ply, Location::Line(13), "negative index -2");

    assert_err(
        b"v 0 0 0\nv 1 0 0\nf 1 2 3\n",
        MeshFormat::Obj,
        Location::Line(3),
        "index 3",
    );
    assert_err(
        b"v 0 0 0\nf 1 -2 1\n",
        MeshFormat::Obj,
        Location::Line(2),
        "relative vertex index -2",
    );
    assert_err(
        b"v 0 0 0\nf 0 1 1\n",
        MeshFormat::Obj,
        Location::Line(2),
        "index 0",
    );
    assert_err(
        b"v 0 0 0\nf 1/2 1/1 1/1\nvt 0 0\n",
        MeshFormat::Obj,
        Location::Line(2),
        "texture",
    );
    assert_err(
        b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
        MeshFormat::Off,
        Location::Line(6),
        "face 0 has index 3 but the file has 3 vertices",
    );
    assert_err(
        b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
        MeshFormat::Off,
        Location::Line(6),
        "negative index -1",
    );
    assert_err(
        b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n5 0 1 2\n",
        MeshFormat::Off,
        Location::Line(6),
        "claims 5 vertices",
    );

    // Writers reject out-of-range indices before producing anything.
    let mut bad = PolygonMesh::from_triangles(vec![DVec3::ZERO; 3], &[[0, 1, 2]]);
    bad.face_indices[2] = 3;
    for f in [
        MeshFormat::Ply,
        MeshFormat::Obj,
        MeshFormat::Off,
        MeshFormat::Stl,
    ] {
        let e = write_mesh_bytes(&bad, f, &Default::default()).unwrap_err();
        assert!(e.to_string().contains("out of range"), "{e}");
    }
}

#[test]
fn header_errors_name_the_line() {
    assert_err(
        b"plx\n",
        MeshFormat::Ply,
        Location::Line(1),
        "not a PLY file",
    );
    assert_err(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n",
        MeshFormat::Ply,
        Location::Line(4),
        "unknown type",
    );
    assert_err(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        MeshFormat::Ply,
        Location::Line(5),
        "end_header",
    );
    assert_err(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
        property list uchar float z\nend_header\n",
        MeshFormat::Ply,
        Location::Line(3),
        "not supported",
    );
    assert_err(
        b"COFF 1 0 0\n1 2 3\n",
        MeshFormat::Off,
        Location::Line(2),
        "vertex 0 has 3 values",
    );
    assert_err(
        b"4OFF\n",
        MeshFormat::Off,
        Location::Line(1),
        "not supported",
    );
    assert_err(
        b"hello\n",
        MeshFormat::Off,
        Location::Line(1),
        "not an OFF file",
    );
    assert_err(
        b"v 1 2\n",
        MeshFormat::Obj,
        Location::Line(1),
        "found 2 values",
    );
    assert_err(
        b"\x01\x02 1 2\n",
        MeshFormat::Obj,
        Location::Line(1),
        "unknown statement",
    );
    assert_err(
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n",
        MeshFormat::Stl,
        Location::Line(5),
        "expected `vertex`",
    );
    assert_err(b"", MeshFormat::Stl, Location::None, "not an STL file");
}

#[test]
fn error_display_names_file_line_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.off");
    std::fs::write(&p, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
    let e = read_mesh(&p).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}: line 6: face 0 has index 7 but the file has 3 vertices",
            p.display()
        )
    );
    let e = read_mesh(dir.path().join("missing.ply")).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
    assert!(e.to_string().contains("missing.ply"));
    let e = read_mesh(std::path::Path::new("mesh.xyz")).unwrap_err();
    assert!(matches!(e, IoError::UnknownFormat { .. }));
    assert_eq!(
        e.to_string(),
        "mesh.xyz: unknown mesh format (expected .obj, .ply, .off or .stl, optionally .gz)"
    );
    assert!(MeshFormat::from_path(std::path::Path::new("noext")).is_err());
}

#[test]
fn garbage_never_panics() {
    // A cheap deterministic sweep of pseudo-random bytes and mutated valid files.
    let seeds: Vec<(MeshFormat, Vec<u8>)> = vec![
        (MeshFormat::Ply, data_bytes("cube_quad_poly.ply")),
        (
            MeshFormat::Ply,
            write_mesh_bytes(&rich_mesh(), MeshFormat::Ply, &ply(PlyEncoding::Ascii)).unwrap(),
        ),
        (MeshFormat::Off, data_bytes("cube_quad.off")),
        (MeshFormat::Obj, data_bytes("cube_degenerate_om.obj")),
        (MeshFormat::Stl, data_bytes("back_to_back_scad.stl")),
    ];
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    for (f, seed) in &seeds {
        for _ in 0..400 {
            let mut b = seed.clone();
            for _ in 0..1 + rnd() % 4 {
                let i = (rnd() as usize) % b.len();
                b[i] = match rnd() % 4 {
                    0 => rnd() as u8,
                    1 => b"0123456789 -.\n"[(rnd() % 14) as usize],
                    2 => 0xff,
                    _ => b'9',
                };
            }
            fuzz_read(*f, &b);
        }
    }
}
