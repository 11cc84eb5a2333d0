//! The half-edge triangle mesh: typed slotmap handles, connectivity queries and circulators.
//!
//! Every edge is a pair of twin half-edges. Boundaries are explicit: a half-edge without a face
//! runs along a hole, and boundary half-edges are linked by `next`/`prev` into loops, so every
//! circulator works the same on open and closed surfaces. A boundary vertex stores one of its
//! *boundary* out-going half-edges, which makes [`Mesh::is_boundary_vertex`] O(1).

use glam::DVec3;
use slotmap::{Key, SlotMap, new_key_type};
use smallvec::SmallVec;

new_key_type! {
    /// Handle of a vertex.
    pub struct VertexId;
    /// Handle of a half-edge (a directed edge; its twin runs the other way).
    pub struct HalfedgeId;
    /// Handle of a triangle.
    pub struct FaceId;
}

/// The slot index of a handle. For a mesh fresh from the builder (no deletions) this is the
/// dense index `0..n` in insertion order, which is how results map back onto the input.
pub trait SlotIndex {
    /// Slot position of the handle, counted from 0.
    fn slot(self) -> usize;
}

macro_rules! slot_index {
    ($t:ty) => {
        impl SlotIndex for $t {
            #[inline]
            fn slot(self) -> usize {
                // slotmap reserves slot 0 as its sentinel, so the first key has index 1.
                ((self.data().as_ffi() & 0xffff_ffff) as usize).wrapping_sub(1)
            }
        }
    };
}
slot_index!(VertexId);
slot_index!(HalfedgeId);
slot_index!(FaceId);

/// Per-vertex record.
#[derive(Clone, Debug)]
pub(crate) struct VertexRecord {
    /// An out-going half-edge (a boundary one when the vertex is on a boundary); `None` for an
    /// isolated vertex.
    pub halfedge: Option<HalfedgeId>,
    /// Position.
    pub position: DVec3,
}

/// Per-half-edge record.
#[derive(Clone, Debug)]
pub(crate) struct HalfedgeRecord {
    /// The vertex this half-edge points to.
    pub to: VertexId,
    /// Next half-edge around the face (or boundary loop).
    pub next: HalfedgeId,
    /// Previous half-edge around the face (or boundary loop).
    pub prev: HalfedgeId,
    /// The opposite half-edge.
    pub twin: HalfedgeId,
    /// The face on the left, `None` on a boundary.
    pub face: Option<FaceId>,
}

impl HalfedgeRecord {
    /// A record with null links, to be filled once the handles it links to exist.
    pub(crate) fn unlinked() -> Self {
        let null = HalfedgeId::default();
        HalfedgeRecord {
            to: VertexId::default(),
            next: null,
            prev: null,
            twin: null,
            face: None,
        }
    }
}

/// Per-face record.
#[derive(Clone, Debug)]
pub(crate) struct FaceRecord {
    /// One of the face's three half-edges.
    pub halfedge: HalfedgeId,
}

/// A half-edge triangle mesh with `f64` positions.
///
/// Build one with [`Mesh::from_polygons`](crate::mesh::Mesh::from_polygons) or
/// [`Mesh::from_triangles`](crate::mesh::Mesh::from_triangles); check it with
/// [`Mesh::validate`](crate::mesh::Mesh::validate). The record maps are public to the crate's
/// topological operators (`pm`, `subdiv`); everyone else uses the accessors.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub(crate) vertices: SlotMap<VertexId, VertexRecord>,
    pub(crate) halfedges: SlotMap<HalfedgeId, HalfedgeRecord>,
    pub(crate) faces: SlotMap<FaceId, FaceRecord>,
}

impl Mesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of vertices (isolated ones included).
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of half-edges (twice the number of edges).
    pub(crate) fn n_halfedges(&self) -> usize {
        self.halfedges.len()
    }

    /// Number of edges.
    pub(crate) fn n_edges(&self) -> usize {
        self.halfedges.len() / 2
    }

    /// Number of triangles.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// All vertex handles, in slot order.
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = VertexId> + '_ {
        self.vertices.keys()
    }

    /// All half-edge handles, in slot order.
    pub fn halfedges(&self) -> impl ExactSizeIterator<Item = HalfedgeId> + '_ {
        self.halfedges.keys()
    }

    /// All face handles, in slot order.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = FaceId> + '_ {
        self.faces.keys()
    }

    /// One half-edge per edge: the one whose slot is smaller than its twin's.
    pub fn edges(&self) -> impl Iterator<Item = HalfedgeId> + '_ {
        self.halfedges
            .iter()
            .filter(|(h, r)| h.slot() < r.twin.slot())
            .map(|(h, _)| h)
    }

    /// True if the handle refers to a live vertex.
    pub(crate) fn contains_vertex(&self, v: VertexId) -> bool {
        self.vertices.contains_key(v)
    }

    /// True if the handle refers to a live half-edge.
    #[cfg(test)]
    pub(crate) fn contains_halfedge(&self, h: HalfedgeId) -> bool {
        self.halfedges.contains_key(h)
    }

    /// Position of `v`.
    #[inline]
    pub fn position(&self, v: VertexId) -> DVec3 {
        self.vertices[v].position
    }

    /// Moves `v` to `p`.
    #[inline]
    pub fn set_position(&mut self, v: VertexId, p: DVec3) {
        self.vertices[v].position = p;
    }

    /// The vertex `h` points to.
    #[inline]
    pub fn to_vertex(&self, h: HalfedgeId) -> VertexId {
        self.halfedges[h].to
    }

    /// The vertex `h` starts from.
    #[inline]
    pub fn from_vertex(&self, h: HalfedgeId) -> VertexId {
        self.halfedges[self.halfedges[h].twin].to
    }

    /// Next half-edge around the face or boundary loop.
    #[inline]
    pub fn next(&self, h: HalfedgeId) -> HalfedgeId {
        self.halfedges[h].next
    }

    /// Previous half-edge around the face or boundary loop.
    #[inline]
    pub(crate) fn prev(&self, h: HalfedgeId) -> HalfedgeId {
        self.halfedges[h].prev
    }

    /// The opposite half-edge.
    #[inline]
    pub fn twin(&self, h: HalfedgeId) -> HalfedgeId {
        self.halfedges[h].twin
    }

    /// The face left of `h`, `None` on a boundary.
    #[inline]
    pub fn face(&self, h: HalfedgeId) -> Option<FaceId> {
        self.halfedges[h].face
    }

    /// One half-edge of face `f`.
    #[inline]
    pub(crate) fn face_halfedge(&self, f: FaceId) -> HalfedgeId {
        self.faces[f].halfedge
    }

    /// True if `h` has no face (it runs along a hole).
    #[inline]
    pub(crate) fn is_boundary_halfedge(&self, h: HalfedgeId) -> bool {
        self.halfedges[h].face.is_none()
    }

    /// True if either side of the edge of `h` is a boundary.
    #[inline]
    pub(crate) fn is_boundary_edge(&self, h: HalfedgeId) -> bool {
        self.is_boundary_halfedge(h) || self.is_boundary_halfedge(self.twin(h))
    }

    /// True if `v` lies on a boundary. Isolated vertices count as boundary.
    #[inline]
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        match self.vertices[v].halfedge {
            Some(h) => self.is_boundary_halfedge(h),
            None => true,
        }
    }

    /// True if `v` has no incident edge.
    #[inline]
    pub fn is_isolated(&self, v: VertexId) -> bool {
        self.vertices[v].halfedge.is_none()
    }

    /// The three vertices of `f`, counter-clockwise, starting at the origin of its half-edge.
    #[inline]
    pub fn face_vertices(&self, f: FaceId) -> [VertexId; 3] {
        let h = self.faces[f].halfedge;
        let r = &self.halfedges[h];
        [self.halfedges[r.prev].to, r.to, self.halfedges[r.next].to]
    }

    /// The three half-edges of `f`, starting at its stored half-edge.
    #[inline]
    pub(crate) fn face_halfedges(&self, f: FaceId) -> [HalfedgeId; 3] {
        let h = self.faces[f].halfedge;
        let r = &self.halfedges[h];
        [h, r.next, r.prev]
    }

    /// The three corner positions of `f`.
    #[inline]
    pub fn face_positions(&self, f: FaceId) -> [DVec3; 3] {
        self.face_vertices(f).map(|v| self.position(v))
    }

    /// Circulates the out-going half-edges of `v` (counter-clockwise; a boundary vertex starts
    /// at its boundary half-edge). Empty for an isolated vertex.
    #[inline]
    pub(crate) fn outgoing(&self, v: VertexId) -> Outgoing<'_> {
        let start = self.vertices[v].halfedge;
        Outgoing {
            mesh: self,
            start,
            current: start,
        }
    }

    /// The neighbours of `v` in circulation order.
    pub fn neighbors(&self, v: VertexId) -> SmallVec<[VertexId; 8]> {
        self.outgoing(v).map(|h| self.to_vertex(h)).collect()
    }

    /// The faces around `v` in circulation order.
    pub(crate) fn vertex_faces(&self, v: VertexId) -> SmallVec<[FaceId; 8]> {
        self.outgoing(v).filter_map(|h| self.face(h)).collect()
    }

    /// Number of edges at `v`.
    pub fn valence(&self, v: VertexId) -> usize {
        self.outgoing(v).count()
    }

    /// The half-edge from `a` to `b`, if that edge exists.
    pub(crate) fn find_halfedge(&self, a: VertexId, b: VertexId) -> Option<HalfedgeId> {
        self.outgoing(a).find(|&h| self.to_vertex(h) == b)
    }

    /// Positions of all vertices in slot order.
    pub fn positions(&self) -> Vec<DVec3> {
        self.vertices.values().map(|r| r.position).collect()
    }

    /// Dense copy: positions in slot order and triangles indexing them (faces in slot order).
    /// Deleted slots are skipped, so indices are compacted.
    pub fn to_triangles(&self) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut index = slotmap::SecondaryMap::with_capacity(self.vertices.len());
        let mut pos = Vec::with_capacity(self.vertices.len());
        for (i, (v, r)) in self.vertices.iter().enumerate() {
            index.insert(v, i as u32);
            pos.push(r.position);
        }
        let tris = self
            .faces()
            .map(|f| self.face_vertices(f).map(|v| index[v]))
            .collect();
        (pos, tris)
    }
}

/// Iterator over the out-going half-edges of a vertex; see [`Mesh::outgoing`].
pub(crate) struct Outgoing<'a> {
    mesh: &'a Mesh,
    start: Option<HalfedgeId>,
    current: Option<HalfedgeId>,
}

impl Iterator for Outgoing<'_> {
    type Item = HalfedgeId;

    #[inline]
    fn next(&mut self) -> Option<HalfedgeId> {
        let h = self.current?;
        // prev(h) arrives at v; its twin leaves v on the next face counter-clockwise.
        let n = self.mesh.twin(self.mesh.prev(h));
        self.current = if Some(n) == self.start { None } else { Some(n) };
        Some(h)
    }
}
