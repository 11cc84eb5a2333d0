//! Conforming newest-vertex bisection: a compatible initial marking (a perfect matching of
//! the dual graph, completed with Edmonds' blossoms), and the levels on flat arrays.

use super::{Prolongation, Refined, build};
use crate::mesh::{Mesh, SlotIndex};
use crate::subdiv::SubdivError;
use crate::subdiv::halfedge_arrays::{HalfedgeArrays, NONE};

/// Newest-vertex marking for bisection: for each face (slot order), the local index (0..3,
/// in [`Mesh::face_vertices`] order) of its newest vertex. The refinement edge is the edge
/// opposite that vertex.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Marking {
    pub(super) newest: Vec<u8>,
}

fn slot_bound(slots: impl Iterator<Item = usize>) -> usize {
    slots.max().map_or(0, |m| m + 1)
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
