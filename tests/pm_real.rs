//! The progressive mesh on real meshes (tests/data): high genus, high valence, an open disk,
//! a dirty multi-component model with repaired non-manifold spots and zero-area faces.

use meshpyr::io::read_mesh;
use meshpyr::mesh::{Mesh, SlotIndex};
use meshpyr::pm::{MeshRecords, PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use std::path::Path;

mod common;

fn load(name: &str) -> Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    let poly = read_mesh(&path).unwrap();
    let built = Mesh::from_polygons(&poly).unwrap();
    built.mesh.validate().unwrap();
    built.mesh
}

/// Full hierarchy: small base, exact walk down and up with validation at every level, and the
/// finest level equal to the input through the permutation.
fn check(name: &str, max_base_vertices: usize) {
    let mesh = load(name);
    let before = mesh.topology();
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    let n0 = pm.n_base_vertices();
    assert!(
        n0 <= max_base_vertices,
        "{name}: base has {n0} vertices (of {}), expected at most {max_base_vertices}",
        pm.n_vertices()
    );
    let base = pm.base_mesh();
    base.validate().unwrap();
    let after = base.topology();
    assert_eq!(
        after.components, before.components,
        "{name}: components changed"
    );
    assert_eq!(after.genus, before.genus, "{name}: genus changed");
    assert_eq!(
        after.boundary_loops, before.boundary_loops,
        "{name}: boundary loops changed"
    );

    let mut cursor = pm.cursor();
    let finest = MeshRecords::of(cursor.mesh());
    let mut steps = 0;
    while cursor.collapse() {
        steps += 1;
        if steps % 7 == 0 {
            cursor.mesh().validate().unwrap();
        }
    }
    assert_eq!(cursor.level(), n0);
    while cursor.split() {}
    assert_eq!(
        MeshRecords::of(cursor.mesh()),
        finest,
        "{name}: base → finest not exact"
    );
    let (_, input_faces) = mesh.to_triangles();
    let (pos, faces) = cursor.mesh().to_triangles();
    let mapped: Vec<[u32; 3]> = faces
        .iter()
        .map(|t| t.map(|i| pm.pm_to_mesh()[i as usize]))
        .collect();
    assert_eq!(mapped, input_faces, "{name}: faces differ from the input");
    let verts: Vec<_> = mesh.vertices().collect();
    for (i, p) in pos.iter().enumerate() {
        let q = mesh.position(verts[pm.pm_to_mesh()[i] as usize]);
        assert_eq!(
            p.to_array().map(f64::to_bits),
            q.to_array().map(f64::to_bits)
        );
        assert_eq!(
            verts[pm.pm_to_mesh()[i] as usize].slot(),
            pm.pm_to_mesh()[i] as usize
        );
    }
}

#[test]
fn joint_genus_2() {
    check("joint.ply", 40);
}

#[test]
fn anchor_genus_4_high_valence() {
    check("anchor.ply", 70);
}

#[test]
fn nefertiti_open_disk() {
    check("nefertiti.ply", 20);
}

#[test]
fn torus_quad() {
    check("torus_quad.ply", 16);
}

#[test]
fn spider_dirty_many_components() {
    // 18 components (some split further by the builder's repairs): a handful of vertices each.
    check("spider_assimp.ply", 200);
}

#[test]
fn simplify_to_targets() {
    let mesh = load("anchor.ply");
    for target in [500, 200, 100] {
        let pm = ProgressiveMesh::build(
            &mesh,
            &PmOptions {
                target_faces: target,
                ..Default::default()
            },
            &NoProgress,
        )
        .unwrap();
        assert!(pm.n_base_faces() <= target && pm.n_base_faces() + 2 >= target);
        let full = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
        // The targeted build is a prefix of the full one (same greedy order up to the cut).
        assert!(full.n_base_faces() <= pm.n_base_faces());
    }
    let coarse = ProgressiveMesh::build(
        &mesh,
        &PmOptions {
            max_error: Some(0.01),
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    let fine = ProgressiveMesh::build(
        &mesh,
        &PmOptions {
            max_error: Some(0.001),
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    assert!(coarse.n_base_faces() < fine.n_base_faces());
    let diag = mesh.bbox_diagonal() as f32;
    assert!(
        fine.split_errors()
            .iter()
            .all(|&e| e <= 0.001 * diag * 1.0001)
    );
}

/// A scan far from the origin (georeferenced coordinates) gets the same hierarchy as at the
/// origin. fandisk's coordinates are snapped to multiples of 2^-20 and then translated by 2^20,
/// both exactly, so only the arithmetic could tell the two copies apart: with plane quadrics in
/// absolute coordinates their `d²` terms (~1e12) swamped the errors (~1e-6) and the collapse
/// order was nearly random; the decimator now works relative to the bounding-box centre, which
/// gives the very same splits.
#[test]
fn a_scan_far_from_the_origin_gets_the_same_hierarchy() {
    let fandisk = load("fandisk.ply");
    let (near, far) = (
        common::snapped_and_moved(&fandisk, 0.0),
        common::snapped_and_moved(&fandisk, f64::from(1u32 << 20)),
    );
    let a = ProgressiveMesh::build(&near, &PmOptions::default(), &NoProgress).unwrap();
    let b = ProgressiveMesh::build(&far, &PmOptions::default(), &NoProgress).unwrap();
    assert_eq!(a.n_base_vertices(), b.n_base_vertices());
    assert!(
        a.pm_to_mesh() == b.pm_to_mesh(),
        "the collapse order differs"
    );
    assert!(a.splits() == b.splits(), "the splits differ");
}

/// Every part of two hierarchies, compared field by field (positions bit for bit).
fn assert_same_hierarchy(name: &str, a: &ProgressiveMesh, b: &ProgressiveMesh) {
    assert_eq!(a.n_base_vertices(), b.n_base_vertices(), "{name}: base");
    assert_eq!(a.splits(), b.splits(), "{name}: splits");
    assert_eq!(a.split_errors(), b.split_errors(), "{name}: split errors");
    assert_eq!(a.pm_to_mesh(), b.pm_to_mesh(), "{name}: vertex order");
    assert_eq!(a.mesh_to_pm(), b.mesh_to_pm(), "{name}: vertex order");
    assert_eq!(a.finest_faces(), b.finest_faces(), "{name}: faces");
    assert_eq!(a.n_base_faces(), b.n_base_faces(), "{name}: base faces");
    let bits = |pm: &ProgressiveMesh| -> Vec<[u64; 3]> {
        let p = pm.original_positions();
        p.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
    };
    assert_eq!(bits(a), bits(b), "{name}: positions");
}

#[test]
fn from_polygons_builds_the_hierarchy_of_the_built_mesh_without_its_records() {
    // Closed, open with holes, dirty (repaired non-manifold spots, isolated vertices) and
    // many-component inputs, one far from the origin (the decimator works recentred).
    let mut far = read_mesh(common::data("bunny.ply")).unwrap();
    for p in &mut far.positions {
        *p += glam::DVec3::new(1e5, -3e4, 7e3);
    }
    let named = [
        "bunny.ply",
        "elephant_holes.ply",
        "spider_assimp.ply",
        "tripod.ply",
    ]
    .map(|name| (name, read_mesh(common::data(name)).unwrap()));
    for (name, poly) in named.into_iter().chain([("far bunny", far)]) {
        let built = Mesh::from_polygons(&poly).unwrap();
        let opts = PmOptions::default();
        let from_mesh = ProgressiveMesh::build(&built.mesh, &opts, &NoProgress).unwrap();
        let (direct, source) = ProgressiveMesh::from_polygons(&poly, &opts, &NoProgress).unwrap();
        assert_same_hierarchy(name, &from_mesh, &direct);
        assert_eq!(source.vertex_source, built.source.vertex_source, "{name}");
        // The finest level holds the input's own coordinates.
        for (pm_vertex, &slot) in direct.pm_to_mesh().iter().enumerate() {
            let row = source.vertex_source[slot as usize] as usize;
            assert_eq!(
                direct.original_positions()[pm_vertex],
                poly.positions[row],
                "{name}"
            );
        }
    }
}
