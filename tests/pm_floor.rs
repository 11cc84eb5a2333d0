//! The progressive mesh reaches the floor of the surface's topology on the meshes scanners
//! and reconstructions emit: degenerate clusters (coincident vertices, zero-area faces) and
//! slivers do not stall it, and where it stops it says why.

mod common;

use common::data;
use glam::DVec3;
use meshpyr::io::read_mesh;
use meshpyr::mesh::{Mesh, PolygonMesh, shapes};
use meshpyr::pm::{PmOptions, ProgressiveMesh, SimplifyTarget, Stop, simplify};
use meshpyr::progress::NoProgress;
use proptest::prelude::*;

fn build(positions: Vec<DVec3>, tris: &[[u32; 3]]) -> Mesh {
    Mesh::from_polygons(&PolygonMesh::from_triangles(positions, tris))
        .unwrap()
        .mesh
}

fn pm(mesh: &Mesh) -> ProgressiveMesh {
    ProgressiveMesh::build(mesh, &PmOptions::default(), &NoProgress).unwrap()
}

/// A closed genus-0 surface in the manner of a marching-cubes scan: an icosphere made bumpy
/// (star-shaped, so embedded), with clusters of vertices snapped onto a neighbour (zero-length
/// edges, zero-area faces) and coordinates quantised to a coarse grid (runs of coplanar and
/// collinear vertices).
fn scan_like_sphere(
    levels: usize,
    bumps: &[f64],
    snaps: &[(usize, usize)],
    grid: f64,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let (mut p, t) = shapes::icosphere(levels);
    for (i, x) in p.iter_mut().enumerate() {
        *x *= 1.0 + 0.4 * bumps[i % bumps.len()];
    }
    for &(vertex, corner) in snaps {
        let tri = t[vertex % t.len()];
        let (a, b) = (tri[corner % 3], tri[(corner + 1) % 3]);
        p[a as usize] = p[b as usize];
    }
    if grid > 0.0 {
        for x in &mut p {
            *x = (*x / grid).round() * grid;
        }
    }
    (p, t)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Whatever its clusters of coincident vertices, zero-area faces and slivers, a closed
    /// genus-0 surface simplifies to at most 8 vertices (its floor is a tetrahedron's 4), and
    /// the hierarchy still reproduces every level exactly.
    #[test]
    fn a_closed_genus_0_surface_reaches_at_most_8_vertices(
        levels in 1usize..=3,
        bumps in prop::collection::vec(-1.0f64..1.0, 1..40),
        snaps in prop::collection::vec((any::<usize>(), 0usize..3), 0..60),
        grid in prop_oneof![Just(0.0), 0.02f64..0.2],
    ) {
        let (p, t) = scan_like_sphere(levels, &bumps, &snaps, grid);
        let mesh = build(p, &t);
        let topology = mesh.topology();
        prop_assume!(topology.components == 1 && topology.genus == Some(0));
        let pm = pm(&mesh);
        prop_assert!(pm.n_base_vertices() <= 8, "base {} vertices: {}", pm.n_base_vertices(), pm.describe_base());
        let mut cursor = pm.cursor();
        cursor.seek(pm.n_base_vertices());
        cursor.mesh().validate().unwrap();
        cursor.seek(pm.n_vertices());
        prop_assert_eq!(cursor.mesh().n_faces(), mesh.n_faces());
    }
}

/// The marching-cubes scans of `tests/data/mc` (voxelised, quantised with zero-area faces,
/// open, many-component implicits): the base level is at most 1 % of the vertices or at most
/// twice the floor of its topology.
#[test]
fn marching_cubes_scans_reach_their_floor() {
    let dir = data("mc");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    names.sort();
    assert!(names.len() >= 5, "{names:?}");
    for path in names {
        let mesh = Mesh::from_polygons(&read_mesh(&path).unwrap())
            .unwrap()
            .mesh;
        let floor = mesh.topology().floor_vertices;
        let pm = pm(&mesh);
        let base = pm.n_base_vertices();
        assert!(
            base * 100 <= mesh.n_vertices() || base <= 2 * floor,
            "{}: {}",
            path.display(),
            pm.describe_base()
        );
    }
}

/// `simplify` at 1 % reaches the target, or stops at the floor and says why.
#[test]
fn simplify_reaches_one_percent_or_says_why_not() {
    for name in [
        "mc/mc_bunny_quant36.ply",
        "mc/mc_armadillo_open52.ply",
        "elephant_holes.ply",
    ] {
        let input = read_mesh(data(name)).unwrap();
        let faces = input.n_triangles();
        let done = simplify(
            &input,
            SimplifyTarget::Ratio(0.01),
            &PmOptions::default(),
            &NoProgress,
        )
        .unwrap();
        let target = (0.01 * faces as f64).round() as usize;
        if done.mesh.n_faces() <= target {
            assert_eq!(done.stop, Stop::Target, "{name}");
            assert!(done.shortfall().is_none());
            continue;
        }
        let Stop::NoLegalCollapse(refusals) = &done.stop else {
            panic!(
                "{name}: short of the target without a reason: {:?}",
                done.stop
            );
        };
        assert!(!refusals.is_empty(), "{name}");
        let topology = done.short_of_target.as_ref().unwrap();
        assert!(
            done.mesh.n_vertices() <= 2 * topology.floor_vertices,
            "{name}"
        );
        let line = done.shortfall().unwrap();
        assert!(
            line.contains("no legal collapse left") && line.contains("holes"),
            "{line}"
        );
    }
}

/// A cluster of coincident vertices costs nothing to collapse and no rule blocks it: the
/// hierarchy of a sphere with snapped vertices starts with free collapses (a zero-length edge
/// next to an earlier collapse's survivor costs that survivor's error, so not all are free).
#[test]
fn degenerate_clusters_collapse_first() {
    let snaps: Vec<(usize, usize)> = (0..30).map(|i| (i * 37, i % 3)).collect();
    let (p, t) = scan_like_sphere(3, &[0.0], &snaps, 0.0);
    let mesh = build(p, &t);
    let zero_length = mesh
        .edges()
        .filter(|&h| mesh.position(mesh.from_vertex(h)) == mesh.position(mesh.to_vertex(h)))
        .count();
    assert!(zero_length >= 10, "{zero_length}");
    let pm = pm(&mesh);
    // Split errors run from the coarsest level up: the first collapse is the last split.
    let errors = pm.split_errors();
    let first = errors.iter().rev().take_while(|&&e| e == 0.0).count();
    assert!(first >= zero_length / 2, "{first} free of {zero_length}");
    assert!(pm.n_base_vertices() <= 8);
}
