//! Building a half-edge [`Mesh`] from indexed polygons, repairing what would break the
//! half-edge invariants and counting every repair in a [`BuildReport`].
//!
//! The policy (never fails on topology):
//! 1. Polygons are fan-triangulated; triangles with a repeated vertex index are dropped.
//!    Zero-area triangles are kept (they are counted).
//! 2. Each undirected edge pairs at most two triangles. An edge with more (a non-manifold
//!    edge) pairs the first triangle with the first later one of opposite direction (or the
//!    second, if none), and the rest become boundary along that edge.
//! 3. Orientation is made consistent per connected component by a breadth-first walk from the
//!    component's first triangle; the majority orientation wins. Where a component cannot be
//!    oriented (a Möbius band) the offending edge is cut.
//! 4. Every vertex whose triangles form more than one fan (a pinched vertex, or the endpoint of
//!    a cut edge) gets one copy per extra fan, appended after the input's vertices.
//!
//! Input vertices keep their slots `0..n` in input order (unreferenced ones stay, isolated);
//! faces keep the order of the triangles they come from. [`SourceMap`] maps mesh vertices and
//! faces back onto the input, so processed results can be written in the user's layout.

use super::halfedge::{
    FaceId, FaceRecord, HalfedgeId, HalfedgeRecord, Mesh, VertexId, VertexRecord,
};
use super::polygon::PolygonMesh;
use glam::DVec3;
use serde::Serialize;

/// What the builder changed, in counts. All zero for a clean manifold triangle mesh.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BuildReport {
    /// Polygons with more than three corners that were fan-triangulated.
    pub triangulated_polygons: usize,
    /// Triangles dropped because a vertex index repeats in them.
    pub dropped_repeated_index: usize,
    /// Triangles of zero area (kept).
    pub zero_area_faces: usize,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangles form several fans although all their edges are manifold
    /// (pinched vertices).
    pub non_manifold_vertices: usize,
    /// Vertex copies added so that every vertex has a single fan.
    pub split_vertices: usize,
    /// Triangles whose orientation was flipped to agree with their neighbours.
    pub flipped_faces: usize,
    /// Edges cut because their two triangles could not be oriented consistently.
    pub orientation_cuts: usize,
    /// Input vertices no face refers to (kept, isolated).
    pub unreferenced_vertices: usize,
}

impl BuildReport {
    /// True when the input was already a manifold mesh (no non-manifold edge or vertex).
    pub fn input_was_manifold(&self) -> bool {
        self.non_manifold_edges == 0 && self.non_manifold_vertices == 0
    }

    /// True when the builder changed the connectivity in any way.
    pub fn repaired_anything(&self) -> bool {
        self.triangulated_polygons
            + self.dropped_repeated_index
            + self.non_manifold_edges
            + self.split_vertices
            + self.flipped_faces
            + self.orientation_cuts
            > 0
    }
}

/// Where each mesh element came from in the input.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SourceMap {
    /// Input vertex index of each mesh vertex, in mesh slot order. The first
    /// `input_vertices` entries are the identity; split copies follow.
    pub vertex_source: Vec<u32>,
    /// Input polygon index of each mesh face, in mesh slot order.
    pub face_source: Vec<u32>,
    /// Number of vertices in the input.
    pub input_vertices: usize,
}

impl SourceMap {
    /// Maps per-mesh-vertex values back onto the input's vertices. A vertex that was split
    /// gets the mean of its copies; vertices no face refers to get `fallback[i]`.
    pub fn to_input_positions(&self, mesh_values: &[DVec3], fallback: &[DVec3]) -> Vec<DVec3> {
        let mut out = fallback.to_vec();
        let mut sum = vec![DVec3::ZERO; self.input_vertices];
        let mut count = vec![0u32; self.input_vertices];
        for (i, &src) in self.vertex_source.iter().enumerate() {
            sum[src as usize] += mesh_values[i];
            count[src as usize] += 1;
        }
        for i in 0..self.input_vertices {
            if count[i] > 0 {
                out[i] = sum[i] / count[i] as f64;
            }
        }
        out
    }
}

/// The result of building: the mesh, what was repaired, and where elements came from.
#[derive(Clone, Debug)]
pub struct Built {
    /// The half-edge mesh.
    pub mesh: Mesh,
    /// What the builder changed.
    pub report: BuildReport,
    /// Mesh → input correspondence.
    pub source: SourceMap,
}

const NONE: u32 = u32::MAX;

/// Input the builder cannot turn into a mesh.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BuildError {
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// Input vertex index.
        vertex: usize,
    },
    /// A polygon refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Input polygon index.
        face: usize,
        /// The offending index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// More than 2^32 − 1 vertices or 1.4e9 triangles.
    #[error("mesh too large for 32-bit indices")]
    TooLarge,
}

impl Mesh {
    /// Builds from a file-level polygon mesh; see the module docs for the repair policy.
    ///
    /// Fails only on geometry the mesh cannot hold: a non-finite coordinate or an index out
    /// of range (readers already reject both, so this guards programmatic input).
    pub fn from_polygons(input: &PolygonMesh) -> Result<Built, BuildError> {
        let mut report = BuildReport::default();
        let nv = input.positions.len();
        if let Some(vertex) = input.positions.iter().position(|p| !p.is_finite()) {
            return Err(BuildError::NonFinite { vertex });
        }
        if nv >= NONE as usize {
            return Err(BuildError::TooLarge);
        }
        let mut tris: Vec<[u32; 3]> = Vec::with_capacity(input.n_triangles());
        let mut tri_source: Vec<u32> = Vec::with_capacity(input.n_triangles());
        for (fi, poly) in input.faces().enumerate() {
            if poly.len() > 3 {
                report.triangulated_polygons += 1;
            }
            if let Some(&index) = poly.iter().find(|&&i| i as usize >= nv) {
                return Err(BuildError::IndexOutOfRange {
                    face: fi,
                    index,
                    vertices: nv,
                });
            }
            for k in 1..poly.len().saturating_sub(1) {
                let t = [poly[0], poly[k], poly[k + 1]];
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    report.dropped_repeated_index += 1;
                } else {
                    tris.push(t);
                    tri_source.push(fi as u32);
                }
            }
        }
        if tris.len() >= (NONE / 3) as usize {
            return Err(BuildError::TooLarge);
        }
        let (mesh, source) = build_triangles(&input.positions, &tris, &tri_source, &mut report);
        Ok(Built {
            mesh,
            report,
            source,
        })
    }

    /// Builds from positions and triangles (a convenience over [`Mesh::from_polygons`]).
    pub fn from_triangles(
        positions: &[DVec3],
        triangles: &[[u32; 3]],
    ) -> Result<Built, BuildError> {
        Mesh::from_polygons(&PolygonMesh::from_triangles(positions.to_vec(), triangles))
    }
}

/// Union-find over corners, with path halving.
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[parent[x as usize] as usize];
        parent[x as usize] = p;
        x = p;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    // Smaller root wins so the result does not depend on the order of unions.
    if ra < rb {
        parent[rb as usize] = ra;
    } else if rb < ra {
        parent[ra as usize] = rb;
    }
}

/// Counting sort of `0..keys.len()` by `keys` into CSR form (`starts`, `items`).
fn bucket(keys: impl Iterator<Item = u32> + Clone, n_buckets: usize) -> (Vec<u32>, Vec<u32>) {
    let mut starts = vec![0u32; n_buckets + 1];
    for k in keys.clone() {
        starts[k as usize + 1] += 1;
    }
    for i in 0..n_buckets {
        starts[i + 1] += starts[i];
    }
    let mut fill = starts.clone();
    let mut items = vec![0u32; starts[n_buckets] as usize];
    for (i, k) in keys.enumerate() {
        items[fill[k as usize] as usize] = i as u32;
        fill[k as usize] += 1;
    }
    (starts, items)
}

fn build_triangles(
    positions: &[DVec3],
    input_tris: &[[u32; 3]],
    tri_source: &[u32],
    report: &mut BuildReport,
) -> (Mesh, SourceMap) {
    let nv = positions.len();
    let nt = input_tris.len();
    let mut tris = input_tris.to_vec();
    // Corner/half-edge c = 3t + k runs from tris[t][k] to tris[t][(k+1)%3].
    let he_from = |tris: &[[u32; 3]], c: u32| tris[c as usize / 3][c as usize % 3];
    let he_to = |tris: &[[u32; 3]], c: u32| tris[c as usize / 3][(c as usize % 3 + 1) % 3];

    for t in &tris {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        if (b - a).cross(c - a).length_squared() == 0.0 {
            report.zero_area_faces += 1;
        }
    }

    // --- 1. group half-edges by undirected edge: bucket by the smaller endpoint, then match
    // the larger endpoint inside the (small) bucket. Linear time, deterministic.
    let nh = 3 * nt;
    let (starts, items) = bucket(
        (0..nh as u32).map(|c| he_from(&tris, c).min(he_to(&tris, c))),
        nv,
    );
    let mut mate = vec![NONE; nh];
    let mut scratch: Vec<(u32, u32)> = Vec::new();
    for lo in 0..nv {
        // Sorting the bucket by the far endpoint keeps high-valence vertices O(k log k).
        scratch.clear();
        scratch.extend(
            items[starts[lo] as usize..starts[lo + 1] as usize]
                .iter()
                .map(|&c| (he_from(&tris, c).max(he_to(&tris, c)), c)),
        );
        scratch.sort_unstable();
        for group in scratch.chunk_by(|a, b| a.0 == b.0) {
            if group.len() < 2 {
                continue;
            }
            let first = group[0].1;
            let partner = if group.len() == 2 {
                group[1].1
            } else {
                report.non_manifold_edges += 1;
                let dir = he_from(&tris, first);
                group[1..]
                    .iter()
                    .map(|g| g.1)
                    .find(|&d| he_from(&tris, d) != dir)
                    .unwrap_or(group[1].1)
            };
            mate[first as usize] = partner;
            mate[partner as usize] = first;
        }
    }

    // --- 2. consistent orientation per component (BFS over paired edges).
    let mut state = vec![0u8; nt]; // 0 unvisited, 1 kept, 2 flipped
    let mut queue: Vec<u32> = Vec::new();
    let mut component: Vec<u32> = Vec::new();
    for seed in 0..nt {
        if state[seed] != 0 {
            continue;
        }
        state[seed] = 1;
        queue.clear();
        component.clear();
        queue.push(seed as u32);
        let mut qi = 0;
        while qi < queue.len() {
            let t = queue[qi] as usize;
            qi += 1;
            component.push(t as u32);
            for k in 0..3 {
                let c = (3 * t + k) as u32;
                let m = mate[c as usize];
                if m == NONE {
                    continue;
                }
                let u = m as usize / 3;
                // Opposite directions agree when both triangles have the same state.
                let same_dir = he_from(&tris, c) == he_from(&tris, m);
                let want = if same_dir { 3 - state[t] } else { state[t] };
                if state[u] == 0 {
                    state[u] = want;
                    queue.push(u as u32);
                } else if state[u] != want {
                    mate[c as usize] = NONE;
                    mate[m as usize] = NONE;
                    report.orientation_cuts += 1;
                }
            }
        }
        let flipped = component
            .iter()
            .filter(|&&t| state[t as usize] == 2)
            .count();
        if 2 * flipped > component.len() {
            for &t in &component {
                state[t as usize] = 3 - state[t as usize];
            }
        }
    }
    // Flip: [a,b,c] -> [a,c,b]; local edge j becomes edge 2 - j.
    let mut mate2 = vec![NONE; nh];
    let remap = |state: &[u8], c: u32| -> u32 {
        let t = c / 3;
        if state[t as usize] == 2 {
            3 * t + (2 - c % 3)
        } else {
            c
        }
    };
    for c in 0..nh as u32 {
        if mate[c as usize] != NONE {
            mate2[remap(&state, c) as usize] = remap(&state, mate[c as usize]);
        }
    }
    let mate = mate2;
    for (t, tri) in tris.iter_mut().enumerate() {
        if state[t] == 2 {
            tri.swap(1, 2);
            report.flipped_faces += 1;
        }
    }

    // --- 3. split vertices into fans. Corner c = 3t + k sits at tris[t][k]; half-edge c leaves
    // that corner, so across a pair (c, m) corner c meets corner next(m) and next(c) meets m.
    let next_c = |c: u32| 3 * (c / 3) + (c % 3 + 1) % 3;
    let mut parent: Vec<u32> = (0..nh as u32).collect();
    for c in 0..nh as u32 {
        let m = mate[c as usize];
        if m != NONE && c < m {
            union(&mut parent, c, next_c(m));
            union(&mut parent, next_c(c), m);
        }
    }
    let (vstarts, vitems) = bucket((0..nh as u32).map(|c| he_from(&tris, c)), nv);
    let mut corner_vertex = vec![0u32; nh];
    let mut vertex_source: Vec<u32> = (0..nv as u32).collect();
    let mut roots: Vec<u32> = Vec::new();
    for v in 0..nv {
        let corners = &vitems[vstarts[v] as usize..vstarts[v + 1] as usize];
        if corners.is_empty() {
            report.unreferenced_vertices += 1;
            continue;
        }
        roots.clear();
        for &c in corners {
            let r = find(&mut parent, c);
            let slot = match roots.iter().position(|&x| x == r) {
                Some(i) => i,
                None => {
                    roots.push(r);
                    roots.len() - 1
                }
            };
            corner_vertex[c as usize] = if slot == 0 {
                v as u32
            } else {
                (nv + slot - 1) as u32 // provisional, fixed below
            };
        }
        if roots.len() > 1 {
            // Real ids of the copies: appended in order of (vertex, fan).
            let base = vertex_source.len() as u32;
            for &c in corners {
                let cv = corner_vertex[c as usize];
                if cv != v as u32 {
                    corner_vertex[c as usize] = base + (cv - nv as u32);
                }
            }
            for _ in 1..roots.len() {
                vertex_source.push(v as u32);
            }
            report.split_vertices += roots.len() - 1;
        }
    }
    // Pinched vertices: several fans although no cut or non-manifold edge touches them.
    // (A boundary edge that simply has one triangle is unpaired too, so test the vertex's
    // edges for having more than one triangle.)
    report.non_manifold_vertices =
        count_pinched(&tris, &mate, &vstarts, &vitems, &vertex_source, nv);

    // --- 4. assemble the half-edge structure.
    let n_total = vertex_source.len();
    let mut mesh = Mesh::new();
    mesh.vertices.reserve(n_total);
    let vids: Vec<VertexId> = vertex_source
        .iter()
        .map(|&s| {
            mesh.vertices.insert(VertexRecord {
                halfedge: None,
                position: positions[s as usize],
            })
        })
        .collect();
    let n_boundary = mate.iter().filter(|&&m| m == NONE).count();
    mesh.halfedges.reserve(nh + n_boundary);
    mesh.faces.reserve(nt);
    let null = HalfedgeId::default();
    let hids: Vec<HalfedgeId> = (0..nh)
        .map(|c| {
            mesh.halfedges.insert(HalfedgeRecord {
                to: vids[corner_vertex[next_c(c as u32) as usize] as usize],
                next: null,
                prev: null,
                twin: null,
                face: None,
            })
        })
        .collect();
    let fids: Vec<FaceId> = (0..nt)
        .map(|t| {
            mesh.faces.insert(FaceRecord {
                halfedge: hids[3 * t],
            })
        })
        .collect();
    for c in 0..nh {
        let t = c / 3;
        let h = hids[c];
        let r = &mut mesh.halfedges[h];
        r.next = hids[3 * t + (c + 1) % 3];
        r.prev = hids[3 * t + (c + 2) % 3];
        r.face = Some(fids[t]);
        if mate[c] != NONE {
            r.twin = hids[mate[c] as usize];
        }
        let from = vids[corner_vertex[c] as usize];
        mesh.vertices[from].halfedge.get_or_insert(h);
    }
    // Boundary half-edges, and per vertex its (unique, after splitting) boundary out-edge.
    let mut boundary_out: Vec<Option<HalfedgeId>> = vec![None; n_total];
    let mut boundary: Vec<(HalfedgeId, usize)> = Vec::with_capacity(n_boundary);
    for c in 0..nh {
        if mate[c] != NONE {
            continue;
        }
        let h = hids[c];
        let from = corner_vertex[c] as usize;
        let b = mesh.halfedges.insert(HalfedgeRecord {
            to: vids[from],
            next: null,
            prev: null,
            twin: h,
            face: None,
        });
        mesh.halfedges[h].twin = b;
        // b runs to -> from of h, so it leaves the vertex at h's head.
        let head = corner_vertex[next_c(c as u32) as usize] as usize;
        boundary_out[head] = Some(b);
        boundary.push((b, from));
    }
    for &(b, to) in &boundary {
        if let Some(n) = boundary_out[to] {
            mesh.halfedges[b].next = n;
            mesh.halfedges[n].prev = b;
        }
    }
    for (i, &v) in vids.iter().enumerate() {
        if let Some(b) = boundary_out[i] {
            mesh.vertices[v].halfedge = Some(b);
        }
    }
    let face_source = tri_source.to_vec();
    (
        mesh,
        SourceMap {
            vertex_source,
            face_source,
            input_vertices: nv,
        },
    )
}

/// Counts input vertices with several fans when every undirected edge with exactly two
/// triangles is considered joined (orientation ignored) — the classic "pinched vertex" test,
/// independent of the cuts made for non-manifold edges.
fn count_pinched(
    tris: &[[u32; 3]],
    mate: &[u32],
    vstarts: &[u32],
    vitems: &[u32],
    vertex_source: &[u32],
    nv: usize,
) -> usize {
    let mut split = vec![0u32; nv];
    for &s in &vertex_source[nv..] {
        split[s as usize] += 1;
    }
    let mut pinched = 0;
    for v in 0..nv {
        if split[v] == 0 {
            continue;
        }
        // A vertex is "pinched" if none of its incident half-edges was cut from a partner
        // (i.e. every unpaired half-edge at v is a genuine one-triangle boundary edge).
        let corners = &vitems[vstarts[v] as usize..vstarts[v + 1] as usize];
        let mut edge_ok = true;
        for &c in corners {
            for e in [c, 3 * (c / 3) + (c % 3 + 2) % 3] {
                if mate[e as usize] == NONE && edge_multiplicity(tris, vitems, vstarts, e) > 1 {
                    edge_ok = false;
                }
            }
        }
        if edge_ok {
            pinched += 1;
        }
    }
    pinched
}

/// Number of triangles on the undirected edge of half-edge `e`.
fn edge_multiplicity(tris: &[[u32; 3]], vitems: &[u32], vstarts: &[u32], e: u32) -> usize {
    let t = tris[e as usize / 3];
    let (a, b) = (t[e as usize % 3], t[(e as usize % 3 + 1) % 3]);
    let corners = &vitems[vstarts[a as usize] as usize..vstarts[a as usize + 1] as usize];
    corners
        .iter()
        .filter(|&&c| {
            let tt = tris[c as usize / 3];
            tt.contains(&b)
        })
        .count()
}
