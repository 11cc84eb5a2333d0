//! A triangle mesh's connectivity as flat half-edge arrays, the form quadrisection reads and
//! writes on every level instead of the slotmap [`Mesh`].
//!
//! Why: at a million vertices the slotmap mesh takes about 400 B per vertex (versioned handles
//! in 48-byte half-edge records, plus the handle vectors needed to fill a fresh one), and the
//! page faults on that memory were a third of `meshpyr subdivide`'s time. These arrays take
//! 20 B per half-edge. They keep the slot layout of the mesh they mirror (half-edge `h` here
//! is slot `h` there), so every loop over them visits elements in the same order as the loop
//! over the mesh did, and results keep their bits.

use crate::mesh::{FaceId, HalfedgeId, Mesh, SlotIndex, VertexId};
use glam::DVec3;

/// "No element": a boundary half-edge's face, an isolated vertex's half-edge.
pub(crate) const NONE: u32 = u32::MAX;

/// One half-edge: indices into [`HalfedgeArrays::halfedges`], the vertex list and the face
/// list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Halfedge {
    /// The vertex it points to.
    pub to: u32,
    /// The opposite half-edge.
    pub twin: u32,
    /// Next around its face (or boundary loop).
    pub next: u32,
    /// Previous around its face (or boundary loop).
    pub prev: u32,
    /// Its face, [`NONE`] on a boundary.
    pub face: u32,
}

/// Half-edge connectivity of a triangle mesh with the same invariants as [`Mesh`]: twins
/// pair up, boundary half-edges form loops, a boundary vertex's half-edge is a boundary one.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct HalfedgeArrays {
    /// All half-edges.
    pub halfedges: Vec<Halfedge>,
    /// One half-edge of each face; the face's vertex order starts at its origin's successor
    /// as in [`Mesh::face_vertices`].
    pub face_halfedge: Vec<u32>,
    /// An out-going half-edge of each vertex, [`NONE`] for an isolated vertex.
    pub vertex_halfedge: Vec<u32>,
}

impl HalfedgeArrays {
    /// The connectivity of `mesh`, elements numbered by their rank in slot order (which is the
    /// slot itself for a dense mesh, as [`super::compact`] makes).
    pub(crate) fn from_mesh(mesh: &Mesh) -> Self {
        let rank = |slots: &mut dyn Iterator<Item = usize>| {
            let slots: Vec<usize> = slots.collect();
            let mut rank = vec![NONE; slots.iter().max().map_or(0, |m| m + 1)];
            for (i, s) in slots.into_iter().enumerate() {
                rank[s] = i as u32;
            }
            rank
        };
        let v_rank = rank(&mut mesh.vertices().map(|v| v.slot()));
        let h_rank = rank(&mut mesh.halfedges().map(|h| h.slot()));
        let f_rank = rank(&mut mesh.faces().map(|f| f.slot()));
        let h = |id: HalfedgeId| h_rank[id.slot()];
        Self {
            halfedges: mesh
                .halfedges
                .values()
                .map(|r| Halfedge {
                    to: v_rank[r.to.slot()],
                    twin: h(r.twin),
                    next: h(r.next),
                    prev: h(r.prev),
                    face: r.face.map_or(NONE, |f| f_rank[f.slot()]),
                })
                .collect(),
            face_halfedge: mesh.faces.values().map(|r| h(r.halfedge)).collect(),
            vertex_halfedge: mesh
                .vertices
                .values()
                .map(|r| r.halfedge.map_or(NONE, h))
                .collect(),
        }
    }

    /// The slotmap mesh with this connectivity and `positions` (one per vertex); element `i`
    /// here is slot `i` there.
    pub(crate) fn to_mesh(&self, positions: &[DVec3]) -> Mesh {
        use crate::mesh::halfedge::{FaceRecord, HalfedgeRecord, VertexRecord};
        debug_assert_eq!(positions.len(), self.n_vertices());
        let mut mesh = Mesh::new();
        mesh.vertices.reserve(positions.len());
        mesh.halfedges.reserve(self.halfedges.len());
        mesh.faces.reserve(self.face_halfedge.len());
        // A fresh slotmap's handles are only known once inserted, so the records go in as
        // placeholders first and are filled through the handle tables.
        let vid: Vec<VertexId> = positions
            .iter()
            .map(|&position| {
                mesh.vertices.insert(VertexRecord {
                    halfedge: None,
                    position,
                })
            })
            .collect();
        let hid: Vec<HalfedgeId> = (0..self.halfedges.len())
            .map(|_| mesh.halfedges.insert(HalfedgeRecord::unlinked()))
            .collect();
        let fid: Vec<FaceId> = self
            .face_halfedge
            .iter()
            .map(|&h| {
                mesh.faces.insert(FaceRecord {
                    halfedge: hid[h as usize],
                })
            })
            .collect();
        for (r, e) in mesh.halfedges.values_mut().zip(&self.halfedges) {
            *r = HalfedgeRecord {
                to: vid[e.to as usize],
                next: hid[e.next as usize],
                prev: hid[e.prev as usize],
                twin: hid[e.twin as usize],
                face: (e.face != NONE).then(|| fid[e.face as usize]),
            };
        }
        for (r, &h) in mesh.vertices.values_mut().zip(&self.vertex_halfedge) {
            r.halfedge = (h != NONE).then(|| hid[h as usize]);
        }
        mesh
    }

    /// Number of vertices (isolated ones included).
    pub(crate) fn n_vertices(&self) -> usize {
        self.vertex_halfedge.len()
    }

    /// Number of triangles.
    pub(crate) fn n_faces(&self) -> usize {
        self.face_halfedge.len()
    }

    /// The half-edge `h`.
    #[inline]
    pub(crate) fn get(&self, h: u32) -> Halfedge {
        self.halfedges[h as usize]
    }

    /// The vertex `h` leaves.
    #[inline]
    pub(crate) fn from(&self, h: u32) -> u32 {
        self.get(self.get(h).twin).to
    }

    /// True if `h` has no face.
    #[inline]
    pub(crate) fn is_boundary(&self, h: u32) -> bool {
        self.get(h).face == NONE
    }

    /// The three half-edges of face `t`, from its stored one (as [`Mesh::face_halfedges`]).
    #[inline]
    pub(crate) fn face_halfedges(&self, t: usize) -> [u32; 3] {
        let h = self.face_halfedge[t];
        let e = self.get(h);
        [h, e.next, e.prev]
    }

    /// The three vertices of face `t` (as [`Mesh::face_vertices`]).
    #[inline]
    pub(crate) fn face_vertices(&self, t: usize) -> [u32; 3] {
        let h = self.face_halfedge[t];
        let e = self.get(h);
        [self.get(e.prev).to, e.to, self.get(e.next).to]
    }

    /// Every half-edge's corner: `3t + k` for the `k`-th of face `t`'s
    /// [`Self::face_halfedges`], [`NONE`] for a boundary half-edge.
    pub(crate) fn corners(&self) -> Vec<u32> {
        let mut corner = vec![NONE; self.halfedges.len()];
        for t in 0..self.n_faces() {
            for (k, h) in self.face_halfedges(t).into_iter().enumerate() {
                corner[h as usize] = (3 * t + k) as u32;
            }
        }
        corner
    }

    /// One half-edge per edge, the one smaller than its twin, in index order (as
    /// [`Mesh::edges`]).
    pub(crate) fn edges(&self) -> impl Iterator<Item = u32> + '_ {
        self.halfedges
            .iter()
            .enumerate()
            .filter(|(h, e)| (*h as u32) < e.twin)
            .map(|(h, _)| h as u32)
    }

    /// The out-going half-edges of vertex `v`, in [`Mesh::outgoing`]'s order.
    pub(crate) fn outgoing(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        let start = self.vertex_halfedge[v as usize];
        let mut current = (start != NONE).then_some(start);
        std::iter::from_fn(move || {
            let h = current?;
            let n = self.get(self.get(h).prev).twin;
            current = (n != start).then_some(n);
            Some(h)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangles(a: &HalfedgeArrays) -> Vec<[u32; 3]> {
        (0..a.n_faces()).map(|t| a.face_vertices(t)).collect()
    }

    fn open_grid_with_a_hole_and_an_isolated_vertex() -> Mesh {
        let (mut p, t) = crate::mesh::shapes::grid(4, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        p.push(DVec3::splat(9.0));
        let t: Vec<[u32; 3]> = t
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| i != 9)
            .map(|(_, f)| f)
            .collect();
        Mesh::from_triangles(&p, &t).unwrap().mesh
    }

    #[test]
    fn a_mesh_round_trips_and_every_query_matches_the_slotmap_mesh() {
        let mesh = open_grid_with_a_hole_and_an_isolated_vertex();
        let a = HalfedgeArrays::from_mesh(&mesh);
        let back = a.to_mesh(&mesh.positions());
        assert!(back.validate().is_ok());
        assert_eq!(back.to_triangles(), mesh.to_triangles());
        assert_eq!(HalfedgeArrays::from_mesh(&back), a);
        assert_eq!(triangles(&a), mesh.to_triangles().1);
        let slots = |it: &mut dyn Iterator<Item = HalfedgeId>| -> Vec<u32> {
            it.map(|h| h.slot() as u32).collect()
        };
        assert_eq!(a.edges().collect::<Vec<_>>(), slots(&mut mesh.edges()));
        for v in mesh.vertices() {
            let ours: Vec<u32> = a.outgoing(v.slot() as u32).collect();
            assert_eq!(ours, slots(&mut mesh.outgoing(v)));
        }
        let isolated = a.n_vertices() as u32 - 1;
        assert_eq!(a.outgoing(isolated).count(), 0);
        let corners = a.corners();
        for t in 0..a.n_faces() {
            for (k, h) in a.face_halfedges(t).into_iter().enumerate() {
                assert_eq!(corners[h as usize] as usize, 3 * t + k);
            }
        }
        for h in mesh.halfedges() {
            let s = h.slot() as u32;
            assert_eq!(corners[h.slot()] == NONE, mesh.is_boundary_halfedge(h));
            assert_eq!(a.from(s) as usize, mesh.from_vertex(h).slot());
            assert_eq!(a.is_boundary(s), mesh.is_boundary_halfedge(h));
        }
    }

    #[test]
    fn meshes_with_deleted_elements_are_numbered_by_rank() {
        // An isolated vertex in slot 0, then deleted: every other vertex's rank is its slot − 1.
        let (p, t) = crate::mesh::shapes::grid(3, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        let p: Vec<DVec3> = std::iter::once(DVec3::splat(9.0)).chain(p).collect();
        let t: Vec<[u32; 3]> = t.iter().map(|f| f.map(|v| v + 1)).collect();
        let mut mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let isolated = mesh.vertices().next().unwrap();
        mesh.vertices.remove(isolated);
        let a = HalfedgeArrays::from_mesh(&mesh);
        assert_eq!(a.n_vertices(), p.len() - 1);
        assert_eq!(triangles(&a), mesh.to_triangles().1);
        let back = a.to_mesh(&mesh.positions());
        assert!(back.validate().is_ok());
        assert_eq!(back.to_triangles(), mesh.to_triangles());
    }
}
