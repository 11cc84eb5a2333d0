//! Checks every half-edge invariant; used by tests, property tests and fuzz targets after each
//! topological operation.

use super::halfedge::{HalfedgeId, Mesh};
use slotmap::SecondaryMap;

/// A broken invariant, with the element it was found on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid mesh: {0}")]
pub struct ValidationError(pub String);

fn fail<T>(msg: String) -> Result<T, ValidationError> {
    Err(ValidationError(msg))
}

impl Mesh {
    /// Verifies the half-edge invariants:
    /// - handles stored in records are live; `twin(twin(h)) == h`, `twin(h) != h`;
    ///   `prev(next(h)) == h`; `from(next(h)) == to(h)`;
    /// - twins run in opposite directions and never form a loop edge (`from == to`);
    /// - a face's loop has exactly three half-edges, all pointing at the face;
    /// - boundary half-edges chain into boundary loops;
    /// - every vertex's out-going half-edges form one fan reachable from its stored half-edge
    ///   (no pinched vertices), the stored half-edge is a boundary one on boundary vertices,
    ///   and isolated vertices have no half-edge;
    /// - positions are finite.
    pub fn validate(&self) -> Result<(), ValidationError> {
        for (h, r) in self.halfedges.iter() {
            for (what, k) in [("next", r.next), ("prev", r.prev), ("twin", r.twin)] {
                if !self.halfedges.contains_key(k) {
                    return fail(format!("half-edge {h:?}: dangling {what}"));
                }
            }
            if !self.vertices.contains_key(r.to) {
                return fail(format!("half-edge {h:?}: dangling vertex"));
            }
            if let Some(f) = r.face
                && !self.faces.contains_key(f)
            {
                return fail(format!("half-edge {h:?}: dangling face"));
            }
            if r.twin == h || self.halfedges[r.twin].twin != h {
                return fail(format!("half-edge {h:?}: twin is not symmetric"));
            }
            if self.halfedges[r.next].prev != h || self.halfedges[r.prev].next != h {
                return fail(format!("half-edge {h:?}: next/prev mismatch"));
            }
            if self.from_vertex(r.next) != r.to {
                return fail(format!("half-edge {h:?}: next does not start at its head"));
            }
            if self.from_vertex(h) == r.to {
                return fail(format!("half-edge {h:?}: loop edge"));
            }
            if r.face.is_none() && self.halfedges[r.twin].face.is_none() {
                return fail(format!("half-edge {h:?}: both sides are boundary"));
            }
            if r.face != self.halfedges[r.next].face {
                return fail(format!("half-edge {h:?}: next lies on another face"));
            }
        }
        for (f, r) in self.faces.iter() {
            if !self.halfedges.contains_key(r.halfedge) {
                return fail(format!("face {f:?}: dangling half-edge"));
            }
            let h = r.halfedge;
            if self.face(h) != Some(f) {
                return fail(format!("face {f:?}: its half-edge points to another face"));
            }
            if self.next(self.next(self.next(h))) != h {
                return fail(format!("face {f:?}: not a triangle"));
            }
        }
        // Out-going half-edge counts per vertex, to check that each fan is complete.
        let mut out_count: SecondaryMap<_, u32> = SecondaryMap::with_capacity(self.vertices.len());
        for (h, _) in self.halfedges.iter() {
            *out_count.entry(self.from_vertex(h)).unwrap().or_insert(0) += 1;
        }
        for (v, r) in self.vertices.iter() {
            if !r.position.is_finite() {
                return fail(format!("vertex {v:?}: non-finite position"));
            }
            let expected = out_count.get(v).copied().unwrap_or(0);
            let Some(h0) = r.halfedge else {
                if expected > 0 {
                    return fail(format!("vertex {v:?}: has edges but no half-edge"));
                }
                continue;
            };
            if !self.halfedges.contains_key(h0) || self.from_vertex(h0) != v {
                return fail(format!("vertex {v:?}: stored half-edge does not leave it"));
            }
            let mut n = 0u32;
            let mut boundary_seen = 0u32;
            let mut h: HalfedgeId = h0;
            loop {
                if self.from_vertex(h) != v {
                    return fail(format!("vertex {v:?}: circulation left the vertex"));
                }
                if self.is_boundary_halfedge(h) {
                    boundary_seen += 1;
                }
                n += 1;
                if n > expected {
                    return fail(format!("vertex {v:?}: circulation does not close"));
                }
                h = self.twin(self.prev(h));
                if h == h0 {
                    break;
                }
            }
            if n != expected {
                return fail(format!(
                    "vertex {v:?}: non-manifold ({n} of {expected} out-going half-edges in its fan)"
                ));
            }
            if boundary_seen > 1 {
                return fail(format!("vertex {v:?}: several boundary out-edges"));
            }
            if boundary_seen == 1 && !self.is_boundary_halfedge(h0) {
                return fail(format!(
                    "vertex {v:?}: boundary vertex stores an interior half-edge"
                ));
            }
        }
        Ok(())
    }
}
