//! 1-to-4 quadrisection: the connectivity by index arithmetic on flat half-edge arrays, the
//! interpolated positions, and the fine level's cotangent stiffness read off the coarse mesh.

use super::{Prolongation, Refined};
use crate::mesh::Mesh;
use crate::subdiv::SubdivError;
use crate::subdiv::halfedge_arrays::{Halfedge, HalfedgeArrays, NONE};
use glam::DVec3;

/// Connectivity of a quadrisection, shared by [`quadrisect`] and Loop's scheme: fine vertex
/// `i < n_coarse` is coarse vertex `i`; fine vertex `n_coarse + k` is the midpoint of the edge
/// of coarse half-edge `edges[k]`.
pub(crate) struct QuadTopology {
    pub n_coarse: usize,
    pub edges: Vec<u32>,
    pub triangles: Vec<[u32; 3]>,
    /// Fine midpoint vertex of every coarse half-edge.
    pub mid: Vec<u32>,
}

pub(crate) fn quad_topology(mesh: &HalfedgeArrays) -> (QuadTopology, Prolongation) {
    let nv = mesh.n_vertices();
    let mut parents: Vec<[u32; 2]> = (0..nv as u32).map(|i| [i, i]).collect();
    let mut mid = vec![NONE; mesh.halfedges.len()];
    let mut edges = Vec::with_capacity(mesh.halfedges.len() / 2);
    parents.reserve(mesh.halfedges.len() / 2);
    for h in mesh.edges() {
        let k = (nv + edges.len()) as u32;
        let e = mesh.get(h);
        mid[h as usize] = k;
        mid[e.twin as usize] = k;
        parents.push([mesh.get(e.twin).to, e.to]);
        edges.push(h);
    }
    let mut triangles = Vec::with_capacity(4 * mesh.n_faces());
    for t in 0..mesh.n_faces() {
        // face_halfedges = [v0→v1, v1→v2, v2→v0].
        let [v0, v1, v2] = mesh.face_vertices(t);
        let [m01, m12, m20] = mesh.face_halfedges(t).map(|h| mid[h as usize]);
        triangles.extend_from_slice(&[
            [v0, m01, m20],
            [v1, m12, m01],
            [v2, m20, m12],
            [m01, m12, m20],
        ]);
    }
    let topo = QuadTopology {
        n_coarse: nv,
        edges,
        triangles,
        mid,
    };
    (topo, Prolongation { parents })
}

/// The connectivity of the quadrisected mesh, by index arithmetic alone — no sorting, no
/// hashing, no repair pass — which is what keeps refinement linear and cache friendly on
/// large levels.
///
/// Layout: coarse half-edge `s` becomes fine half-edges `2s` (from its origin to the
/// midpoint) and `2s+1` (midpoint to its head); coarse face `t` adds six interior half-edges
/// at `2·nh + 6t ..` and fine faces `4t..4t+4` in the order of `topo.triangles`.
pub(crate) fn quadrisect_connectivity(
    mesh: &HalfedgeArrays,
    topo: &QuadTopology,
) -> HalfedgeArrays {
    let nh = mesh.halfedges.len() as u32;
    let nf = mesh.n_faces();
    let unset = Halfedge {
        to: NONE,
        twin: NONE,
        next: NONE,
        prev: NONE,
        face: NONE,
    };
    let mut he = vec![unset; 2 * nh as usize + 6 * nf];
    let first = |h: u32| 2 * h;
    let second = |h: u32| 2 * h + 1;
    // Split coarse half-edges: targets and twins; boundary ones also get their loop links.
    for (s, e) in (0..nh).zip(&mesh.halfedges) {
        he[first(s) as usize].to = topo.mid[s as usize];
        he[first(s) as usize].twin = second(e.twin);
        he[second(s) as usize].to = e.to;
        he[second(s) as usize].twin = first(e.twin);
        if e.face == NONE {
            let r = &mut he[first(s) as usize];
            r.next = second(s);
            r.prev = second(e.prev);
            let r = &mut he[second(s) as usize];
            r.next = first(e.next);
            r.prev = first(s);
        }
    }
    let mut face_halfedge = vec![NONE; 4 * nf];
    for t in 0..nf {
        let [h0, h1, h2] = mesh.face_halfedges(t);
        let [m01, m12, m20] = [h0, h1, h2].map(|h| topo.mid[h as usize]);
        let base = 2 * nh + 6 * t as u32;
        // Inner half-edges: I0 m01→m20, I1 m12→m01, I2 m20→m12 and their twins
        // C0 m20→m01, C1 m01→m12, C2 m12→m20 (the centre face).
        let (i0, i1, i2, c0, c1, c2) = (base, base + 1, base + 2, base + 3, base + 4, base + 5);
        let tos = [m20, m01, m12, m01, m12, m20];
        let twins = [c0, c1, c2, i0, i1, i2];
        for k in 0..6 {
            let r = &mut he[(base + k) as usize];
            r.to = tos[k as usize];
            r.twin = twins[k as usize];
        }
        // Faces: corner v0 (first h0, I0, second h2), corner v1 (first h1, I1, second h0),
        // corner v2 (first h2, I2, second h1), centre (C1, C2, C0).
        let cycles = [
            [first(h0), i0, second(h2)],
            [first(h1), i1, second(h0)],
            [first(h2), i2, second(h1)],
            [c1, c2, c0],
        ];
        for (k, cycle) in cycles.iter().enumerate() {
            let face = 4 * t + k;
            face_halfedge[face] = cycle[0];
            for j in 0..3 {
                let r = &mut he[cycle[j] as usize];
                r.next = cycle[(j + 1) % 3];
                r.prev = cycle[(j + 2) % 3];
                r.face = face as u32;
            }
        }
    }
    // Out-going half-edges: coarse vertices keep the first half of theirs (a boundary one
    // stays boundary); a midpoint takes the second half of a boundary side if there is one.
    let mut vertex_halfedge = Vec::with_capacity(topo.n_coarse + topo.edges.len());
    vertex_halfedge.extend(
        mesh.vertex_halfedge
            .iter()
            .map(|&h| if h == NONE { NONE } else { first(h) }),
    );
    vertex_halfedge.extend(topo.edges.iter().map(|&h| {
        let t = mesh.get(h).twin;
        second(if mesh.is_boundary(t) { t } else { h })
    }));
    HalfedgeArrays {
        halfedges: he,
        face_halfedge,
        vertex_halfedge,
    }
}

/// The cotangent stiffness of a quadrisection, read off the coarse mesh instead of sorted out
/// of the fine triangles: every fine edge lies in a known pair of fine triangles (corner
/// triangles `4t + k`, centre `4t + 3`, as [`quad_topology`] lays them out), so each row is a
/// handful of index lookups and a sort of at most a vertex's valence. `tri_weights` are the
/// fine triangles' [`triangle_weights`](crate::numerics::fem::triangle_weights).
///
/// Gives exactly [`cotangent_stiffness`](crate::numerics::fem::cotangent_stiffness)'s matrix, bit for
/// bit (an entry's two terms commute, the diagonal sums in column order as there). Returns
/// `None` when the coarse mesh is not one the layout covers (two faces sharing more than one
/// edge), and the caller falls back to the general assembly.
pub(crate) fn quadrisection_stiffness(
    mesh: &HalfedgeArrays,
    topo: &QuadTopology,
    tri_weights: &[[f64; 4]],
) -> Option<crate::numerics::fem::SymmetricCsr> {
    if tri_weights.len() != 4 * mesh.n_faces() {
        return None;
    }
    let rings = FineRings {
        mesh,
        topo,
        corner: mesh.corners(),
        tri_weights,
    };
    let n = topo.n_coarse + topo.edges.len();
    let parallel = n >= 2 * STIFFNESS_CHUNK;
    let row_start = rings.row_starts(n, parallel)?;
    let (col, val) = rings.fill_rows(&row_start, parallel)?;
    Some(crate::numerics::fem::SymmetricCsr {
        row_start,
        col,
        val,
    })
}

/// Rows per parallel task of [`quadrisection_stiffness`].
const STIFFNESS_CHUNK: usize = 4096;

/// The fine stiffness rows of a quadrisection, read off the coarse mesh.
struct FineRings<'a> {
    mesh: &'a HalfedgeArrays,
    topo: &'a QuadTopology,
    /// Face index t and position k (h = u_k → u_{k+1}) of every face half-edge, as 3t + k.
    corner: Vec<u32>,
    tri_weights: &'a [[f64; 4]],
}

impl FineRings<'_> {
    #[inline]
    fn w(&self, tri: usize, j: usize) -> f64 {
        self.tri_weights[tri][j]
    }

    // The fine edge from coarse vertex u_k (or u_{k+1}) to the midpoint of side s = h_k of
    // face t: corner triangle 4t+k, edge (0,1), and corner triangle 4t+k+1, edge (2,0).
    // `None` for a boundary half-edge (no face, no term).

    #[inline]
    fn at_origin(&self, c: u32) -> Option<f64> {
        let (t, k) = (c as usize / 3, c as usize % 3);
        (c != NONE).then(|| self.w(4 * t + k, 0))
    }

    #[inline]
    fn at_head(&self, c: u32) -> Option<f64> {
        let (t, k) = (c as usize / 3, c as usize % 3);
        (c != NONE).then(|| self.w(4 * t + (k + 1) % 3, 2))
    }

    /// Row i's off-diagonal terms, unsorted.
    #[inline]
    fn ring_of(&self, i: usize, ring: &mut Vec<(u32, f64)>) {
        ring.clear();
        if i < self.topo.n_coarse {
            self.coarse_ring(i, ring);
        } else {
            self.midpoint_ring(i, ring);
        }
    }

    /// A coarse vertex: one fine edge to the midpoint of each coarse edge around it; it is
    /// the origin of each out-going h and the head of its twin.
    #[inline]
    fn coarse_ring(&self, i: usize, ring: &mut Vec<(u32, f64)>) {
        let (mesh, corner) = (self.mesh, &self.corner);
        for h in mesh.outgoing(i as u32) {
            let (own, twin) = (corner[h as usize], corner[mesh.get(h).twin as usize]);
            ring.push((
                self.topo.mid[h as usize],
                sum_terms(self.at_origin(own), self.at_head(twin)),
            ));
        }
    }

    /// A midpoint: the edge's two ends, and the two other midpoints of each adjacent face.
    #[inline]
    fn midpoint_ring(&self, i: usize, ring: &mut Vec<(u32, f64)>) {
        let (mesh, topo, corner) = (self.mesh, self.topo, &self.corner);
        let h = topo.edges[i - topo.n_coarse];
        let e = mesh.get(h);
        let g = e.twin;
        let (own, twin) = (corner[h as usize], corner[g as usize]);
        // a is the origin of h and the head of g; b the reverse.
        let (a, b) = (mesh.get(g).to, e.to);
        ring.push((a, sum_terms(self.at_origin(own), self.at_head(twin))));
        ring.push((b, sum_terms(self.at_head(own), self.at_origin(twin))));
        for (side, c) in [(h, own), (g, twin)] {
            if c == NONE {
                continue;
            }
            let (t, k) = (c as usize / 3, c as usize % 3);
            // Next side m_{k+1,k+2}: corner triangle at u_{k+1}, edge (1,2), and the centre,
            // edge k. Previous side m_{k+2,k}: corner triangle at u_k, edge (1,2), centre
            // edge k+2.
            let next = self.w(4 * t + (k + 1) % 3, 1) + self.w(4 * t + 3, k);
            let prev = self.w(4 * t + k, 1) + self.w(4 * t + 3, (k + 2) % 3);
            let s = mesh.get(side);
            ring.push((topo.mid[s.next as usize], next));
            ring.push((topo.mid[s.prev as usize], prev));
        }
    }

    // A row's length is known before its entries: a coarse vertex has one neighbour per
    // out-going half-edge, a midpoint its two ends and two midpoints per adjacent face. So
    // the rows go straight into the final arrays, with no per-chunk pieces to copy (at a
    // million rows those copies were a sixth of the page faults of a whole subdivision).

    #[inline]
    fn row_len(&self, i: usize) -> u32 {
        let (mesh, topo) = (self.mesh, self.topo);
        if i < topo.n_coarse {
            1 + mesh.outgoing(i as u32).count() as u32
        } else {
            let e = mesh.get(topo.edges[i - topo.n_coarse]);
            let faces = u32::from(e.face != NONE) + u32::from(!mesh.is_boundary(e.twin));
            3 + 2 * faces
        }
    }

    /// The CSR row starts of the `n` rows; `None` if the entries overflow `u32`.
    fn row_starts(&self, n: usize, parallel: bool) -> Option<Vec<u32>> {
        use rayon::prelude::*;
        let lens: Vec<u32> = if parallel {
            (0..n).into_par_iter().map(|i| self.row_len(i)).collect()
        } else {
            (0..n).map(|i| self.row_len(i)).collect()
        };
        let mut row_start = Vec::with_capacity(n + 1);
        row_start.push(0u32);
        let mut at = 0u32;
        for l in lens {
            at = at.checked_add(l)?;
            row_start.push(at);
        }
        Some(row_start)
    }

    /// The matrix's columns and values, in chunks of rows when `parallel`; `None` on a
    /// repeated column.
    fn fill_rows(&self, row_start: &[u32], parallel: bool) -> Option<(Vec<u32>, Vec<f64>)> {
        use rayon::prelude::*;
        let n = row_start.len() - 1;
        let mut col = vec![0u32; row_start[n] as usize];
        let mut val = vec![0.0f64; row_start[n] as usize];
        if parallel {
            let mut chunks = Vec::with_capacity(n.div_ceil(STIFFNESS_CHUNK));
            let (mut col_rest, mut val_rest) = (&mut col[..], &mut val[..]);
            for first in (0..n).step_by(STIFFNESS_CHUNK) {
                let rows = first..(first + STIFFNESS_CHUNK).min(n);
                let len = (row_start[rows.end] - row_start[rows.start]) as usize;
                let (c, c_rest) = std::mem::take(&mut col_rest).split_at_mut(len);
                let (v, v_rest) = std::mem::take(&mut val_rest).split_at_mut(len);
                (col_rest, val_rest) = (c_rest, v_rest);
                chunks.push((rows, c, v));
            }
            chunks
                .into_par_iter()
                .try_for_each(|(rows, c, v)| self.fill_chunk(rows, c, v))?;
        } else {
            self.fill_chunk(0..n, &mut col, &mut val)?;
        }
        Some((col, val))
    }

    /// Rows `rows` into `col`/`val`, which start at the first row's entries; `None` on a
    /// repeated column.
    fn fill_chunk(
        &self,
        rows: std::ops::Range<usize>,
        col: &mut [u32],
        val: &mut [f64],
    ) -> Option<()> {
        let mut ring: Vec<(u32, f64)> = Vec::with_capacity(16);
        let mut at = 0;
        for i in rows {
            self.ring_of(i, &mut ring);
            ring.sort_unstable_by_key(|e| e.0);
            if ring.windows(2).any(|p| p[0].0 == p[1].0) {
                return None;
            }
            col[at] = i as u32;
            val[at] = ring.iter().map(|e| e.1).fold(0.0, |d, x| d + x);
            for (k, &(c, x)) in ring.iter().enumerate() {
                col[at + 1 + k] = c;
                val[at + 1 + k] = -x;
            }
            at += 1 + ring.len();
        }
        debug_assert_eq!(at, col.len());
        Some(())
    }
}

/// The two terms of a fine edge, either of which is absent on the boundary.
#[inline]
fn sum_terms(p: Option<f64>, q: Option<f64>) -> f64 {
    match (p, q) {
        (Some(p), Some(q)) => p + q,
        (Some(p), None) | (None, Some(p)) => p,
        (None, None) => 0.0,
    }
}

/// 1-to-4 quadrisection: every triangle splits into three corner triangles and the midpoint
/// triangle; new vertices sit at the edge midpoints. Meshes with deleted elements work
/// (elements are numbered by slot order).
pub fn quadrisect(mesh: &Mesh) -> Result<Refined, SubdivError> {
    let coarse = HalfedgeArrays::from_mesh(mesh);
    let (topo, prolongation, positions) = quadrisection_parts(&coarse, &mesh.positions());
    let fine = quadrisect_connectivity(&coarse, &topo);
    Ok(Refined {
        mesh: fine.to_mesh(&positions),
        triangles: topo.triangles,
        prolongation,
    })
}

/// A quadrisection before its connectivity exists: topology, prolongation and the
/// interpolated positions. Flat arrays are all a finite-element solve on the new level needs,
/// so [`subdivide_mcm`](crate::subdiv::cascadic::subdivide_mcm) builds the next level's connectivity
/// ([`quadrisect_connectivity`]) while it solves, and not at all on the last level.
pub(crate) fn quadrisection_parts(
    mesh: &HalfedgeArrays,
    coarse_positions: &[DVec3],
) -> (QuadTopology, Prolongation, Vec<DVec3>) {
    let (topo, prolongation) = quad_topology(mesh);
    let positions = prolongation.apply(coarse_positions);
    (topo, prolongation, positions)
}
