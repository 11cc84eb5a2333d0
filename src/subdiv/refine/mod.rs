//! Mesh refinement for subdivision: 1-to-4 quadrisection and conforming newest-vertex
//! bisection. Each step returns a new [`Mesh`] whose first vertices are the coarse vertices
//! (dense order) and a [`Prolongation`] saying which coarse vertices every new vertex
//! interpolates (trivial interpolation: copies and edge midpoints).
//!
//! [`bisect`] expects a mesh with dense slots (fresh from the builder, as
//! [`subdivide`](super::subdivide) guarantees); [`quadrisect`] numbers any mesh's elements by
//! slot order. Both outputs are dense. Inside [`subdivide`](super::subdivide), quadrisection
//! levels work on flat half-edge arrays (`quadrisect_connectivity`) and never build a
//! [`Mesh`].

use super::SubdivError;
use super::halfedge_arrays::{Halfedge, HalfedgeArrays, NONE};
use crate::mesh::{Mesh, SlotIndex};
use glam::DVec3;
use std::ops::{Add, Mul};

/// Trivial interpolation from a coarse to a refined mesh: fine vertex `i` takes
/// `(f[a] + f[b]) / 2` with `[a, b] = parents()[i]` (`a == b` for a copied coarse vertex).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Prolongation {
    parents: Vec<[u32; 2]>,
}

impl Prolongation {
    /// The two coarse parents of every fine vertex (equal for a copy).
    #[cfg(test)]
    pub(crate) fn parents(&self) -> &[[u32; 2]] {
        &self.parents
    }

    /// Number of fine vertices.
    #[cfg(test)]
    pub(crate) fn n_fine(&self) -> usize {
        self.parents.len()
    }

    /// Interpolates coarse values onto the fine vertices.
    pub(crate) fn apply<T>(&self, coarse: &[T]) -> Vec<T>
    where
        T: Copy + Add<Output = T> + Mul<f64, Output = T>,
    {
        self.parents
            .iter()
            .map(|&[a, b]| {
                if a == b {
                    coarse[a as usize]
                } else {
                    (coarse[a as usize] + coarse[b as usize]) * 0.5
                }
            })
            .collect()
    }
}

/// A refined mesh with its prolongation.
#[derive(Clone, Debug)]
pub struct Refined {
    /// The new mesh, vertex positions trivially interpolated from the coarse ones.
    pub mesh: Mesh,
    /// The new mesh's triangles as dense vertex indices, in face slot order.
    pub triangles: Vec<[u32; 3]>,
    /// Coarse-to-fine interpolation.
    pub prolongation: Prolongation,
}

/// Newest-vertex marking for bisection: for each face (slot order), the local index (0..3,
/// in [`Mesh::face_vertices`] order) of its newest vertex. The refinement edge is the edge
/// opposite that vertex.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Marking {
    newest: Vec<u8>,
}

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

fn slot_bound(slots: impl Iterator<Item = usize>) -> usize {
    slots.max().map_or(0, |m| m + 1)
}

/// Builds the half-edge mesh of a refinement; the triangles are consistently oriented and
/// manifold by construction, so the builder must not repair anything.
pub(crate) fn build(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    level: usize,
) -> Result<Mesh, SubdivError> {
    let built = Mesh::from_triangles(positions, triangles)
        .map_err(|_| SubdivError::NotManifold { level })?;
    if built.report.repaired_anything() || built.mesh.n_vertices() != positions.len() {
        return Err(SubdivError::NotManifold { level });
    }
    Ok(built.mesh)
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
/// so [`subdivide_mcm`](super::cascadic::subdivide_mcm) builds the next level's connectivity
/// ([`quadrisect_connectivity`]) while it solves, and not at all on the last level.
pub(crate) fn quadrisection_parts(
    mesh: &HalfedgeArrays,
    coarse_positions: &[DVec3],
) -> (QuadTopology, Prolongation, Vec<DVec3>) {
    let (topo, prolongation) = quad_topology(mesh);
    let positions = prolongation.apply(coarse_positions);
    (topo, prolongation, positions)
}

/// A compatible initial marking for newest-vertex bisection.
///
/// Uniform bisection stays conforming only if every refinement edge is the refinement edge of
/// both its triangles (or lies on the boundary): the marking is a perfect matching of the
/// dual graph in which a triangle may also pair with one of its boundary edges. We take a
/// greedy matching by decreasing edge length (so that long edges get bisected first, as in
/// longest-edge bisection), then complete it with Edmonds' augmenting paths. Closed meshes
/// always have one (Petersen: the dual graph is cubic and bridgeless); an open mesh without
/// one gives [`SubdivError::NoCompatibleMarking`]. Once compatible, newest-vertex bisection
/// keeps the marking compatible on every later level.
pub(crate) fn initial_marking(mesh: &Mesh) -> Result<Marking, SubdivError> {
    let faces: Vec<_> = mesh.faces().collect();
    let nf = faces.len();
    let mut face_index = vec![NONE; slot_bound(faces.iter().map(|f| f.slot()))];
    for (i, f) in faces.iter().enumerate() {
        face_index[f.slot()] = i as u32;
    }
    // Graph nodes: faces 0..nf, then one dummy per boundary edge (adjacent to its face only).
    // adjacency: for face t, local half-edge j -> neighbour node.
    let mut nbr = vec![[NONE; 3]; nf];
    let mut dummy_face: Vec<u32> = Vec::new();
    let mut dummy_local: Vec<u8> = Vec::new();
    let mut candidates: Vec<(f64, u32, u8)> = Vec::with_capacity(3 * nf);
    for (t, &f) in faces.iter().enumerate() {
        for (j, h) in mesh.face_halfedges(f).into_iter().enumerate() {
            match mesh.face(mesh.twin(h)) {
                Some(g) => {
                    let u = face_index[g.slot()];
                    nbr[t][j] = u;
                    if (t as u32) < u {
                        candidates.push((mesh.edge_length(h), t as u32, j as u8));
                    }
                }
                None => {
                    nbr[t][j] = (nf + dummy_face.len()) as u32;
                    dummy_face.push(t as u32);
                    dummy_local.push(j as u8);
                }
            }
        }
    }
    let n = nf + dummy_face.len();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in 0..nf {
        for &u in &nbr[t] {
            if u != NONE && !adj[t].contains(&u) {
                adj[t].push(u);
            }
        }
    }
    for (d, &t) in dummy_face.iter().enumerate() {
        adj[nf + d].push(t);
    }
    // Greedy: longest interior edges first; ties by face index for determinism.
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut mate = vec![NONE; n];
    for &(_, t, j) in &candidates {
        let u = nbr[t as usize][j as usize];
        if mate[t as usize] == NONE && mate[u as usize] == NONE {
            mate[t as usize] = u;
            mate[u as usize] = t;
        }
    }
    let mut blossom = Blossom::new(n);
    for t in 0..nf {
        if mate[t] == NONE && !blossom.augment_from(t as u32, &adj, &mut mate) {
            return Err(SubdivError::NoCompatibleMarking { face: t });
        }
    }
    let mut newest = vec![0u8; nf];
    for t in 0..nf {
        let u = mate[t];
        let j = if (u as usize) < nf {
            (0..3).find(|&j| nbr[t][j] == u).unwrap_or(0)
        } else {
            dummy_local[u as usize - nf] as usize
        };
        // Half-edge j runs opposite local corner (j + 2) % 3.
        newest[t] = ((j + 2) % 3) as u8;
    }
    // Two faces sharing more than one edge must agree on which one: use the half-edge the
    // lower face picked and its twin for the partner.
    for t in 0..nf {
        let u = mate[t] as usize;
        if u < nf && t < u {
            let j = (newest[t] as usize + 1) % 3;
            let h = mesh.face_halfedges(faces[t])[j];
            let twin = mesh.twin(h);
            if let Some(k) = mesh
                .face_halfedges(faces[u])
                .iter()
                .position(|&g| g == twin)
            {
                newest[u] = ((k + 2) % 3) as u8;
            }
        }
    }
    Ok(Marking { newest })
}

/// Edmonds' blossom search (BFS with base contraction), reused across roots.
struct Blossom {
    parent: Vec<u32>,
    base: Vec<u32>,
    used: Vec<bool>,
    in_blossom: Vec<bool>,
    on_path: Vec<bool>,
    queue: Vec<u32>,
}

impl Blossom {
    fn new(n: usize) -> Self {
        Blossom {
            parent: vec![NONE; n],
            base: (0..n as u32).collect(),
            used: vec![false; n],
            in_blossom: vec![false; n],
            on_path: vec![false; n],
            queue: Vec::new(),
        }
    }

    fn lca(&mut self, mut a: u32, mut b: u32, mate: &[u32]) -> u32 {
        self.on_path.iter_mut().for_each(|x| *x = false);
        loop {
            a = self.base[a as usize];
            self.on_path[a as usize] = true;
            if mate[a as usize] == NONE {
                break;
            }
            a = self.parent[mate[a as usize] as usize];
        }
        loop {
            b = self.base[b as usize];
            if self.on_path[b as usize] {
                return b;
            }
            b = self.parent[mate[b as usize] as usize];
        }
    }

    fn mark_path(&mut self, mut v: u32, b: u32, mut child: u32, mate: &[u32]) {
        while self.base[v as usize] != b {
            let m = mate[v as usize];
            self.in_blossom[self.base[v as usize] as usize] = true;
            self.in_blossom[self.base[m as usize] as usize] = true;
            self.parent[v as usize] = child;
            child = m;
            v = self.parent[m as usize];
        }
    }

    /// Finds an augmenting path from the free node `root` and flips it; false if none.
    fn augment_from(&mut self, root: u32, adj: &[Vec<u32>], mate: &mut [u32]) -> bool {
        let n = self.base.len();
        self.used.iter_mut().for_each(|x| *x = false);
        self.parent.iter_mut().for_each(|x| *x = NONE);
        for i in 0..n {
            self.base[i] = i as u32;
        }
        self.used[root as usize] = true;
        self.queue.clear();
        self.queue.push(root);
        let mut qi = 0;
        while qi < self.queue.len() {
            let v = self.queue[qi];
            qi += 1;
            for &to in &adj[v as usize] {
                if self.base[v as usize] == self.base[to as usize] || mate[v as usize] == to {
                    continue;
                }
                if to == root
                    || (mate[to as usize] != NONE
                        && self.parent[mate[to as usize] as usize] != NONE)
                {
                    let cur = self.lca(v, to, mate);
                    self.in_blossom.iter_mut().for_each(|x| *x = false);
                    self.mark_path(v, cur, to, mate);
                    self.mark_path(to, cur, v, mate);
                    for i in 0..n {
                        if self.in_blossom[self.base[i] as usize] {
                            self.base[i] = cur;
                            if !self.used[i] {
                                self.used[i] = true;
                                self.queue.push(i as u32);
                            }
                        }
                    }
                } else if self.parent[to as usize] == NONE {
                    self.parent[to as usize] = v;
                    if mate[to as usize] == NONE {
                        // Flip the alternating path ending at `to`.
                        let mut u = to;
                        while u != NONE {
                            let pu = self.parent[u as usize];
                            let next = mate[pu as usize];
                            mate[u as usize] = pu;
                            mate[pu as usize] = u;
                            u = next;
                        }
                        return true;
                    }
                    let m = mate[to as usize];
                    self.used[m as usize] = true;
                    self.queue.push(m);
                }
            }
        }
        false
    }
}

/// One level of newest-vertex bisection: every face is split at the midpoint `m` of its
/// refinement edge into `(m, z0, z1)` and `(m, z2, z0)` (z0 = newest vertex), and `m` becomes
/// the newest vertex of both children. Returns the refined mesh and the children's marking.
///
/// Fails with [`SubdivError::NoCompatibleMarking`] if the marking is not compatible (a
/// refinement edge that is not the refinement edge of the face across it).
pub fn bisect(mesh: &Mesh, marking: &Marking) -> Result<(Refined, Marking), SubdivError> {
    let level = BisectionLevel::from_mesh(mesh, marking)?;
    let (fine, prolongation) = bisect_level(&level, mesh.n_vertices())?;
    let positions = prolongation.apply(&mesh.positions());
    let built = build(&positions, &fine.triangles, 1)?;
    // Children's newest vertex is `m`, at local index 0 as emitted; find it in the built
    // face's own vertex order rather than relying on the builder keeping corner order.
    let newest = built
        .faces()
        .zip(&fine.triangles)
        .map(|(f, tri)| {
            let m = tri[0] as usize;
            built
                .face_vertices(f)
                .iter()
                .position(|v| v.slot() == m)
                .unwrap_or(0) as u8
        })
        .collect();
    Ok((
        Refined {
            mesh: built,
            triangles: fine.triangles,
            prolongation,
        },
        Marking { newest },
    ))
}

/// A bisection level in flat arrays, what [`bisect_level`] reads and writes instead of a
/// half-edge mesh (building one per level took most of a bisection's time and memory).
pub(crate) struct BisectionLevel {
    /// The faces, vertex order as [`Mesh::face_vertices`].
    pub triangles: Vec<[u32; 3]>,
    /// For face `t` and its edge `j` (from corner `j` to corner `j + 1`): the face edge across
    /// it as `3t' + j'`, [`NONE`] on a boundary.
    pub across: Vec<[u32; 3]>,
    /// The local index of each face's newest vertex.
    pub newest: Vec<u8>,
}

impl BisectionLevel {
    /// The level of `mesh` (elements numbered by slot order) with `marking`.
    pub(crate) fn from_mesh(mesh: &Mesh, marking: &Marking) -> Result<Self, SubdivError> {
        let a = HalfedgeArrays::from_mesh(mesh);
        let nf = a.n_faces();
        if marking.newest.len() != nf {
            return Err(SubdivError::InvalidOption {
                name: "marking",
                why: format!("has {} entries for {} faces", marking.newest.len(), nf),
            });
        }
        let corner = a.corners();
        Ok(BisectionLevel {
            triangles: (0..nf).map(|t| a.face_vertices(t)).collect(),
            across: (0..nf)
                .map(|t| a.face_halfedges(t).map(|h| corner[a.get(h).twin as usize]))
                .collect(),
            newest: marking.newest.iter().map(|k| k % 3).collect(),
        })
    }
}

/// One level of newest-vertex bisection on flat arrays (see [`bisect`]): the refined level,
/// whose faces are `2t` = `(m, z0, z1)` and `2t + 1` = `(m, z2, z0)` for face `t` with newest
/// vertex `z0`, and the prolongation from `n_vertices` coarse vertices. New vertices are
/// numbered in face order, at the first face that refines their edge.
pub(crate) fn bisect_level(
    level: &BisectionLevel,
    n_vertices: usize,
) -> Result<(BisectionLevel, Prolongation), SubdivError> {
    let BisectionLevel {
        triangles,
        across,
        newest,
    } = level;
    let nf = triangles.len();
    // The face edge opposite the newest vertex, as 3t + j.
    let refinement = |t: usize| (3 * t + (newest[t] as usize + 1) % 3) as u32;
    // The face edge across face t's refinement edge (NONE on the boundary).
    let partner = |t: usize| across[t][refinement(t) as usize % 3];
    let mut parents: Vec<[u32; 2]> = (0..n_vertices as u32).map(|i| [i, i]).collect();
    let mut mid = vec![NONE; 3 * nf];
    for (t, v) in triangles.iter().enumerate() {
        let c = refinement(t);
        if mid[c as usize] == NONE {
            let m = parents.len() as u32;
            mid[c as usize] = m;
            let twin = partner(t);
            if twin != NONE {
                mid[twin as usize] = m;
            }
            let j = c as usize % 3;
            parents.push([v[j], v[(j + 1) % 3]]);
        }
    }
    // Conformity: the face across every refinement edge must refine the same edge.
    for t in 0..nf {
        let (c, twin) = (refinement(t), partner(t));
        if twin != NONE {
            let u = twin as usize / 3;
            if refinement(u) != twin {
                return Err(SubdivError::NoCompatibleMarking { face: t });
            }
            // Both sides' new edges would join the midpoint to the same apex.
            let apex = |t: usize, c: u32| triangles[t][(c as usize % 3 + 2) % 3];
            if apex(t, c) == apex(u, twin) {
                return Err(SubdivError::FoldedPair { face: t });
            }
        }
    }
    // The child edge that is coarse face edge e (not a refinement edge): face u's edge k_u
    // (z0 → z1) is edge 1 of child 2u, its edge k_u + 2 (z2 → z0) edge 1 of child 2u + 1.
    let child_edge = |e: u32| {
        if e == NONE {
            return NONE;
        }
        let u = e / 3;
        if e % 3 == u32::from(newest[u as usize]) {
            6 * u + 1
        } else {
            6 * u + 4
        }
    };
    let mut fine = BisectionLevel {
        triangles: Vec::with_capacity(2 * nf),
        across: Vec::with_capacity(2 * nf),
        newest: vec![0; 2 * nf],
    };
    for t in 0..nf {
        let k = newest[t] as usize;
        let v = triangles[t];
        let (z0, z1, z2) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
        let c = refinement(t);
        let m = mid[c as usize];
        fine.triangles.push([m, z0, z1]);
        fine.triangles.push([m, z2, z0]);
        // Child a = 2t: m → z0 (twin of b's z0 → m), z0 → z1 (coarse edge k), z1 → m (twin of
        // the partner's second child's m → z1). Child b = 2t + 1: m → z2 (twin of the
        // partner's first child's z2 → m), z2 → z0 (coarse edge k + 2), z0 → m.
        let (a, b) = (6 * t as u32, 6 * t as u32 + 3);
        let (pa, pb) = match partner(t) {
            NONE => (NONE, NONE),
            p => (6 * (p / 3) + 2, 6 * (p / 3) + 3),
        };
        fine.across.push([b + 2, child_edge(across[t][k]), pb]);
        fine.across
            .push([pa, child_edge(across[t][(k + 2) % 3]), a]);
    }
    Ok((fine, Prolongation { parents }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrisection_stiffness_is_the_general_assembly_bit_for_bit() {
        use crate::numerics::fem::{cotangent_stiffness, triangle_weights};
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        // Closed with a valence-4 vertex (octahedron), open with boundary corners (a jittered
        // grid with a hole and an isolated vertex), checked at every level, with and without
        // face coefficients, on 1 and 3 threads.
        let (mut p, t) = crate::mesh::shapes::grid(6, |i, j| {
            let h = ((i * 7 + j * 13) % 5) as f64 / 10.0;
            DVec3::new(i as f64 + 0.2 * h, j as f64 - 0.1 * h, h)
        });
        p.push(DVec3::new(50.0, 50.0, 50.0)); // an isolated vertex
        let holed: Vec<[u32; 3]> = t
            .into_iter()
            .enumerate()
            .filter(|(i, _)| *i != 31)
            .map(|(_, f)| f)
            .collect();
        let grid = Mesh::from_triangles(&p, &holed).unwrap().mesh;
        // Six octahedron levels reach 16k fine rows, past the size where rows split over
        // threads.
        for (mesh, levels) in [(octahedron(), 6), (grid, 2)] {
            let mut coarse_positions = mesh.positions();
            let mut mesh = HalfedgeArrays::from_mesh(&mesh);
            for _ in 0..levels {
                let (topo, _, positions) = quadrisection_parts(&mesh, &coarse_positions);
                let coef: Vec<f64> = (0..topo.triangles.len())
                    .map(|i| 0.5 + (i % 7) as f64)
                    .collect();
                for c in [None, Some(&coef[..])] {
                    let w = triangle_weights(&topo.triangles, &positions, c);
                    let general = cotangent_stiffness(&topo.triangles, &positions, c);
                    for threads in [1, 3] {
                        let fast = rayon::ThreadPoolBuilder::new()
                            .num_threads(threads)
                            .build()
                            .unwrap()
                            .install(|| quadrisection_stiffness(&mesh, &topo, &w))
                            .expect("covered layout");
                        assert_eq!(fast.row_start, general.row_start);
                        assert_eq!(fast.col, general.col);
                        assert_eq!(bits(&fast.val), bits(&general.val));
                    }
                }
                let fine = quadrisect_connectivity(&mesh, &topo);
                // The arrays are the mesh the general builder makes of the same triangles.
                let built = build(&positions, &topo.triangles, 1).unwrap();
                assert_eq!(
                    built.to_triangles(),
                    fine.to_mesh(&positions).to_triangles()
                );
                assert!(fine.to_mesh(&positions).validate().is_ok());
                (mesh, coarse_positions) = (fine, positions);
            }
        }
    }

    fn octahedron() -> Mesh {
        let p = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ]
        .map(DVec3::from_array);
        let f = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        Mesh::from_triangles(&p, &f).unwrap().mesh
    }

    #[test]
    fn prolongation_copies_and_averages() {
        let p = Prolongation {
            parents: vec![[0, 0], [1, 1], [0, 1]],
        };
        assert_eq!(p.apply(&[2.0, 4.0]), vec![2.0, 4.0, 3.0]);
        assert_eq!(p.n_fine(), 3);
    }

    #[test]
    fn quadrisection_puts_midpoints_and_keeps_coarse_vertices_first() {
        let m = octahedron();
        let r = quadrisect(&m).unwrap();
        assert_eq!(r.mesh.n_faces(), 32);
        assert_eq!(r.mesh.n_vertices(), 6 + 12);
        assert!(r.mesh.validate().is_ok());
        // The direct construction equals the builder's, face by face.
        let (p, t) = r.mesh.to_triangles();
        let built = Mesh::from_triangles(&p, &t).unwrap();
        assert!(!built.report.repaired_anything());
        assert_eq!(built.mesh.to_triangles(), (p, t));
        let pos = r.mesh.positions();
        for (i, &[a, b]) in r.prolongation.parents().iter().enumerate() {
            let expect = (m.positions()[a as usize] + m.positions()[b as usize]) / 2.0;
            assert_eq!(pos[i], expect);
            // Midpoints join coarse neighbours only.
            if a != b {
                assert!(m.neighbors(m.vertices().nth(a as usize).unwrap()).len() == 4);
            }
        }
    }

    #[test]
    fn bisection_marking_is_compatible_and_stays_so() {
        let mut m = octahedron();
        let mut marking = initial_marking(&m).unwrap();
        let mut faces = m.n_faces();
        for _ in 0..4 {
            let (r, next) = bisect(&m, &marking).unwrap();
            assert_eq!(r.mesh.n_faces(), 2 * faces);
            assert_eq!(r.mesh.topology().euler_characteristic, 2);
            faces = r.mesh.n_faces();
            m = r.mesh;
            marking = next;
        }
    }

    #[test]
    fn flat_bisection_levels_are_the_levels_of_the_built_meshes() {
        // Closed (octahedron) and open (a jittered grid with a hole, marked with boundary
        // edges): after each flat level, the neighbours across every face edge are those of
        // the half-edge mesh the builder makes of the same triangles, and the newest vertex is
        // the one the mesh-based step finds.
        let (p, t) = crate::mesh::shapes::grid(4, |i, j| {
            DVec3::new(i as f64 + 0.1 * ((i * j) % 3) as f64, j as f64, 0.0)
        });
        let t: Vec<[u32; 3]> = t
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| i != 12 && i != 13)
            .map(|(_, f)| f)
            .collect();
        let grid = Mesh::from_triangles(&p, &t).unwrap().mesh;
        for mut mesh in [octahedron(), grid] {
            let mut marking = initial_marking(&mesh).unwrap();
            let mut level = BisectionLevel::from_mesh(&mesh, &marking).unwrap();
            for _ in 0..5 {
                let (fine, prolongation) = bisect_level(&level, mesh.n_vertices()).unwrap();
                let (refined, next) = bisect(&mesh, &marking).unwrap();
                assert_eq!(prolongation, refined.prolongation);
                assert_eq!(fine.triangles, refined.triangles);
                let built = BisectionLevel::from_mesh(&refined.mesh, &next).unwrap();
                assert_eq!(fine.triangles, built.triangles);
                assert_eq!(fine.across, built.across);
                assert_eq!(fine.newest, built.newest);
                (mesh, marking, level) = (refined.mesh, next, fine);
            }
        }
    }

    #[test]
    fn incompatible_marking_is_rejected() {
        let m = octahedron();
        let mut marking = initial_marking(&m).unwrap();
        marking.newest[0] = (marking.newest[0] + 1) % 3;
        assert!(matches!(
            bisect(&m, &marking),
            Err(SubdivError::NoCompatibleMarking { .. })
        ));
    }

    #[test]
    fn marking_on_an_open_strip_uses_boundary_edges() {
        // Three triangles in a fan: an odd count, so one must take a boundary edge.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ]
        .map(DVec3::from_array);
        let m = Mesh::from_triangles(&p, &[[0, 1, 2], [0, 2, 3], [0, 3, 4]])
            .unwrap()
            .mesh;
        let marking = initial_marking(&m).unwrap();
        let (r, _) = bisect(&m, &marking).unwrap();
        assert_eq!(r.mesh.n_faces(), 6);
        assert!(r.mesh.validate().is_ok());
        // Direct quadrisection of an open mesh: valid, boundary loop intact, and the same
        // faces the generic builder makes.
        let q = quadrisect(&m).unwrap().mesh;
        assert!(q.validate().is_ok());
        assert_eq!(q.topology().boundary_loops, 1);
        assert_eq!(q.topology().euler_characteristic, 1);
        let (p, t) = q.to_triangles();
        assert_eq!(
            Mesh::from_triangles(&p, &t).unwrap().mesh.to_triangles(),
            (p, t)
        );
        let boundary = q.vertices().filter(|&v| q.is_boundary_vertex(v)).count();
        assert_eq!(boundary, 2 * 5);
    }
}
