//! Replaying vertex splits on flat arrays: the same half-edge records, slot numbers and
//! canonical vertex half-edges as [`vertex_split`](super::vertex_split) on a [`Mesh`], without
//! slotmap handles, generation checks or per-split allocation.
//!
//! Why it exists: the `.pyr` format codes a split's wings as indices into the survivor's ring
//! *as `Mesh::outgoing` lists it* after replaying the earlier splits, so reading and writing a
//! file replay every split. On the slotmap mesh each split cost about 6 µs (seven walks around
//! the survivor: the ring, two `find_halfedge`, the fan, four `set_canonical`), which capped
//! `.pyr` input/output near 20 MB/s. Here one walk lists the ring with its half-edges, the fan is
//! a range of it, and the canonical half-edges of the four touched vertices follow from the
//! split's case analysis instead of fresh walks (see [`FlatReplay::split`]).
//!
//! Exactness rests on two facts the tests check against [`SplitReplay`](super::SplitReplay):
//! a replay only inserts (no slot is ever freed), so a new half-edge's slot is the current
//! count, in `vertex_split`'s insertion order `o, h, o2, o1, h2, h1`; and the mesh is in
//! canonical form (a boundary vertex stores its boundary out-edge, an interior vertex its
//! out-edge of smallest slot), which the builder produces and every split preserves.

use super::{PmError, SplitError, VertexSplit};
use crate::mesh::{Mesh, SlotIndex};
use glam::DVec3;

const NIL: u32 = u32::MAX;

/// Rotates a triangle so that its smallest index comes first (orientation kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

#[inline]
fn is_boundary(he: &[He], g: u32) -> bool {
    !he[g as usize].face
}

/// One half-edge: the slotmap record with indices for handles and a flag for the face.
#[derive(Clone, Copy, Debug)]
struct He {
    to: u32,
    next: u32,
    prev: u32,
    twin: u32,
    face: bool,
}

fn invalid(reason: impl Into<String>) -> PmError {
    PmError::Internal(format!(
        "inconsistent progressive mesh data: {}",
        reason.into()
    ))
}

/// The base mesh and the splits applied so far, on flat arrays (vertex `i` is PM vertex `i`,
/// half-edge and face `i` are the slots the slotmap mesh would give them).
#[derive(Clone, Debug)]
pub struct FlatReplay {
    he: Vec<He>,
    /// Canonical out-going half-edge of each vertex.
    vhe: Vec<u32>,
    /// Stored half-edge of each face, in face slot order.
    faces: Vec<u32>,
    n_base_faces: usize,
    /// The ring last listed by [`Self::ring`]: neighbours and the out-going half-edges to them.
    ring_v: Vec<u32>,
    ring_h: Vec<u32>,
    ring_of: u32,
    fan: Vec<u32>,
}

impl FlatReplay {
    /// Builds the base mesh from its triangles with the same checks as
    /// [`SplitReplay::new`](super::SplitReplay::new) (clean manifold, every vertex used), then
    /// copies it into flat arrays. `splits_hint` reserves room for that many splits.
    pub fn new(
        base_positions: &[DVec3],
        base_faces: &[[u32; 3]],
        splits_hint: usize,
    ) -> Result<Self, PmError> {
        let base = super::SplitReplay::new(base_positions, base_faces)?;
        let mesh: &Mesh = base.mesh();
        let n_he = mesh.n_halfedges();
        if !mesh.halfedges().all(|h| h.slot() < n_he)
            || !mesh.faces().all(|f| f.slot() < mesh.n_faces())
        {
            return Err(invalid("base mesh slots are not dense"));
        }
        let mut he = Vec::with_capacity(n_he + splits_hint.min(1 << 26) * 6);
        he.resize(
            n_he,
            He {
                to: NIL,
                next: NIL,
                prev: NIL,
                twin: NIL,
                face: false,
            },
        );
        for h in mesh.halfedges() {
            let r = &mesh.halfedges[h];
            he[h.slot()] = He {
                to: r.to.slot() as u32,
                next: r.next.slot() as u32,
                prev: r.prev.slot() as u32,
                twin: r.twin.slot() as u32,
                face: r.face.is_some(),
            };
        }
        let mut faces = vec![NIL; mesh.n_faces()];
        for f in mesh.faces() {
            faces[f.slot()] = mesh.faces[f].halfedge.slot() as u32;
        }
        faces.reserve(splits_hint.min(1 << 26) * 2);
        let mut vhe = Vec::with_capacity(base_positions.len() + splits_hint.min(1 << 26));
        for v in mesh.vertices() {
            let h = mesh.vertices[v].halfedge.map_or(NIL, |h| h.slot() as u32);
            vhe.push(h);
        }
        let mut replay = FlatReplay {
            he,
            vhe,
            n_base_faces: faces.len(),
            faces,
            ring_v: Vec::new(),
            ring_h: Vec::new(),
            ring_of: NIL,
            fan: Vec::new(),
        };
        // The shortcuts in `split` need canonical form; the builder promises it, check.
        for v in 0..replay.vhe.len() as u32 {
            replay.ring(v)?;
            let boundary = replay
                .ring_h
                .iter()
                .position(|&g| !replay.he[g as usize].face);
            let canonical = match boundary {
                Some(k) => replay.ring_h[k],
                None => replay.ring_h.iter().copied().min().unwrap_or(NIL),
            };
            if canonical != replay.vhe[v as usize] {
                return Err(invalid("base mesh is not in canonical form"));
            }
        }
        replay.ring_of = NIL;
        Ok(replay)
    }

    /// Number of vertices so far.
    pub fn level(&self) -> usize {
        self.vhe.len()
    }

    /// Number of faces of the base mesh.
    pub fn n_base_faces(&self) -> usize {
        self.n_base_faces
    }

    /// Number of faces so far.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    #[inline]
    fn ccw(&self, g: u32) -> u32 {
        self.he[self.he[g as usize].prev as usize].twin
    }

    /// The PM indices around `v` in [`Mesh::outgoing`] order (counter-clockwise from the
    /// canonical half-edge; a boundary vertex starts at its boundary out-edge) — the ring the
    /// `.pyr` format indexes wings into.
    pub fn ring(&mut self, v: u32) -> Result<&[u32], PmError> {
        let start = *self
            .vhe
            .get(v as usize)
            .ok_or_else(|| invalid(format!("survivor {v} does not exist yet")))?;
        self.ring_v.clear();
        self.ring_h.clear();
        self.ring_of = v;
        if start != NIL {
            let mut g = start;
            loop {
                self.ring_v.push(self.he[g as usize].to);
                self.ring_h.push(g);
                g = self.ccw(g);
                // A consistent mesh closes the loop within its half-edge count; the bound only
                // keeps a broken one from looping forever.
                if g == start || self.ring_h.len() > self.he.len() {
                    break;
                }
            }
        }
        Ok(&self.ring_v)
    }

    /// The ring [`Self::ring`] or [`Self::wing_indices`] listed last.
    pub fn listed_ring(&self) -> &[u32] {
        &self.ring_v
    }

    /// Applies `s` (which must create vertex `level()`), finding its wings in the survivor's
    /// ring. Equivalent to [`SplitReplay::apply`](super::SplitReplay::apply).
    pub fn apply(&mut self, s: &VertexSplit) -> Result<(), PmError> {
        let (il, ir) = self.wing_indices(s)?;
        self.apply_indexed(s.vertex, s.survivor, il, ir)?;
        Ok(())
    }

    /// The positions of `s`'s wings in its survivor's ring (listing the ring), for coding the
    /// split; [`Self::apply_indexed`] with the same indices then applies it without a new walk.
    pub fn wing_indices(
        &mut self,
        s: &VertexSplit,
    ) -> Result<(Option<usize>, Option<usize>), PmError> {
        let level = self.level();
        for x in [Some(s.survivor), s.left, s.right].into_iter().flatten() {
            if x as usize >= level {
                return Err(invalid(format!(
                    "split {level} refers to future vertex {x}"
                )));
            }
        }
        let ring = self.ring(s.survivor)?;
        let find = |w: Option<u32>| match w {
            None => Ok(None),
            Some(x) => ring.iter().position(|&r| r == x).map(Some).ok_or_else(|| {
                invalid(format!(
                    "split creating vertex {level}: {}",
                    SplitError::Inconsistent
                ))
            }),
        };
        Ok((find(s.left)?, find(s.right)?))
    }

    /// Applies the split creating vertex `vertex` (which must be `level()`) at `survivor`, whose
    /// ring [`Self::ring`] listed last, with wings given as ring indices. Returns the record.
    pub fn apply_indexed(
        &mut self,
        vertex: u32,
        survivor: u32,
        il: Option<usize>,
        ir: Option<usize>,
    ) -> Result<VertexSplit, PmError> {
        let level = self.level();
        if vertex as usize != level {
            return Err(invalid(format!(
                "split creates vertex {vertex}, expected {level}"
            )));
        }
        if self.ring_of != survivor {
            self.ring(survivor)?;
        }
        let n = self.ring_v.len();
        if il.is_some_and(|i| i >= n) || ir.is_some_and(|i| i >= n) {
            return Err(invalid(format!(
                "split creating vertex {level}: {}",
                SplitError::Inconsistent
            )));
        }
        let split = VertexSplit {
            vertex,
            survivor,
            left: il.map(|i| self.ring_v[i]),
            right: ir.map(|i| self.ring_v[i]),
        };
        self.split(il, ir).map_err(|e| {
            self.ring_of = NIL;
            invalid(format!("split creating vertex {level}: {e}"))
        })?;
        self.ring_of = NIL;
        Ok(split)
    }

    /// `vertex_split` on the listed ring of the survivor `v`, same checks, same records. The
    /// fan is the ring range from the left wing (or the edge after the boundary out-edge)
    /// counter-clockwise to the right wing (or through the boundary out-edge).
    fn split(&mut self, il: Option<usize>, ir: Option<usize>) -> Result<(), SplitError> {
        let v = self.ring_of;
        let n = self.ring_v.len();
        if n == 0 {
            return Err(SplitError::Inconsistent);
        }
        let left = il.map(|i| self.ring_v[i]);
        let right = ir.map(|i| self.ring_v[i]);
        if (left.is_none() && right.is_none())
            || (left.is_some() && left == right)
            || left == Some(v)
            || right == Some(v)
        {
            return Err(SplitError::Inconsistent);
        }
        let t2 = il.map(|i| self.ring_h[i]);
        let s2 = ir.map(|i| self.ring_h[i]);
        // The ring starts at the stored (canonical) half-edge, the one `vertex_split` checks.
        let bout = match (left, right) {
            (Some(_), Some(_)) => None,
            _ => {
                let b = self.ring_h[0];
                if !is_boundary(&self.he, b) {
                    return Err(SplitError::Inconsistent);
                }
                Some(b)
            }
        };
        let start = match il {
            Some(i) => i,
            None => 1 % n,
        };
        self.fan.clear();
        let mut e = start;
        match ir {
            Some(ir) => {
                while e != ir {
                    let g = self.ring_h[e];
                    if self.fan.len() > n || is_boundary(&self.he, g) {
                        return Err(SplitError::Inconsistent);
                    }
                    self.fan.push(g);
                    e = (e + 1) % n;
                }
            }
            None => loop {
                let g = self.ring_h[e];
                if self.fan.len() > n {
                    return Err(SplitError::Inconsistent);
                }
                self.fan.push(g);
                if is_boundary(&self.he, g) {
                    break;
                }
                e = (e + 1) % n;
            },
        }
        let s1 = s2.map(|s| self.he[s as usize].twin);
        let t1 = t2.map(|t| self.he[t as usize].twin);

        // Same insertion order as `vertex_split`, hence the same slots.
        let u = self.vhe.len() as u32;
        let blank = He {
            to: NIL,
            next: NIL,
            prev: NIL,
            twin: NIL,
            face: false,
        };
        let alloc = |he: &mut Vec<He>| {
            he.push(blank);
            (he.len() - 1) as u32
        };
        let o = alloc(&mut self.he);
        let h = alloc(&mut self.he);
        let (o2, o1) = if right.is_some() {
            (Some(alloc(&mut self.he)), Some(alloc(&mut self.he)))
        } else {
            (None, None)
        };
        let (h2, h1) = if left.is_some() {
            (Some(alloc(&mut self.he)), Some(alloc(&mut self.he)))
        } else {
            (None, None)
        };
        if right.is_some() {
            self.faces.push(o);
        }
        if left.is_some() {
            self.faces.push(h);
        }
        for &g in &self.fan {
            if Some(g) != t2 {
                let t = self.he[g as usize].twin;
                self.he[t as usize].to = u;
            }
        }
        if let Some(s1) = s1 {
            self.he[s1 as usize].to = u;
        }
        self.he[h as usize].to = v;
        self.he[h as usize].twin = o;
        self.he[h as usize].face = left.is_some();
        self.he[o as usize].to = u;
        self.he[o as usize].twin = h;
        self.he[o as usize].face = right.is_some();
        match (left, h1, h2, t1, t2) {
            (Some(vl), Some(h1), Some(h2), Some(t1), Some(t2)) => {
                self.he[h1 as usize] = He {
                    to: vl,
                    next: h2,
                    prev: h,
                    twin: t1,
                    face: true,
                };
                self.he[h2 as usize] = He {
                    to: u,
                    next: h,
                    prev: h1,
                    twin: t2,
                    face: true,
                };
                self.he[h as usize].next = h1;
                self.he[h as usize].prev = h2;
                self.he[t1 as usize].twin = h1;
                self.he[t2 as usize].twin = h2;
            }
            _ => {
                let b = bout.ok_or(SplitError::Inconsistent)?;
                let bin = self.he[b as usize].prev;
                self.he[h as usize].prev = bin;
                self.he[h as usize].next = b;
                self.he[bin as usize].next = h;
                self.he[b as usize].prev = h;
            }
        }
        match (right, o1, o2, s1, s2) {
            (Some(vr), Some(o1), Some(o2), Some(s1), Some(s2)) => {
                self.he[o1 as usize] = He {
                    to: vr,
                    next: o2,
                    prev: o,
                    twin: s1,
                    face: true,
                };
                self.he[o2 as usize] = He {
                    to: v,
                    next: o,
                    prev: o1,
                    twin: s2,
                    face: true,
                };
                self.he[o as usize].next = o1;
                self.he[o as usize].prev = o2;
                self.he[s1 as usize].twin = o1;
                self.he[s2 as usize].twin = o2;
            }
            _ => {
                let gk = *self.fan.last().ok_or(SplitError::Inconsistent)?;
                let p = self.he[gk as usize].prev;
                self.he[o as usize].prev = p;
                self.he[o as usize].next = gk;
                self.he[p as usize].next = o;
                self.he[gk as usize].prev = o;
            }
        }
        // Canonical half-edges, as `set_canonical` would find them. New half-edges have the
        // largest slots, so only boundary status and which old half-edges moved matter.
        // u: without a left face h = u→v is its boundary out-edge; without a right face the
        // fan ends at the old boundary out-edge of v, now u's; else u is interior and its
        // smallest slot is an old fan half-edge (the fan holds at least t2).
        let cu = match (left, right) {
            (None, _) => h,
            (_, None) => *self.fan.last().ok_or(SplitError::Inconsistent)?,
            _ => self.fan.iter().copied().min().unwrap_or(h),
        };
        // v: without a right face o = v→u is its boundary out-edge; a boundary v otherwise
        // keeps its boundary out-edge (never in the fan); an interior v takes the smallest
        // half-edge left to it.
        let old = self.ring_h[0];
        let cv = if right.is_none() {
            o
        } else if is_boundary(&self.he, old) {
            old
        } else {
            let (a, b) = (start, ir.unwrap_or(start));
            let in_fan = |k: usize| {
                if a <= b {
                    (a..b).contains(&k)
                } else {
                    k >= a || k < b
                }
            };
            let mut best = NIL;
            for (k, &g) in self.ring_h.iter().enumerate() {
                if !in_fan(k) && g < best {
                    best = g;
                }
            }
            best.min(o)
        };
        // v_l and v_r only gain a new (largest) half-edge and keep their boundary status, so
        // their canonical half-edges do not change.
        self.vhe.push(cu);
        self.vhe[v as usize] = cv;
        Ok(())
    }

    /// The current triangles in face slot order, each starting where
    /// [`Mesh::face_vertices`] starts (what [`Mesh::to_triangles`] gives for the replayed mesh).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.faces
            .iter()
            .map(|&h| {
                let r = &self.he[h as usize];
                [
                    self.he[r.prev as usize].to,
                    r.to,
                    self.he[r.next as usize].to,
                ]
            })
            .collect()
    }

    /// The current triangles in PM indices, canonically rotated (smallest index first) and
    /// sorted.
    pub fn canonical_faces(&self) -> Vec<[u32; 3]> {
        let mut f: Vec<[u32; 3]> = self.triangles().into_iter().map(canonical).collect();
        f.sort_unstable();
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pm::{PmOptions, ProgressiveMesh, SplitReplay};
    use crate::progress::NoProgress;

    /// Replays every split on both the slotmap mesh and the flat arrays and compares every
    /// ring the format would index after each split, and the faces at the end.
    fn same_as_slotmap(mesh: &Mesh) {
        let pm = ProgressiveMesh::build(mesh, &PmOptions::default(), &NoProgress).unwrap();
        let nb = pm.n_base_vertices();
        let pos = pm.original_positions();
        let base = pm.base_triangles();
        let mut slow = SplitReplay::new(&pos[..nb], &base).unwrap();
        let mut fast = FlatReplay::new(&pos[..nb], &base, pm.splits().len()).unwrap();
        let mut ring = Vec::new();
        for (i, s) in pm.splits().iter().enumerate() {
            slow.ring(s.survivor, &mut ring).unwrap();
            assert_eq!(fast.ring(s.survivor).unwrap(), &ring[..], "split {i}");
            let (il, ir) = fast.wing_indices(s).unwrap();
            let rec = fast.apply_indexed(s.vertex, s.survivor, il, ir).unwrap();
            assert_eq!(&rec, s);
            slow.apply(s, pos[nb + i]).unwrap();
            for x in [s.vertex, s.survivor] {
                slow.ring(x, &mut ring).unwrap();
                assert_eq!(fast.ring(x).unwrap(), &ring[..], "split {i} vertex {x}");
            }
        }
        assert_eq!(fast.triangles(), slow.mesh().to_triangles().1);
        assert_eq!(fast.canonical_faces(), slow.canonical_faces());
        for v in 0..fast.level() as u32 {
            slow.ring(v, &mut ring).unwrap();
            assert_eq!(fast.ring(v).unwrap(), &ring[..]);
        }
    }

    #[test]
    fn flat_replay_matches_the_slotmap_mesh() {
        // Closed, with boundary, and with holes.
        let (p, t) = crate::mesh::shapes::icosphere(3);
        same_as_slotmap(&Mesh::from_triangles(&p, &t).unwrap().mesh);
        let (p, t) = crate::mesh::shapes::grid(12, |i, j| {
            DVec3::new(i as f64, j as f64, ((i * 7 + j * 3) % 5) as f64 * 0.1)
        });
        same_as_slotmap(&Mesh::from_triangles(&p, &t).unwrap().mesh);
        let t: Vec<[u32; 3]> = t
            .iter()
            .enumerate()
            .filter(|(k, _)| k % 17 != 5)
            .map(|(_, t)| *t)
            .collect();
        same_as_slotmap(&Mesh::from_triangles(&p, &t).unwrap().mesh);
    }

    #[test]
    fn bad_splits_are_errors() {
        let (p, t) = crate::mesh::shapes::icosphere(1);
        let m = Mesh::from_triangles(&p, &t).unwrap().mesh;
        let pm = ProgressiveMesh::build(&m, &PmOptions::default(), &NoProgress).unwrap();
        let nb = pm.n_base_vertices();
        let pos = pm.original_positions();
        let base = pm.base_triangles();
        let mut r = FlatReplay::new(&pos[..nb], &base, 0).unwrap();
        let s = pm.splits()[0];
        assert!(
            r.apply_indexed(s.vertex + 1, s.survivor, Some(0), Some(1))
                .is_err()
        );
        assert!(
            r.apply_indexed(s.vertex, s.survivor, Some(0), Some(0))
                .is_err()
        );
        assert!(
            r.apply_indexed(s.vertex, s.survivor, Some(99), None)
                .is_err()
        );
        // An interior survivor needs both wings.
        assert!(
            r.apply_indexed(s.vertex, s.survivor, Some(0), None)
                .is_err()
        );
        assert!(
            r.apply_indexed(s.vertex, s.vertex, Some(0), Some(1))
                .is_err()
        );
        r.apply(&s).unwrap();
        assert_eq!(r.level(), nb + 1);
    }
}
