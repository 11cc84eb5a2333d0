//! Greedy quadric-error decimation by half-edge collapses: the engine behind
//! [`ProgressiveMesh::build`](super::ProgressiveMesh::build) and `meshpyr simplify`.
//!
//! Every edge is evaluated in both directions (`u→v` keeps `v`'s original position, so the
//! cost is `(Q_u + Q_v)(p_v)`, normalised to a squared distance). The priority queue is
//! batched, in the manner of meshoptimizer: each pass evaluates all live edges, sorts them by
//! `(cost, half-edge slot)` and collapses them in that order, skipping an edge once one of its
//! endpoints was the survivor of a collapse in this pass — the only vertex whose quadric
//! changed — so every cost used is exact. A pass stops at the target or once costs exceed
//! 1.5× the cost of the candidate that would meet the pass's share of the target, which keeps
//! the order close to a global heap's. Legality ([`super::Legality`]) is tested when an edge's
//! turn comes; an illegal cheaper direction falls back to the other one. A collapse that leaves
//! a new sliver adds its penalty to its cost and waits while that exceeds the pass's cut, and
//! each pass's normal bound is the one for its level ([`super::Legality`]'s widening towards
//! the coarse end; `docs/pm-legality.md`). A pass that finds no
//! legal collapse is repeated without the cost cut, then with the shape rules relaxed step by
//! step ([`Schedule`]; `docs/pm-legality.md`); the build ends when even that finds none, so "no
//! legal collapse left" really means none, and [`Stop`] says which rules refused what is left.
//! A decimation that keeps texture seams relaxes nothing: its floor is the seam floor, where
//! the relaxed rules would fold faces across the charts (`docs/seams.md`). Nor does it take
//! every legal collapse there for a target it cannot reach: a pass without the cost cut takes
//! none dearer than [`SEAM_FLOOR_COST_FACTOR`] times the dearest one made under a cut.
//!
//! **Why a corner table.** The collapses visit the mesh in cost order, i.e. at random, so the
//! time goes into cache misses on the records a legality test walks. The decimator therefore
//! works on a flat corner table instead of the slotmap half-edge [`Mesh`]: triangle `t` owns
//! corners `3t..3t+3`, half-edge `c` runs from corner `c` to the next corner of its triangle
//! (`next`/`prev` are arithmetic), and each corner stores its vertex and its half-edge's twin,
//! so a face is 24 contiguous bytes. Boundary half-edges, which have no corner, get ids after
//! the corners; they only ever need their twin. Each vertex's position and state share one
//! 32-byte record, and the loop prefetches the records of the candidates a few places ahead
//! ([`super::prefetch`]).
//!
//! **Same result as on the half-edge mesh.** Half-edge ids keep the order of the source mesh's
//! half-edge slots ([`FlatMesh::from_mesh`]; for the builder's own output ids *are* the slots),
//! ties are broken by slot, and the legality tests are those of [`super::collapse`] written for
//! the corner table, so the collapse sequence is identical to collapsing the [`Mesh`] itself
//! (a test replays it against the half-edge implementation).

use super::legality::{Legality, Refusal, Relaxation, RingFace, shape_check};
use super::prefetch::prefetch;
use super::quadric::{POINT_REGULARISATION, Quadric, Quadrics};
use super::seams::Seams;
use crate::mesh::build::{next_c, prev_c};
use crate::mesh::{BoundingBox, CornerTable, Mesh, SlotIndex};
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;

/// What to stop at and what to forbid (the library-level subset of `PmOptions`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DecimateParams {
    pub target_vertices: usize,
    pub target_faces: usize,
    /// Largest allowed normalised quadric error (a squared distance), `f64::INFINITY` for none.
    pub max_error_sq: f64,
    pub legality: Legality,
    pub boundary_weight: f64,
}

/// One performed collapse, as vertex slots (`u32::MAX` = none), and its error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Collapse {
    pub from: u32,
    pub to: u32,
    pub left: u32,
    pub right: u32,
    pub error_sq: f64,
}

const NONE: u32 = u32::MAX;

/// A vertex of the working mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Vertex {
    position: DVec3,
    /// A live corner at the vertex, `NONE` for isolated and removed vertices.
    corner: u32,
    /// Number of out-going half-edges (= neighbours) in the low 30 bits (a mesh has fewer than
    /// 2^30 triangles around one vertex in any realistic input; the builder caps meshes at
    /// 1.4e9 triangles), and the `BOUNDARY` and `LOCKED` flags. Whether a vertex lies on a boundary never changes: a boundary vertex
    /// only slides along its boundary and the link condition keeps the surface manifold.
    valence_flags: u32,
}

const BOUNDARY: u32 = 1 << 31;
/// The survivor of a collapse in the current pass: its quadric changed, so its edges wait for
/// the next pass.
const LOCKED: u32 = 1 << 30;
/// A vertex on a block border of a partitioned build (`block.rs`): no edge at it collapses.
const PINNED: u32 = 1 << 29;
const VALENCE: u32 = PINNED - 1;

/// A corner: its vertex and the twin of the half-edge that leaves it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Corner {
    vertex: u32,
    twin: u32,
}

/// Below this many triangles a pass's candidate scan and sort stay on one thread.
const PAR_MIN: usize = 1 << 14;

/// The decimator's working mesh: a corner table with per-vertex state. Vertices are the source
/// mesh's vertex slots; removed and isolated vertices have no corner.
#[derive(Clone, Debug)]
pub(crate) struct FlatMesh {
    /// Per-vertex state, one 32-byte record per vertex so that a legality test pays one
    /// cache miss per vertex it touches.
    vertices: Vec<Vertex>,
    /// Vertex and twin of every corner, a triangle's three corners next to each other so that
    /// a ring walk touches one cache line per face. All three vertices of a removed triangle
    /// are `NONE`.
    corners: Vec<Corner>,
    /// Twin of every boundary half-edge (id `n_corners + i` at `i`), `NONE` once the collapse
    /// of its edge removed it.
    boundary_twin: Vec<u32>,
    /// Source slot of every half-edge id, for tie-breaking; `None` when ids are the slots.
    slot: Option<Vec<u32>>,
    n_faces: usize,
    /// Vertices with at least one face.
    n_vertices: usize,
}

impl FlatMesh {
    /// The working mesh of the builder's output: vertex `i` at `positions[i]`, half-edge ids
    /// equal to the slots [`Mesh::from_polygons`] would give (`CornerTable` docs).
    pub(crate) fn from_corners(positions: Vec<DVec3>, corners: &CornerTable) -> FlatMesh {
        let nh = corners.corner_vertex.len();
        let nb = corners.mate.iter().filter(|&&m| m == NONE).count();
        let mut twin = Vec::with_capacity(nh + nb);
        twin.extend_from_slice(&corners.mate);
        for c in 0..nh as u32 {
            if twin[c as usize] == NONE {
                twin[c as usize] = twin.len() as u32;
                twin.push(c);
            }
        }
        FlatMesh::with_vertex_state(positions, &corners.corner_vertex, twin, None)
    }

    /// The working mesh of any valid half-edge mesh: triangle `t` is the `t`-th face in slot
    /// order with corners starting at its stored half-edge (as [`Mesh::face_vertices`]), and
    /// boundary half-edges are numbered in slot order.
    pub(super) fn from_mesh(mesh: &Mesh) -> FlatMesh {
        let n_vslots = mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0);
        let n_hslots = mesh.halfedges().map(|h| h.slot() + 1).max().unwrap_or(0);
        let mut positions = vec![DVec3::ZERO; n_vslots];
        for v in mesh.vertices() {
            positions[v.slot()] = mesh.position(v);
        }
        let mut id_of_slot = vec![NONE; n_hslots];
        let mut slot: Vec<u32> = Vec::with_capacity(n_hslots);
        let mut corner_vertex = Vec::with_capacity(3 * mesh.n_faces());
        for f in mesh.faces() {
            for h in mesh.face_halfedges(f) {
                id_of_slot[h.slot()] = slot.len() as u32;
                slot.push(h.slot() as u32);
                corner_vertex.push(mesh.from_vertex(h).slot() as u32);
            }
        }
        let boundary: Vec<_> = mesh
            .halfedges()
            .filter(|&h| mesh.is_boundary_halfedge(h))
            .collect();
        for &h in &boundary {
            id_of_slot[h.slot()] = slot.len() as u32;
            slot.push(h.slot() as u32);
        }
        let mut twin = Vec::with_capacity(slot.len());
        for f in mesh.faces() {
            for h in mesh.face_halfedges(f) {
                twin.push(id_of_slot[mesh.twin(h).slot()]);
            }
        }
        for &h in &boundary {
            twin.push(id_of_slot[mesh.twin(h).slot()]);
        }
        let identity = slot.iter().enumerate().all(|(i, &s)| i as u32 == s);
        let slot = (!identity).then_some(slot);
        FlatMesh::with_vertex_state(positions, &corner_vertex, twin, slot)
    }

    fn with_vertex_state(
        positions: Vec<DVec3>,
        corner_vertex: &[u32],
        twin: Vec<u32>,
        slot: Option<Vec<u32>>,
    ) -> FlatMesh {
        let mut mesh = FlatMesh::at_positions(positions, corner_vertex, twin, slot);
        mesh.recentre();
        mesh
    }

    /// [`Self::with_vertex_state`] without moving the positions to the bounding box's centre
    /// (the blocks of a partitioned build share the whole mesh's frame: `block.rs`).
    pub(crate) fn at_positions(
        positions: Vec<DVec3>,
        corner_vertex: &[u32],
        twin: Vec<u32>,
        slot: Option<Vec<u32>>,
    ) -> FlatMesh {
        let nh = corner_vertex.len();
        let mut vertices: Vec<Vertex> = positions
            .iter()
            .map(|&position| Vertex {
                position,
                corner: NONE,
                valence_flags: 0,
            })
            .collect();
        for (c, &v) in corner_vertex.iter().enumerate() {
            let x = &mut vertices[v as usize];
            if x.corner == NONE {
                x.corner = c as u32;
            }
            x.valence_flags += 1;
            if twin[c] as usize >= nh {
                // The boundary twin of c leaves c's head.
                x.valence_flags |= BOUNDARY;
                let head = &mut vertices[corner_vertex[next_c(c as u32) as usize] as usize];
                head.valence_flags = (head.valence_flags + 1) | BOUNDARY;
            }
        }
        let n_vertices = vertices.iter().filter(|x| x.corner != NONE).count();
        let corners = corner_vertex
            .iter()
            .zip(&twin)
            .map(|(&vertex, &twin)| Corner { vertex, twin })
            .collect();
        FlatMesh {
            vertices,
            corners,
            boundary_twin: twin[nh..].to_vec(),
            slot,
            n_faces: nh / 3,
            n_vertices,
        }
    }

    /// Moves the positions to the centre of the used vertices' bounding box.
    fn recentre(&mut self) {
        let vertices = &mut self.vertices;
        // Work relative to the centre of the mesh's bounding box. Plane quadrics in absolute
        // coordinates carry `d² = (n·p)²` terms that cancel in every error evaluation: a scan
        // in georeferenced units (offsets of 1e5–1e7 from the origin are common) would lose
        // most of the error's digits and collapse in a nearly random order. Errors, normals
        // and shapes are translation-invariant, and collapses create no positions, so the
        // hierarchy only gains digits.
        let used = vertices.iter().filter(|x| x.corner != NONE);
        if let Some(bounds) = BoundingBox::of(used.map(|x| x.position)) {
            let origin = bounds.centre();
            for x in vertices.iter_mut() {
                x.position -= origin;
            }
        }
    }

    /// The positions of all vertices, in the working frame (recentred unless built
    /// [`at_positions`](Self::at_positions)).
    pub(crate) fn positions(&self) -> Vec<DVec3> {
        self.vertices.iter().map(|x| x.position).collect()
    }

    /// Number of vertex slots, with faces or not.
    pub(crate) fn n_vertex_slots(&self) -> usize {
        self.vertices.len()
    }

    /// Number of live triangles.
    pub(crate) fn n_faces(&self) -> usize {
        self.n_faces
    }

    /// The vertices that still have faces, in slot order.
    pub(crate) fn survivors(&self) -> Vec<u32> {
        (0..self.vertices.len() as u32)
            .filter(|&v| self.vertices[v as usize].corner != NONE)
            .collect()
    }

    /// The live triangles in triangle order, each starting at its first corner.
    pub(crate) fn triangles(&self) -> Vec<[u32; 3]> {
        self.triangles_in(0..self.corners.len() / 3)
    }

    /// Triangle `t`'s vertices, from its first corner (dead or live).
    pub(crate) fn triangle(&self, t: usize) -> [u32; 3] {
        let c = &self.corners[3 * t..3 * t + 3];
        [c[0].vertex, c[1].vertex, c[2].vertex]
    }

    /// The live triangles among triangles `range`, in triangle order.
    pub(crate) fn triangles_in(&self, range: std::ops::Range<usize>) -> Vec<[u32; 3]> {
        let range = 3 * range.start..3 * range.end.min(self.corners.len() / 3);
        self.corners[range]
            .chunks_exact(3)
            .filter(|t| t[0].vertex != NONE)
            .map(|t| [t[0].vertex, t[1].vertex, t[2].vertex])
            .collect()
    }

    #[inline]
    fn n_corners(&self) -> u32 {
        self.corners.len() as u32
    }

    /// Vertex of corner `c`.
    #[inline]
    fn cv(&self, c: u32) -> u32 {
        self.corners[c as usize].vertex
    }

    /// Twin of half-edge `h` (a corner or a boundary half-edge).
    #[inline]
    pub(super) fn twin(&self, h: u32) -> u32 {
        match self.corners.get(h as usize) {
            Some(c) => c.twin,
            None => self.boundary_twin[(h - self.n_corners()) as usize],
        }
    }

    #[inline]
    fn set_twin(&mut self, h: u32, t: u32) {
        let nh = self.n_corners();
        match self.corners.get_mut(h as usize) {
            Some(c) => c.twin = t,
            None => self.boundary_twin[(h - nh) as usize] = t,
        }
    }

    #[inline]
    pub(super) fn is_boundary_halfedge(&self, h: u32) -> bool {
        h >= self.n_corners()
    }

    #[inline]
    fn slot_of(&self, h: u32) -> u32 {
        match &self.slot {
            None => h,
            Some(s) => s[h as usize],
        }
    }

    #[inline]
    fn is_live(&self, h: u32) -> bool {
        if self.is_boundary_halfedge(h) {
            self.twin(h) != NONE
        } else {
            self.cv(h) != NONE
        }
    }

    #[inline]
    pub(super) fn tail_vertex(&self, h: u32) -> u32 {
        if self.is_boundary_halfedge(h) {
            self.cv(next_c(self.twin(h)))
        } else {
            self.cv(h)
        }
    }

    #[inline]
    fn head_vertex(&self, h: u32) -> u32 {
        if self.is_boundary_halfedge(h) {
            self.cv(self.twin(h))
        } else {
            self.cv(next_c(h))
        }
    }

    #[inline]
    pub(super) fn position(&self, v: u32) -> DVec3 {
        self.vertices[v as usize].position
    }

    #[inline]
    fn valence(&self, v: u32) -> u32 {
        self.vertices[v as usize].valence_flags & VALENCE
    }

    #[inline]
    fn is_boundary_vertex(&self, v: u32) -> bool {
        self.vertices[v as usize].valence_flags & BOUNDARY != 0
    }

    #[inline]
    fn is_locked(&self, v: u32) -> bool {
        self.vertices[v as usize].valence_flags & LOCKED != 0
    }

    /// Pins vertex `v`: no edge at it collapses (a block border of a partitioned build).
    pub(crate) fn pin(&mut self, v: u32) {
        self.vertices[v as usize].valence_flags |= PINNED;
    }

    #[inline]
    fn is_pinned(&self, v: u32) -> bool {
        self.vertices[v as usize].valence_flags & PINNED != 0
    }

    #[inline]
    fn set_locked(&mut self, v: u32, locked: bool) {
        let x = &mut self.vertices[v as usize].valence_flags;
        *x = if locked { *x | LOCKED } else { *x & !LOCKED };
    }

    #[inline]
    fn set_valence(&mut self, v: u32, valence: u32) {
        let x = &mut self.vertices[v as usize].valence_flags;
        *x = (*x & !VALENCE) | valence;
    }

    /// Calls `f` on every corner at `v` (the faces around it).
    #[inline]
    pub(super) fn for_each_corner(&self, v: u32, mut f: impl FnMut(u32)) {
        let c0 = self.vertices[v as usize].corner;
        let nh = self.n_corners();
        let mut c = c0;
        loop {
            f(c);
            // Counter-clockwise: the twin of the in-coming half-edge leaves v.
            let t = self.corners[prev_c(c) as usize].twin;
            if t >= nh {
                break;
            }
            c = t;
            if c == c0 {
                return;
            }
        }
        // An open fan: go clockwise from the start to the other boundary edge.
        let mut c = c0;
        loop {
            let t = self.corners[c as usize].twin;
            if t >= nh {
                return;
            }
            c = next_c(t);
            f(c);
        }
    }

    /// Calls `f` on every neighbour of `v`.
    #[inline]
    fn for_each_neighbour(&self, v: u32, mut f: impl FnMut(u32)) {
        let nh = self.n_corners();
        self.for_each_corner(v, |c| {
            f(self.cv(next_c(c)));
            // The corner whose in-coming edge is on the boundary also sees the neighbour
            // across that edge, which no corner's out-going edge reaches.
            let p = self.corners[prev_c(c) as usize];
            if p.twin >= nh {
                f(p.vertex);
            }
        });
    }

    /// Costs of collapsing the edge of `h` in both directions (`h`'s direction first); `None`
    /// for a direction that is never allowed (a boundary vertex may only slide along its
    /// boundary).
    #[inline]
    fn edge_costs(
        &self,
        quadric: &Quadrics,
        seams: Option<&Seams>,
        h: u32,
        o: u32,
    ) -> (Option<f64>, Option<f64>) {
        let boundary_edge = self.is_boundary_halfedge(h) || self.is_boundary_halfedge(o);
        let (a, b) = (self.tail_vertex(h), self.head_vertex(h));
        if self.is_pinned(a) || self.is_pinned(b) {
            return (None, None);
        }
        let q = quadric.merged(a, b);
        let cost = |e: u32, p: DVec3| match seams {
            None => q.error(p),
            Some(s) => q.error(p) + s.cost(self, e, p),
        };
        let ab = (boundary_edge || !self.is_boundary_vertex(a)).then(|| cost(h, self.position(b)));
        let ba = (boundary_edge || !self.is_boundary_vertex(b)).then(|| cost(o, self.position(a)));
        (ab, ba)
    }

    /// The candidate of the edge of corner `c`, if `c` represents it (it has the smaller slot
    /// of the two half-edges, or its twin is a boundary half-edge, which has no corner to
    /// represent it) and some direction is allowed within `max_error_sq`.
    #[inline]
    fn candidate(
        &self,
        quadric: &Quadrics,
        seams: Option<&Seams>,
        c: u32,
        max_error_sq: f64,
    ) -> Option<Candidate> {
        let t = self.corners[c as usize].twin;
        let (sc, st) = (self.slot_of(c), self.slot_of(t));
        let (h, o) = if sc < st {
            (c, t)
        } else if self.is_boundary_halfedge(t) {
            (t, c)
        } else {
            return None;
        };
        let (ch, co) = self.edge_costs(quadric, seams, h, o);
        let (cost, h) = match (ch, co) {
            (Some(a), Some(b)) if b < a => (b, o),
            (Some(a), _) => (a, h),
            (None, Some(b)) => (b, o),
            (None, None) => return None,
        };
        (cost <= max_error_sq).then(|| Candidate {
            cost,
            key: self.slot_of(h),
            h,
        })
    }

    /// The cost of collapsing `h` in its own direction, `None` if that is never allowed:
    /// [`Self::edge_costs`] taken from the half-edge with the smaller slot, as
    /// [`Self::candidate`] takes it, so the value is the one the candidate's collection saw as
    /// long as neither end has collapsed since.
    #[inline]
    fn direction_cost(&self, quadric: &Quadrics, seams: Option<&Seams>, h: u32) -> Option<f64> {
        let o = self.twin(h);
        if self.slot_of(h) < self.slot_of(o) {
            self.edge_costs(quadric, seams, h, o).0
        } else {
            self.edge_costs(quadric, seams, o, h).1
        }
    }

    /// The topological rules of [`super::is_collapse_topologically_legal`] on the corner
    /// table. Returns the valence the survivor would have, or the rule that refuses.
    fn topologically_legal(&self, h: u32, max_valence: usize) -> Result<u32, Refusal> {
        let o = self.twin(h);
        let (u, v) = (self.tail_vertex(h), self.head_vertex(h));
        let has_l = !self.is_boundary_halfedge(h);
        let has_r = !self.is_boundary_halfedge(o);
        if self.is_boundary_vertex(u) && has_l && has_r {
            return Err(Refusal::Boundary);
        }
        let mut wings = [NONE; 2];
        let mut n_wings = 0;
        for (has, e) in [(has_l, h), (has_r, o)] {
            if !has {
                continue;
            }
            let (e1, e2) = (next_c(e), prev_c(e));
            // Both outer edges on the boundary: the face would dangle.
            if self.is_boundary_halfedge(self.corners[e1 as usize].twin)
                && self.is_boundary_halfedge(self.corners[e2 as usize].twin)
            {
                return Err(Refusal::DanglingFace);
            }
            let w = self.cv(e2);
            // An interior wing vertex loses an edge; valence 3 would leave a degenerate pillow.
            if !self.is_boundary_vertex(w) && self.valence(w) <= 3 {
                return Err(Refusal::Pillow);
            }
            wings[n_wings] = w;
            n_wings += 1;
        }
        if n_wings == 2 && wings[0] == wings[1] {
            return Err(Refusal::Link);
        }
        // The valence cap first: it is cheap, and it bounds both rings for the link test.
        let new_valence = (self.valence(u) + self.valence(v)) as usize - 2 - n_wings;
        if new_valence > max_valence {
            return Err(Refusal::Valence);
        }
        // Link condition: the common neighbours of u and v are exactly the wings. The rings
        // are small (the cap above), so a linear search in u's ring beats per-vertex marks,
        // which cost a cache miss per neighbour.
        let mut ring_u: smallvec::SmallVec<[u32; 40]> = smallvec::SmallVec::new();
        self.for_each_neighbour(u, |w| ring_u.push(w));
        let mut common = 0;
        let mut legal = true;
        self.for_each_neighbour(v, |w| {
            if ring_u.contains(&w) {
                common += 1;
                legal &= wings[..n_wings].contains(&w);
            }
        });
        if legal && common == n_wings {
            Ok(new_valence as u32)
        } else {
            Err(Refusal::Link)
        }
    }

    /// The shape rules of [`super::Legality`] ([`shape_check`]) on the faces around `h`'s
    /// tail.
    fn geometrically_legal(&self, h: u32, legality: &Legality) -> Result<f64, Refusal> {
        let o = self.twin(h);
        let (u, v) = (self.tail_vertex(h), self.head_vertex(h));
        let dead = |c: u32| {
            (!self.is_boundary_halfedge(h) && c / 3 == h / 3)
                || (!self.is_boundary_halfedge(o) && c / 3 == o / 3)
        };
        let mut ring: smallvec::SmallVec<[RingFace; 16]> = smallvec::SmallVec::new();
        self.for_each_corner(u, |c| {
            ring.push(RingFace {
                a: self.position(self.cv(next_c(c))),
                b: self.position(self.cv(prev_c(c))),
                dies: dead(c),
            })
        });
        shape_check(self.position(u), self.position(v), &ring, legality)
    }

    /// Whether collapsing `h` is legal: the survivor's valence and the sliver penalty, or the
    /// rule that refuses.
    fn legal(
        &self,
        h: u32,
        legality: &Legality,
        seams: Option<&Seams>,
    ) -> Result<(u32, f64), Refusal> {
        let valence = self.topologically_legal(h, legality.max_valence)?;
        if let Some(s) = seams
            && !s.allows(self, h)
        {
            return Err(Refusal::Seam);
        }
        let penalty = self.geometrically_legal(h, legality)?;
        Ok((valence, penalty))
    }

    /// Asks the cache for what testing and collapsing the edge of half-edge `h` reads first:
    /// both vertices' records and quadrics and the twin's triangle.
    #[inline]
    fn prefetch_edge(&self, quadric: &[Quadric], h: u32) {
        let (Some(c), Some(n)) = (
            self.corners.get(h as usize),
            self.corners.get(next_c(h) as usize),
        ) else {
            return; // a boundary half-edge: rare, not worth a second chain
        };
        prefetch(self.corners.as_ptr().wrapping_add(c.twin as usize));
        for v in [c.vertex, n.vertex] {
            prefetch(self.vertices.as_ptr().wrapping_add(v as usize));
            let q = quadric.as_ptr().wrapping_add(v as usize);
            prefetch(q);
            prefetch((q as *const u8).wrapping_add(64)); // a quadric spans two lines
        }
    }

    #[inline]
    fn set_twins(&mut self, a: u32, b: u32) {
        self.set_twin(a, b);
        self.set_twin(b, a);
    }

    /// Collapses `h = u→v` (legal, giving `v` valence `new_valence`); returns `(u, v, v_l,
    /// v_r)` with `NONE` for a missing wing.
    fn collapse(&mut self, h: u32, new_valence: u32) -> [u32; 4] {
        let o = self.twin(h);
        let (u, v) = (self.tail_vertex(h), self.head_vertex(h));
        // Everything at u is now at v (the two dying faces included; they go below).
        let mut at_u: smallvec::SmallVec<[u32; 16]> = smallvec::SmallVec::new();
        self.for_each_corner(u, |c| at_u.push(c));
        for c in at_u {
            self.corners[c as usize].vertex = v;
        }
        let mut wings = [NONE; 2];
        for (side, e) in [h, o].into_iter().enumerate() {
            if self.is_boundary_halfedge(e) {
                self.set_twin(e, NONE);
                continue;
            }
            // e runs x→y in the face (x, y, w); its outer half-edges e1 = y→w and e2 = w→x
            // die, and their twins t1 = w→y and t2 = x→w (now v→w on both sides) are glued.
            let (e1, e2) = (next_c(e), prev_c(e));
            let w = self.cv(e2);
            let (t1, t2) = (
                self.corners[e1 as usize].twin,
                self.corners[e2 as usize].twin,
            );
            self.set_twins(t1, t2);
            // The glued edge joins w and v on both sides (t1 = w→v, t2 = v→w); at most one
            // of its half-edges is a boundary one, so each end keeps a live corner: t1 leaves
            // w, else the corner after t2 does; t2 leaves v, else the corner after t1 does.
            self.vertices[w as usize].corner = if self.is_boundary_halfedge(t1) {
                next_c(t2)
            } else {
                t1
            };
            self.vertices[v as usize].corner = if self.is_boundary_halfedge(t2) {
                next_c(t1)
            } else {
                t2
            };
            self.vertices[w as usize].valence_flags -= 1;
            wings[side] = w;
            let t = (e / 3 * 3) as usize;
            for c in &mut self.corners[t..t + 3] {
                c.vertex = NONE;
            }
            self.n_faces -= 1;
        }
        self.vertices[u as usize].corner = NONE;
        self.set_valence(u, 0);
        self.set_valence(v, new_valence);
        self.n_vertices -= 1;
        [u, v, wings[0], wings[1]]
    }
}

/// A candidate collapse: the cheaper allowed direction of an edge (half-edge id `h`, its slot
/// `key` for ties). The other direction's cost is recomputed on the rare turns that need it
/// ([`FlatMesh::direction_cost`]): the list holds every live edge, the decimation's largest
/// array, and 16 bytes a record instead of 24 keep it a third smaller.
#[derive(Clone, Copy)]
struct Candidate {
    cost: f64,
    key: u32,
    h: u32,
}

#[inline]
fn by_cost(a: &Candidate, b: &Candidate) -> std::cmp::Ordering {
    a.cost.total_cmp(&b.cost).then(a.key.cmp(&b.key))
}

pub(crate) fn initial_quadrics(mesh: &FlatMesh, boundary_weight: f64) -> Quadrics {
    let mut q = vec![Quadric::default(); mesh.vertices.len()];
    for t in mesh.corners.chunks_exact(3) {
        let [a, b, c] = [t[0].vertex, t[1].vertex, t[2].vertex];
        let (pa, pb, pc) = (mesh.position(a), mesh.position(b), mesh.position(c));
        let Some(fq) = Quadric::of_triangle(pa, pb, pc) else {
            continue; // zero-area faces carry no plane
        };
        for x in [a, b, c] {
            q[x as usize].add(&fq);
        }
    }
    // Before the boundary planes, which add no weight: the regulariser scales with the faces'.
    for (v, qv) in q.iter_mut().enumerate() {
        let scale = POINT_REGULARISATION * qv.weight;
        qv.add(&Quadric::from_point(mesh.position(v as u32), scale));
    }
    let mut rims = Vec::new();
    if boundary_weight > 0.0 {
        let nh = mesh.n_corners();
        for h in nh..nh + mesh.boundary_twin.len() as u32 {
            // The face is on the twin's side; the constraint plane contains the edge and is
            // perpendicular to that face.
            let t = mesh.twin(h);
            let (a, b) = (mesh.tail_vertex(h), mesh.head_vertex(h));
            let (pa, pb) = (mesh.position(a), mesh.position(b));
            let f = t / 3 * 3;
            let [fa, fb, fc] = [f, f + 1, f + 2].map(|c| mesh.position(mesh.cv(c)));
            let face_normal = (fb - fa).cross(fc - fa).normalize_or_zero();
            let e = pb - pa;
            let n = e.cross(face_normal).normalize_or_zero();
            if n == DVec3::ZERO {
                continue;
            }
            let cq = Quadric::from_plane(n, pa, boundary_weight * e.length_squared(), 0.0);
            rims.push((a, cq));
            rims.push((b, cq));
        }
    }
    Quadrics::new(q, &rims)
}

/// Why a decimation ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The face or vertex target was met.
    Target,
    /// Every collapse left would exceed the error bound.
    ErrorBound,
    /// No legal collapse is left, even with every shape rule relaxed (a seam-keeping
    /// decimation relaxes none, and counts one far dearer than those it made as refused,
    /// [`Refusal::Costly`]): for each rule, how many of the remaining edges it refused (in
    /// their cheaper direction), most first.
    NoLegalCollapse(Vec<(Refusal, usize)>),
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Target => write!(f, "target reached"),
            Stop::ErrorBound => write!(f, "error bound reached"),
            Stop::NoLegalCollapse(refusals) => {
                write!(f, "no legal collapse left")?;
                for (i, (rule, n)) in refusals.iter().enumerate() {
                    let sep = if i == 0 { " (" } else { ", " };
                    let edges = if *n == 1 { "edge" } else { "edges" };
                    write!(f, "{sep}{}: {n} {edges}", rule.describe())?;
                }
                if !refusals.is_empty() {
                    write!(f, ")")?;
                }
                Ok(())
            }
        }
    }
}

/// Passes of the decimator one at a time, for blocks that take them in step.
#[path = "partition/passes.rs"]
pub(crate) mod passes;

/// What a decimation did besides its collapses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Outcome {
    /// Why it ended.
    pub stop: Stop,
    /// Collapses made under each relaxation step (`Valence`, `Slivers`, `Normals`).
    pub relaxed: [usize; 3],
}

/// The pass schedule shared by the decimator and its reference. A pass normally visits the
/// candidates under a cost cut; one that collapses nothing is repeated without the cut, and a
/// full pass that collapses nothing relaxes the shape rules one step for a pass of limited
/// length. Any collapse returns to the full rules, so relaxed collapses happen only where
/// nothing else can move.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Schedule {
    pub use_goal: bool,
    pub relaxation: Relaxation,
    /// The furthest relaxation step this decimation may take.
    pub last: Relaxation,
}

impl Schedule {
    /// A schedule whose relaxation stops at step `last`.
    pub(super) fn up_to(last: Relaxation) -> Schedule {
        Schedule {
            use_goal: true,
            relaxation: Relaxation::None,
            last,
        }
    }

    /// The rules of this pass.
    pub(super) fn legality(&self, params: &DecimateParams) -> Legality {
        params.legality.relaxed(self.relaxation)
    }

    /// How many collapses this pass may make: relaxed passes do a small share of the faces
    /// left, the cheapest first, then hand back to the full rules.
    pub(crate) fn budget(&self, n_faces: usize) -> usize {
        match self.relaxation {
            Relaxation::None => usize::MAX,
            _ => (n_faces / 64).max(1),
        }
    }

    /// After a pass: whether decimation is over, i.e. a full pass with every rule relaxed
    /// found no legal collapse.
    pub(crate) fn pass_ended(
        &mut self,
        collapsed: bool,
        error_cut: f64,
        params: &DecimateParams,
    ) -> bool {
        if collapsed {
            *self = Schedule::up_to(self.last);
            return false;
        }
        if self.use_goal && error_cut.is_finite() && error_cut < params.max_error_sq {
            self.use_goal = false;
            return false;
        }
        match self.relaxation.next().filter(|&r| r <= self.last) {
            Some(r) => {
                self.relaxation = r;
                self.use_goal = false;
                false
            }
            None => true,
        }
    }
}

/// The rules of one pass (shared with the reference decimator): the cost cut, the legality
/// tests and how many collapses it may make.
#[derive(Clone, Copy)]
pub(super) struct Pass {
    pub error_cut: f64,
    pub legality: Legality,
    pub budget: usize,
}

/// What the passes accumulate: the quadrics, the survivors locked in the current pass and the
/// collapses made so far.
struct Decimation<'a> {
    quadric: Quadrics,
    locked: Vec<u32>,
    collapses: Vec<Collapse>,
    /// The corners' wedges of a mesh with texture seams (`super::seams`), `None` without.
    seams: Option<&'a mut Seams>,
}

/// Decimates `mesh`; returns the collapses in order, the final mesh and why it stopped.
#[cfg(test)]
pub(crate) fn decimate(
    mesh: FlatMesh,
    params: &DecimateParams,
    progress: &dyn Progress,
) -> (Vec<Collapse>, FlatMesh, Outcome) {
    decimate_with_seams(mesh, params, None, progress)
}

/// [`decimate`] keeping the seams of `seams` (whose wedges follow the collapses).
pub(crate) fn decimate_with_seams(
    mesh: FlatMesh,
    params: &DecimateParams,
    seams: Option<&mut Seams>,
    progress: &dyn Progress,
) -> (Vec<Collapse>, FlatMesh, Outcome) {
    let quadric = initial_quadrics(&mesh, params.boundary_weight);
    let run = Run {
        input_faces: mesh.n_faces,
        relax: true,
        seam_floor: SeamFloor::default(),
    };
    let (collapses, mesh, outcome, _) = decimate_from(mesh, quadric, run, params, seams, progress);
    (collapses, mesh, outcome)
}

/// How a decimation relates to the whole build: a block of a partitioned build
/// (`partition/block.rs`) starts from a mesh already decimated and stops where the whole
/// mesh's build would relax its rules.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Run {
    /// The faces the rules' coarseness is measured against (the input faces the mesh covers).
    pub input_faces: usize,
    /// Whether a pass that finds nothing relaxes the shape rules (else the decimation stops).
    pub relax: bool,
    /// The dearest collapse made under a cost cut before this decimation (by a partitioned
    /// build's passes), which the seam floor's cap starts from.
    pub seam_floor: SeamFloor,
}

/// [`decimate`] from the given quadrics; also returns the quadrics at the end.
pub(crate) fn decimate_from(
    mut mesh: FlatMesh,
    quadric: Quadrics,
    run: Run,
    params: &DecimateParams,
    seams: Option<&mut Seams>,
    progress: &dyn Progress,
) -> (Vec<Collapse>, FlatMesh, Outcome, Quadrics) {
    let mut state = Decimation {
        quadric,
        locked: Vec::new(),
        collapses: Vec::new(),
        seams,
    };
    let mut cands: Vec<Candidate> = Vec::new();
    let mut relaxed = [0usize; 3];
    let start_faces = run.input_faces.max(mesh.n_faces);
    let work = start_faces.saturating_sub(params.target_faces).max(1);
    // Keeping seams, the floor is the seam floor: there the relaxed rules would only fold
    // faces across the charts around it (docs/seams.md), so a seam-keeping decimation ends
    // where the full rules find nothing left.
    let mut schedule = Schedule::up_to(if state.seams.is_some() {
        Relaxation::None
    } else {
        Relaxation::Normals
    });
    let mut stop = Stop::Target;
    let mut live = live_triangles(&mesh);
    let mut floor = run.seam_floor;
    while !is_done(&mesh, params) {
        drop_dead_triangles(&mesh, &mut live);
        state.quadric.rim_scale = rim_scale_at_level(mesh.n_faces, start_faces);
        collect_candidates(
            &mesh,
            &live,
            &state.quadric,
            state.seams.as_deref(),
            params.max_error_sq,
            &mut cands,
        );
        if cands.is_empty() {
            stop = if params.max_error_sq.is_finite() {
                Stop::ErrorBound
            } else if !run.relax {
                Stop::NoLegalCollapse(Vec::new())
            } else {
                Stop::NoLegalCollapse(mesh.refusals(
                    &state.quadric,
                    state.seams.as_deref(),
                    params,
                    schedule.last,
                    f64::INFINITY,
                ))
            };
            break;
        }
        let mut error_cut = cut_at_goal(&mut cands, mesh.n_faces, &schedule, params);
        let cap = floor.cap(state.seams.is_some() && !schedule.use_goal);
        if cap < error_cut {
            error_cut = cap;
            cands.retain(|c| c.cost <= error_cut);
        }
        let first_new = state.collapses.len();
        rank_candidates(&mut cands);
        let pass = Pass {
            error_cut,
            legality: schedule
                .legality(params)
                .at_level(mesh.n_faces, start_faces),
            budget: schedule.budget(mesh.n_faces),
        };
        let made = perform_collapses(&mut mesh, &mut state, &cands, &pass, params);
        if schedule.use_goal {
            floor.took(&state.collapses[first_new..]);
        }
        unlock_survivors(&mut mesh, &mut state.locked);
        if schedule.relaxation != Relaxation::None {
            relaxed[schedule.relaxation as usize - 1] += made;
        }
        progress.update((start_faces - mesh.n_faces) as f64 / work as f64);
        if schedule.pass_ended(made > 0, error_cut, params) {
            stop = Stop::NoLegalCollapse(mesh.refusals(
                &state.quadric,
                state.seams.as_deref(),
                params,
                schedule.last,
                floor.cap(state.seams.is_some()),
            ));
            break;
        }
        if !run.relax && schedule.relaxation != Relaxation::None {
            stop = Stop::NoLegalCollapse(Vec::new());
            break;
        }
    }
    progress.update(1.0);
    let outcome = Outcome { stop, relaxed };
    (state.collapses, mesh, outcome, state.quadric)
}

/// How much dearer than the dearest collapse made under a pass's cost cut a collapse at the
/// seam floor may be. There, with the target out of reach, a pass without the cut would take
/// every legal collapse however dear, such as a hole's rim losing the tip of a strip one face
/// wide, which the boundary planes barely charge (docs/seams.md, docs/performance.md).
pub(crate) const SEAM_FLOOR_COST_FACTOR: f64 = 4.0;

/// The dearest collapse a seam-keeping decimation made under a cost cut, which caps its passes
/// without one ([`SEAM_FLOOR_COST_FACTOR`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SeamFloor {
    dearest: f64,
}

impl SeamFloor {
    /// Records the collapses of a pass made under a cost cut.
    pub(crate) fn took(&mut self, collapses: &[Collapse]) {
        for c in collapses {
            self.dearest = self.dearest.max(c.error_sq);
        }
    }

    /// The cost cap of a pass: none unless `capped` and some collapse cost anything yet.
    pub(crate) fn cap(&self, capped: bool) -> f64 {
        if capped && self.dearest > 0.0 {
            SEAM_FLOOR_COST_FACTOR * self.dearest
        } else {
            f64::INFINITY
        }
    }
}

/// What the boundary planes count for in a pass starting with `faces` of the input's
/// `input_faces`: their full weight at fine levels, where a rim that drifts inward is a visible
/// loss, and `COARSE_RIM_SCALE` of it at the coarse end, where each hole's rim otherwise keeps
/// the vertices the surface needs (`docs/pm-legality.md`).
pub(super) fn rim_scale_at_level(faces: usize, input_faces: usize) -> f64 {
    1.0 + super::legality::coarseness(faces, input_faces) * (COARSE_RIM_SCALE - 1.0)
}

/// The boundary planes' weight at the coarse end relative to the configured one.
const COARSE_RIM_SCALE: f64 = 0.3;

/// Whether the face or vertex target is met.
#[inline]
fn is_done(mesh: &FlatMesh, params: &DecimateParams) -> bool {
    mesh.n_faces <= params.target_faces || mesh.n_vertices <= params.target_vertices
}

/// The live triangles, in order: dead ones are dropped after every pass, so a pass reads only
/// what is left.
pub(super) fn live_triangles(mesh: &FlatMesh) -> Vec<u32> {
    (0..mesh.corners.len() as u32 / 3)
        .filter(|&t| mesh.corners[3 * t as usize].vertex != NONE)
        .collect()
}

/// Drops the triangles the last pass removed from `live`.
#[inline]
fn drop_dead_triangles(mesh: &FlatMesh, live: &mut Vec<u32>) {
    live.retain(|&t| mesh.corners[3 * t as usize].vertex != NONE);
}

/// Keeps the candidates under this pass's cost cut and returns the cut. Each collapse removes
/// about two faces; aim for this pass's share of the target and allow 1.5× the cost of the
/// candidate that would meet it (many get locked). Only the candidates under the cut are ever
/// visited, so only they are kept for the sort.
#[inline]
fn cut_at_goal(
    cands: &mut Vec<Candidate>,
    n_faces: usize,
    schedule: &Schedule,
    params: &DecimateParams,
) -> f64 {
    let goal = passes::pass_goal(n_faces, params.target_faces);
    let nth = (schedule.use_goal && goal < cands.len())
        .then(|| cands.select_nth_unstable_by(goal, by_cost).1.cost);
    let error_cut = passes::cut_at(nth, params.max_error_sq);
    if error_cut < f64::INFINITY {
        cands.retain(|c| c.cost <= error_cut);
    }
    error_cut
}

/// Sorts the candidates by `(cost, slot)`, in parallel when there are many.
#[inline]
fn rank_candidates(cands: &mut [Candidate]) {
    if cands.len() >= PAR_MIN {
        cands.par_sort_unstable_by(by_cost);
    } else {
        cands.sort_unstable_by(by_cost);
    }
}

/// Collapses the ranked candidates in order, each in its cheaper legal direction, skipping
/// edges at a survivor of this pass (locked); returns how many it collapsed.
#[inline]
fn perform_collapses(
    mesh: &mut FlatMesh,
    state: &mut Decimation,
    cands: &[Candidate],
    pass: &Pass,
    params: &DecimateParams,
) -> usize {
    let mut budget = pass.budget;
    let before = state.collapses.len();
    let quadric: &mut Quadrics = &mut state.quadric;
    let mut seams = state.seams.as_deref_mut();
    for (i, c) in cands.iter().enumerate() {
        if is_done(mesh, params) || budget == 0 {
            break;
        }
        // Candidates come in cost order, i.e. at random places in memory, and each one's
        // records are a chain of dependent loads: fetch the next ones' in two steps (their
        // triangle 16 ahead, then what it points to 8 ahead) while this one is tested.
        if let Some(far) = cands.get(i + 16) {
            prefetch(mesh.corners.as_ptr().wrapping_add(far.h as usize));
        }
        if let Some(near) = cands.get(i + 8) {
            mesh.prefetch_edge(&quadric.faces, near.h);
        }
        let h0 = c.h;
        if !mesh.is_live(h0) {
            continue;
        }
        let o0 = mesh.twin(h0);
        let (a, b) = (mesh.tail_vertex(h0), mesh.head_vertex(h0));
        if mesh.is_locked(a) || mesh.is_locked(b) {
            continue;
        }
        // A collapse that leaves a new sliver pays its penalty against this pass's cut: it
        // waits for a pass whose errors have grown to its price.
        let within_cut = |legal: Result<(u32, f64), Refusal>, cost: f64| match legal {
            Ok((valence, penalty)) if cost + penalty <= pass.error_cut => Some(valence),
            _ => None,
        };
        let (h, cost, valence) = if let Some(val) =
            within_cut(mesh.legal(h0, &pass.legality, seams.as_deref()), c.cost)
        {
            (h0, c.cost, val)
        } else if let Some(alt_cost) = mesh.direction_cost(quadric, seams.as_deref(), o0)
            && alt_cost <= pass.error_cut
            && let Some(val) =
                within_cut(mesh.legal(o0, &pass.legality, seams.as_deref()), alt_cost)
        {
            (o0, alt_cost, val)
        } else {
            continue;
        };
        if let Some(s) = seams.as_deref_mut() {
            s.collapse(mesh, h);
        }
        let [u, v, left, right] = mesh.collapse(h, valence);
        quadric.absorb(u, v);
        mesh.set_locked(v, true);
        state.locked.push(v);
        state.collapses.push(Collapse {
            from: u,
            to: v,
            left,
            right,
            error_sq: cost,
        });
        budget -= 1;
    }
    state.collapses.len() - before
}

/// Unlocks this pass's survivors for the next pass.
#[inline]
fn unlock_survivors(mesh: &mut FlatMesh, locked: &mut Vec<u32>) {
    for &v in locked.iter() {
        mesh.set_locked(v, false);
    }
    locked.clear();
}

/// [`collect_candidates`] scans the live triangles in this many slices, one after another.
const COLLECT_ROUNDS: usize = 16;

/// Every live edge once, by the corner that represents it, into `cands` (in no particular
/// order). Costs are independent, so they are computed in parallel.
fn collect_candidates(
    mesh: &FlatMesh,
    live: &[u32],
    quadric: &Quadrics,
    seams: Option<&Seams>,
    max_error_sq: f64,
    cands: &mut Vec<Candidate>,
) {
    cands.clear();
    let scan = |i: usize, out: &mut Vec<Candidate>| {
        // Triangles are read in order, their vertices' records at random.
        if let Some(&ahead) = live.get(i + 8) {
            for x in &mesh.corners[3 * ahead as usize..3 * ahead as usize + 3] {
                prefetch(quadric.faces.as_ptr().wrapping_add(x.vertex as usize));
                prefetch(mesh.vertices.as_ptr().wrapping_add(x.vertex as usize));
            }
        }
        let t = live[i];
        for c in 3 * t..3 * t + 3 {
            if let Some(x) = mesh.candidate(quadric, seams, c, max_error_sq) {
                out.push(x);
            }
        }
    };
    if live.len() >= PAR_MIN {
        // Every triangle gives at most three candidates: reserving that bound never moves the
        // vector (untouched capacity costs address space only). The threads' partial vectors
        // are held beside it until appended, so they are kept to a slice of the triangles at a
        // time instead of all of them, which doubled the decimation's memory peak.
        cands.reserve(3 * live.len());
        let slice = (live.len() / COLLECT_ROUNDS).max(PAR_MIN);
        let mut start = 0;
        while start < live.len() {
            let end = (start + slice).min(live.len());
            cands.par_extend(
                (start..end)
                    .into_par_iter()
                    .with_min_len(PAR_MIN / 4)
                    .fold(Vec::new, |mut out, i| {
                        scan(i, &mut out);
                        out
                    })
                    .flatten_iter(),
            );
            start = end;
        }
    } else {
        for i in 0..live.len() {
            scan(i, cands);
        }
    }
}

impl FlatMesh {
    /// For each rule, how many live edges within the error bound it refuses under the rules
    /// relaxed up to step `last` (each edge counted once, in its cheaper allowed direction; an interior
    /// edge between two boundary vertices has none and counts as `Boundary`; a legal one dearer
    /// than `cap` counts as `Costly`), most first.
    fn refusals(
        &self,
        quadric: &Quadrics,
        seams: Option<&Seams>,
        params: &DecimateParams,
        last: Relaxation,
        cap: f64,
    ) -> Vec<(Refusal, usize)> {
        let legality = params.legality.relaxed(last);
        let mut counts = std::collections::BTreeMap::<Refusal, usize>::new();
        for c in 0..self.n_corners() {
            let t = self.corners[c as usize].twin;
            let represents = self.slot_of(c) < self.slot_of(t) || self.is_boundary_halfedge(t);
            if self.cv(c) == NONE || !represents {
                continue;
            }
            let refusal = match self.candidate(quadric, seams, c, f64::INFINITY) {
                None => Some(Refusal::Boundary),
                Some(x) if x.cost <= params.max_error_sq => self
                    .legal(x.h, &legality, seams)
                    .err()
                    .or((x.cost > cap).then_some(Refusal::Costly)),
                Some(_) => None,
            };
            if let Some(r) = refusal {
                *counts.entry(r).or_default() += 1;
            }
        }
        let mut counts: Vec<_> = counts.into_iter().collect();
        counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::super::collapse::{Marks, half_edge_collapse, is_collapse_legal};
    use super::super::decimate_reference;
    use super::super::legality::Legality;
    use super::*;
    use crate::mesh::{PolygonMesh, shapes};
    use crate::progress::NoProgress;

    fn params(target_faces: usize, max_error_sq: f64, boundary_weight: f64) -> DecimateParams {
        DecimateParams {
            target_vertices: 0,
            target_faces,
            max_error_sq,
            legality: Legality {
                max_valence: 32,
                min_normal_cos: 45f64.to_radians().cos(),
                min_quality: 0.05,
            },
            boundary_weight,
        }
    }

    /// Decimates `mesh` with both implementations and checks that they collapse the same
    /// edges in the same order with the same errors, and end in the same mesh.
    fn assert_same_as_reference(mesh: &Mesh, p: &DecimateParams) -> usize {
        let (want, coarse) = decimate_reference::decimate(mesh, p, &NoProgress);
        let (got, flat, _) = decimate(FlatMesh::from_mesh(mesh), p, &NoProgress);
        assert_eq!(got.len(), want.len(), "number of collapses");
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(g, w, "collapse {i}");
            assert_eq!(g.error_sq.to_bits(), w.error_sq.to_bits());
        }
        let survivors: Vec<u32> = coarse
            .vertices()
            .filter(|&v| !coarse.is_isolated(v))
            .map(|v| v.slot() as u32)
            .collect();
        assert_eq!(flat.survivors(), survivors);
        let faces: Vec<[u32; 3]> = coarse
            .faces()
            .map(|f| coarse.face_vertices(f).map(|v| v.slot() as u32))
            .collect();
        assert_eq!(flat.triangles(), faces);
        assert_eq!(flat.n_faces(), coarse.n_faces());
        got.len()
    }

    fn built(positions: Vec<DVec3>, tris: &[[u32; 3]]) -> Mesh {
        Mesh::from_polygons(&PolygonMesh::from_triangles(positions, tris))
            .unwrap()
            .mesh
    }

    fn bumpy_grid(n: usize) -> Mesh {
        let (p, t) = shapes::grid(n, |i, j| {
            let (x, y) = (i as f64, j as f64);
            DVec3::new(x, y, 0.3 * (0.7 * x).sin() * (0.9 * y).cos())
        });
        built(p, &t)
    }

    #[test]
    fn closed_and_open_meshes_match_the_half_edge_decimator() {
        let (p, t) = shapes::icosphere(3);
        let sphere = built(p, &t);
        let grid = bumpy_grid(24);
        for mesh in [&sphere, &grid] {
            for p in [
                params(0, f64::INFINITY, 100.0),
                params(mesh.n_faces() / 10, f64::INFINITY, 100.0),
                params(0, 1e-4, 0.0),
            ] {
                assert!(assert_same_as_reference(mesh, &p) > 0);
            }
        }
    }

    #[test]
    fn dirty_scans_match_the_half_edge_decimator() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        let mut total = 0;
        for name in [
            "bunny.ply",
            "snowden_lo.ply",
            "elephant_holes.ply",
            "spider_assimp.ply",
            "cube_degenerate_om.obj",
            "planar_pymeshfix_vtk.ply",
            "back_to_back_scad.stl",
            "sphere_highval.ply",
        ] {
            let input = crate::io::read_mesh(dir.join(name)).unwrap();
            let mesh = Mesh::from_polygons(&input).unwrap().mesh;
            let target = mesh.n_faces() / 50;
            total += assert_same_as_reference(&mesh, &params(target, f64::INFINITY, 100.0));
        }
        assert!(total > 10_000);
    }

    #[test]
    fn degenerate_scans_match_the_half_edge_decimator_down_to_the_floor() {
        // Marching-cubes output with zero-area faces and coincident vertices, and a
        // many-component implicit: decimated to nothing, they exercise every relaxation step
        // and the census of what stopped.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mc");
        let mut relaxed = 0;
        for name in [
            "mc_bunny_quant36.ply",
            "mc_implicit_n40.ply",
            "mc_armadillo_open52.ply",
        ] {
            let input = crate::io::read_mesh(dir.join(name)).unwrap();
            let mesh = Mesh::from_polygons(&input).unwrap().mesh;
            assert_same_as_reference(&mesh, &params(0, f64::INFINITY, 100.0));
            let (_, _, outcome) = decimate(
                FlatMesh::from_mesh(&mesh),
                &params(0, f64::INFINITY, 100.0),
                &NoProgress,
            );
            assert!(
                matches!(&outcome.stop, Stop::NoLegalCollapse(r) if !r.is_empty()),
                "{name}: {outcome:?}"
            );
            // Slivers only cost, and the coarse end allows the fold bound: what still needs
            // relaxing is a tight valence cap (and faces that would lose their normal).
            let mut tight = params(0, f64::INFINITY, 100.0);
            tight.legality.max_valence = 6;
            assert_same_as_reference(&mesh, &tight);
            let (_, _, outcome) = decimate(FlatMesh::from_mesh(&mesh), &tight, &NoProgress);
            relaxed += outcome.relaxed.iter().sum::<usize>();
        }
        assert!(relaxed > 0);
    }

    #[test]
    fn meshes_with_free_slots_match_the_half_edge_decimator() {
        // After some collapses the slots have holes, so half-edge ids are no longer slots and
        // ties go through the slot table.
        let mut mesh = bumpy_grid(16);
        let mut marks = Marks::default();
        let legality = Legality::default();
        let mut done = 0;
        let hs: Vec<_> = mesh.halfedges().collect();
        for h in hs.into_iter().step_by(7) {
            if mesh.contains_halfedge(h) && is_collapse_legal(&mesh, h, &legality, &mut marks) {
                half_edge_collapse(&mut mesh, h);
                done += 1;
            }
        }
        assert!(done > 10);
        assert!(FlatMesh::from_mesh(&mesh).slot.is_some());
        assert!(assert_same_as_reference(&mesh, &params(0, f64::INFINITY, 100.0)) > 0);
    }

    #[test]
    fn random_soups_match_the_half_edge_decimator() {
        // Non-manifold, multiply connected, flipped, degenerate: whatever the builder repairs.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        for _ in 0..200 {
            let nv = 4 + next(40) as usize;
            let positions: Vec<DVec3> = (0..nv)
                .map(|_| DVec3::new(next(8) as f64, next(8) as f64, next(3) as f64))
                .collect();
            let tris: Vec<[u32; 3]> = (0..next(80) + 1)
                .map(|_| [0; 3].map(|_| next(nv as u64) as u32))
                .collect();
            let mesh = built(positions, &tris);
            let target = next(mesh.n_faces() as u64 + 1) as usize;
            assert_same_as_reference(&mesh, &params(target, f64::INFINITY, 100.0));
        }
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        // Big enough for the parallel candidate scan and sort.
        let input = crate::io::read_mesh(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply"),
        )
        .unwrap();
        let mesh = Mesh::from_polygons(&input).unwrap().mesh;
        assert!(mesh.n_faces() > 2 * PAR_MIN);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let p = params(500, f64::INFINITY, 100.0);
                let (collapses, flat, _) = decimate(FlatMesh::from_mesh(&mesh), &p, &NoProgress);
                (collapses, flat.triangles())
            })
        };
        let one = run(1);
        assert!(one.0.len() > 30_000);
        assert!(one == run(3));
    }

    #[test]
    fn builder_corner_table_equals_the_mesh_it_builds() {
        let input = crate::io::read_mesh(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/snowden_lo.ply"),
        )
        .unwrap();
        let repaired = CornerTable::from_polygons(&input).unwrap();
        let positions = repaired
            .source
            .vertex_source
            .iter()
            .map(|&s| input.positions[s as usize])
            .collect();
        let a = FlatMesh::from_corners(positions, &repaired.corners);
        let b = FlatMesh::from_mesh(&Mesh::from_polygons(&input).unwrap().mesh);
        assert!(b.slot.is_none(), "builder slots are the corner ids");
        assert_eq!(a.corners, b.corners);
        assert_eq!(a.boundary_twin, b.boundary_twin);
        assert_eq!(a.vertices, b.vertices);
    }
}
