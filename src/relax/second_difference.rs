//! Guskov's non-uniform relaxation operator (Guskov–Sweldens–Schröder 1999; `docs/algorithms.md`
//! §1a–1b): the value at a vertex that minimises the sum of squared hinge-map second
//! differences over the edges whose flap contains the vertex.
//!
//! For an interior edge `e = (j1, j2)` with apexes `l1` (left of `j1→j2`) and `l2` (right), the
//! second difference is `D_e f = Σ c_{e,v} f_v` with the cotangent-form coefficients
//!
//! ```text
//! c_l1 =  2 (cot α1 + cot β1) / L      c_l2 =  2 (cot α2 + cot β2) / L
//! c_j1 = −2 (cot β1 + cot β2) / L      c_j2 = −2 (cot α1 + cot α2) / L
//! ```
//!
//! (α_k, β_k: angles at j1, j2 in triangle k; L = |e|). They are signed automatically, so
//! non-convex hinges keep linear precision, and they need no explicit flattening because the
//! hinge map preserves angles. Minimising `Σ_e (D_e f)²` over `f_i` gives
//! `R f_i = Σ_j w_ij f_j` with `w_ij = −Σ_e c_{e,i} c_{e,j} / Σ_e c_{e,i}²`; the weights sum to
//! one because every `D_e` kills constants.
//!
//! Rules for the awkward cases:
//! * boundary edges have no second difference and are skipped;
//! * an edge with a triangle of area below `degenerate_area_ratio · L²` is skipped too (its
//!   coefficients would blow up like `L/A`), as is a flap whose apexes coincide;
//! * a vertex left with no edge at all (an isolated triangle, or only degenerate edges) keeps
//!   its value: `R f_i = f_i`;
//! * so does a vertex whose weights' absolute sum exceeds [`MAX_WEIGHT_SUM`]: such a stencil
//!   (its second differences barely involve the vertex, so `Σ_e c_{e,i}²` is tiny against the
//!   products) predicts values far outside the neighbourhood, and the pyramid's `q + (f − q)`
//!   then cancels catastrophically — a coarse level of a holed grid had weights summing to
//!   1e15, and an identity filter moved vertices by 0.8 % of the diagonal. Weights summing to
//!   a few hundred do the same more slowly, level after level (`docs/algorithms.md` §1b).
//!
//! The memos that compute each edge flap once per batch of stencils are in `memo`; the tests
//! in `tests`, beside this file.

use super::{Relaxation, RingStencils};
use crate::mesh::{HalfedgeId, Mesh, SlotIndex, VertexId};
use crate::pm::FlatReplay;
use glam::DVec3;
use memo::{FlapCache, RING_FLAPS, RingFlap, RingFlapCache, canonical_halfedge, orient_flap};
use smallvec::SmallVec;

mod memo;

/// Weights of one vertex: `(neighbour, w)` pairs in a fixed, deterministic order (first
/// appearance while circulating the vertex counter-clockwise).
pub(crate) type Stencil = SmallVec<[(VertexId, f64); 24]>;

/// Largest absolute sum of a stencil's weights that is kept (see the [module docs](self)).
/// Regular grids give 2 and most stencils of scans stay below 10; the few above 20 sit at
/// coarse levels of repaired or marching-cubes meshes, where they put spikes into low-passes
/// (`docs/algorithms.md` §1b). Rounding, and the presmoothed signal of the analysis, can grow
/// by about this factor per level.
pub(crate) const MAX_WEIGHT_SUM: f64 = 20.0;

/// Guskov's second-difference relaxation; see the docs of the `second_difference` module.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SecondDifference {
    /// An edge whose adjacent triangle has `2·area < degenerate_area_ratio · L²` is treated as a
    /// boundary edge and skipped (dimensionless; default `1e-12`).
    pub degenerate_area_ratio: f64,
}

impl Default for SecondDifference {
    fn default() -> Self {
        Self {
            degenerate_area_ratio: 1e-12,
        }
    }
}

/// The four coefficients `[c_j1, c_j2, c_l1, c_l2]` of `D_e` on the hinge `(j1, j2 | l1, l2)`,
/// or `None` when either triangle is degenerate (`2·area < ratio · L²`) or the edge has zero
/// length. Units: 1/length.
///
/// With `cot α = p / 2A` and `cot β = q / 2A` (`p = e·(l − j1)`, `q = L² − p`) each triangle
/// needs one factor `t = 2 / (L · 2A)`: `c_l = (cot α + cot β)·2/L = L²·t` and
/// `c_j1 = −(q1 t1 + q2 t2)`, `c_j2 = −(p1 t1 + p2 t2)`. That is three square roots and two
/// divisions per hinge instead of three and five (the hinges were a fifth of the analysis'
/// samples in `perf`, about half of them waiting for positions, the rest for the divider).
#[inline]
pub(crate) fn hinge_coefficients(
    pj1: DVec3,
    pj2: DVec3,
    pl1: DVec3,
    pl2: DVec3,
    degenerate_area_ratio: f64,
) -> Option<[f64; 4]> {
    let e = pj2 - pj1;
    let l2 = e.length_squared();
    if l2.is_nan() || l2 <= 0.0 || !l2.is_finite() {
        return None;
    }
    let length = l2.sqrt();
    let min_double_area = degenerate_area_ratio * l2;
    let (p1, t1) = apex_terms(e, length, pl1 - pj1, min_double_area)?;
    let (p2, t2) = apex_terms(e, length, pl2 - pj1, min_double_area)?;
    let (q1, q2) = (l2 - p1, l2 - p2);
    Some([-(q1 * t1 + q2 * t2), -(p1 * t1 + p2 * t2), l2 * t1, l2 * t2])
}

/// For the triangle `(j1, j2, l)` with `e = j2 − j1` and `w = l − j1`: `p = e·w` and
/// `t = 2 / (|e| · 2A)`, or `None` when the doubled area `2A` is below `min_double_area`.
#[inline]
fn apex_terms(e: DVec3, length: f64, w: DVec3, min_double_area: f64) -> Option<(f64, f64)> {
    let double_area = e.cross(w).length();
    if double_area.is_nan() || double_area < min_double_area || double_area == 0.0 {
        return None;
    }
    Some((e.dot(w), 2.0 / (length * double_area)))
}

/// Hinge weights that fade the second differences across creases (the normal-adaptive operator,
/// `relax::normal_adaptive`): the hinge's coefficients are scaled by `√ω`, so its terms in the
/// stencil by `ω = exp(−(1 − cos θ) / s²)`, with `θ` the angle between the normals of the
/// hinge's two triangles in the guide geometry and `s` the normal scale.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Steering<'a> {
    /// The positions the normals come from, indexed like the parameter geometry; `None`: the
    /// parameter geometry itself.
    pub guide: Option<&'a [DVec3]>,
    /// `1 / (2 s²)`.
    pub half_inverse_scale2: f64,
}

impl Steering<'_> {
    /// `√ω` of the hinge `[j1, j2, l1, l2]` (indices into the geometry); 1 where a triangle
    /// has no normal or a vertex has no guide position.
    #[inline]
    fn hinge_factor(&self, geometry: &[DVec3], v: [usize; 4]) -> f64 {
        let g = self.guide.unwrap_or(geometry);
        let (Some(&a), Some(&b), Some(&l1), Some(&l2)) =
            (g.get(v[0]), g.get(v[1]), g.get(v[2]), g.get(v[3]))
        else {
            return 1.0;
        };
        let e = b - a;
        let (n1, n2) = (e.cross(l1 - a), (l2 - a).cross(e));
        let norms = (n1.length_squared() * n2.length_squared()).sqrt();
        if !(norms > 0.0 && norms.is_finite()) {
            return 1.0;
        }
        let cos = (n1.dot(n2) / norms).clamp(-1.0, 1.0);
        (-(1.0 - cos) * self.half_inverse_scale2).exp()
    }
}

/// The coefficients `c` of the hinge `v`, scaled by its steering factor when there is one.
#[inline]
fn steer(c: [f64; 4], steering: Option<&Steering>, geometry: &[DVec3], v: [usize; 4]) -> [f64; 4] {
    match steering {
        None => c,
        Some(s) => {
            let f = s.hinge_factor(geometry, v);
            c.map(|x| x * f)
        }
    }
}

impl SecondDifference {
    /// Coefficients of the interior edge of half-edge `h` as `([j1, j2, l1, l2], [c; 4])` with
    /// `j1 → j2` along `h`, or `None` for boundary and degenerate edges.
    ///
    /// The arithmetic always runs on the edge's half-edge of smaller slot and is permuted for
    /// its twin, so both directions (and a cached copy, see [`Relaxation::stencils`]) give the
    /// same bits.
    #[inline]
    fn edge_flap(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        h: HalfedgeId,
        steering: Option<&Steering>,
    ) -> Option<([VertexId; 4], [f64; 4])> {
        let (canonical, flipped) = canonical_halfedge(mesh, h);
        Some(orient_flap(
            self.canonical_flap(mesh, geometry, canonical, steering)?,
            flipped,
        ))
    }

    /// [`Self::edge_flap`] evaluated along `h` itself.
    #[inline]
    fn canonical_flap(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        h: HalfedgeId,
        steering: Option<&Steering>,
    ) -> Option<([VertexId; 4], [f64; 4])> {
        let t = mesh.twin(h);
        if mesh.face(h).is_none() || mesh.face(t).is_none() {
            return None;
        }
        let j1 = mesh.to_vertex(t);
        let j2 = mesh.to_vertex(h);
        let l1 = mesh.to_vertex(mesh.next(h));
        let l2 = mesh.to_vertex(mesh.next(t));
        if l1 == l2 {
            // A folded flap (both triangles share their apex): no hinge to unfold.
            return None;
        }
        let p = |v: VertexId| geometry[v.slot()];
        let c = hinge_coefficients(p(j1), p(j2), p(l1), p(l2), self.degenerate_area_ratio)?;
        let c = steer(c, steering, geometry, [j1, j2, l1, l2].map(|v| v.slot()));
        Some(([j1, j2, l1, l2], c))
    }

    /// The relaxation weights `w_ij` of vertex `i` (the stencil `V2(i)`: the 1-ring plus the
    /// flap apexes across the link edges), from the parameter geometry `geometry[v.slot()]`.
    /// Returns `false` and leaves `out` empty when `i` has no usable edge (then `R f_i = f_i`).
    pub fn stencil(&self, mesh: &Mesh, geometry: &[DVec3], i: VertexId, out: &mut Stencil) -> bool {
        self.steered_stencil(mesh, geometry, i, out, None)
    }

    /// [`Self::stencil`] with every hinge scaled by `steering` (see [`Steering`]).
    pub(crate) fn steered_stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        i: VertexId,
        out: &mut Stencil,
        steering: Option<&Steering>,
    ) -> bool {
        self.stencil_with(mesh, i, out, |h| {
            self.edge_flap(mesh, geometry, h, steering)
        })
    }

    /// The stencil of `i` with the flaps of its edges supplied by `flap` (direct or cached).
    #[inline]
    fn stencil_with<F>(&self, mesh: &Mesh, i: VertexId, out: &mut Stencil, mut flap: F) -> bool
    where
        F: FnMut(HalfedgeId) -> Option<([VertexId; 4], [f64; 4])>,
    {
        out.clear();
        let mut den = 0.0;
        let mut accumulate = |flap: [VertexId; 4], c: [f64; 4], at: usize, out: &mut Stencil| {
            let ci = c[at];
            den += ci * ci;
            for k in 0..4 {
                if k == at {
                    continue;
                }
                let v = flap[k];
                let x = ci * c[k];
                match out.iter_mut().find(|(u, _)| *u == v) {
                    Some((_, acc)) => *acc += x,
                    None => out.push((v, x)),
                }
            }
        };
        for h in mesh.outgoing(i) {
            // (a) the edge i → to(h): i is j1 of its flap.
            if let Some((f, c)) = flap(h) {
                accumulate(f, c, 0, out);
            }
            // (b) the link edge opposite i in the face left of h: i is its apex l1.
            if mesh.face(h).is_some() {
                let g = mesh.next(h);
                if let Some((f, c)) = flap(g)
                    && f[2] == i
                    && f[3] != i
                {
                    accumulate(f, c, 2, out);
                }
            }
        }
        let ok = normalize_stencil(out, den);
        if !ok {
            out.clear();
        }
        ok
    }
}

/// Turns the summed products `Σ_e c_{e,i} c_{e,j}` of a stencil into its weights by dividing
/// by `−den = −Σ_e c_{e,i}²`; `false` when the vertex must keep its value instead (no usable
/// edge, or weights summing past [`MAX_WEIGHT_SUM`]; see the [module docs](self)).
fn normalize_stencil<T>(entries: &mut [(T, f64)], den: f64) -> bool {
    if den.is_nan() || den <= 0.0 || !den.is_finite() {
        return false;
    }
    let scale = -1.0 / den;
    let mut gain = 0.0;
    for (_, w) in entries.iter_mut() {
        *w *= scale;
        gain += w.abs();
    }
    !(gain.is_nan() || gain > MAX_WEIGHT_SUM)
}

impl Relaxation for SecondDifference {
    fn name(&self) -> &'static str {
        "second-difference"
    }

    fn as_ring_stencils(&self) -> Option<&dyn RingStencils> {
        Some(self)
    }

    fn stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
    ) -> bool {
        self.vec_stencil(mesh, geometry, vertex, out, None)
    }

    /// Shares each edge's hinge coefficients among the batch's stencils (an edge enters the
    /// stencils of up to four vertices of a 1-ring); bit-identical to per-vertex stencils.
    fn stencils(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertices: &[VertexId],
        out: &mut Vec<(VertexId, f64)>,
        lens: &mut Vec<usize>,
    ) {
        self.batch_stencils(mesh, geometry, vertices, out, lens, None)
    }
}

impl SecondDifference {
    /// [`Relaxation::stencil`], steered.
    pub(crate) fn vec_stencil(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertex: VertexId,
        out: &mut Vec<(VertexId, f64)>,
        steering: Option<&Steering>,
    ) -> bool {
        let mut s = Stencil::new();
        let ok = self.steered_stencil(mesh, geometry, vertex, &mut s, steering);
        out.clear();
        out.extend_from_slice(&s);
        ok
    }

    /// [`Relaxation::stencils`], steered.
    pub(crate) fn batch_stencils(
        &self,
        mesh: &Mesh,
        geometry: &[DVec3],
        vertices: &[VertexId],
        out: &mut Vec<(VertexId, f64)>,
        lens: &mut Vec<usize>,
        steering: Option<&Steering>,
    ) {
        let mut cache = FlapCache::new(u32::MAX);
        let mut s = Stencil::new();
        for &v in vertices {
            let flap = |h| cache.flap(self, mesh, geometry, h, steering);
            if self.stencil_with(mesh, v, &mut s, flap) {
                out.extend_from_slice(&s);
                lens.push(s.len());
            } else {
                lens.push(0);
            }
        }
    }

    /// [`RingStencils::ring_stencils`], steered.
    pub(crate) fn steered_ring_stencils(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        vertices: &[u32],
        out: &mut Vec<(u32, f64)>,
        lens: &mut Vec<usize>,
        steering: Option<&Steering>,
    ) {
        RING_FLAPS.with_borrow_mut(|cache| {
            cache.clear();
            for &v in vertices {
                let start = out.len();
                self.append_ring_stencil(replay, geometry, v, out, cache, steering);
                lens.push(out.len() - start);
            }
        });
    }
}

impl RingStencils for SecondDifference {
    /// Shares each edge's hinge coefficients among the batch's stencils, as
    /// [`Relaxation::stencils`] does.
    fn ring_stencils(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        vertices: &[u32],
        out: &mut Vec<(u32, f64)>,
        lens: &mut Vec<usize>,
    ) {
        self.steered_ring_stencils(replay, geometry, vertices, out, lens, None)
    }
}

impl SecondDifference {
    /// The flap of edge `a`–`b` on the rings of `replay`, computed along the edge's half-edge
    /// of smaller slot as [`Self::canonical_flap`] does (so the same bits as on the half-edge
    /// mesh with the replay's slots), or `None` for a boundary or degenerate edge and for
    /// vertices that are not neighbours. `ka`: where `b` is in `a`'s ring, when known.
    ///
    /// Out of line: it runs on the memo's misses only, and inlined it made every lookup pay
    /// for its registers.
    #[inline(never)]
    fn ring_flap(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        a: u32,
        b: u32,
        ka: Option<usize>,
        steering: Option<&Steering>,
    ) -> Option<RingFlap> {
        let (ra, boundary_a) = replay.ring_entries(a);
        let (rb, boundary_b) = replay.ring_entries(b);
        let ka = match ka {
            Some(k) if ra.get(k).is_some_and(|e| e.nbr == b) => k,
            _ => ra.iter().position(|e| e.nbr == b)?,
        };
        let kb = rb.iter().position(|e| e.nbr == a)?;
        // Entry 0 of a boundary vertex has no face on its left.
        if (ka == 0 && boundary_a) || (kb == 0 && boundary_b) {
            return None;
        }
        let left_ab = ra[if ka + 1 == ra.len() { 0 } else { ka + 1 }].nbr;
        let left_ba = rb[if kb + 1 == rb.len() { 0 } else { kb + 1 }].nbr;
        if left_ab == left_ba {
            return None;
        }
        let v = if ra[ka].slot < rb[kb].slot {
            [a, b, left_ab, left_ba]
        } else {
            [b, a, left_ba, left_ab]
        };
        let p = |x: u32| geometry.get(x as usize).copied();
        let c = hinge_coefficients(
            p(v[0])?,
            p(v[1])?,
            p(v[2])?,
            p(v[3])?,
            self.degenerate_area_ratio,
        )?;
        let c = steer(c, steering, geometry, v.map(|x| x as usize));
        Some(RingFlap { v, c })
    }

    /// [`Self::stencil`] of vertex `i` on the rings of `replay`, appended to `entries` (same
    /// order and bits as on the half-edge mesh with the replay's slots); `false`, appending
    /// nothing, when `i` keeps its value.
    ///
    /// Entries appear in the order of their first contribution while circulating `i`, and
    /// each sums its contributions in that order. Most flap vertices are ring vertices at a
    /// known place (a spoke's apexes are the ends of the spokes before and after it, a link
    /// edge joins the ends of two consecutive spokes), so their entry is remembered per spoke
    /// and only the far apexes across the link edges are searched for.
    fn append_ring_stencil(
        &self,
        replay: &FlatReplay,
        geometry: &[DVec3],
        i: u32,
        entries: &mut Vec<(u32, f64)>,
        cache: &mut RingFlapCache,
        steering: Option<&Steering>,
    ) -> bool {
        let start = entries.len();
        let (ring, boundary) = replay.ring_entries(i);
        let n = ring.len();
        // Each ring vertex's entry, once it has one; on the stack for rings of up to 16.
        let mut inline = [u32::MAX; 16];
        let mut spilled = Vec::new();
        let ring_entry = if n <= inline.len() {
            &mut inline[..n]
        } else {
            spilled.resize(n, u32::MAX);
            &mut spilled[..]
        };
        let mut den = 0.0;
        // A macro, not a closure: the five calls per spoke are the stencil's inner loop and a
        // closure call here was not inlined (a quarter of the stencil's instructions).
        macro_rules! add {
            ($v:expr, $at:expr, $x:expr) => {
                add_ring_vertex_entry(entries, start, ring[$at].nbr, &mut ring_entry[$at], $v, $x)
            };
        }
        for k in 0..n {
            let r = ring[k].nbr;
            let after = if k + 1 == n { 0 } else { k + 1 };
            let before = if k == 0 { n - 1 } else { k - 1 };
            // (a) the edge i → r: i is j1 of its flap (`f` is seen flipped when x = 1).
            if let Some((f, x)) = cache.flap(self, replay, geometry, (i, r, Some(k)), steering) {
                let ci = f.c[x];
                den += ci * ci;
                add!(f.v[1 ^ x], k, ci * f.c[1 ^ x]);
                add!(f.v[2 ^ x], after, ci * f.c[2 ^ x]);
                add!(f.v[3 ^ x], before, ci * f.c[3 ^ x]);
            }
            // (b) the link edge r → next opposite i in the face left of i → r: i is its apex l1.
            if !(k == 0 && boundary)
                && let Some((f, x)) =
                    cache.flap(self, replay, geometry, (r, ring[after].nbr, None), steering)
                && f.v[2 ^ x] == i
                && f.v[3 ^ x] != i
            {
                let ci = f.c[2 ^ x];
                den += ci * ci;
                add!(f.v[x], k, ci * f.c[x]);
                add!(f.v[1 ^ x], after, ci * f.c[1 ^ x]);
                add_ring_entry(entries, start, f.v[3 ^ x], ci * f.c[3 ^ x]);
            }
        }
        let ok = normalize_stencil(&mut entries[start..], den);
        if !ok {
            entries.truncate(start);
        }
        ok
    }
}

/// [`add_ring_entry`] for a flap vertex `v` expected to be the ring vertex `expected`, whose
/// entry is remembered in `memo`.
#[inline(always)]
fn add_ring_vertex_entry(
    entries: &mut Vec<(u32, f64)>,
    start: usize,
    expected: u32,
    memo: &mut u32,
    v: u32,
    x: f64,
) {
    if v != expected {
        add_ring_entry(entries, start, v, x);
    } else if *memo == u32::MAX {
        *memo = add_ring_entry(entries, start, v, x) as u32;
    } else {
        entries[start + *memo as usize].1 += x;
    }
}

/// Adds `x` to the entry of `v` among `entries[start..]`, appending `(v, x)` when `v` has none
/// yet; returns the entry's index relative to `start`.
#[inline(always)]
fn add_ring_entry(entries: &mut Vec<(u32, f64)>, start: usize, v: u32, x: f64) -> usize {
    match entries[start..].iter().position(|&(u, _)| u == v) {
        Some(e) => {
            entries[start + e].1 += x;
            e
        }
        None => {
            entries.push((v, x));
            entries.len() - 1 - start
        }
    }
}

/// `Σ w_j signal[j]` in stencil order.
#[inline]
#[cfg(test)]
pub(crate) fn apply_stencil(stencil: &[(VertexId, f64)], signal: &[DVec3]) -> DVec3 {
    stencil
        .iter()
        .fold(DVec3::ZERO, |acc, &(v, w)| acc + w * signal[v.slot()])
}

// The tests live beside this file (`second_difference/tests.rs`): the operator is long enough
// on its own.
#[cfg(test)]
mod tests;
