//! The decimator as first written, on the slotmap half-edge [`Mesh`] with the public legality
//! tests of [`super::collapse`]: kept as the test oracle of the corner-table decimator in
//! `decimate.rs`, which must perform exactly the same collapses. The rules are documented there.

use super::collapse::{
    Marks, half_edge_collapse, is_collapse_geometrically_legal, is_collapse_topologically_legal,
};
use super::decimate::{Collapse, DecimateParams, Pass, Schedule};
use super::legality::Relaxation;
use super::quadric::{POINT_REGULARISATION, Quadric, Quadrics};
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
    quadric: &Quadrics,
    h: HalfedgeId,
    o: HalfedgeId,
) -> (Option<f64>, Option<f64>) {
    let boundary_edge = mesh.is_boundary_halfedge(h) || mesh.is_boundary_halfedge(o);
    let (a, b) = (mesh.to_vertex(o), mesh.to_vertex(h));
    let q = quadric.merged(a.slot() as u32, b.slot() as u32);
    let ab = (boundary_edge || !mesh.is_boundary_vertex(a)).then(|| q.error(mesh.position(b)));
    let ba = (boundary_edge || !mesh.is_boundary_vertex(b)).then(|| q.error(mesh.position(a)));
    (ab, ba)
}

fn initial_quadrics(mesh: &Mesh, boundary_weight: f64) -> Quadrics {
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
    let mut rims = Vec::new();
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
            rims.push((a.slot() as u32, cq));
            rims.push((b.slot() as u32, cq));
        }
    }
    Quadrics::new(q, &rims)
}

/// What the passes accumulate: the quadrics, the survivors locked in the current pass, the
/// collapses made so far and the scratch of the legality tests.
struct Decimation {
    quadric: Quadrics,
    marks: Marks,
    locked: Vec<bool>,
    locked_list: Vec<u32>,
    collapses: Vec<Collapse>,
}

/// One half-edge slot per live edge (may hold dead or duplicate entries until
/// [`drop_dead_edges`] cleans it), with the scratch of the cleaning.
struct EdgeList {
    edges: Vec<u32>,
    next_edges: Vec<u32>,
    seen: Vec<bool>,
}

/// Runs the decimation on a copy of `input`; returns the collapses in order and the final mesh.
pub(crate) fn decimate(
    input: &Mesh,
    params: &DecimateParams,
    progress: &dyn Progress,
) -> (Vec<Collapse>, Mesh) {
    let mut mesh = centred_copy(input);
    let n_he = mesh.halfedges().map(|h| h.slot() + 1).max().unwrap_or(0);
    let n_v = mesh.vertices().map(|v| v.slot() + 1).max().unwrap_or(0);
    let mut hid = vec![HalfedgeId::default(); n_he];
    for h in mesh.halfedges() {
        hid[h.slot()] = h;
    }
    let mut state = Decimation {
        quadric: initial_quadrics(&mesh, params.boundary_weight),
        marks: Marks::default(),
        locked: vec![false; n_v],
        locked_list: Vec::new(),
        collapses: Vec::new(),
    };
    let edges: Vec<u32> = mesh.edges().map(|h| h.slot() as u32).collect();
    let mut cands: Vec<Candidate> = Vec::with_capacity(edges.len());
    let mut edges = EdgeList {
        next_edges: Vec::with_capacity(edges.len()),
        edges,
        seen: vec![false; n_he],
    };

    let isolated = mesh.vertices().filter(|&v| mesh.is_isolated(v)).count();
    let start_faces = mesh.n_faces();
    let work = start_faces.saturating_sub(params.target_faces).max(1);
    let done = |m: &Mesh| {
        m.n_faces() <= params.target_faces || m.n_vertices() - isolated <= params.target_vertices
    };
    let mut schedule = Schedule::up_to(Relaxation::Normals);
    while !done(&mesh) {
        drop_dead_edges(&mesh, &hid, &mut edges);
        state.quadric.rim_scale = super::decimate::rim_scale_at_level(mesh.n_faces(), start_faces);
        collect_candidates(
            &mesh,
            &hid,
            &edges.edges,
            &state.quadric,
            params,
            &mut cands,
        );
        if cands.is_empty() {
            break;
        }
        // Unlike `decimate.rs`, the whole list is sorted and the cut read off it.
        rank_candidates(&mut cands);
        let error_cut = cut_at_goal(&cands, mesh.n_faces(), &schedule, params);
        let pass = Pass {
            error_cut,
            legality: schedule
                .legality(params)
                .at_level(mesh.n_faces(), start_faces),
            budget: schedule.budget(mesh.n_faces()),
        };
        let made = perform_collapses(&mut mesh, &mut state, &mut edges, &cands, &hid, &pass, done);
        unlock_survivors(&mut state);
        progress.update((start_faces - mesh.n_faces()) as f64 / work as f64);
        if schedule.pass_ended(made > 0, error_cut, params) {
            break;
        }
    }
    progress.update(1.0);
    (state.collapses, mesh)
}

/// A copy of `mesh` relative to the bounding-box centre of the vertices with faces, as
/// `decimate.rs` does.
fn centred_copy(input: &Mesh) -> Mesh {
    let mut mesh = input.clone();
    let used = mesh.vertices().filter(|&v| !mesh.is_isolated(v));
    if let Some(bounds) = BoundingBox::of(used.map(|v| mesh.position(v))) {
        let origin = bounds.centre();
        let vertices: Vec<_> = mesh.vertices().collect();
        for v in vertices {
            let p = mesh.position(v);
            mesh.set_position(v, p - origin);
        }
    }
    mesh
}

/// Leaves the live edges in `edges.edges`, deduplicated, each by the smaller slot of its two
/// half-edges.
fn drop_dead_edges(mesh: &Mesh, hid: &[HalfedgeId], edges: &mut EdgeList) {
    edges.next_edges.clear();
    for &s in &edges.edges {
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
        if !edges.seen[r] {
            edges.seen[r] = true;
            edges.next_edges.push(r as u32);
        }
    }
    for &r in &edges.next_edges {
        edges.seen[r as usize] = false;
    }
    std::mem::swap(&mut edges.edges, &mut edges.next_edges);
}

/// Every edge of `edges` within the error bound, in its cheaper allowed direction, into
/// `cands`.
fn collect_candidates(
    mesh: &Mesh,
    hid: &[HalfedgeId],
    edges: &[u32],
    quadric: &Quadrics,
    params: &DecimateParams,
    cands: &mut Vec<Candidate>,
) {
    cands.clear();
    for &s in edges {
        let h = hid[s as usize];
        let o = mesh.twin(h);
        let (ch, co) = edge_costs(mesh, quadric, h, o);
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
}

/// Sorts the candidates by `(cost, slot)`.
fn rank_candidates(cands: &mut [Candidate]) {
    cands.sort_unstable_by(|a, b| a.cost.total_cmp(&b.cost).then(a.h.cmp(&b.h)));
}

/// This pass's cost cut, read off the ranked candidates. Each collapse removes about two
/// faces; aim for this pass's share of the target and allow 1.5× the cost of the candidate
/// that would meet it (many get locked).
fn cut_at_goal(
    cands: &[Candidate],
    n_faces: usize,
    schedule: &Schedule,
    params: &DecimateParams,
) -> f64 {
    let faces_left = n_faces - params.target_faces.min(n_faces);
    let goal = (faces_left / 2).max(1);
    if schedule.use_goal && goal < cands.len() {
        1.5 * cands[goal].cost
    } else {
        f64::INFINITY
    }
    .min(params.max_error_sq)
}

/// Collapses the ranked candidates under the cut in order, each in its cheaper legal
/// direction, skipping edges at a survivor of this pass (locked); returns how many it
/// collapsed.
fn perform_collapses(
    mesh: &mut Mesh,
    state: &mut Decimation,
    edges: &mut EdgeList,
    cands: &[Candidate],
    hid: &[HalfedgeId],
    pass: &Pass,
    done: impl Fn(&Mesh) -> bool,
) -> usize {
    let mut budget = pass.budget;
    let before = state.collapses.len();
    let legality = &pass.legality;
    for c in cands {
        if done(mesh) || c.cost > pass.error_cut || budget == 0 {
            break;
        }
        let h0 = hid[c.h as usize];
        if !mesh.contains_halfedge(h0) {
            continue;
        }
        let o0 = mesh.twin(h0);
        let (a, b) = (mesh.to_vertex(o0), mesh.to_vertex(h0));
        if state.locked[a.slot()] || state.locked[b.slot()] {
            continue;
        }
        let legal = |mesh: &Mesh, marks: &mut Marks, h: HalfedgeId, cost: f64| {
            is_collapse_topologically_legal(mesh, h, legality.max_valence, marks).is_some()
                && is_collapse_geometrically_legal(mesh, h, legality)
                    .is_some_and(|penalty| cost + penalty <= pass.error_cut)
        };
        let (h, cost) = if legal(mesh, &mut state.marks, h0, c.cost) {
            (h0, c.cost)
        } else if c.alt_cost <= pass.error_cut && legal(mesh, &mut state.marks, o0, c.alt_cost) {
            (o0, c.alt_cost)
        } else {
            continue;
        };
        let o = mesh.twin(h);
        let (u, v) = (mesh.to_vertex(o), mesh.to_vertex(h));
        let topo = half_edge_collapse(mesh, h);
        state.quadric.absorb(u.slot() as u32, v.slot() as u32);
        state.locked[v.slot()] = true;
        state.locked_list.push(v.slot() as u32);
        // Glued edges may have lost their representative: re-list v's edges.
        for g in mesh.outgoing(v) {
            edges.edges.push(g.slot() as u32);
        }
        state.collapses.push(Collapse {
            from: u.slot() as u32,
            to: v.slot() as u32,
            left: topo.left.map_or(NONE, |x| x.slot() as u32),
            right: topo.right.map_or(NONE, |x| x.slot() as u32),
            error_sq: cost,
        });
        budget -= 1;
    }
    state.collapses.len() - before
}

/// Unlocks this pass's survivors for the next pass.
fn unlock_survivors(state: &mut Decimation) {
    for &v in &state.locked_list {
        state.locked[v as usize] = false;
    }
    state.locked_list.clear();
}
