//! The body of the `pm_ops` fuzz target, kept in the library so that the committed corpus is
//! replayed by `cargo test` without cargo-fuzz.

use super::collapse::{Marks, MeshRecords, half_edge_collapse, is_collapse_legal, vertex_split};
use super::legality::Legality;
use super::progressive::{PmOptions, ProgressiveMesh};
use crate::mesh::{HalfedgeId, Mesh, SlotIndex};
use crate::progress::NoProgress;
use glam::DVec3;

/// A byte reader that yields zeros past the end (fuzz inputs are any length).
pub(crate) struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    /// Reads `data` from the start.
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Bytes { data, pos: 0 }
    }

    /// The next byte (0 past the end).
    pub(crate) fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }
    /// True while unread bytes remain.
    pub(crate) fn more(&self) -> bool {
        self.pos < self.data.len()
    }
}

/// A small mesh from bytes: a grid (open), a torus (closed) or a grid with holes, optionally
/// with a second component, jittered positions and shuffled vertex order.
pub(crate) fn mesh_from_bytes(r: &mut Bytes) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let kind = r.u8() % 4;
    let nx = 2 + (r.u8() % 6) as usize;
    let ny = 2 + (r.u8() % 6) as usize;
    let closed = kind == 1 && nx >= 3 && ny >= 3;
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    let components = if kind == 3 { 2 } else { 1 };
    for c in 0..components {
        let base = pos.len() as u32;
        let (cols, rows) = if closed { (nx, ny) } else { (nx + 1, ny + 1) };
        for j in 0..rows {
            for i in 0..cols {
                let jitter = (r.u8() as f64 - 128.0) / 1024.0;
                let p = if closed {
                    let (a, b) = (
                        i as f64 / nx as f64 * std::f64::consts::TAU,
                        j as f64 / ny as f64 * std::f64::consts::TAU,
                    );
                    let rr = 2.0 + (b.cos() + jitter);
                    DVec3::new(rr * a.cos(), rr * a.sin(), b.sin())
                } else {
                    DVec3::new(i as f64, j as f64 + 10.0 * c as f64, jitter)
                };
                pos.push(p);
            }
        }
        let idx = |i: usize, j: usize| base + ((j % rows) * cols + (i % cols)) as u32;
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, cc, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                let drop = kind == 2 && r.u8().is_multiple_of(5);
                if drop {
                    continue;
                }
                if r.u8().is_multiple_of(2) {
                    tris.push([a, b, cc]);
                    tris.push([a, cc, d]);
                } else {
                    tris.push([a, b, d]);
                    tris.push([b, cc, d]);
                }
            }
        }
    }
    // Shuffle the vertex order (Fisher–Yates driven by the bytes).
    let n = pos.len();
    let mut perm: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = r.u8() as usize % (i + 1);
        perm.swap(i, j);
    }
    let mut new_pos = vec![DVec3::ZERO; n];
    for (old, &new) in perm.iter().enumerate() {
        new_pos[new as usize] = pos[old];
    }
    let tris = tris.iter().map(|t| t.map(|x| perm[x as usize])).collect();
    (new_pos, tris)
}

/// Degenerate clusters as scanners leave them: up to 15 triangle corners snapped onto the next
/// corner of their triangle (zero-length edges, zero-area faces, coincident vertices).
fn snap_corners(r: &mut Bytes, pos: &mut [DVec3], tris: &[[u32; 3]]) {
    let snaps = if tris.is_empty() { 0 } else { r.u8() % 16 };
    for _ in 0..snaps {
        let t = tris[r.u8() as usize % tris.len()];
        let k = (r.u8() % 3) as usize;
        pos[t[k] as usize] = pos[t[(k + 1) % 3] as usize];
    }
}

fn sorted_triangles(tris: impl Iterator<Item = [u32; 3]>) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = tris
        .map(|t| {
            // Rotate so the smallest index comes first (keeps orientation).
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect();
    v.sort_unstable();
    v
}

/// Interprets `data` as a small mesh (with degenerate clusters), build options and a sequence of collapse / split /
/// level-jump operations, and checks every invariant after every step: `validate()`, vertex
/// slot == PM index, vertex and face counts per level, bit-exact positions, the cursor mesh
/// equal to [`ProgressiveMesh::level_triangles`], exact records after returning to the finest
/// level, and split∘collapse = identity for raw legal collapses.
///
/// # Panics
/// On any violated invariant — that is how the fuzzer reports a bug. Never on valid input
/// otherwise.
pub(crate) fn fuzz_operations(data: &[u8]) {
    let mut r = Bytes { data, pos: 0 };
    let mesh = built_mesh(&mut r);
    check_collapses_undone(&mut r, &mesh);
    let pm = progressive_mesh(&mut r, &mesh);
    check_level_walk(&mut r, &pm);
}

/// A generated mesh through the builder, which must succeed and produce a valid mesh.
fn built_mesh(r: &mut Bytes) -> Mesh {
    let (mut pos, tris) = mesh_from_bytes(r);
    snap_corners(r, &mut pos, &tris);
    let built = match Mesh::from_triangles(&pos, &tris) {
        Ok(b) => b,
        Err(e) => panic!("builder failed on a generated mesh: {e}"),
    };
    let mesh = built.mesh;
    if let Err(e) = mesh.validate() {
        panic!("builder output invalid: {e}");
    }
    mesh
}

/// Raw primitives: random legal collapses, undone in stack order, must give back the records
/// exactly, split by split.
fn check_collapses_undone(r: &mut Bytes, mesh: &Mesh) {
    let mut m = mesh.clone();
    let original = MeshRecords::of(&m);
    let legality = Legality {
        max_valence: 3 + (r.u8() % 40) as usize,
        min_normal_cos: -1.0,
        min_quality: 0.0,
    };
    let mut marks = Marks::default();
    let mut stack = Vec::new();
    // Re-inserted vertices get new generations: track the live handle of every slot.
    let mut handle: Vec<crate::mesh::VertexId> = vec![Default::default(); m.n_vertices()];
    for v in m.vertices() {
        handle[v.slot()] = v;
    }
    let rounds = r.u8() % 16;
    for _ in 0..rounds {
        let hs: Vec<HalfedgeId> = m.halfedges().collect();
        if hs.is_empty() {
            break;
        }
        let h = hs[r.u8() as usize % hs.len()];
        if is_collapse_legal(&m, h, &legality, &mut marks) {
            let before = MeshRecords::of(&m);
            let u = m.from_vertex(h);
            let p = m.position(u);
            let topo = half_edge_collapse(&mut m, h);
            if let Err(e) = m.validate() {
                panic!("collapse broke the mesh: {e}");
            }
            stack.push((topo, p, before));
        }
    }
    while let Some((topo, p, before)) = stack.pop() {
        let h = |x: crate::mesh::VertexId| handle[x.slot()];
        match vertex_split(&mut m, h(topo.to), topo.left.map(h), topo.right.map(h), p) {
            Ok(u) => {
                assert_eq!(u.slot(), topo.from.slot(), "split reused another slot");
                handle[u.slot()] = u;
            }
            Err(e) => panic!("split of a collapse failed: {e}"),
        }
        assert_eq!(
            MeshRecords::of(&m),
            before,
            "split∘collapse is not the identity"
        );
    }
    assert_eq!(MeshRecords::of(&m), original);
}

/// A progressive mesh of `mesh` with options from the bytes.
fn progressive_mesh(r: &mut Bytes, mesh: &Mesh) -> ProgressiveMesh {
    let opts = PmOptions {
        target_vertices: (r.u8() % 8) as usize,
        max_normal_angle_degrees: 30.0 + (r.u8() % 151) as f64,
        min_quality: (r.u8() % 4) as f64 * 0.05,
        max_valence: 4 + (r.u8() % 30) as usize,
        ..PmOptions::default()
    };
    match ProgressiveMesh::build(mesh, &opts, &NoProgress) {
        Ok(pm) => pm,
        Err(e) => panic!("build failed: {e}"),
    }
}

/// Collapses, splits and level jumps from the rest of the bytes, checking the cursor after
/// each; walking back to the finest level must give back its records exactly.
fn check_level_walk(r: &mut Bytes, pm: &ProgressiveMesh) {
    let n0 = pm.n_base_vertices();
    let n = pm.n_vertices();
    let mut cursor = pm.cursor();
    let finest = MeshRecords::of(cursor.mesh());
    check_cursor(pm, &cursor);
    while r.more() {
        match r.u8() % 4 {
            0 => {
                let before = cursor.level();
                let moved = cursor.collapse();
                assert_eq!(moved, before > n0);
                assert_eq!(cursor.level(), if moved { before - 1 } else { before });
            }
            1 => {
                let before = cursor.level();
                let moved = cursor.split();
                assert_eq!(moved, before < n);
                assert_eq!(cursor.level(), if moved { before + 1 } else { before });
            }
            2 => {
                let span = (n - n0 + 1).max(1);
                cursor.seek(n0 + r.u8() as usize % span);
            }
            _ => {
                let f = r.u8() as usize * pm.n_faces().max(1) / 255;
                cursor.seek_faces(f);
                assert!(pm.n_faces_at(cursor.level()) <= f || cursor.level() == n0);
            }
        }
        check_cursor(pm, &cursor);
    }
    cursor.seek(n);
    assert_eq!(
        MeshRecords::of(cursor.mesh()),
        finest,
        "walking back to the finest level is not exact"
    );
}

/// The cursor's mesh is valid, has the level's counts, the original positions bit for bit
/// and the level's triangles.
fn check_cursor(pm: &ProgressiveMesh, c: &super::PmCursor) {
    let m = c.mesh();
    if let Err(e) = m.validate() {
        panic!("cursor mesh invalid at level {}: {e}", c.level());
    }
    assert_eq!(m.n_vertices(), c.level());
    assert_eq!(m.n_faces(), pm.n_faces_at(c.level()));
    for v in m.vertices() {
        let i = v.slot();
        assert!(i < c.level(), "vertex slot {i} beyond level {}", c.level());
        assert_eq!(
            m.position(v).to_array().map(f64::to_bits),
            pm.original_positions()[i].to_array().map(f64::to_bits)
        );
    }
    let (_, faces) = m.to_triangles();
    assert_eq!(
        sorted_triangles(faces.into_iter()),
        sorted_triangles(pm.level_triangles(c.level()).into_iter())
    );
}
