//! Geodesic neighbourhoods on the dual mesh (`docs/algorithms.md` §2.2, §2.5).
//!
//! The dual vertices are the triangle centroids; two are joined when their triangles share an
//! interior edge, at length `d(P, Q) = |P − M| + |M − Q|` through the edge midpoint `M`
//! (eq. 3). Distances from a source triangle are shortest paths in that graph (Dijkstra), cut
//! at the kernel support. Nothing crosses a boundary edge: boundary and repaired non-manifold
//! edges have no dual edge. The anisotropic variant lengthens each dual edge by how much the
//! normals around it disagree with each other and with the source ([`edge_weight`]).

use super::surface::{FlatSurface, NO_FACE};
use glam::DVec3;

/// The dual graph: for each face, its (up to) three neighbours and the dual edge lengths.
#[derive(Clone, Debug, Default)]
pub(crate) struct DualGraph<'a> {
    /// `neighbors[f][k]`: the face across edge `k` of `f`, or [`NO_FACE`] (the surface's
    /// adjacency, borrowed).
    pub neighbors: &'a [[u32; 3]],
    /// `lengths[f][k]`: `|C_f − M_k| + |M_k − C_g|`, with `M_k` the midpoint of edge `k`
    /// (0 where there is no neighbour).
    pub lengths: Vec<[f64; 3]>,
}

impl<'a> DualGraph<'a> {
    /// The dual graph of `surface` at `positions`.
    pub(crate) fn new(surface: &'a FlatSurface, positions: &[DVec3]) -> DualGraph<'a> {
        let mut lengths = Vec::with_capacity(surface.n_faces());
        for (f, t) in surface.triangles.iter().enumerate() {
            let mut l = [0.0; 3];
            for k in 0..3 {
                let g = surface.adjacency[f][k];
                if g == NO_FACE {
                    continue;
                }
                let m = 0.5 * (positions[t[k] as usize] + positions[t[(k + 1) % 3] as usize]);
                l[k] = (surface.centroid(positions, f) - m).length()
                    + (m - surface.centroid(positions, g as usize)).length();
            }
            lengths.push(l);
        }
        DualGraph {
            neighbors: &surface.adjacency,
            lengths,
        }
    }

    /// Number of dual vertices (faces).
    pub(crate) fn len(&self) -> usize {
        self.neighbors.len()
    }
}

/// Length of the dual edge `P–Q` (base length `length`) in the metric centred at the source
/// triangle `O`, §2.5:
///
/// ```text
/// D_O(P, Q) = d(P, Q) · [1 + (ρ/2)(‖n_P − n_Q‖² + ‖n_O − n_P‖² + ‖n_O − n_Q‖²)]
/// ```
///
/// `rho = 0` gives the isotropic length. The reading of the garbled source is reconstructed;
/// this function is the one place that fixes how the three terms combine.
#[inline]
pub(crate) fn edge_weight(length: f64, rho: f64, n_o: DVec3, n_p: DVec3, n_q: DVec3) -> f64 {
    if rho == 0.0 {
        return length;
    }
    let spread =
        (n_p - n_q).length_squared() + (n_o - n_p).length_squared() + (n_o - n_q).length_squared();
    length * (1.0 + 0.5 * rho * spread)
}

/// Reusable Dijkstra workspace for one thread: tentative distances, a binary min-heap and the
/// result ball.
///
/// The distances are one `f64` per face, infinite except during a search: every face a search
/// writes is pushed, hence settled, hence in the ball, so resetting the ball's faces afterwards
/// clears them all, at the cost of the ball rather than of the mesh. Half the bytes of a
/// distance with a generation stamp, and each worker thread holds one array.
#[derive(Clone, Debug, Default)]
pub(crate) struct DualBall {
    dist: Vec<f64>,
    heap: Vec<u128>,
    /// The faces within the radius of the last search with their distances, in the order
    /// Dijkstra settled them (non-decreasing distance; the source first at 0).
    pub ball: Vec<(f64, u32)>,
}

impl DualBall {
    /// A workspace for graphs of up to `n_faces` dual vertices.
    pub(crate) fn new(n_faces: usize) -> DualBall {
        DualBall {
            dist: vec![f64::INFINITY; n_faces],
            heap: Vec::with_capacity(256),
            ball: Vec::with_capacity(1024),
        }
    }

    /// Fills [`DualBall::ball`] with every face at distance `< radius` from `source`, in the
    /// metric of [`edge_weight`] with `rho` and the face normals `normals` (isotropic for
    /// `rho = 0`).
    pub(crate) fn grow(
        &mut self,
        graph: &DualGraph,
        normals: &[DVec3],
        rho: f64,
        source: u32,
        radius: f64,
    ) {
        if self.dist.len() < graph.len() {
            self.dist.resize(graph.len(), f64::INFINITY);
        }
        for &(_, f) in &self.ball {
            self.dist[f as usize] = f64::INFINITY;
        }
        self.ball.clear();
        self.heap.clear();
        let n_o = normals[source as usize];
        self.dist[source as usize] = 0.0;
        heap_push(&mut self.heap, heap_key(0.0, source));
        while let Some((d, p)) = heap_pop(&mut self.heap).map(heap_item) {
            let pi = p as usize;
            if d > self.dist[pi] {
                continue; // stale entry; p was reached more cheaply
            }
            self.ball.push((d, p));
            let nbrs = graph.neighbors[pi];
            let lens = graph.lengths[pi];
            for k in 0..3 {
                let q = nbrs[k];
                if q == NO_FACE {
                    continue;
                }
                let qi = q as usize;
                // The isotropic metric reads no normals (the array is the largest one here).
                let nd = d + if rho == 0.0 {
                    lens[k]
                } else {
                    edge_weight(lens[k], rho, n_o, normals[pi], normals[qi])
                };
                if nd < radius && nd < self.dist[qi] {
                    self.dist[qi] = nd;
                    heap_push(&mut self.heap, heap_key(nd, q));
                }
            }
        }
    }
}

/// Heap order: by distance, ties by face index, so the settle order is fully deterministic.
/// Both go into one integer (the bits of a non-negative `f64` order like its values), so
/// the heap compares once per step instead of branching on a float test and a tie test.
#[inline]
fn heap_key(distance: f64, face: u32) -> u128 {
    (u128::from(distance.to_bits()) << 32) | u128::from(face)
}

#[inline]
fn heap_item(key: u128) -> (f64, u32) {
    (f64::from_bits((key >> 32) as u64), key as u32)
}

#[inline]
fn heap_push(heap: &mut Vec<u128>, item: u128) {
    let mut i = heap.len();
    heap.push(item);
    while i > 0 {
        let parent = (i - 1) / 2;
        if item >= heap[parent] {
            break;
        }
        heap[i] = heap[parent];
        i = parent;
    }
    heap[i] = item;
}

#[inline]
fn heap_pop(heap: &mut Vec<u128>) -> Option<u128> {
    let last = heap.pop()?;
    if heap.is_empty() {
        return Some(last);
    }
    let top = heap[0];
    let n = heap.len();
    let mut i = 0;
    loop {
        let l = 2 * i + 1;
        if l >= n {
            break;
        }
        let r = l + 1;
        let c = if r < n && heap[r] < heap[l] { r } else { l };
        if heap[c] >= last {
            break;
        }
        heap[i] = heap[c];
        i = c;
    }
    heap[i] = last;
    Some(top)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fairing::surface::FaceFrames;
    use crate::mesh::Mesh;

    /// An n×n grid of unit squares in the plane z = 0, each split along the same diagonal.
    fn grid(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        crate::mesh::shapes::grid(n, |i, j| DVec3::new(i as f64, j as f64, 0.0))
    }

    fn setup(p: &[DVec3], t: &[[u32; 3]]) -> (FlatSurface, FaceFrames, Vec<DVec3>) {
        let built = Mesh::from_triangles(p, t).expect("valid mesh");
        let s = FlatSurface::new(&built.mesh);
        let pos = built.mesh.positions();
        let frames = s.face_frames(&pos);
        (s, frames, pos)
    }

    #[test]
    fn distances_on_a_regular_grid() {
        let (p, t) = grid(8);
        let (s, frames, pos) = setup(&p, &t);
        let g = DualGraph::new(&s, &pos);
        // Centroid to a leg midpoint: the lower triangle of square (i, j) has centroid
        // (i + 2/3, j + 1/3); the diagonal's midpoint is (i + 1/2, j + 1/2).
        let to_diag = (DVec3::new(2.0 / 3.0, 1.0 / 3.0, 0.0) - DVec3::new(0.5, 0.5, 0.0)).length();
        let to_leg = (DVec3::new(2.0 / 3.0, 1.0 / 3.0, 0.0) - DVec3::new(1.0, 0.5, 0.0)).length();
        let src = (2 * (4 * 8 + 4)) as u32; // lower triangle of square (4, 4)
        let mut ball = DualBall::new(g.len());
        ball.grow(&g, &frames.normals, 0.0, src, 100.0);
        assert_eq!(
            ball.ball.len(),
            g.len(),
            "a large radius reaches every face"
        );
        assert_eq!(ball.ball[0], (0.0, src));
        let dist = |f: u32| ball.ball.iter().find(|e| e.1 == f).map(|e| e.0);
        // Its upper partner, across the diagonal.
        assert!((dist(src + 1).unwrap_or(-1.0) - 2.0 * to_diag).abs() < 1e-12);
        // The upper triangle of square (5, 4), across the right leg.
        assert!((dist(src + 3).unwrap_or(-1.0) - 2.0 * to_leg).abs() < 1e-12);
        // Two steps: lower of (4,4) → upper of (4,4) → lower of (4,5) across the top leg.
        let up = src + 2 * 8;
        assert!((dist(up).unwrap_or(-1.0) - 2.0 * to_diag - 2.0 * to_leg).abs() < 1e-12);
        // Sorted, and the cut is strict.
        assert!(ball.ball.windows(2).all(|w| w[0].0 <= w[1].0));
        ball.grow(&g, &frames.normals, 0.0, src, 2.0 * to_diag);
        assert_eq!(
            ball.ball.len(),
            1,
            "the partner at exactly the radius is cut"
        );
        ball.grow(&g, &frames.normals, 0.0, src, 2.0 * to_leg + 1e-9);
        assert_eq!(ball.ball.len(), 4, "the source and its three neighbours");
    }

    #[test]
    fn nothing_crosses_a_boundary() {
        // Two separate squares: the ball of one never reaches the other.
        let (mut p, mut t) = grid(1);
        let (p2, t2) = grid(1);
        let off = p.len() as u32;
        p.extend(p2.iter().map(|q| *q + DVec3::new(1.5, 0.0, 0.0)));
        t.extend(t2.iter().map(|f| f.map(|v| v + off)));
        let (s, frames, pos) = setup(&p, &t);
        let g = DualGraph::new(&s, &pos);
        let mut ball = DualBall::new(g.len());
        ball.grow(&g, &frames.normals, 0.0, 0, 1e9);
        let mut faces: Vec<u32> = ball.ball.iter().map(|e| e.1).collect();
        faces.sort_unstable();
        assert_eq!(faces, vec![0, 1]);
    }

    #[test]
    fn the_anisotropic_metric_stretches_across_a_crease() {
        // A grid folded by 90° along x = 4.
        let (mut p, t) = grid(8);
        for q in &mut p {
            if q.x > 4.0 {
                *q = DVec3::new(4.0, q.y, q.x - 4.0);
            }
        }
        let (s, frames, pos) = setup(&p, &t);
        let g = DualGraph::new(&s, &pos);
        let src = (2 * (4 * 8 + 3)) as u32; // lower triangle of square (3, 4), left of the fold
        let mut iso = DualBall::new(g.len());
        iso.grow(&g, &frames.normals, 0.0, src, 100.0);
        let mut aniso = DualBall::new(g.len());
        aniso.grow(&g, &frames.normals, 20.0, src, 100.0);
        let d = |b: &DualBall, f: u32| b.ball.iter().find(|e| e.1 == f).map_or(-1.0, |e| e.0);
        // On the same flat side distances agree; across the fold they grow by 1 + ρ/2·(2+2) = 41
        // on the crossing edge (the two normals are orthogonal: ‖Δn‖² = 2).
        let same_side = src - 2;
        assert!((d(&iso, same_side) - d(&aniso, same_side)).abs() < 1e-12);
        let across = src + 3; // upper triangle of square (4, 4): on the other side
        assert!(
            d(&aniso, across) > 10.0 * d(&iso, across),
            "{} vs {}",
            d(&aniso, across),
            d(&iso, across)
        );
        assert!((edge_weight(2.0, 20.0, DVec3::Z, DVec3::Z, DVec3::X) - 2.0 * 41.0).abs() < 1e-12);
    }

    #[test]
    fn the_heap_pops_in_order_when_pushes_and_pops_interleave() {
        // As in a search: pop the least, push a few larger ones, many duplicates of a distance.
        let mut h = Vec::new();
        let mut popped = Vec::new();
        let mut x = 12345u64;
        let mut next = |m: u64| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 33) % m
        };
        let mut face = 0u32;
        heap_push(&mut h, heap_key(0.0, face));
        while let Some(top) = heap_pop(&mut h) {
            popped.push(top);
            let (d, _) = heap_item(top);
            for _ in 0..1 + next(3) {
                face += 1;
                if face < 5000 {
                    heap_push(&mut h, heap_key(d + next(8) as f64 * 0.25, face));
                }
            }
        }
        assert!(popped.len() > 1000, "{}", popped.len());
        assert!(popped.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn the_heap_pops_in_order() {
        let mut h = Vec::new();
        let vals = [5.0, 1.0, 3.0, 1.0, 9.0, 0.5, 7.0, 2.0];
        for (i, &v) in vals.iter().enumerate() {
            heap_push(&mut h, heap_key(v, i as u32));
        }
        let mut out = Vec::new();
        while let Some(x) = heap_pop(&mut h).map(heap_item) {
            out.push(x);
        }
        let mut sorted: Vec<(f64, u32)> = vals
            .iter()
            .enumerate()
            .map(|(i, &v)| (v, i as u32))
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        assert_eq!(out, sorted);
    }
}
