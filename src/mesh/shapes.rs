//! Small generated meshes for tests, benchmarks and examples.

use glam::DVec3;
use std::collections::HashMap;

/// The unit icosphere: the icosahedron split 1-to-4 `levels` times, every new vertex (an edge
/// midpoint) pushed onto the sphere. `10·4^levels + 2` vertices and `20·4^levels` triangles,
/// consistently oriented (outward normals). Deterministic: vertices in order of creation,
/// each triangle `[a, b, c]` replaced by `[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]`.
///
/// ```
/// let (p, t) = meshpyr::mesh::shapes::icosphere(2);
/// assert_eq!((p.len(), t.len()), (162, 320));
/// assert!(p.iter().all(|q| (q.length() - 1.0).abs() < 1e-12));
/// ```
pub fn icosphere(levels: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|a| DVec3::from_array(*a).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = HashMap::new();
        let mut split = |a: u32, b: u32, p: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push((p[a as usize] + p[b as usize]).normalize());
                (p.len() - 1) as u32
            })
        };
        let mut g = Vec::with_capacity(4 * f.len());
        for [a, b, c] in f {
            let (ab, bc, ca) = (
                split(a, b, &mut p),
                split(b, c, &mut p),
                split(c, a, &mut p),
            );
            g.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = g;
    }
    (p, f)
}

/// A regular grid of `n × n` quads, each split along the same diagonal: `(n + 1)²` vertices
/// `point(i, j)` (`i, j` in `0..=n`, vertex `j·(n+1) + i`) and `2n²` counter-clockwise
/// triangles (seen from +z for an increasing `point`). An open disk.
///
/// ```
/// use glam::DVec3;
/// let (p, t) = meshpyr::mesh::shapes::grid(2, |i, j| DVec3::new(i as f64, j as f64, 0.0));
/// assert_eq!((p.len(), t.len()), (9, 8));
/// assert_eq!(t[0], [0, 1, 4]);
/// ```
pub fn grid(n: usize, mut point: impl FnMut(usize, usize) -> DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            p.push(point(i, j));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut t = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, t)
}

/// A closed `n × m` torus grid: vertex `i·m + j` sits at `point(u, v)` with angles
/// `u = 2πi/n` (around the axis) and `v = 2πj/m` (around the tube), visited with `i` outer and
/// `j` inner; each grid quad makes the triangles `[(i, j), (i+1, j), (i+1, j+1)]` and
/// `[(i, j), (i+1, j+1), (i, j+1)]` (indices wrapping), `2·n·m` in all, consistently oriented.
///
/// ```
/// use glam::DVec3;
/// let (p, t) = meshpyr::mesh::shapes::torus(8, 6, |u, v| {
///     let r = 2.0 + v.cos();
///     DVec3::new(r * u.cos(), r * u.sin(), v.sin())
/// });
/// assert_eq!((p.len(), t.len()), (48, 96));
/// assert_eq!(t[0], [0, 6, 7]);
/// ```
pub fn torus(
    n: u32,
    m: u32,
    mut point: impl FnMut(f64, f64) -> DVec3,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = Vec::with_capacity((n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            let u = i as f64 / n as f64 * std::f64::consts::TAU;
            let v = j as f64 / m as f64 * std::f64::consts::TAU;
            p.push(point(u, v));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut t = Vec::with_capacity((2 * n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, t)
}

/// A closed UV sphere: the poles (vertices 0 = +z and 1 = −z) and `nv − 1` rings of `nu`
/// vertices, `2·nu·(nv − 1)` outward-facing triangles. Vertex `k` of ring `j` (1-based) at
/// longitude step `i` sits at distance `radius(k, i, j)` from the origin.
///
/// ```
/// let (p, t) = meshpyr::mesh::shapes::uv_sphere(8, 4, |_, _, _| 1.0);
/// assert_eq!((p.len(), t.len()), (2 + 8 * 3, 2 * 8 * 3));
/// ```
pub fn uv_sphere(
    nu: usize,
    nv: usize,
    mut radius: impl FnMut(usize, usize, usize) -> f64,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = vec![DVec3::Z, -DVec3::Z];
    for j in 1..nv {
        let th = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let ph = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            let r = radius(p.len(), i, j);
            p.push(r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    let id = |i: usize, j: usize| (2 + (j - 1) * nu + i % nu) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        t.push([0, id(i, 1), id(i + 1, 1)]);
        t.push([1, id(i + 1, nv - 1), id(i, nv - 1)]);
        for j in 1..nv - 1 {
            t.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    (p, t)
}
