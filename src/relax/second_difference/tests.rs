//! Tests of the second-difference operator: its weights against independent forms, the
//! awkward cases of the module docs, and its ring and batched forms against the mesh one.

use super::*;
use crate::mesh::Mesh;
use crate::relax::relax_by_stencils;

fn cot(v: DVec3, a: DVec3, b: DVec3) -> f64 {
    let (u, w) = (a - v, b - v);
    u.dot(w) / u.cross(w).length()
}

/// Signed-area form (Guskov eq. 1) after explicit hinge flattening: an independent check of
/// the cotangent form.
fn coefficients_signed_area(pj1: DVec3, pj2: DVec3, pl1: DVec3, pl2: DVec3) -> [f64; 4] {
    let e = pj2 - pj1;
    let l = e.length();
    let t = e / l;
    let place = |p: DVec3, sign: f64| {
        let d = p - pj1;
        let x = d.dot(t);
        let y = (d - x * t).length();
        (x, sign * y)
    };
    let q1 = (0.0, 0.0);
    let q2 = (l, 0.0);
    let r1 = place(pl1, 1.0);
    let r2 = place(pl2, -1.0);
    let sarea = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        0.5 * ((b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0))
    };
    let a1 = sarea(q1, q2, r1);
    let a2 = sarea(q2, q1, r2);
    [
        l * sarea(q2, r2, r1) / (a1 * a2),
        l * sarea(q1, r1, r2) / (a1 * a2),
        l / a1,
        l / a2,
    ]
}

/// A deterministic pseudo-random generator (xorshift) so tests need no extra dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn vec(&mut self, s: f64) -> DVec3 {
        DVec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * 2.0 * s
    }
}

#[test]
fn cotangent_form_matches_signed_area_form_on_random_hinges() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut checked = 0;
    let mut non_convex = 0;
    for _ in 0..2000 {
        let pj1 = rng.vec(1.0);
        let pj2 = pj1 + rng.vec(1.0);
        let (pl1, pl2) = (rng.vec(1.5), rng.vec(1.5));
        let e = pj2 - pj1;
        if e.cross(pl1 - pj1).length() < 1e-2 || e.cross(pl2 - pj1).length() < 1e-2 {
            continue;
        }
        let c = hinge_coefficients(pj1, pj2, pl1, pl2, 1e-12).unwrap();
        let r = coefficients_signed_area(pj1, pj2, pl1, pl2);
        for k in 0..4 {
            assert!(
                (c[k] - r[k]).abs() <= 1e-10 * c[k].abs().max(1.0),
                "{c:?} vs {r:?}"
            );
        }
        assert!(c.iter().sum::<f64>().abs() <= 1e-12 * c.iter().map(|x| x.abs()).sum::<f64>());
        if r[0] > 0.0 || r[1] > 0.0 {
            non_convex += 1;
        }
        // The cot form as written in `docs/algorithms.md`, from angles computed independently.
        let l = e.length();
        let (a1, b1) = (cot(pj1, pj2, pl1), cot(pj2, pj1, pl1));
        assert!((c[2] - 2.0 * (a1 + b1) / l).abs() <= 1e-9 * c[2].abs().max(1.0));
        checked += 1;
    }
    assert!(checked > 1500 && non_convex > 100, "{checked} {non_convex}");
}

#[test]
fn hinge_annihilates_functions_linear_in_the_hinge_plane() {
    let mut rng = Rng(42);
    for _ in 0..500 {
        // A planar hinge (z = 0): any affine function of (x, y) has D_e f = 0.
        let mut p = [rng.vec(1.0), rng.vec(1.0), rng.vec(1.5), rng.vec(1.5)];
        for q in &mut p {
            q.z = 0.0;
        }
        // Put l1 left and l2 right of j1 → j2 as a CCW flap requires.
        let e = p[1] - p[0];
        let o = p[0];
        let side = |q: DVec3| e.x * (q.y - o.y) - e.y * (q.x - o.x);
        if side(p[2]) < 0.0 {
            p.swap(2, 3);
        }
        if side(p[2]) < 1e-2 || side(p[3]) > -1e-2 {
            continue;
        }
        let Some(c) = hinge_coefficients(p[0], p[1], p[2], p[3], 1e-12) else {
            continue;
        };
        let f = |q: DVec3| 0.7 * q.x - 1.3 * q.y + 0.4;
        let d: f64 = (0..4).map(|k| c[k] * f(p[k])).sum();
        let scale: f64 = c.iter().map(|x| x.abs()).sum();
        assert!(d.abs() <= 1e-13 * scale, "D_e(linear) = {d}");
    }
}

#[test]
fn degenerate_triangle_gives_no_coefficients() {
    let z = DVec3::ZERO;
    let x = DVec3::X;
    assert!(hinge_coefficients(z, x, DVec3::new(0.5, 1e-9, 0.0), -DVec3::Y, 1e-12).is_some());
    assert!(hinge_coefficients(z, x, DVec3::new(0.5, 1e-14, 0.0), -DVec3::Y, 1e-12).is_none());
    assert!(hinge_coefficients(z, z, DVec3::Y, -DVec3::Y, 1e-12).is_none());
    let nan = DVec3::splat(f64::NAN);
    assert!(hinge_coefficients(z, x, nan, -DVec3::Y, 1e-12).is_none());
}

/// A regular triangular grid of `n × n` vertices (equilateral triangles of side 1).
fn regular_grid(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let h = 3f64.sqrt() / 2.0;
    let mut p = Vec::new();
    for j in 0..n {
        for i in 0..n {
            p.push(DVec3::new(i as f64 + 0.5 * j as f64, j as f64 * h, 0.0));
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut t = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            t.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
            t.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, t)
}

/// An irregular planar mesh: a jittered grid with alternating diagonals and a boundary.
fn jittered_plane(n: usize, seed: u64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut rng = Rng(seed);
    let mut p = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let interior = i > 0 && j > 0 && i + 1 < n && j + 1 < n;
            let jitter = if interior { 0.35 } else { 0.0 };
            p.push(DVec3::new(
                i as f64 + jitter * (rng.next() - 0.5),
                j as f64 + jitter * (rng.next() - 0.5),
                0.0,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut t = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            if (i + j) % 2 == 0 {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                t.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                t.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    (p, t)
}

#[test]
fn regular_grid_stencil_is_one_quarter_and_minus_one_twelfth() {
    let (p, t) = regular_grid(9);
    let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
    let geometry = mesh.positions();
    let centre = mesh.vertices().nth(4 * 9 + 4).unwrap();
    let mut s = Stencil::new();
    assert!(SecondDifference::default().stencil(&mesh, &geometry, centre, &mut s));
    assert_eq!(s.len(), 12);
    let ring = mesh.neighbors(centre);
    let mut quarters = 0;
    let mut twelfths = 0;
    for &(v, w) in &s {
        let d = (geometry[v.slot()] - geometry[centre.slot()]).length();
        if ring.contains(&v) {
            assert!((w - 0.25).abs() < 1e-13, "{w}");
            assert!((d - 1.0).abs() < 1e-12);
            quarters += 1;
        } else {
            assert!((w + 1.0 / 12.0).abs() < 1e-13, "{w}");
            // The flap apexes sit across the link edges, at distance √3 — not the whole
            // 2-ring (whose other six vertices are at distance 2).
            assert!((d - 3f64.sqrt()).abs() < 1e-12);
            twelfths += 1;
        }
    }
    assert_eq!((quarters, twelfths), (6, 6));
}

fn check_linear_precision(p: &[DVec3], t: &[[u32; 3]]) {
    let mesh = Mesh::from_triangles(p, t).unwrap().mesh;
    let geometry = mesh.positions();
    let signal: Vec<DVec3> = geometry
        .iter()
        .map(|q| {
            DVec3::new(
                0.7 * q.x - 1.3 * q.y + 0.4,
                -2.0 * q.x + 0.5 * q.y - 3.0,
                q.x + q.y,
            )
        })
        .collect();
    let op = SecondDifference::default();
    let verts: Vec<VertexId> = mesh.vertices().collect();
    let mut out = vec![DVec3::ZERO; verts.len()];
    relax_by_stencils(&op, &mesh, &geometry, &signal, &verts, &mut out);
    let mut boundary_checked = 0;
    let mut s = Stencil::new();
    for (k, &v) in verts.iter().enumerate() {
        assert!(op.stencil(&mesh, &geometry, v, &mut s), "no stencil at {k}");
        let sum: f64 = s.iter().map(|&(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-12, "weights sum to {sum} at {k}");
        assert!(s.iter().all(|&(u, _)| u != v), "R f_i must not read f_i");
        let err = (out[k] - signal[v.slot()]).length();
        assert!(err < 1e-11, "linear precision broken at {k}: {err}");
        if mesh.is_boundary_vertex(v) {
            boundary_checked += 1;
        }
    }
    assert!(boundary_checked > 0);
}

#[test]
fn reproduces_linear_functions_on_planar_meshes_interior_and_boundary() {
    let (p, t) = regular_grid(7);
    check_linear_precision(&p, &t);
    for seed in [1, 2, 3] {
        let (p, t) = jittered_plane(9, seed);
        check_linear_precision(&p, &t);
    }
}

#[test]
fn weights_sum_to_one_on_a_curved_irregular_surface() {
    // A bumpy jittered height field: weights are affine (sum to 1) whatever the geometry.
    let (mut p, t) = jittered_plane(10, 7);
    for q in &mut p {
        q.z = 0.3 * (q.x * 0.9).sin() * (q.y * 0.7).cos();
    }
    let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
    let geometry = mesh.positions();
    let mut s = Stencil::new();
    for v in mesh.vertices() {
        assert!(SecondDifference::default().stencil(&mesh, &geometry, v, &mut s));
        let sum: f64 = s.iter().map(|&(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-12, "{sum}");
        assert!(s.iter().all(|&(_, w)| w.is_finite()));
    }
}

/// Stencils on the rings of a flat replay against stencils on the slotmap mesh the same
/// splits build, at many levels of a progressive mesh: same vertices, same order, same bits.
fn ring_stencils_match_mesh_stencils(mesh: &Mesh) {
    use crate::pm::{PmOptions, ProgressiveMesh, SplitReplay};
    let pm =
        ProgressiveMesh::build(mesh, &PmOptions::default(), &crate::progress::NoProgress).unwrap();
    let nb = pm.n_base_vertices();
    let pos = pm.original_positions();
    let base = pm.base_triangles();
    let mut slow = SplitReplay::new(&pos[..nb], &base).unwrap();
    let mut fast = FlatReplay::new(&pos[..nb], &base, pm.splits().len()).unwrap();
    let op = SecondDifference::default();
    let mut compared = 0;
    for (i, s) in pm.splits().iter().enumerate() {
        slow.apply(s, pos[nb + i]).unwrap();
        fast.apply(s).unwrap();
        if i % 11 != 0 && i + 1 != pm.splits().len() {
            continue;
        }
        let m = slow.mesh();
        let all: Vec<VertexId> = m.vertices().collect();
        let ids: Vec<u32> = all.iter().map(|v| v.slot() as u32).collect();
        let (mut want, mut want_lens) = (Vec::new(), Vec::new());
        op.stencils(m, pos, &all, &mut want, &mut want_lens);
        let (mut got, mut got_lens) = (Vec::new(), Vec::new());
        op.ring_stencils(&fast, pos, &ids, &mut got, &mut got_lens);
        assert_eq!(got_lens, want_lens, "split {i}");
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.0 as usize, w.0.slot(), "split {i}");
            assert_eq!(g.1.to_bits(), w.1.to_bits(), "split {i}");
        }
        compared += want.len();
    }
    assert!(compared > 1000);
}

#[test]
fn ring_stencils_are_the_mesh_stencils_bit_for_bit() {
    // Open (a bumpy grid with a hole: boundary vertices, boundary edges) and closed.
    let (mut p, t) = jittered_plane(16, 5);
    for q in &mut p {
        q.z = 0.2 * (q.x * 1.3).sin() * (q.y * 0.4).cos();
    }
    let holed: Vec<[u32; 3]> = t
        .into_iter()
        .enumerate()
        .filter(|(i, _)| !(100..112).contains(i))
        .map(|(_, f)| f)
        .collect();
    ring_stencils_match_mesh_stencils(&Mesh::from_triangles(&p, &holed).unwrap().mesh);
    let (p, t) = crate::mesh::shapes::icosphere(3);
    ring_stencils_match_mesh_stencils(&Mesh::from_triangles(&p, &t).unwrap().mesh);
}

#[test]
fn batched_stencils_are_bit_identical_to_single_ones() {
    // The batch shares hinge coefficients through a cache (with collisions, since the
    // batch holds every vertex); the weights must not change by a single bit.
    let (mut p, t) = jittered_plane(14, 3);
    for q in &mut p {
        q.z = 0.2 * (q.x * 1.3).sin() * (q.y * 0.4).cos();
    }
    let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
    let geometry = mesh.positions();
    let op = SecondDifference::default();
    let all: Vec<VertexId> = mesh.vertices().collect();
    let (mut batch, mut lens) = (Vec::new(), Vec::new());
    op.stencils(&mesh, &geometry, &all, &mut batch, &mut lens);
    assert_eq!(lens.len(), all.len());
    let mut at = 0;
    let mut s = Stencil::new();
    for (&v, &len) in all.iter().zip(&lens) {
        let ok = op.stencil(&mesh, &geometry, v, &mut s);
        assert_eq!(ok, len > 0);
        let got = &batch[at..at + len];
        assert_eq!(got.len(), s.len());
        for (a, b) in got.iter().zip(&s) {
            assert_eq!(a.0, b.0);
            assert_eq!(a.1.to_bits(), b.1.to_bits());
        }
        at += len;
    }
    assert_eq!(at, batch.len());
}

#[test]
fn isolated_triangle_and_degenerate_fans_fall_back_to_identity() {
    let sd = SecondDifference::default();
    // One triangle: no interior edge anywhere.
    let p = [DVec3::ZERO, DVec3::X, DVec3::Y];
    let mesh = Mesh::from_triangles(&p, &[[0, 1, 2]]).unwrap().mesh;
    let geometry = mesh.positions();
    let signal = vec![DVec3::splat(1.0), DVec3::splat(2.0), DVec3::splat(3.0)];
    let verts: Vec<VertexId> = mesh.vertices().collect();
    let mut out = vec![DVec3::ZERO; 3];
    relax_by_stencils(&sd, &mesh, &geometry, &signal, &verts, &mut out);
    assert_eq!(out, signal);

    // Two triangles sharing an edge, one of zero area: the only interior edge is skipped.
    let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.5, 0.0, 0.0)];
    let mesh = Mesh::from_triangles(&p, &[[0, 1, 2], [1, 0, 3]])
        .unwrap()
        .mesh;
    let geometry = mesh.positions();
    let signal = geometry.clone();
    let verts: Vec<VertexId> = mesh.vertices().collect();
    let mut out = vec![DVec3::ZERO; 4];
    relax_by_stencils(&sd, &mesh, &geometry, &signal, &verts, &mut out);
    assert_eq!(out, signal);

    // Coincident vertices (a zero-length edge) must not produce NaN either.
    let p = [DVec3::ZERO, DVec3::ZERO, DVec3::Y, -DVec3::Y];
    let mesh = Mesh::from_triangles(&p, &[[0, 1, 2], [1, 0, 3]])
        .unwrap()
        .mesh;
    let geometry = mesh.positions();
    let verts: Vec<VertexId> = mesh.vertices().collect();
    let mut out = vec![DVec3::ZERO; 4];
    relax_by_stencils(&sd, &mesh, &geometry, &geometry, &verts, &mut out);
    assert!(out.iter().all(|q| q.is_finite()));
}

#[test]
fn stencils_with_exploding_weights_fall_back_to_identity() {
    // A hinge whose apex l1 lies far from its edge: l1's coefficient is tiny, so its
    // weights −c_k / c_l1 are huge (an extrapolation across the whole model).
    let weights_of_apex = |far: f64| {
        let p = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, far, 0.0),
            DVec3::new(0.5, -1.0, 0.0),
        ];
        let mesh = Mesh::from_triangles(&p, &[[0, 1, 2], [1, 0, 3]])
            .unwrap()
            .mesh;
        let apex = mesh.vertices().nth(2).unwrap();
        let mut s = Stencil::new();
        let ok = SecondDifference::default().stencil(&mesh, &mesh.positions(), apex, &mut s);
        (ok, s.iter().map(|&(_, w)| w.abs()).sum::<f64>())
    };
    let (ok, sum) = weights_of_apex(2.0);
    assert!(ok && sum > 1.0 && sum <= MAX_WEIGHT_SUM, "{sum}");
    assert_eq!(weights_of_apex(1e5), (false, 0.0));
}

#[test]
fn two_triangle_hinge_extrapolates_to_a_flat_hinge() {
    // A valence-2 boundary vertex keeps its single link edge: R puts it in the plane of the
    // neighbouring triangle.
    let p = [
        DVec3::ZERO,
        DVec3::X,
        DVec3::new(0.4, 0.8, 0.0),
        DVec3::new(0.6, -0.9, 0.5),
    ];
    let mesh = Mesh::from_triangles(&p, &[[0, 1, 2], [1, 0, 3]])
        .unwrap()
        .mesh;
    let geometry = mesh.positions();
    let apex = mesh.vertices().nth(3).unwrap();
    let mut out = [DVec3::ZERO];
    // Geometry as parameter, but a signal linear in the hinge-flattened plane is awkward to
    // build; instead check that D_e of the relaxed signal vanishes.
    let signal: Vec<DVec3> = geometry
        .iter()
        .map(|q| DVec3::new(q.x * q.y, 1.0, q.z))
        .collect();
    let sd = SecondDifference::default();
    relax_by_stencils(&sd, &mesh, &geometry, &signal, &[apex], &mut out);
    let c = hinge_coefficients(p[0], p[1], p[2], p[3], 1e-12).unwrap();
    let mut relaxed = signal.clone();
    relaxed[3] = out[0];
    let d = c[0] * relaxed[0] + c[1] * relaxed[1] + c[2] * relaxed[2] + c[3] * relaxed[3];
    assert!(d.length() < 1e-12, "{d}");
    assert!((out[0].y - 1.0).abs() < 1e-12);
}
