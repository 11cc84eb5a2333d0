//! Half-edge collapse and its exact inverse, the vertex split, with the legality tests of
//! `docs/algorithms.md` §4.2.
//!
//! Collapse `u → v` (half-edge `h = u→v`, `o = twin(h)`): the face `f_l = (u, v, v_l)` left of
//! `h` and `f_r = (v, u, v_r)` right of it are deleted together with their six half-edges;
//! the outer half-edges of each deleted face are glued into one edge; every other half-edge
//! that pointed at `u` now points at `v`; `v` keeps its position.
//!
//! **Exactness.** Both primitives keep the mesh in *canonical form*: a face stores its
//! half-edge of smallest slot; a boundary vertex stores its boundary out-going half-edge and an
//! interior vertex its out-going half-edge of smallest slot. The builder produces canonical
//! meshes. Collapse frees slots in a fixed order and split re-inserts in the reverse order;
//! slotmap reuses the most recently freed slot first, so a split that directly undoes a
//! collapse (or any sequence undone in stack order) restores every record in its original slot
//! — the data structure is identical up to slotmap's internal generation counters.

use super::legality::{Legality, RingFace, shape_check};
use crate::mesh::halfedge::{FaceRecord, HalfedgeRecord, VertexRecord};
use crate::mesh::{FaceId, HalfedgeId, Mesh, SlotIndex, VertexId};
use glam::DVec3;
use smallvec::SmallVec;

/// The vertices of a half-edge collapse `from → to`, i.e. what a vertex split needs besides the
/// position of the re-inserted vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CollapseTopology {
    /// The removed vertex `u`.
    pub from: VertexId,
    /// The survivor `v` (keeps its position).
    pub to: VertexId,
    /// Apex of the face left of `u→v`; `None` when `u→v` is a boundary half-edge.
    pub left: Option<VertexId>,
    /// Apex of the face right of `u→v`; `None` when `v→u` is a boundary half-edge.
    pub right: Option<VertexId>,
}

/// Why a vertex split could not be applied.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SplitError {
    /// A vertex of the record is not in the mesh.
    #[error("vertex split refers to a vertex that is not in the mesh")]
    MissingVertex,
    /// The record's wing vertices are not neighbours of the survivor in a way a collapse leaves.
    #[error("vertex split does not match the mesh around its survivor")]
    Inconsistent,
}

/// Reads the vertices involved in collapsing `h`.
pub(crate) fn collapse_topology(mesh: &Mesh, h: HalfedgeId) -> CollapseTopology {
    let o = mesh.twin(h);
    CollapseTopology {
        from: mesh.from_vertex(h),
        to: mesh.to_vertex(h),
        left: mesh.face(h).map(|_| mesh.to_vertex(mesh.next(h))),
        right: mesh.face(o).map(|_| mesh.to_vertex(mesh.next(o))),
    }
}

/// CCW successor of an out-going half-edge around its origin.
#[inline]
fn ccw(mesh: &Mesh, g: HalfedgeId) -> HalfedgeId {
    mesh.twin(mesh.prev(g))
}

/// Canonical out-going half-edge of the vertex `start` leaves: its boundary one, else the one
/// of smallest slot.
fn canonical_out(mesh: &Mesh, start: HalfedgeId) -> HalfedgeId {
    let mut best = start;
    let mut g = start;
    loop {
        if mesh.halfedges[g].face.is_none() {
            return g;
        }
        if g.slot() < best.slot() {
            best = g;
        }
        g = ccw(mesh, g);
        if g == start {
            return best;
        }
    }
}

fn set_canonical(mesh: &mut Mesh, v: VertexId, start: HalfedgeId) {
    let c = canonical_out(mesh, start);
    mesh.vertices[v].halfedge = Some(c);
}

fn min_slot(hs: [HalfedgeId; 3]) -> HalfedgeId {
    let mut m = hs[0];
    for h in &hs[1..] {
        if h.slot() < m.slot() {
            m = *h;
        }
    }
    m
}

/// Collapses `h = u→v`: removes `u` and the (one or two) faces on `h`'s edge. The caller must
/// have checked legality (`is_collapse_topologically_legal` at least); an illegal collapse
/// breaks the half-edge invariants.
///
/// Frees, in this order: half-edges `h1 = v→v_l`, `h2 = v_l→u`, `o1 = u→v_r`, `o2 = v_r→v`,
/// `h`, `o`; faces `f_l`, `f_r`; vertex `u` ([`vertex_split`] re-inserts in reverse order).
pub fn half_edge_collapse(mesh: &mut Mesh, h: HalfedgeId) -> CollapseTopology {
    let topo = collapse_topology(mesh, h);
    let (u, v) = (topo.from, topo.to);
    let o = mesh.twin(h);
    // Everything that arrived at u now arrives at v.
    let mut g = h;
    loop {
        let t = mesh.halfedges[g].twin;
        mesh.halfedges[t].to = v;
        g = mesh.halfedges[t].next;
        if g == h {
            break;
        }
    }
    let mut v_out = None;
    let mut fix_l = None;
    let mut fix_r = None;
    let mut dead_faces: [Option<FaceId>; 2] = [None, None];
    let mut dead_he: SmallVec<[HalfedgeId; 6]> = SmallVec::new();
    if let Some(fl) = mesh.halfedges[h].face {
        let h1 = mesh.halfedges[h].next;
        let h2 = mesh.halfedges[h].prev;
        let t1 = mesh.halfedges[h1].twin;
        let t2 = mesh.halfedges[h2].twin;
        mesh.halfedges[t1].twin = t2;
        mesh.halfedges[t2].twin = t1;
        fix_l = Some(t1);
        v_out = Some(t2);
        dead_he.push(h1);
        dead_he.push(h2);
        dead_faces[0] = Some(fl);
    } else {
        let (p, n) = (mesh.halfedges[h].prev, mesh.halfedges[h].next);
        mesh.halfedges[p].next = n;
        mesh.halfedges[n].prev = p;
        v_out = v_out.or(Some(n));
    }
    if let Some(fr) = mesh.halfedges[o].face {
        let o1 = mesh.halfedges[o].next;
        let o2 = mesh.halfedges[o].prev;
        let s1 = mesh.halfedges[o1].twin;
        let s2 = mesh.halfedges[o2].twin;
        mesh.halfedges[s1].twin = s2;
        mesh.halfedges[s2].twin = s1;
        fix_r = Some(s1);
        v_out = Some(s2);
        dead_he.push(o1);
        dead_he.push(o2);
        dead_faces[1] = Some(fr);
    } else {
        let (p, n) = (mesh.halfedges[o].prev, mesh.halfedges[o].next);
        mesh.halfedges[p].next = n;
        mesh.halfedges[n].prev = p;
        v_out = v_out.or(Some(n));
    }
    dead_he.push(h);
    dead_he.push(o);
    for d in dead_he {
        mesh.halfedges.remove(d);
    }
    for f in dead_faces.into_iter().flatten() {
        mesh.faces.remove(f);
    }
    mesh.vertices.remove(u);
    if let (Some(vl), Some(t1)) = (topo.left, fix_l) {
        set_canonical(mesh, vl, t1);
    }
    if let (Some(vr), Some(s1)) = (topo.right, fix_r) {
        set_canonical(mesh, vr, s1);
    }
    if let Some(start) = v_out {
        set_canonical(mesh, v, start);
    }
    topo
}

fn placeholder(mesh: &mut Mesh) -> HalfedgeId {
    mesh.halfedges.insert(HalfedgeRecord::unlinked())
}

/// Re-inserts a vertex at `position` next to `survivor`, undoing the collapse described by
/// `left`/`right` (see [`CollapseTopology`]): the fan of faces around `survivor` from the edge
/// to `left` counter-clockwise to the edge to `right` (or to the boundary) moves to the new
/// vertex, and the faces `(new, survivor, left)` and `(survivor, new, right)` are re-created.
/// Returns the new vertex. Checks the record against the mesh and fails instead of corrupting it.
pub fn vertex_split(
    mesh: &mut Mesh,
    survivor: VertexId,
    left: Option<VertexId>,
    right: Option<VertexId>,
    position: DVec3,
) -> Result<VertexId, SplitError> {
    let v = survivor;
    check_split_vertices(mesh, v, left, right)?;
    let wings = find_wings(mesh, v, left, right)?;
    let fan = collect_fan(mesh, &wings)?;
    let s1 = wings.s2.map(|s| mesh.twin(s));
    let t1 = wings.t2.map(|t| mesh.twin(t));
    let new = insert_records(mesh, position, left.is_some(), right.is_some());
    redirect_fan(mesh, &fan, wings.t2, s1, new.u);
    link_new_edge(mesh, &new, v);
    match (left, new.h1, new.h2, t1, wings.t2) {
        (Some(vl), Some(h1), Some(h2), Some(t1), Some(t2)) => {
            rebuild_left_face(mesh, &new, vl, [h1, h2], [t1, t2])
        }
        _ => splice_boundary_h(mesh, new.h, wings.bout)?,
    }
    match (right, new.o1, new.o2, s1, wings.s2) {
        (Some(vr), Some(o1), Some(o2), Some(s1), Some(s2)) => {
            rebuild_right_face(mesh, &new, v, vr, [o1, o2], [s1, s2])
        }
        _ => splice_boundary_o(mesh, new.o, &fan)?,
    }
    set_canonical(mesh, new.u, new.h);
    set_canonical(mesh, v, new.o);
    if let (Some(vl), Some(h2)) = (left, new.h2) {
        set_canonical(mesh, vl, h2);
    }
    if let (Some(vr), Some(o2)) = (right, new.o2) {
        set_canonical(mesh, vr, o2);
    }
    Ok(new.u)
}

/// The record's vertices exist and can describe a collapse: at least one wing, two different
/// wings, neither of them the survivor.
#[inline]
fn check_split_vertices(
    mesh: &Mesh,
    v: VertexId,
    left: Option<VertexId>,
    right: Option<VertexId>,
) -> Result<(), SplitError> {
    for x in [Some(v), left, right].into_iter().flatten() {
        if !mesh.contains_vertex(x) {
            return Err(SplitError::MissingVertex);
        }
    }
    if (left.is_none() && right.is_none())
        || (left.is_some() && left == right)
        || left == Some(v)
        || right == Some(v)
    {
        return Err(SplitError::Inconsistent);
    }
    Ok(())
}

/// The survivor's half-edges to the wings, and its boundary out-going half-edge when a wing is
/// missing.
struct Wings {
    /// `v → v_l`.
    t2: Option<HalfedgeId>,
    /// `v → v_r`.
    s2: Option<HalfedgeId>,
    bout: Option<HalfedgeId>,
}

#[inline]
fn find_wings(
    mesh: &Mesh,
    v: VertexId,
    left: Option<VertexId>,
    right: Option<VertexId>,
) -> Result<Wings, SplitError> {
    let find = |x: VertexId| mesh.find_halfedge(v, x).ok_or(SplitError::Inconsistent);
    let t2 = left.map(find).transpose()?;
    let s2 = right.map(find).transpose()?;
    let bout = match (left, right) {
        (Some(_), Some(_)) => None,
        _ => {
            let b = mesh.vertices[v].halfedge.ok_or(SplitError::Inconsistent)?;
            if !mesh.is_boundary_halfedge(b) {
                return Err(SplitError::Inconsistent);
            }
            Some(b)
        }
    };
    Ok(Wings { t2, s2, bout })
}

/// The fan that moves to the new vertex: the survivor's out-going half-edges, counter-clockwise
/// from the edge to the left wing (or the one after the boundary out-edge) to the edge to the
/// right wing (exclusive; or through the boundary out-edge).
#[inline]
fn collect_fan(mesh: &Mesh, wings: &Wings) -> Result<SmallVec<[HalfedgeId; 16]>, SplitError> {
    let (t2, s2) = (wings.t2, wings.s2);
    let start = match (t2, wings.bout) {
        (Some(t2), _) => t2,
        (None, Some(b)) => ccw(mesh, b),
        (None, None) => return Err(SplitError::Inconsistent),
    };
    let limit = mesh.n_halfedges();
    let mut fan: SmallVec<[HalfedgeId; 16]> = SmallVec::new();
    let mut e = start;
    match s2 {
        Some(s2) => {
            while e != s2 {
                if fan.len() > limit || mesh.is_boundary_halfedge(e) {
                    return Err(SplitError::Inconsistent);
                }
                fan.push(e);
                e = ccw(mesh, e);
            }
        }
        None => loop {
            if fan.len() > limit || Some(e) == s2 {
                return Err(SplitError::Inconsistent);
            }
            fan.push(e);
            if mesh.is_boundary_halfedge(e) {
                break;
            }
            e = ccw(mesh, e);
        },
    }
    if let (Some(t2), None) = (t2, s2)
        && fan.first() != Some(&t2)
    {
        return Err(SplitError::Inconsistent);
    }
    // A boundary half-edge may only close the fan when there is no right face, and t2 may be
    // boundary only when it is also the last one.
    if s2.is_some() && fan.iter().any(|&g| mesh.is_boundary_halfedge(g)) {
        return Err(SplitError::Inconsistent);
    }
    Ok(fan)
}

/// The records a split creates (the `Option`s exist when their wing does).
struct NewRecords {
    u: VertexId,
    /// `v → u`.
    o: HalfedgeId,
    /// `u → v`.
    h: HalfedgeId,
    o2: Option<HalfedgeId>,
    o1: Option<HalfedgeId>,
    h2: Option<HalfedgeId>,
    h1: Option<HalfedgeId>,
    fr: Option<FaceId>,
    fl: Option<FaceId>,
}

/// Inserts the new records in the reverse order of [`half_edge_collapse`]'s frees, so each
/// lands in the slot the collapse freed.
#[inline]
fn insert_records(mesh: &mut Mesh, position: DVec3, has_left: bool, has_right: bool) -> NewRecords {
    let u = mesh.vertices.insert(VertexRecord {
        halfedge: None,
        position,
    });
    let o = placeholder(mesh);
    let h = placeholder(mesh);
    let (o2, o1) = if has_right {
        (Some(placeholder(mesh)), Some(placeholder(mesh)))
    } else {
        (None, None)
    };
    let (h2, h1) = if has_left {
        (Some(placeholder(mesh)), Some(placeholder(mesh)))
    } else {
        (None, None)
    };
    let fr = has_right.then(|| mesh.faces.insert(FaceRecord { halfedge: o }));
    let fl = has_left.then(|| mesh.faces.insert(FaceRecord { halfedge: h }));
    NewRecords {
        u,
        o,
        h,
        o2,
        o1,
        h2,
        h1,
        fr,
        fl,
    }
}

/// Every half-edge that arrived at `v` from the fan (but the left wing's, which `t2`'s new twin
/// takes over) and the right wing's `s1` now arrives at `u`.
#[inline]
fn redirect_fan(
    mesh: &mut Mesh,
    fan: &[HalfedgeId],
    t2: Option<HalfedgeId>,
    s1: Option<HalfedgeId>,
    u: VertexId,
) {
    for &g in fan {
        if Some(g) != t2 {
            let t = mesh.halfedges[g].twin;
            mesh.halfedges[t].to = u;
        }
    }
    if let Some(s1) = s1 {
        mesh.halfedges[s1].to = u;
    }
}

/// The new edge `h = u → v`, `o = v → u`, on the faces that will be left and right of it.
#[inline]
fn link_new_edge(mesh: &mut Mesh, new: &NewRecords, v: VertexId) {
    {
        let r = &mut mesh.halfedges[new.h];
        r.to = v;
        r.twin = new.o;
        r.face = new.fl;
    }
    {
        let r = &mut mesh.halfedges[new.o];
        r.to = new.u;
        r.twin = new.h;
        r.face = new.fr;
    }
}

/// The face `f_l = (u, v, v_l)`: `h`, `h1 = v → v_l`, `h2 = v_l → u`, twinned with `t1`, `t2`.
#[inline]
fn rebuild_left_face(
    mesh: &mut Mesh,
    new: &NewRecords,
    vl: VertexId,
    [h1, h2]: [HalfedgeId; 2],
    [t1, t2]: [HalfedgeId; 2],
) {
    let (h, fl) = (new.h, new.fl);
    mesh.halfedges[h1] = HalfedgeRecord {
        to: vl,
        next: h2,
        prev: h,
        twin: t1,
        face: fl,
    };
    mesh.halfedges[h2] = HalfedgeRecord {
        to: new.u,
        next: h,
        prev: h1,
        twin: t2,
        face: fl,
    };
    mesh.halfedges[h].next = h1;
    mesh.halfedges[h].prev = h2;
    mesh.halfedges[t1].twin = h1;
    mesh.halfedges[t2].twin = h2;
    if let Some(fl) = fl {
        mesh.faces[fl].halfedge = min_slot([h, h1, h2]);
    }
}

/// Without a left face `h` is a boundary half-edge: spliced in front of v's boundary
/// out-edge.
#[inline]
fn splice_boundary_h(
    mesh: &mut Mesh,
    h: HalfedgeId,
    bout: Option<HalfedgeId>,
) -> Result<(), SplitError> {
    let b = bout.ok_or(SplitError::Inconsistent)?;
    let bin = mesh.halfedges[b].prev;
    mesh.halfedges[h].prev = bin;
    mesh.halfedges[h].next = b;
    mesh.halfedges[bin].next = h;
    mesh.halfedges[b].prev = h;
    Ok(())
}

/// The face `f_r = (v, u, v_r)`: `o`, `o1 = u → v_r`, `o2 = v_r → v`, twinned with `s1`, `s2`.
#[inline]
fn rebuild_right_face(
    mesh: &mut Mesh,
    new: &NewRecords,
    v: VertexId,
    vr: VertexId,
    [o1, o2]: [HalfedgeId; 2],
    [s1, s2]: [HalfedgeId; 2],
) {
    let (o, fr) = (new.o, new.fr);
    mesh.halfedges[o1] = HalfedgeRecord {
        to: vr,
        next: o2,
        prev: o,
        twin: s1,
        face: fr,
    };
    mesh.halfedges[o2] = HalfedgeRecord {
        to: v,
        next: o,
        prev: o1,
        twin: s2,
        face: fr,
    };
    mesh.halfedges[o].next = o1;
    mesh.halfedges[o].prev = o2;
    mesh.halfedges[s1].twin = o1;
    mesh.halfedges[s2].twin = o2;
    if let Some(fr) = fr {
        mesh.faces[fr].halfedge = min_slot([o, o1, o2]);
    }
}

/// Without a right face `o` is a boundary half-edge: it runs v→u in front of u's boundary
/// out-edge, the last half-edge of the fan.
#[inline]
fn splice_boundary_o(mesh: &mut Mesh, o: HalfedgeId, fan: &[HalfedgeId]) -> Result<(), SplitError> {
    let gk = *fan.last().ok_or(SplitError::Inconsistent)?;
    let p = mesh.halfedges[gk].prev;
    mesh.halfedges[o].prev = p;
    mesh.halfedges[o].next = gk;
    mesh.halfedges[p].next = o;
    mesh.halfedges[gk].prev = o;
    Ok(())
}

/// Reusable per-vertex marks for the link-condition test (indexed by vertex slot).
#[derive(Clone, Debug, Default)]
pub struct Marks {
    stamp: Vec<u32>,
    current: u32,
}

impl Marks {
    fn next_round(&mut self, len: usize) -> u32 {
        if self.stamp.len() < len {
            self.stamp.resize(len, 0);
        }
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.current = 1;
        }
        self.current
    }
}

/// The topological rules of `docs/algorithms.md` §4.2 (link condition, boundary rules, no
/// collapse of a lone triangle or a tetrahedron, no interior vertex left with valence < 3,
/// valence cap). Returns the valence the survivor would have, or `None` if illegal.
pub(crate) fn is_collapse_topologically_legal(
    mesh: &Mesh,
    h: HalfedgeId,
    max_valence: usize,
    marks: &mut Marks,
) -> Option<usize> {
    let o = mesh.twin(h);
    let u = mesh.to_vertex(o);
    let v = mesh.to_vertex(h);
    let has_l = mesh.face(h).is_some();
    let has_r = mesh.face(o).is_some();
    let boundary_edge = !has_l || !has_r;
    // A boundary vertex may only slide along its boundary (this also forbids pinching two
    // boundary vertices through the interior).
    if mesh.is_boundary_vertex(u) && !boundary_edge {
        return None;
    }
    let mut wings: SmallVec<[VertexId; 2]> = SmallVec::new();
    for (has, e) in [(has_l, h), (has_r, o)] {
        if !has {
            continue;
        }
        let e1 = mesh.next(e);
        let e2 = mesh.next(e1);
        // Both outer edges on the boundary: the face would dangle.
        if mesh.is_boundary_halfedge(mesh.twin(e1)) && mesh.is_boundary_halfedge(mesh.twin(e2)) {
            return None;
        }
        let w = mesh.to_vertex(e1);
        // An interior wing vertex loses an edge; valence 3 would leave a degenerate pillow
        // (this is also the tetrahedron rule).
        if !mesh.is_boundary_vertex(w) && mesh.outgoing(w).take(4).count() <= 3 {
            return None;
        }
        wings.push(w);
    }
    if wings.len() == 2 && wings[0] == wings[1] {
        return None;
    }
    // Link condition: the common neighbours of u and v are exactly the wings.
    let len = mesh.vertices.capacity().max(u.slot().max(v.slot()) + 1);
    let stamp = marks.next_round(len);
    let mut deg_u = 0usize;
    for g in mesh.outgoing(u) {
        let w = mesh.to_vertex(g);
        let s = w.slot();
        if s >= marks.stamp.len() {
            marks.stamp.resize(s + 1, 0);
        }
        marks.stamp[s] = stamp;
        deg_u += 1;
    }
    let mut deg_v = 0usize;
    let mut common = 0usize;
    for g in mesh.outgoing(v) {
        let w = mesh.to_vertex(g);
        deg_v += 1;
        if marks.stamp.get(w.slot()) == Some(&stamp) {
            common += 1;
            if !wings.contains(&w) {
                return None;
            }
        }
    }
    if common != wings.len() {
        return None;
    }
    let new_valence = deg_u + deg_v - 2 - wings.len();
    if new_valence > max_valence {
        return None;
    }
    Some(new_valence)
}

/// The shape rules of [`Legality`] (normals, slivers) on the faces around `h`'s tail: the
/// sliver penalty the collapse pays when it is legal, `None` when it is not.
pub(crate) fn is_collapse_geometrically_legal(
    mesh: &Mesh,
    h: HalfedgeId,
    legality: &Legality,
) -> Option<f64> {
    let o = mesh.twin(h);
    let u = mesh.to_vertex(o);
    let pu = mesh.position(u);
    let pv = mesh.position(mesh.to_vertex(h));
    let (fl, fr) = (mesh.face(h), mesh.face(o));
    let mut ring: SmallVec<[RingFace; 16]> = SmallVec::new();
    for g in mesh.outgoing(u) {
        let Some(f) = mesh.face(g) else { continue };
        ring.push(RingFace {
            a: mesh.position(mesh.to_vertex(g)),
            b: mesh.position(mesh.to_vertex(mesh.next(g))),
            dies: Some(f) == fl || Some(f) == fr,
        });
    }
    shape_check(pu, pv, &ring, legality).ok()
}

/// Topological and geometric legality together.
pub fn is_collapse_legal(
    mesh: &Mesh,
    h: HalfedgeId,
    legality: &Legality,
    marks: &mut Marks,
) -> bool {
    is_collapse_topologically_legal(mesh, h, legality.max_valence, marks).is_some()
        && is_collapse_geometrically_legal(mesh, h, legality).is_some()
}

/// A slot-level copy of every record of a mesh (handles as slot indices, positions as bits),
/// for checking that operations are exact inverses: two meshes with equal snapshots have the
/// same records in the same slots.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeshRecords {
    /// `(slot, out-going half-edge slot, position bits)` per live vertex.
    pub vertices: Vec<(usize, Option<usize>, [u64; 3])>,
    /// `(slot, to, next, prev, twin, face)` per live half-edge.
    pub halfedges: Vec<(usize, usize, usize, usize, usize, Option<usize>)>,
    /// `(slot, half-edge slot)` per live face.
    pub faces: Vec<(usize, usize)>,
}

impl MeshRecords {
    /// Copies the records of `mesh`.
    pub fn of(mesh: &Mesh) -> MeshRecords {
        MeshRecords {
            vertices: mesh
                .vertices
                .iter()
                .map(|(k, r)| {
                    let p = r.position;
                    (
                        k.slot(),
                        r.halfedge.map(|h| h.slot()),
                        [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()],
                    )
                })
                .collect(),
            halfedges: mesh
                .halfedges
                .iter()
                .map(|(k, r)| {
                    (
                        k.slot(),
                        r.to.slot(),
                        r.next.slot(),
                        r.prev.slot(),
                        r.twin.slot(),
                        r.face.map(|f| f.slot()),
                    )
                })
                .collect(),
            faces: mesh
                .faces
                .iter()
                .map(|(k, r)| (k.slot(), r.halfedge.slot()))
                .collect(),
        }
    }
}
