//! The half-edge builder: repairs on small hand-made cases, and property tests on random
//! polygon soups (never panics, always valid).

mod common;

use common::on_threads;
use glam::DVec3;
use meshpyr::mesh::{Mesh, PolygonMesh};
use proptest::prelude::*;

fn p(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn tetra() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    (
        vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.), p(0., 0., 1.)],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
}

/// A k×k grid of quads split into triangles, in the z = 0 plane.
fn grid(k: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            pos.push(p(i as f64, j as f64, 0.0));
        }
    }
    let id = |i: u32, j: u32| j * (k + 1) + i;
    let mut t = Vec::new();
    for j in 0..k {
        for i in 0..k {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (pos, t)
}

/// An n×m torus.
fn torus(n: u32, m: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    meshpyr::mesh::shapes::torus(n, m, |u, v| {
        let r = 2.0 + v.cos();
        p(r * u.cos(), r * u.sin(), v.sin())
    })
}

#[test]
fn closed_tetrahedron_is_clean() {
    let (pos, t) = tetra();
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    assert!(!b.report.repaired_anything());
    let topo = b.mesh.topology();
    assert_eq!(
        (topo.edges, topo.boundary_loops, topo.components),
        (6, 0, 1)
    );
    assert_eq!(topo.euler_characteristic, 2);
    assert_eq!(topo.genus, Some(0));
    for v in b.mesh.vertices() {
        assert_eq!(b.mesh.valence(v), 3);
        assert!(!b.mesh.is_boundary_vertex(v));
    }
}

#[test]
fn grid_has_one_boundary_loop_and_keeps_order() {
    let (pos, t) = grid(4);
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    let topo = b.mesh.topology();
    assert_eq!(
        (topo.boundary_loops, topo.components, topo.genus),
        (1, 1, Some(0))
    );
    assert_eq!(b.mesh.positions(), pos);
    let (p2, t2) = b.mesh.to_triangles();
    assert_eq!(p2, pos);
    // Faces keep their order; each triangle may start at a different corner only if flipped,
    // which never happens for a consistently oriented input.
    assert_eq!(t2, t);
}

#[test]
fn torus_has_genus_one() {
    let (pos, t) = torus(8, 6);
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    let topo = b.mesh.topology();
    assert_eq!((topo.euler_characteristic, topo.genus), (0, Some(1)));
}

#[test]
fn pinched_vertex_is_split() {
    // Two triangles touching at vertex 0 only (a bow tie).
    let pos = vec![
        p(0., 0., 0.),
        p(1., 0., 0.),
        p(1., 1., 0.),
        p(-1., 0., 0.),
        p(-1., -1., 0.),
    ];
    let b = Mesh::from_triangles(&pos, &[[0, 1, 2], [0, 3, 4]]).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.report.split_vertices, 1);
    assert_eq!(b.report.non_manifold_vertices, 1);
    assert_eq!(b.report.non_manifold_edges, 0);
    assert_eq!(b.mesh.n_vertices(), 6);
    assert_eq!(b.source.vertex_source, vec![0, 1, 2, 3, 4, 0]);
    assert_eq!(b.mesh.topology().components, 2);
}

#[test]
fn non_manifold_edge_is_cut() {
    // Three triangles on edge 0-1 (a book with three pages).
    let pos = vec![
        p(0., 0., 0.),
        p(1., 0., 0.),
        p(0.5, 1., 0.),
        p(0.5, -1., 0.),
        p(0.5, 0., 1.),
    ];
    let b = Mesh::from_triangles(&pos, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.report.non_manifold_edges, 1);
    assert_eq!(b.report.non_manifold_vertices, 0);
    assert!(b.report.split_vertices >= 2);
    assert_eq!(b.mesh.n_faces(), 3);
}

#[test]
fn flipped_face_is_reoriented() {
    let (pos, mut t) = tetra();
    t[2] = [1, 3, 2];
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.report.flipped_faces, 1);
    assert_eq!(b.mesh.topology().genus, Some(0));
}

#[test]
fn moebius_strip_is_cut_once() {
    // A strip of 6 quads whose ends are glued with a half twist.
    let n = 6u32;
    let mut pos = Vec::new();
    for i in 0..n {
        let a = i as f64 / n as f64 * std::f64::consts::TAU;
        let tw = a / 2.0;
        for s in [-0.3, 0.3] {
            let r = 1.0 + s * tw.cos();
            pos.push(p(r * a.cos(), r * a.sin(), s * tw.sin()));
        }
    }
    let mut t = Vec::new();
    for i in 0..n {
        let (a0, a1) = (2 * i, 2 * i + 1);
        let (b0, b1) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        t.push([a0, b0, b1]);
        t.push([a0, b1, a1]);
    }
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.report.orientation_cuts, 1);
}

#[test]
fn polygons_are_triangulated_and_degenerates_dropped() {
    let mut m = PolygonMesh::new();
    m.positions = vec![
        p(0., 0., 0.),
        p(1., 0., 0.),
        p(1., 1., 0.),
        p(0., 1., 0.),
        p(5., 5., 5.),
    ];
    m.push_face(&[0, 1, 2, 3]); // quad -> 2 triangles
    m.push_face(&[0, 1, 1]); // repeated index -> dropped
    m.push_face(&[0, 1]); // too short -> nothing
    let b = Mesh::from_polygons(&m).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.mesh.n_faces(), 2);
    assert_eq!(b.report.triangulated_polygons, 1);
    assert_eq!(b.report.dropped_repeated_index, 1);
    assert_eq!(b.report.unreferenced_vertices, 1);
    assert_eq!(b.source.face_source, vec![0, 0]);
    assert!(b.mesh.is_isolated(b.mesh.vertices().nth(4).unwrap()));
}

#[test]
fn duplicate_faces_make_a_valid_mesh() {
    let pos = vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.)];
    let b = Mesh::from_triangles(&pos, &[[0, 1, 2], [0, 1, 2], [0, 1, 2]]).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.mesh.n_faces(), 3);
}

#[test]
fn non_finite_and_out_of_range_are_errors() {
    let pos = vec![p(0., 0., 0.), p(f64::NAN, 0., 0.), p(0., 1., 0.)];
    assert!(Mesh::from_triangles(&pos, &[[0, 1, 2]]).is_err());
    let pos = vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.)];
    assert!(Mesh::from_triangles(&pos, &[[0, 1, 3]]).is_err());
}

#[test]
fn high_valence_fan() {
    let k = 200u32;
    let mut pos = vec![p(0., 0., 0.)];
    for i in 0..k {
        let a = i as f64 / k as f64 * std::f64::consts::TAU;
        pos.push(p(a.cos(), a.sin(), 0.0));
    }
    let t: Vec<[u32; 3]> = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % k]).collect();
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(
        b.mesh.valence(b.mesh.vertices().next().unwrap()),
        k as usize
    );
}

fn soup() -> impl Strategy<Value = PolygonMesh> {
    (1usize..14).prop_flat_map(|nv| {
        let coord = prop_oneof![
            20 => -10.0f64..10.0,
            1 => Just(f64::NAN),
            1 => Just(0.0),
        ];
        (
            proptest::collection::vec((coord.clone(), coord.clone(), coord), nv),
            proptest::collection::vec(proptest::collection::vec(0..nv as u32, 1..6), 0..30),
        )
            .prop_map(|(pos, faces)| {
                let mut m = PolygonMesh::new();
                m.positions = pos.into_iter().map(|(x, y, z)| p(x, y, z)).collect();
                for f in faces {
                    m.push_face(&f);
                }
                m
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn random_soups_build_valid_meshes(m in soup()) {
        match Mesh::from_polygons(&m) {
            Ok(b) => {
                b.mesh.validate().map_err(|e| TestCaseError::fail(e.to_string()))?;
                prop_assert_eq!(b.source.vertex_source.len(), b.mesh.n_vertices());
                prop_assert_eq!(b.source.face_source.len(), b.mesh.n_faces());
                prop_assert_eq!(&b.source.vertex_source[..m.n_vertices()],
                    &(0..m.n_vertices() as u32).collect::<Vec<_>>()[..]);
                let _ = b.mesh.topology();
                // The repaired mesh is expressible as a triangle list: rebuilding it from its
                // own triangles changes nothing (the PM and .pyr files rely on this).
                let (pos, tris) = b.mesh.to_triangles();
                let again = Mesh::from_triangles(&pos, &tris)
                    .map_err(|e| TestCaseError::fail(e.to_string()))?;
                prop_assert!(!again.report.repaired_anything(), "{:?}", again.report);
                prop_assert_eq!(again.mesh.n_vertices(), b.mesh.n_vertices());
            }
            Err(_) => prop_assert!(m.positions.iter().any(|p| !p.is_finite())),
        }
    }
}

#[test]
fn solids_touching_along_an_edge_become_two_closed_surfaces() {
    // Two tetrahedra sharing the edge 0-1 (four triangles on it): pairing the triangles by
    // their angle around the edge keeps both solids closed instead of leaving flaps.
    let pos = vec![
        p(0., 0., 0.),
        p(0., 0., 1.),
        p(1., 0., 0.5),
        p(0.5, 1., 0.5),
        p(-1., 0., 0.5),
        p(-0.5, -1., 0.5),
    ];
    let tet = |a: u32, b: u32, c: u32, d: u32| [[a, c, b], [a, b, d], [b, c, d], [a, d, c]];
    let mut t = tet(0, 1, 2, 3).to_vec();
    t.extend(tet(0, 1, 4, 5));
    let b = Mesh::from_triangles(&pos, &t).unwrap();
    b.mesh.validate().unwrap();
    assert_eq!(b.report.non_manifold_edges, 1);
    assert_eq!(b.report.non_manifold_vertices, 0);
    let topo = b.mesh.topology();
    assert_eq!(
        (topo.components, topo.boundary_loops, topo.genus),
        (2, 0, Some(0))
    );
    assert_eq!(b.report.split_vertices, 2);
}

#[test]
fn large_dirty_soup_builds_the_same_on_any_number_of_threads() {
    // Large enough that pairing splits into several parallel chunks and pieces (135k corners),
    // dirty enough to take every repair path: shuffled faces, flipped faces (orientation
    // walk) and duplicated faces (non-manifold edges, fan splitting, detaching).
    let (pos, grid_tris) = grid(150);
    let n = grid_tris.len();
    let mut tris = Vec::with_capacity(n + n / 50);
    for k in 0..n {
        let mut t = grid_tris[(k * 7919) % n]; // 7919 is prime and does not divide n
        if k % 7 == 0 {
            t.swap(1, 2);
        }
        tris.push(t);
        if k % 50 == 0 {
            tris.push(t);
        }
    }
    let build = |threads: usize| on_threads(threads, || Mesh::from_triangles(&pos, &tris).unwrap());
    let one = build(1);
    one.mesh.validate().unwrap();
    assert!(one.report.flipped_faces > 0, "{:?}", one.report);
    assert!(one.report.non_manifold_edges > 0, "{:?}", one.report);
    assert_eq!(one.mesh.n_faces(), tris.len());
    for threads in [2, 3] {
        let many = build(threads);
        assert_eq!(many.report, one.report);
        assert_eq!(many.source, one.source);
        assert_eq!(many.mesh.to_triangles(), one.mesh.to_triangles());
    }
}
