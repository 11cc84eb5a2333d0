//! Greedy quadric-error decimation by half-edge collapses: the engine behind
//! [`ProgressiveMesh::build`](super::ProgressiveMesh::build).
//!
//! Every edge is evaluated in both directions (`u→v` keeps `v`'s original position, so the
//! cost is `(Q_u + Q_v)(p_v)`) and the cheaper allowed direction goes into a binary min-heap
//! keyed by `(cost, half-edge)`. Entries are invalidated lazily by per-half-edge version
//! stamps. Legality is tested when an entry is popped: an illegal cheaper direction falls back
//! to the other direction; an edge illegal both ways is parked and re-queued when a collapse
//! changes its neighbourhood (its endpoints' 1-rings). When the heap runs dry, one sweep
//! re-queues every edge; the build stops when a sweep finds nothing to collapse, so "no legal
//! collapse left" really means none.
//!
//! All per-element state lives in flat arrays indexed by slot (the working mesh only loses
//! elements, so slots are stable); the loop allocates nothing per collapse.

use super::collapse::{
    Legality, Marks, half_edge_collapse, is_collapse_geometrically_legal,
    is_collapse_topologically_legal,
};
use super::quadric::Quadric;
use crate::mesh::{HalfedgeId, Mesh, SlotIndex, VertexId};
use crate::progress::Progress;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

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

/// One performed collapse, as mesh slots (`u32::MAX` = none), and its error.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Collapse {
    pub from: u32,
    pub to: u32,
    pub left: u32,
    pub right: u32,
    pub error_sq: f64,
}

const NONE: u32 = u32::MAX;
const ALT: u32 = 1 << 31;

#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Entry {
    /// f64 bits of a non-negative cost: ordered like the cost.
    key: u64,
    /// Slot of the half-edge giving the direction (from → to).
    h: u32,
    /// Version of that half-edge when queued; `ALT` set for the fallback direction.
    stamp: u32,
}

struct State<'a> {
    mesh: Mesh,
    /// Half-edge handle by slot (slots are stable: nothing is inserted).
    hid: Vec<HalfedgeId>,
    version: Vec<u32>,
    parked: Vec<bool>,
    quadric: Vec<Quadric>,
    heap: BinaryHeap<Reverse<Entry>>,
    marks: Marks,
    params: &'a DecimateParams,
}

impl State<'_> {
    /// Cost of collapsing `h` (from → to), or `None` if its direction is never allowed.
    #[inline]
    fn direction_cost(&self, h: HalfedgeId) -> Option<f64> {
        let m = &self.mesh;
        let o = m.twin(h);
        let u = m.to_vertex(o);
        if m.is_boundary_vertex(u) && !(m.is_boundary_halfedge(h) || m.is_boundary_halfedge(o)) {
            return None;
        }
        let v = m.to_vertex(h);
        let q = self.quadric[u.slot()].sum(&self.quadric[v.slot()]);
        Some(q.error(m.position(v)))
    }

    /// Re-evaluates the edge of `h` (both directions), invalidating its queued entries, and
    /// returns the entry of the cheaper allowed direction.
    fn evaluate_edge(&mut self, h: HalfedgeId) -> Option<Entry> {
        let o = self.mesh.twin(h);
        let (hs, os) = (h.slot(), o.slot());
        self.version[hs] = (self.version[hs] + 1) & !ALT;
        self.version[os] = (self.version[os] + 1) & !ALT;
        self.parked[hs] = false;
        self.parked[os] = false;
        let ch = self.direction_cost(h);
        let co = self.direction_cost(o);
        let best = match (ch, co) {
            (Some(a), Some(b)) => {
                if (b, os) < (a, hs) {
                    Some((b, os))
                } else {
                    Some((a, hs))
                }
            }
            (Some(a), None) => Some((a, hs)),
            (None, Some(b)) => Some((b, os)),
            (None, None) => None,
        };
        best.map(|(cost, s)| Entry {
            key: cost.to_bits(),
            h: s as u32,
            stamp: self.version[s],
        })
    }

    /// Re-evaluates the edge of `h` and queues it.
    fn requeue_edge(&mut self, h: HalfedgeId) {
        if let Some(e) = self.evaluate_edge(h) {
            self.heap.push(Reverse(e));
        }
    }

    fn is_legal(&mut self, h: HalfedgeId) -> bool {
        is_collapse_topologically_legal(
            &self.mesh,
            h,
            self.params.legality.max_valence,
            &mut self.marks,
        )
        .is_some()
            && is_collapse_geometrically_legal(&self.mesh, h, &self.params.legality)
    }
}

fn initial_quadrics(mesh: &Mesh, boundary_weight: f64) -> Vec<Quadric> {
    let n = mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0);
    let mut q = vec![Quadric::default(); n];
    for f in mesh.faces() {
        let [a, b, c] = mesh.face_vertices(f);
        let (pa, pb, pc) = (mesh.position(a), mesh.position(b), mesh.position(c));
        let nrm = (pb - pa).cross(pc - pa);
        let len = nrm.length();
        if len.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !len.is_finite() {
            continue; // zero-area faces carry no plane
        }
        let area = 0.5 * len;
        let fq = Quadric::from_plane(nrm / len, pa, area, area);
        for x in [a, b, c] {
            q[x.slot()].add(&fq);
        }
    }
    if boundary_weight > 0.0 {
        for h in mesh.halfedges() {
            if !mesh.is_boundary_halfedge(h) {
                continue;
            }
            // The face is on the twin's side; the constraint plane contains the edge and is
            // perpendicular to that face.
            let t = mesh.twin(h);
            let Some(f) = mesh.face(t) else { continue };
            let (a, b) = (mesh.from_vertex(h), mesh.to_vertex(h));
            let (pa, pb) = (mesh.position(a), mesh.position(b));
            let e = pb - pa;
            let n = e.cross(mesh.face_normal(f)).normalize_or_zero();
            if n == glam::DVec3::ZERO {
                continue;
            }
            let cq = Quadric::from_plane(n, pa, boundary_weight * e.length_squared(), 0.0);
            q[a.slot()].add(&cq);
            q[b.slot()].add(&cq);
        }
    }
    q
}

/// Runs the decimation on a copy of `input`; returns the collapses in order and the final mesh.
pub(crate) fn decimate(
    input: &Mesh,
    params: &DecimateParams,
    progress: &dyn Progress,
) -> (Vec<Collapse>, Mesh) {
    let mesh = input.clone();
    let n_he = mesh.halfedges().map(|h| h.slot() + 1).max().unwrap_or(0);
    let mut hid = vec![HalfedgeId::default(); n_he];
    for h in mesh.halfedges() {
        hid[h.slot()] = h;
    }
    let quadric = initial_quadrics(&mesh, params.boundary_weight);
    let mut st = State {
        mesh,
        hid,
        version: vec![0; n_he],
        parked: vec![false; n_he],
        quadric,
        heap: BinaryHeap::new(),
        marks: Marks::default(),
        params,
    };
    let mut collapses: Vec<Collapse> = Vec::new();
    let start_faces = st.mesh.n_faces();
    let target_faces = params.target_faces;
    let work = start_faces.saturating_sub(target_faces).max(1);
    let report_every = (work / 200).max(64);
    let mut edges: Vec<HalfedgeId> = Vec::new();
    let mut ring: Vec<VertexId> = Vec::new();
    let isolated = st
        .mesh
        .vertices()
        .filter(|&v| st.mesh.is_isolated(v))
        .count();
    let done = |m: &Mesh| {
        m.n_faces() <= params.target_faces || m.n_vertices() - isolated <= params.target_vertices
    };
    'sweeps: loop {
        // (Re-)queue every edge: the first sweep fills the heap, later ones catch edges whose
        // legality changed without their neighbourhood being touched by a collapse.
        edges.clear();
        edges.extend(st.mesh.edges());
        let mut entries = std::mem::take(&mut st.heap).into_vec();
        entries.clear();
        entries.reserve(edges.len());
        for &h in &edges {
            if let Some(e) = st.evaluate_edge(h) {
                entries.push(Reverse(e));
            }
        }
        st.heap = BinaryHeap::from(entries);
        let before = collapses.len();
        while let Some(Reverse(e)) = st.heap.pop() {
            if done(&st.mesh) {
                break 'sweeps;
            }
            let s = (e.h) as usize;
            if st.version[s] != (e.stamp & !ALT) {
                continue; // stale
            }
            let cost = f64::from_bits(e.key);
            if cost > params.max_error_sq {
                break;
            }
            let h = st.hid[s];
            if !st.is_legal(h) {
                let o = st.mesh.twin(h);
                let os = o.slot();
                if e.stamp & ALT == 0
                    && let Some(c) = st.direction_cost(o)
                {
                    st.heap.push(Reverse(Entry {
                        key: c.to_bits(),
                        h: os as u32,
                        stamp: st.version[os] | ALT,
                    }));
                } else {
                    st.parked[s] = true;
                    st.parked[os] = true;
                }
                continue;
            }
            // Collapse.
            let o = st.mesh.twin(h);
            let (u, v) = (st.mesh.to_vertex(o), st.mesh.to_vertex(h));
            // The half-edges that die: bump their versions so queued entries go stale.
            for x in [h, o] {
                st.version[x.slot()] = (st.version[x.slot()] + 1) & !ALT;
                if st.mesh.face(x).is_some() {
                    let n = st.mesh.next(x);
                    let p = st.mesh.prev(x);
                    for y in [n, p] {
                        st.version[y.slot()] = (st.version[y.slot()] + 1) & !ALT;
                    }
                }
            }
            let topo = half_edge_collapse(&mut st.mesh, h);
            let qu = st.quadric[u.slot()];
            st.quadric[v.slot()].add(&qu);
            collapses.push(Collapse {
                from: u.slot() as u32,
                to: v.slot() as u32,
                left: topo.left.map_or(NONE, |x| x.slot() as u32),
                right: topo.right.map_or(NONE, |x| x.slot() as u32),
                error_sq: cost,
            });
            // Costs changed on every edge at v; legality may have changed on every edge at a
            // vertex of v's new 1-ring (re-queue those only if they were parked).
            ring.clear();
            edges.clear();
            for g in st.mesh.outgoing(v) {
                ring.push(st.mesh.to_vertex(g));
                edges.push(g);
            }
            for &g in &edges {
                st.requeue_edge(g);
            }
            for &w in &ring {
                edges.clear();
                for g in st.mesh.outgoing(w) {
                    let (gs, ts) = (g.slot(), st.mesh.twin(g).slot());
                    if st.parked[gs] || st.parked[ts] {
                        edges.push(g);
                    }
                }
                for &g in &edges {
                    st.requeue_edge(g);
                }
            }
            if collapses.len().is_multiple_of(report_every) {
                let removed = start_faces - st.mesh.n_faces();
                progress.update(removed as f64 / work as f64);
            }
        }
        if collapses.len() == before || done(&st.mesh) {
            break;
        }
    }
    progress.update(1.0);
    (collapses, st.mesh)
}
