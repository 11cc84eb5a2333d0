//! The repair steps of the builder's policy (see the parent module) on a corner table:
//! half-edges paired across edges (non-manifold ones by angle), orientation made consistent
//! per component, one vertex copy per extra fan, multi-edges detached.

use super::BuildReport;
use super::NONE;
use super::corners::{CornerTable, next_c, prev_c};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU8, AtomicU32, AtomicU64, Ordering};

/// Pairs the half-edges of a non-manifold edge `{lo, hi}` (`group` holds `(hi, c)`).
///
/// The triangles are sorted by the angle of their third vertex about the edge; two angular
/// neighbours that run along the edge in opposite directions are locally one consistently
/// oriented sheet, so they are paired, as many as possible; among pairings with equally many
/// pairs, the one whose pairs face away from the wedge between them (bound the same solid) wins,
/// so two solids touching along an edge become two closed surfaces. The rest stay unpaired and
/// become boundary. If no opposite pair exists, the first two are paired and the orientation
/// pass sorts them out.
///
/// `position(v)` is input vertex `v`'s position and `tri(t)` triangle `t`'s vertices (lookups
/// rather than slices, so that a cell of the streaming split, which holds only the triangles
/// around its vertices, pairs its edges by the same code).
pub(crate) fn pair_around_edge(
    position: &impl Fn(u32) -> DVec3,
    tri: &impl Fn(u32) -> [u32; 3],
    lo: u32,
    group: &[(u32, u32)],
) -> Vec<(u32, u32)> {
    let hi = group[0].0;
    let p0 = position(lo);
    let axis = (position(hi) - p0).normalize_or_zero();
    let wing = |c: u32| {
        let t = tri(c / 3);
        let w = position(t[((c % 3 + 2) % 3) as usize]) - p0;
        w - axis * w.dot(axis)
    };
    let reference = group
        .iter()
        .map(|g| wing(g.1))
        .find(|w| w.length_squared() > 0.0)
        .unwrap_or(DVec3::X)
        .normalize_or_zero();
    let side = axis.cross(reference);
    let mut around: Vec<(f64, u32, bool)> = group
        .iter()
        .map(|&(_, c)| {
            let w = wing(c);
            let forward = tri(c / 3)[(c % 3) as usize] == lo;
            (w.dot(side).atan2(w.dot(reference)), c, forward)
        })
        .collect();
    around.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let n = around.len();
    // Pair angular neighbours of opposite direction, greedily around the circle from `start`;
    // `solid_only` takes only the pairs that enclose the wedge between them: a triangle running
    // lo → hi has its normal (hi − lo) × wing pointing towards increasing angle, so a backward
    // triangle followed (counter-clockwise) by a forward one faces away from that wedge.
    let pair_from = |start: usize, solid_only: bool| {
        let mut used = vec![false; n];
        let mut pairs = Vec::new();
        for k in 0..n {
            let (i, j) = ((start + k) % n, (start + k + 1) % n);
            let opposite = around[i].2 != around[j].2;
            let encloses = !around[i].2 && around[j].2;
            if i != j && !used[i] && !used[j] && opposite && (encloses || !solid_only) {
                used[i] = true;
                used[j] = true;
                pairs.push((around[i].1, around[j].1));
            }
        }
        pairs
    };
    // Most pairs wins; among equals, the pairing that keeps solids apart.
    let mut best = pair_from(0, true);
    for start in [0, 1] {
        let candidate = pair_from(start, false);
        if candidate.len() > best.len() {
            best = candidate;
        }
    }
    if best.is_empty() {
        vec![(group[0].1, group[1].1)]
    } else {
        best
    }
}

/// Per half-edge flag: its undirected edge has two or more triangles (so being unpaired
/// means it was cut, not that it is a genuine boundary).
const SHARED: u8 = 1;
/// Per half-edge flag: its undirected edge has more than two triangles.
const NON_MANIFOLD: u8 = 2;

/// Calls `f` on every corner of the fan around the tail vertex of corner `c0`, `c0` first.
/// Across the out-going half-edge c the next corner at the same vertex is next(mate(c));
/// across the incoming one, prev(c), it is mate(prev(c)). A closed fan is walked once round;
/// an open one forward to its end, then backward from `c0`.
#[inline]
pub(crate) fn walk_fan(c0: u32, mate: &[u32], mut f: impl FnMut(u32)) {
    f(c0);
    let mut c = c0;
    while mate[c as usize] != NONE {
        c = next_c(mate[c as usize]);
        if c == c0 {
            return;
        }
        f(c);
    }
    let mut c = c0;
    while mate[prev_c(c) as usize] != NONE {
        c = mate[prev_c(c) as usize];
        f(c);
    }
}

/// Step 3 of the build: one mesh vertex per fan. The fan holding a vertex's first corner keeps
/// the input vertex; later fans get copies, appended in order of their first corners. Returns
/// the mesh vertex of every corner, the input vertex of every mesh vertex, and which input
/// vertices are referenced.
///
/// Almost every vertex has a single fan, so this first checks that in parallel (a walk round
/// one fan per vertex that sees all the vertex's corners) and walks fans in corner order only
/// for the vertices that fail, which gives the same numbering as walking all of them.
fn assign_fans(tris: &[[u32; 3]], mate: &[u32], nv: usize) -> (Vec<u32>, Vec<u32>, Vec<bool>) {
    let nh = mate.len();
    let from = |c: u32| tris[(c / 3) as usize][(c % 3) as usize];
    let mut corner_vertex: Vec<u32> = (0..nh as u32)
        .into_par_iter()
        .with_min_len(PAR_MIN)
        .map(from)
        .collect();
    // Corner count and first corner of every vertex, per chunk, then combined.
    let chunk = nh
        .div_ceil(rayon::current_num_threads().max(1))
        .max(PAR_MIN);
    let parts: Vec<(Vec<u32>, Vec<u32>)> = corner_vertex
        .par_chunks(chunk)
        .enumerate()
        .map(|(k, ch)| {
            let (mut degree, mut first) = (vec![0u32; nv], vec![NONE; nv]);
            for (i, &v) in ch.iter().enumerate() {
                degree[v as usize] += 1;
                if first[v as usize] == NONE {
                    first[v as usize] = (k * chunk + i) as u32;
                }
            }
            (degree, first)
        })
        .collect();
    let mut parts = parts.into_iter();
    let (mut degree, mut first) = parts
        .next()
        .unwrap_or_else(|| (vec![0; nv], vec![NONE; nv]));
    for (d, f) in parts {
        for v in 0..nv {
            degree[v] += d[v];
            first[v] = first[v].min(f[v]);
        }
    }
    let several_fans: Vec<u32> = (0..nv as u32)
        .into_par_iter()
        .with_min_len(PAR_MIN / 4)
        .filter(|&v| {
            let c0 = first[v as usize];
            if c0 == NONE {
                return false;
            }
            let mut seen = 0u32;
            walk_fan(c0, mate, |_| seen += 1);
            seen != degree[v as usize]
        })
        .collect();
    let seen: Vec<bool> = degree.iter().map(|&d| d > 0).collect();
    drop((degree, first));
    let mut vertex_source: Vec<u32> = (0..nv as u32).collect();
    if several_fans.is_empty() {
        return (corner_vertex, vertex_source, seen);
    }
    let mut split = vec![false; nv];
    for &v in &several_fans {
        split[v as usize] = true;
    }
    for cv in corner_vertex.iter_mut() {
        if split[*cv as usize] {
            *cv = NONE;
        }
    }
    let mut kept = vec![false; nv];
    for c0 in 0..nh as u32 {
        if corner_vertex[c0 as usize] != NONE {
            continue;
        }
        let v = from(c0);
        let id = if kept[v as usize] {
            vertex_source.push(v);
            (vertex_source.len() - 1) as u32
        } else {
            kept[v as usize] = true;
            v
        };
        walk_fan(c0, mate, |c| corner_vertex[c as usize] = id);
    }
    (corner_vertex, vertex_source, seen)
}

/// Fewest corners worth a parallel task: below this a thread costs more than it saves.
const PAR_MIN: usize = 1 << 15;

/// Half-edges grouped by undirected edge: bucket `lo` holds, sorted, the keys
/// `hi << 32 | corner` of every corner whose half-edge joins vertex `lo` to a larger vertex
/// `hi`. Sorting the packed keys sorts each bucket by `hi`, then by corner, so equal-`hi` runs
/// are the edges, and the layout does not depend on how the work was split between threads.
struct EdgeBuckets {
    /// `starts[v]..starts[v + 1]` is bucket `v` in `keys`.
    starts: Vec<u32>,
    keys: Vec<u64>,
}

impl EdgeBuckets {
    /// Counting sort of the corners by smaller endpoint (`ends[c] = lo << 32 | hi`), then a
    /// sort of each (small) bucket: linear overall, O(k log k) at a valence-k vertex. Each
    /// chunk of corners counts into its own histogram, which fixes where the chunk writes, so
    /// the chunks fill the buckets in parallel. The keys carry `hi`, so the walk over a bucket
    /// reads contiguous memory instead of looking each corner's other endpoint up at random.
    fn new(n_vertices: usize, ends: &[u64]) -> Self {
        let chunk = ends
            .len()
            .div_ceil(rayon::current_num_threads().max(1))
            .max(PAR_MIN);
        let mut fill: Vec<Vec<u32>> = ends
            .par_chunks(chunk)
            .map(|ch| {
                let mut h = vec![0u32; n_vertices];
                for &e in ch {
                    h[(e >> 32) as usize] += 1;
                }
                h
            })
            .collect();
        let mut starts = vec![0u32; n_vertices + 1];
        let mut at = 0u32;
        for v in 0..n_vertices {
            starts[v] = at;
            for h in &mut fill {
                let count = h[v];
                h[v] = at;
                at += count;
            }
        }
        starts[n_vertices] = at;
        // Chunks write interleaved positions; relaxed atomic stores compile to plain stores
        // and keep this free of `unsafe`.
        let keys: Vec<AtomicU64> = (0..ends.len())
            .into_par_iter()
            .map(|_| AtomicU64::new(0))
            .collect();
        ends.par_chunks(chunk)
            .zip(fill.par_iter_mut())
            .enumerate()
            .for_each(|(k, (ch, fill))| {
                for (i, &e) in ch.iter().enumerate() {
                    let slot = &mut fill[(e >> 32) as usize];
                    let c = (k * chunk + i) as u64;
                    keys[*slot as usize].store((e & 0xffff_ffff) << 32 | c, Ordering::Relaxed);
                    *slot += 1;
                }
            });
        drop(fill);
        let mut keys: Vec<u64> = keys.into_iter().map(AtomicU64::into_inner).collect();
        split_buckets(&starts, &mut keys)
            .into_par_iter()
            .for_each(|(v0, v1, piece)| {
                let base = starts[v0] as usize;
                for v in v0..v1 {
                    let b = &mut piece[starts[v] as usize - base..starts[v + 1] as usize - base];
                    if b.len() > 1 {
                        b.sort_unstable();
                    }
                }
            });
        EdgeBuckets { starts, keys }
    }

    /// Calls `f(lo, group)` for every group of two or more corners whose half-edges join the
    /// same two vertices, in order of `lo`: `group` holds the `(hi, corner)` entries sorted by
    /// corner.
    fn for_each_shared_edge(&self, mut f: impl FnMut(u32, &[(u32, u32)])) {
        let mut group: Vec<(u32, u32)> = Vec::new();
        for lo in 0..self.starts.len() - 1 {
            let b = &self.keys[self.starts[lo] as usize..self.starts[lo + 1] as usize];
            for run in b.chunk_by(|x, y| x >> 32 == y >> 32) {
                if run.len() >= 2 {
                    group.clear();
                    group.extend(run.iter().map(|&k| ((k >> 32) as u32, k as u32)));
                    f(lo as u32, &group);
                }
            }
        }
    }
}

/// Splits `keys` at bucket boundaries into pieces of about `PAR_MIN` keys, as
/// `(first vertex, end vertex, keys)`, for parallel work over whole buckets.
fn split_buckets<'a>(starts: &[u32], keys: &'a mut [u64]) -> Vec<(usize, usize, &'a mut [u64])> {
    let n_vertices = starts.len() - 1;
    let mut pieces = Vec::new();
    let mut rest = keys;
    let (mut v0, mut offset) = (0usize, 0usize);
    while v0 < n_vertices {
        let target = offset + PAR_MIN;
        let v1 = starts
            .partition_point(|&s| (s as usize) < target)
            .clamp(v0 + 1, n_vertices);
        let (piece, tail) = std::mem::take(&mut rest).split_at_mut(starts[v1] as usize - offset);
        pieces.push((v0, v1, piece));
        rest = tail;
        offset = starts[v1] as usize;
        v0 = v1;
    }
    pieces
}

/// `lo << 32 | hi` for the half-edge of every corner, `lo < hi` its endpoints.
fn edge_ends(n_corners: usize, endpoints: impl Fn(u32) -> (u32, u32) + Sync) -> Vec<u64> {
    (0..n_corners as u32)
        .into_par_iter()
        .with_min_len(PAR_MIN)
        .map(|c| {
            let (a, b) = endpoints(c);
            (a.min(b) as u64) << 32 | a.max(b) as u64
        })
        .collect()
}

/// Mesh vertices to detach so that no two distinct edges join the same two vertices: for every
/// vertex pair with more half-edges than one twin pair, its smaller endpoint. Sorted and
/// deduplicated.
fn multi_edge_vertices(mate: &[u32], corner_vertex: &[u32], n_vertices: usize) -> Vec<u32> {
    let ends = edge_ends(mate.len(), |c| {
        (corner_vertex[c as usize], corner_vertex[next_c(c) as usize])
    });
    let mut out = Vec::new();
    EdgeBuckets::new(n_vertices, &ends).for_each_shared_edge(|lo, group| {
        let clean = group.len() == 2 && mate[group[0].1 as usize] == group[1].1;
        if !clean && out.last() != Some(&lo) {
            out.push(lo);
        }
    });
    out
}

/// Step 1 of the build: pairs every half-edge with its twin. An edge of two triangles pairs
/// them; an edge of more is paired by `pair_around_edge` (counted in the report). Returns
/// the mate of each corner's half-edge (`NONE` if unpaired), its `SHARED`/`NON_MANIFOLD`
/// flags, and whether some pair runs in the same direction (so orientation must be fixed).
///
/// Buckets are paired in parallel, each writing only its own corners; non-manifold edges are
/// collected and paired afterwards in bucket order, so the result never depends on threads.
fn pair_halfedges(
    positions: &[DVec3],
    tris: &[[u32; 3]],
    report: &mut BuildReport,
) -> (Vec<u32>, Vec<u8>, bool) {
    let nh = 3 * tris.len();
    let from = |c: u32| tris[(c / 3) as usize][(c % 3) as usize];
    let ends = edge_ends(nh, |c| (from(c), from(next_c(c))));
    let mut buckets = EdgeBuckets::new(positions.len(), &ends);
    drop(ends);
    let mate: Vec<AtomicU32> = (0..nh)
        .into_par_iter()
        .with_min_len(PAR_MIN)
        .map(|_| AtomicU32::new(NONE))
        .collect();
    let flags: Vec<AtomicU8> = (0..nh)
        .into_par_iter()
        .with_min_len(PAR_MIN)
        .map(|_| AtomicU8::new(0))
        .collect();
    type Crowded = Vec<(u32, Vec<(u32, u32)>)>;
    let starts = &buckets.starts;
    let pieces: Vec<(bool, Crowded)> = split_buckets(starts, &mut buckets.keys)
        .into_par_iter()
        .map(|(v0, v1, piece)| {
            let base = starts[v0] as usize;
            let mut same_direction = false;
            let mut crowded: Crowded = Vec::new();
            for lo in v0..v1 {
                let b = &piece[starts[lo] as usize - base..starts[lo + 1] as usize - base];
                for run in b.chunk_by(|x, y| x >> 32 == y >> 32) {
                    match *run {
                        [_] => {}
                        [x, y] => {
                            let (a, b) = (x as u32, y as u32);
                            same_direction |= from(a) == from(b);
                            mate[a as usize].store(b, Ordering::Relaxed);
                            mate[b as usize].store(a, Ordering::Relaxed);
                            flags[a as usize].store(SHARED, Ordering::Relaxed);
                            flags[b as usize].store(SHARED, Ordering::Relaxed);
                        }
                        _ => crowded.push((
                            lo as u32,
                            run.iter().map(|&k| ((k >> 32) as u32, k as u32)).collect(),
                        )),
                    }
                }
            }
            (same_direction, crowded)
        })
        .collect();
    drop(buckets);
    let mut mate: Vec<u32> = mate.into_iter().map(AtomicU32::into_inner).collect();
    let mut flags: Vec<u8> = flags.into_iter().map(AtomicU8::into_inner).collect();
    let mut any_same_direction = false;
    for (same_direction, crowded) in pieces {
        any_same_direction |= same_direction;
        for (lo, group) in crowded {
            report.non_manifold_edges += 1;
            for g in &group {
                flags[g.1 as usize] = SHARED | NON_MANIFOLD;
            }
            let position = |v: u32| positions[v as usize];
            let tri = |t: u32| tris[t as usize];
            for (a, b) in pair_around_edge(&position, &tri, lo, &group) {
                any_same_direction |= from(a) == from(b);
                mate[a as usize] = b;
                mate[b as usize] = a;
            }
        }
    }
    (mate, flags, any_same_direction)
}

/// Steps 1–3 of the build (pairing, orientation, fan splitting): the corner table and the
/// input vertex of every mesh vertex.
pub(super) fn repair_triangles(
    positions: &[DVec3],
    input_tris: &[[u32; 3]],
    report: &mut BuildReport,
) -> (CornerTable, Vec<u32>) {
    let nv = positions.len();
    let mut tris = std::borrow::Cow::Borrowed(input_tris);
    report.zero_area_faces = count_zero_area(positions, &tris);

    // --- 1. pair half-edges (see `pair_halfedges`).
    let (mut mate, mut flags, any_same_direction) = pair_halfedges(positions, &tris, report);

    // --- 2. consistent orientation per component (see `orient_components`).
    let state = orient_components(&tris, &mut mate, any_same_direction, report);
    if state.contains(&2) {
        flip_triangles(&mut tris, &mut mate, &mut flags, &state, report);
    }
    drop(state);
    let tris: &[[u32; 3]] = &tris;

    // --- 3. one mesh vertex per fan (see `assign_fans`).
    let (corner_vertex, vertex_source, seen) = assign_fans(tris, &mate, nv);
    if vertex_source.len() > nv {
        report.non_manifold_vertices =
            count_pinched_vertices(tris, &mate, &flags, &vertex_source[nv..], nv);
    }
    // --- 3b. no two distinct edges on one vertex pair (see `detach_multi_edges`).
    let (corner_vertex, vertex_source, seen) = detach_multi_edges(
        tris,
        &mut mate,
        nv,
        (corner_vertex, vertex_source, seen),
        report,
    );
    report.unreferenced_vertices = seen.iter().filter(|s| !**s).count();
    drop(seen);
    report.split_vertices = vertex_source.len() - nv;
    drop(flags);
    (
        CornerTable {
            corner_vertex,
            mate,
        },
        vertex_source,
    )
}

/// The input vertex half-edge `c` leaves.
#[inline]
fn corner_from(tris: &[[u32; 3]], c: u32) -> u32 {
    tris[(c / 3) as usize][(c % 3) as usize]
}

/// The number of triangles of zero area.
fn count_zero_area(positions: &[DVec3], tris: &[[u32; 3]]) -> usize {
    tris.par_iter()
        .with_min_len(PAR_MIN)
        .filter(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a).length_squared() == 0.0
        })
        .count()
}

/// Step 2 of the build: a consistent orientation per component, by a breadth-first walk over
/// paired edges; the majority orientation of each component wins and a pair that contradicts
/// the walk is cut (counted in the report). Returns per triangle 1 (kept) or 2 (flipped).
/// When every pair already runs in opposite directions (`!any_same_direction`) the given
/// orientation is consistent (a non-orientable surface always has a same-direction pair), so
/// the walk is skipped.
fn orient_components(
    tris: &[[u32; 3]],
    mate: &mut [u32],
    any_same_direction: bool,
    report: &mut BuildReport,
) -> Vec<u8> {
    let nt = tris.len();
    let mut state = vec![if any_same_direction { 0u8 } else { 1 }; nt]; // 0 unvisited, 1 kept, 2 flipped
    let mut queue: Vec<u32> = Vec::new();
    for seed in 0..nt {
        if state[seed] != 0 {
            continue;
        }
        state[seed] = 1;
        queue.clear();
        queue.push(seed as u32);
        let mut qi = 0;
        let mut flipped = 0usize;
        while qi < queue.len() {
            let t = queue[qi] as usize;
            qi += 1;
            for c in 3 * t as u32..3 * t as u32 + 3 {
                let m = mate[c as usize];
                if m == NONE {
                    continue;
                }
                let u = (m / 3) as usize;
                // Twins run opposite ways when both triangles share a state.
                let same_dir = corner_from(tris, c) == corner_from(tris, m);
                let want = if same_dir { 3 - state[t] } else { state[t] };
                if state[u] == 0 {
                    state[u] = want;
                    flipped += (want == 2) as usize;
                    queue.push(u as u32);
                } else if state[u] != want {
                    mate[c as usize] = NONE;
                    mate[m as usize] = NONE;
                    report.orientation_cuts += 1;
                }
            }
        }
        if 2 * flipped > queue.len() {
            for &t in &queue {
                state[t as usize] = 3 - state[t as usize];
            }
        }
    }
    state
}

/// Flips the triangles whose `state` is 2, `[a,b,c] -> [a,c,b]`, carrying the mates and flags
/// of their half-edges along (local half-edge j becomes 2 - j, reversed).
fn flip_triangles(
    tris: &mut std::borrow::Cow<[[u32; 3]]>,
    mate: &mut Vec<u32>,
    flags: &mut Vec<u8>,
    state: &[u8],
    report: &mut BuildReport,
) {
    let nh = 3 * tris.len();
    let remap = |c: u32| {
        if state[(c / 3) as usize] == 2 {
            c - c % 3 + (2 - c % 3)
        } else {
            c
        }
    };
    let mut mate2 = vec![NONE; nh];
    let mut flags2 = vec![0u8; nh];
    for c in 0..nh as u32 {
        let m = mate[c as usize];
        mate2[remap(c) as usize] = if m == NONE { NONE } else { remap(m) };
        flags2[remap(c) as usize] = flags[c as usize];
    }
    *mate = mate2;
    *flags = flags2;
    let t = tris.to_mut();
    for (tri, &st) in t.iter_mut().zip(state) {
        if st == 2 {
            tri.swap(1, 2);
            report.flipped_faces += 1;
        }
    }
}

/// Pinched vertices: input vertices split into several fans (`copies_of` lists the input vertex
/// of each copy) although no non-manifold or cut edge (unpaired but shared) touches them.
/// Counted on the first fan split, so the count describes the input, not the detaching after.
fn count_pinched_vertices(
    tris: &[[u32; 3]],
    mate: &[u32],
    flags: &[u8],
    copies_of: &[u32],
    nv: usize,
) -> usize {
    let mut split = vec![0u8; nv]; // 1 split, 2 split and touched by such an edge
    for &s in copies_of {
        split[s as usize] = 1;
    }
    let explained = |e: u32| {
        let f = flags[e as usize];
        f & NON_MANIFOLD != 0 || (mate[e as usize] == NONE && f & SHARED != 0)
    };
    for c in 0..3 * tris.len() as u32 {
        let v = corner_from(tris, c) as usize;
        if split[v] == 1 && (explained(c) || explained(prev_c(c))) {
            split[v] = 2;
        }
    }
    split.iter().filter(|&&s| s == 1).count()
}

/// After fan splitting two distinct edges may still join the same two vertices (a multi-edge:
/// e.g. two pairs of a non-manifold edge whose fans meet again around both endpoints). A
/// half-edge mesh can hold that but a triangle list cannot express it, and every later stage
/// (the PM's base mesh, the .pyr file) rebuilds from triangles. Detach one endpoint into one
/// copy per triangle (unpair all its edges) and split fans again; each round removes
/// pairings, so this ends. Takes and returns [`assign_fans`]' result.
///
/// Only edges shared by more than two triangles, or cut to orient, can leave two edges on one
/// vertex pair: each other pair of vertices has a single edge group of at most two triangles,
/// which stays one edge whatever the fan splitting does.
fn detach_multi_edges(
    tris: &[[u32; 3]],
    mate: &mut [u32],
    nv: usize,
    fans: (Vec<u32>, Vec<u32>, Vec<bool>),
    report: &mut BuildReport,
) -> (Vec<u32>, Vec<u32>, Vec<bool>) {
    let (mut corner_vertex, mut vertex_source, mut seen) = fans;
    let mut detach = if report.non_manifold_edges > 0 || report.orientation_cuts > 0 {
        multi_edge_vertices(mate, &corner_vertex, vertex_source.len())
    } else {
        Vec::new()
    };
    while !detach.is_empty() {
        report.detached_vertices += detach.len();
        let mut marked = vec![false; vertex_source.len()];
        for &u in &detach {
            marked[u as usize] = true;
        }
        for c in 0..mate.len() as u32 {
            if marked[corner_vertex[c as usize] as usize] {
                for e in [c, prev_c(c)] {
                    let m = mate[e as usize];
                    if m != NONE {
                        mate[e as usize] = NONE;
                        mate[m as usize] = NONE;
                    }
                }
            }
        }
        (corner_vertex, vertex_source, seen) = assign_fans(tris, mate, nv);
        detach = multi_edge_vertices(mate, &corner_vertex, vertex_source.len());
    }
    (corner_vertex, vertex_source, seen)
}
