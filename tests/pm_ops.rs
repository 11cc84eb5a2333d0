//! Property tests of the progressive mesh: random meshes (closed, open, several components,
//! high valence, holes, shuffled vertex order) and random sequences of legal collapses.

use glam::DVec3;
use meshpyr::mesh::{Mesh, SlotIndex, VertexId};
use meshpyr::pm::{
    Legality, Marks, MeshRecords, PmOptions, ProgressiveMesh, SimplifyTarget, half_edge_collapse,
    is_collapse_legal, simplify, vertex_split,
};
use meshpyr::progress::NoProgress;
use proptest::prelude::*;

/// Shapes the generator can make.
#[derive(Clone, Debug)]
enum Shape {
    /// Open (nx × ny) grid, optionally with faces removed (holes, pinched spots).
    Grid {
        nx: usize,
        ny: usize,
        holes: Vec<bool>,
    },
    /// Closed torus grid.
    Torus { nx: usize, ny: usize },
    /// Closed double cone: two poles of valence `k`.
    Spindle { k: usize },
    /// Open fan: one centre of valence `k`.
    Fan { k: usize },
}

fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        (
            1usize..7,
            1usize..7,
            prop::collection::vec(prop::bool::weighted(0.15), 36)
        )
            .prop_map(|(nx, ny, holes)| Shape::Grid { nx, ny, holes }),
        (3usize..7, 3usize..7).prop_map(|(nx, ny)| Shape::Torus { nx, ny }),
        (3usize..40).prop_map(|k| Shape::Spindle { k }),
        (3usize..40).prop_map(|k| Shape::Fan { k }),
    ]
}

fn append(
    shape: &Shape,
    offset: DVec3,
    jitter: &[f64],
    pos: &mut Vec<DVec3>,
    tris: &mut Vec<[u32; 3]>,
) {
    let base = pos.len() as u32;
    let j = |i: usize| jitter[i % jitter.len()];
    match shape {
        Shape::Grid { nx, ny, holes } => {
            for y in 0..=*ny {
                for x in 0..=*nx {
                    let i = pos.len();
                    pos.push(
                        offset
                            + DVec3::new(
                                x as f64 + 0.2 * j(i),
                                y as f64 + 0.2 * j(i + 1),
                                j(i + 2),
                            ),
                    );
                }
            }
            let id = |x: usize, y: usize| base + (y * (nx + 1) + x) as u32;
            for y in 0..*ny {
                for x in 0..*nx {
                    // The first cell is never a hole, so that every grid is a surface.
                    if holes[(y * nx + x) % holes.len()] && (x, y) != (0, 0) {
                        continue;
                    }
                    tris.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                    tris.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
                }
            }
        }
        Shape::Torus { nx, ny } => {
            for y in 0..*ny {
                for x in 0..*nx {
                    let (a, b) = (
                        x as f64 / *nx as f64 * std::f64::consts::TAU,
                        y as f64 / *ny as f64 * std::f64::consts::TAU,
                    );
                    let r = 2.0 + b.cos() + 0.05 * j(pos.len());
                    pos.push(offset + DVec3::new(r * a.cos(), r * a.sin(), b.sin()));
                }
            }
            let id = |x: usize, y: usize| base + ((y % ny) * nx + (x % nx)) as u32;
            for y in 0..*ny {
                for x in 0..*nx {
                    tris.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                    tris.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
                }
            }
        }
        Shape::Spindle { k } => {
            pos.push(offset + DVec3::new(0.0, 0.0, 1.0));
            pos.push(offset + DVec3::new(0.0, 0.0, -1.0));
            for i in 0..*k {
                let a = i as f64 / *k as f64 * std::f64::consts::TAU;
                pos.push(offset + DVec3::new(a.cos(), a.sin(), 0.1 * j(i)));
            }
            for i in 0..*k {
                let (a, b) = (base + 2 + i as u32, base + 2 + ((i + 1) % k) as u32);
                tris.push([base, a, b]);
                tris.push([base + 1, b, a]);
            }
        }
        Shape::Fan { k } => {
            pos.push(offset);
            for i in 0..*k {
                let a = i as f64 / *k as f64 * 5.0;
                pos.push(offset + DVec3::new(a.cos(), a.sin(), 0.1 * j(i)));
            }
            for i in 0..k - 1 {
                tris.push([base, base + 1 + i as u32, base + 2 + i as u32]);
            }
        }
    }
}

/// Random mesh: 1–3 components, shuffled vertex order, one unreferenced vertex sometimes.
fn random_mesh() -> impl Strategy<Value = (Vec<DVec3>, Vec<[u32; 3]>)> {
    (
        prop::collection::vec(shape(), 1..4),
        prop::collection::vec(-1.0f64..1.0, 8),
        any::<u64>(),
        any::<bool>(),
    )
        .prop_map(|(shapes, jitter, seed, isolated)| {
            let mut pos = Vec::new();
            let mut tris = Vec::new();
            for (c, s) in shapes.iter().enumerate() {
                append(
                    s,
                    DVec3::new(20.0 * c as f64, 0.0, 0.0),
                    &jitter,
                    &mut pos,
                    &mut tris,
                );
            }
            if isolated {
                pos.push(DVec3::new(-5.0, -5.0, -5.0));
            }
            // Deterministic shuffle of the vertex order.
            let n = pos.len();
            let mut perm: Vec<u32> = (0..n as u32).collect();
            let mut x = seed | 1;
            for i in (1..n).rev() {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                perm.swap(i, (x % (i as u64 + 1)) as usize);
            }
            let mut p2 = vec![DVec3::ZERO; n];
            for (old, &new) in perm.iter().enumerate() {
                p2[new as usize] = pos[old];
            }
            let t2 = tris.iter().map(|t| t.map(|i| perm[i as usize])).collect();
            (p2, t2)
        })
}

fn build(pos: &[DVec3], tris: &[[u32; 3]]) -> Mesh {
    let b = Mesh::from_triangles(pos, tris).unwrap();
    b.mesh.validate().unwrap();
    b.mesh
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Random legal collapses, undone in stack order (interleaved with redo steps): every
    /// split restores the exact records, and the mesh validates after every step.
    #[test]
    fn split_after_collapse_is_identity((pos, tris) in random_mesh(), picks in prop::collection::vec(any::<u32>(), 1..60)) {
        let mut mesh = build(&pos, &tris);
        let original = MeshRecords::of(&mesh);
        let legality = Legality { max_valence: 64, min_normal_cos: -1.0, min_quality: 0.0 };
        let mut marks = Marks::default();
        let mut handle: Vec<VertexId> = mesh.vertices().collect();
        let mut stack = Vec::new();
        for (step, p) in picks.iter().enumerate() {
            if step % 7 == 6 && let Some((topo, before, position)) = stack.pop() {
                let (topo, before, position): (meshpyr::pm::CollapseTopology, MeshRecords, DVec3) = (topo, before, position);
                let h = |x: VertexId| handle[x.slot()];
                let u = vertex_split(&mut mesh, h(topo.to), topo.left.map(h), topo.right.map(h), position).unwrap();
                prop_assert_eq!(u.slot(), topo.from.slot());
                handle[u.slot()] = u;
                mesh.validate().unwrap();
                prop_assert_eq!(&MeshRecords::of(&mesh), &before);
                continue;
            }
            let hs: Vec<_> = mesh.halfedges().collect();
            if hs.is_empty() { break; }
            let h = hs[*p as usize % hs.len()];
            if !is_collapse_legal(&mesh, h, &legality, &mut marks) { continue; }
            let before = MeshRecords::of(&mesh);
            let position = mesh.position(mesh.from_vertex(h));
            let topo = half_edge_collapse(&mut mesh, h);
            mesh.validate().unwrap();
            stack.push((topo, before, position));
        }
        while let Some((topo, before, position)) = stack.pop() {
            let h = |x: VertexId| handle[x.slot()];
            let u = vertex_split(&mut mesh, h(topo.to), topo.left.map(h), topo.right.map(h), position).unwrap();
            handle[u.slot()] = u;
            mesh.validate().unwrap();
            prop_assert_eq!(&MeshRecords::of(&mesh), &before);
        }
        prop_assert_eq!(MeshRecords::of(&mesh), original);
    }

    /// Build → base → finest reproduces the input: positions bit-exact, the same faces in the
    /// same order and rotation, the same vertex order after the permutation; the cursor is
    /// valid at every level and agrees with `level_triangles`.
    #[test]
    fn base_to_finest_reproduces_input((pos, tris) in random_mesh(), target in 0usize..12) {
        let mesh = build(&pos, &tris);
        let opts = PmOptions { target_vertices: target, ..PmOptions::default() };
        let pm = ProgressiveMesh::build(&mesh, &opts, &NoProgress).unwrap();
        let n = pm.n_vertices();
        let n0 = pm.n_base_vertices();
        prop_assert_eq!(pm.pm_to_mesh().len(), mesh.n_vertices());
        // The permutation is a bijection and positions follow it bit for bit.
        let mut seen = vec![false; mesh.n_vertices()];
        let verts: Vec<VertexId> = mesh.vertices().collect();
        for (i, &s) in pm.pm_to_mesh().iter().enumerate() {
            prop_assert!(!seen[s as usize]);
            seen[s as usize] = true;
            prop_assert_eq!(pm.mesh_to_pm()[s as usize] as usize, i);
            let p = mesh.position(verts[s as usize]);
            prop_assert_eq!(p.to_array().map(f64::to_bits), pm.original_positions()[i].to_array().map(f64::to_bits));
        }
        for (i, s) in pm.splits().iter().enumerate() {
            prop_assert_eq!(s.vertex as usize, n0 + i);
            prop_assert!((s.survivor as usize) < n0 + i);
        }
        let mut cursor = pm.cursor();
        let finest = MeshRecords::of(cursor.mesh());
        // Faces at the finest level are the input's faces, in order, through the permutation.
        let (_, input_faces) = mesh.to_triangles();
        let (_, cursor_faces) = cursor.mesh().to_triangles();
        let mapped: Vec<[u32; 3]> = cursor_faces.iter().map(|t| t.map(|i| pm.pm_to_mesh()[i as usize])).collect();
        prop_assert_eq!(&mapped, &input_faces);
        let check = |c: &meshpyr::pm::PmCursor| -> Result<(), TestCaseError> {
            c.mesh().validate().unwrap();
            prop_assert_eq!(c.mesh().n_vertices(), c.level());
            prop_assert!(c.mesh().vertices().all(|v| v.slot() < c.level()));
            prop_assert_eq!(c.mesh().n_faces(), pm.n_faces_at(c.level()));
            let (_, f) = c.mesh().to_triangles();
            prop_assert_eq!(f, pm.level_triangles(c.level()));
            Ok(())
        };
        while cursor.collapse() { check(&cursor)?; }
        prop_assert_eq!(cursor.level(), n0);
        let base = pm.base_mesh();
        prop_assert_eq!(base.n_vertices(), n0);
        prop_assert_eq!(base.n_faces(), pm.n_base_faces());
        while cursor.split() { check(&cursor)?; }
        prop_assert_eq!(cursor.level(), n);
        prop_assert_eq!(MeshRecords::of(cursor.mesh()), finest);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// `simplify` decimates the builder's corner table without making a half-edge mesh; its
    /// result must be the progressive mesh's base level for the same target: the same
    /// surviving input vertices in the same order and the same triangles.
    #[test]
    fn simplify_is_the_progressive_mesh_cut((pos, tris) in random_mesh(), keep in 0usize..40) {
        let input = meshpyr::mesh::PolygonMesh::from_triangles(pos.clone(), &tris);
        let built = Mesh::from_polygons(&input).unwrap();
        let faces = keep.min(built.mesh.n_faces());
        let cut = simplify(&input, SimplifyTarget::Faces(faces), &PmOptions::default(), &NoProgress).unwrap();
        let opts = PmOptions { target_faces: faces, ..PmOptions::default() };
        let pm = ProgressiveMesh::build(&built.mesh, &opts, &NoProgress).unwrap();
        let n0 = pm.n_base_vertices();
        let rows: Vec<u32> = pm.pm_to_mesh()[..n0]
            .iter()
            .map(|&slot| built.source.vertex_source[slot as usize])
            .collect();
        prop_assert_eq!(&cut.source_rows, &rows);
        let (_, cut_tris) = Mesh::from_polygons(&cut.mesh).unwrap().mesh.to_triangles();
        prop_assert_eq!(cut_tris, pm.level_triangles(n0));
        prop_assert!(cut.mesh.n_faces() <= faces.max(pm.n_base_faces()));
    }
}

/// A closed surface never goes below a tetrahedron, and simplification stops at a target.
#[test]
fn targets_and_base_cases() {
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    append(
        &Shape::Torus { nx: 6, ny: 6 },
        DVec3::ZERO,
        &[0.0],
        &mut pos,
        &mut tris,
    );
    let mesh = build(&pos, &tris);
    let pm = ProgressiveMesh::build(
        &mesh,
        &PmOptions {
            target_faces: 40,
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    assert!(pm.n_base_faces() <= 40 && pm.n_base_faces() >= 38);
    let full = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    assert!(full.n_base_faces() < 40);
    full.base_mesh().validate().unwrap();
    assert_eq!(full.base_mesh().topology().genus, Some(1));

    let mut pos = Vec::new();
    let mut tris = Vec::new();
    append(
        &Shape::Spindle { k: 30 },
        DVec3::ZERO,
        &[0.0],
        &mut pos,
        &mut tris,
    );
    let mesh = build(&pos, &tris);
    let pm = ProgressiveMesh::build(
        &mesh,
        &PmOptions {
            max_normal_angle_degrees: 180.0,
            min_quality: 0.0,
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    assert_eq!(
        pm.n_base_vertices(),
        4,
        "a sphere simplifies to a tetrahedron"
    );
    assert_eq!(pm.n_base_faces(), 4);
}

#[test]
fn invalid_options_are_errors() {
    let mesh = build(&[DVec3::ZERO, DVec3::X, DVec3::Y], &[[0, 1, 2]]);
    for o in [
        PmOptions {
            max_normal_angle_degrees: 0.0,
            ..Default::default()
        },
        PmOptions {
            min_quality: 1.5,
            ..Default::default()
        },
        PmOptions {
            max_error: Some(-1.0),
            ..Default::default()
        },
        PmOptions {
            max_valence: 2,
            ..Default::default()
        },
        PmOptions {
            boundary_weight: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(ProgressiveMesh::build(&mesh, &o, &NoProgress).is_err());
    }
    // A single triangle cannot be collapsed.
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    assert_eq!((pm.n_base_vertices(), pm.n_vertices()), (3, 3));
}
