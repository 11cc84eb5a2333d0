//! The decimator as first written, on the slotmap half-edge [`Mesh`] with the public legality
//! tests of [`super::collapse`]: kept as the test oracle of the corner-table decimator in
//! `decimate.rs`, which must perform exactly the same collapses. The rules are documented there.

use super::collapse::{
    Marks, half_edge_collapse, is_collapse_geometrically_legal, is_collapse_topologically_legal,
};
use super::decimate::{Collapse, DecimateParams, Schedule};
use super::quadric::{POINT_REGULARISATION, Quadric};
use crate::mesh::{BoundingBox, HalfedgeId, Mesh, SlotIndex};
use crate::progress::Progress;

const NONE: u32 = u32::MAX;

/// A candidate collapse: the cheaper allowed direction of an edge, and the other direction's
/// cost (`f64::INFINITY` if not allowed).
#[derive(Clone, Copy)]
struct Candidate {
    cost: f64,
    h: u32,
    alt_cost: f64,
}

/// Costs of collapsing the edge of `h` in both directions (`h`'s direction first); `None` for
/// a direction that is never allowed (a boundary vertex may only slide along its boundary).
#[inline]
fn edge_costs(
    mesh: &Mesh,
    quadric: &[Quadric],
    h: HalfedgeId,
    o: HalfedgeId,
) -> (Option<f64>, Option<f64>) {
    let boundary_edge = mesh.is_boundary_halfedge(h) || mesh.is_boundary_halfedge(o);
    let (a, b) = (mesh.to_vertex(o), mesh.to_vertex(h));
    let q = quadric[a.slot()].sum(&quadric[b.slot()]);
    let ab = (boundary_edge || !mesh.is_boundary_vertex(a)).then(|| q.error(mesh.position(b)));
    let ba = (boundary_edge || !mesh.is_boundary_vertex(b)).then(|| q.error(mesh.position(a)));
    (ab, ba)
}

fn initial_quadrics(mesh: &Mesh, boundary_weight: f64) -> Vec<Quadric> {
    let n = mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0);
    let mut q = vec![Quadric::default(); n];
    for f in mesh.faces() {
        let [a, b, c] = mesh.face_vertices(f);
        let (pa, pb, pc) = (mesh.position(a), mesh.position(b), mesh.position(c));
        let Some(fq) = Quadric::of_triangle(pa, pb, pc) else {
            continue; // zero-area faces carry no plane
        };
        for x in [a, b, c] {
            q[x.slot()].add(&fq);
        }
    }
    for v in mesh.vertices() {
        let scale = POINT_REGULARISATION * q[v.slot()].weight;
        q[v.slot()].add(&Quadric::from_point(mesh.position(v), scale));
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
    let mut mesh = input.clone();
    // Relative to the bounding-box centre of the vertices with faces, as `decimate.rs` does.
    let used = mesh.vertices().filter(|&v| !mesh.is_isolated(v));
    if let Some(bounds) = BoundingBox::of(used.map(|v| mesh.position(v))) {
        let origin = bounds.centre();
        let vertices: Vec<_> = mesh.vertices().collect();
        for v in vertices {
            let p = mesh.position(v);
            mesh.set_position(v, p - origin);
        }
    }
    let n_he = mesh.halfedges().map(|h| h.slot() + 1).max().unwrap_or(0);
    let n_v = mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0);
    let mut hid = vec![HalfedgeId::default(); n_he];
    for h in mesh.halfedges() {
        hid[h.slot()] = h;
    }
    let mut quadric = initial_quadrics(&mesh, params.boundary_weight);
    let mut marks = Marks::default();
    let mut locked = vec![false; n_v];
    let mut locked_list: Vec<u32> = Vec::new();
    let mut seen = vec![false; n_he];
    // One half-edge per live edge (may hold dead or duplicate entries; cleaned every pass).
    let mut edges: Vec<u32> = mesh.edges().map(|h| h.slot() as u32).collect();
    let mut next_edges: Vec<u32> = Vec::with_capacity(edges.len());
    let mut cands: Vec<Candidate> = Vec::with_capacity(edges.len());
    let mut collapses: Vec<Collapse> = Vec::new();

    let isolated = mesh.vertices().filter(|&v| mesh.is_isolated(v)).count();
    let start_faces = mesh.n_faces();
    let work = start_faces.saturating_sub(params.target_faces).max(1);
    let done = |m: &Mesh| {
        m.n_faces() <= params.target_faces || m.n_vertices() - isolated <= params.target_vertices
    };
    let mut schedule = Schedule::new();
    while !done(&mesh) {
        // Live, deduplicated edges, each by the smaller slot of its two half-edges.
        next_edges.clear();
        for &s in &edges {
            let h = hid[s as usize];
            if !mesh.contains_halfedge(h) {
                continue;
            }
            let t = mesh.twin(h);
            let r = if t.slot() < h.slot() {
                t.slot()
            } else {
                h.slot()
            };
            if !seen[r] {
                seen[r] = true;
                next_edges.push(r as u32);
            }
        }
        for &r in &next_edges {
            seen[r as usize] = false;
        }
        std::mem::swap(&mut edges, &mut next_edges);

        cands.clear();
        for &s in &edges {
            let h = hid[s as usize];
            let o = mesh.twin(h);
            let (ch, co) = edge_costs(&mesh, &quadric, h, o);
            let (cost, hs, alt_cost) = match (ch, co) {
                (Some(a), Some(b)) if b < a => (b, o.slot(), a),
                (Some(a), Some(b)) => (a, h.slot(), b),
                (Some(a), None) => (a, h.slot(), f64::INFINITY),
                (None, Some(b)) => (b, o.slot(), f64::INFINITY),
                (None, None) => continue,
            };
            if cost <= params.max_error_sq {
                cands.push(Candidate {
                    cost,
                    h: hs as u32,
                    alt_cost,
                });
            }
        }
        if cands.is_empty() {
            break;
        }
        cands.sort_unstable_by(|a, b| a.cost.total_cmp(&b.cost).then(a.h.cmp(&b.h)));
        // Each collapse removes about two faces; aim for this pass's share of the target and
        // allow 1.5× the cost of the candidate that would meet it (many get locked).
        let faces_left = mesh.n_faces() - params.target_faces.min(mesh.n_faces());
        let goal = (faces_left / 2).max(1);
        let error_cut = if schedule.use_goal && goal < cands.len() {
            1.5 * cands[goal].cost
        } else {
            f64::INFINITY
        }
        .min(params.max_error_sq);
        let legality = schedule.legality(params);
        let mut budget = schedule.budget(mesh.n_faces());
        let before = collapses.len();
        for c in &cands {
            if done(&mesh) || c.cost > error_cut || budget == 0 {
                break;
            }
            let h0 = hid[c.h as usize];
            if !mesh.contains_halfedge(h0) {
                continue;
            }
            let o0 = mesh.twin(h0);
            let (a, b) = (mesh.to_vertex(o0), mesh.to_vertex(h0));
            if locked[a.slot()] || locked[b.slot()] {
                continue;
            }
            let legal = |mesh: &Mesh, marks: &mut Marks, h: HalfedgeId| {
                is_collapse_topologically_legal(mesh, h, legality.max_valence, marks).is_some()
                    && is_collapse_geometrically_legal(mesh, h, &legality)
            };
            let (h, cost) = if legal(&mesh, &mut marks, h0) {
                (h0, c.cost)
            } else if c.alt_cost <= error_cut && legal(&mesh, &mut marks, o0) {
                (o0, c.alt_cost)
            } else {
                continue;
            };
            let o = mesh.twin(h);
            let (u, v) = (mesh.to_vertex(o), mesh.to_vertex(h));
            let topo = half_edge_collapse(&mut mesh, h);
            let qu = quadric[u.slot()];
            quadric[v.slot()].add(&qu);
            locked[v.slot()] = true;
            locked_list.push(v.slot() as u32);
            // Glued edges may have lost their representative: re-list v's edges.
            for g in mesh.outgoing(v) {
                edges.push(g.slot() as u32);
            }
            collapses.push(Collapse {
                from: u.slot() as u32,
                to: v.slot() as u32,
                left: topo.left.map_or(NONE, |x| x.slot() as u32),
                right: topo.right.map_or(NONE, |x| x.slot() as u32),
                error_sq: cost,
            });
            budget -= 1;
        }
        for &v in &locked_list {
            locked[v as usize] = false;
        }
        locked_list.clear();
        progress.update((start_faces - mesh.n_faces()) as f64 / work as f64);
        if schedule.pass_ended(collapses.len() > before, error_cut, params) {
            break;
        }
    }
    progress.update(1.0);
    (collapses, mesh)
}
