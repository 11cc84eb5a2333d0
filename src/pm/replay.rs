//! Replaying vertex splits on flat arrays: the rings [`Mesh::outgoing`] would list, the faces
//! and their stored corners, and the half-edge slot numbers as [`vertex_split`](super::vertex_split)
//! on a [`Mesh`] would leave them — without the half-edge mesh.
//!
//! Why it exists: the `.pyr` format codes a split's wings as indices into the survivor's ring
//! *as `Mesh::outgoing` lists it* after replaying the earlier splits, so reading and writing a
//! file replay every split. On the slotmap mesh each split walks around the survivor through
//! pointer-chasing records several times, which bounded `.pyr` input and output (figures in
//! `docs/performance.md`, ".pyr files: sizes and speed"). Here every vertex
//! keeps its ring as one contiguous list of `(neighbour, out-going half-edge slot, face on its
//! left)` in `outgoing` order, so listing a ring is one read and a split rewrites a handful of
//! short lists (survivor, new vertex, the two wings, the fan's vertices) instead of walking
//! linked records.
//!
//! Exactness rests on two facts the tests check against [`SplitReplay`](super::SplitReplay):
//! a replay only inserts (no slot is ever freed), so a new half-edge's slot is the current
//! count, in `vertex_split`'s insertion order `o, h, o2, o1, h2, h1`, and a new face's slot
//! follows `fr, fl`; and the mesh is in canonical form (a ring starts at the vertex's boundary
//! out-edge, else at its out-edge of smallest slot), which the builder produces and every split
//! preserves.

use super::prefetch::prefetch;
use super::{PmError, SplitError, VertexSplit};
use crate::mesh::{Mesh, SlotIndex};
use glam::DVec3;

const NIL: u32 = u32::MAX;

/// Rotates a triangle so that its smallest index comes first (orientation kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// One ring entry: the out-going half-edge `v → nbr` and its slot. Eight bytes, so a typical
/// ring fits a cache line; which entry is a boundary half-edge is in [`Rings::boundary`], and
/// faces are found from their stored half-edge's slot ([`FlatReplay::triangles`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Entry {
    /// The neighbour (PM index).
    pub(crate) nbr: u32,
    /// The out-going half-edge's slot.
    pub(crate) slot: u32,
}

/// Two cache lines per vertex: the header (`nbr`: length, bit 31 set when entry 0 is a
/// boundary out-edge; `slot`: where a longer ring lives in the overflow arena, or `NIL`), then
/// up to [`INLINE`] ring entries. A ring of up to seven entries is one cache line; fifteen
/// hold the rings a replay meets almost always, including a survivor's just before its split
/// (its valence is about the two merged vertices' valences minus four: 8 on a regular
/// mesh, which one line's seven entries sent to the slower overflow path).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Line {
    hdr: Entry,
    e: [Entry; INLINE],
}

const INLINE: usize = 15;
const BOUNDARY: u32 = 1 << 31;
const BLANK: Entry = Entry {
    nbr: NIL,
    slot: NIL,
};

/// The rings of all vertices: inline in each vertex's line, longer ones in `over` (preceded by
/// a cell holding their capacity).
#[derive(Clone, Debug, Default)]
struct Rings {
    lines: Vec<Line>,
    over: Vec<Entry>,
}

impl Rings {
    fn len(&self) -> usize {
        self.lines.len()
    }

    fn push_empty(&mut self) {
        self.lines.push(Line {
            hdr: Entry { nbr: 0, slot: NIL },
            e: [BLANK; INLINE],
        });
    }

    fn boundary(&self, v: u32) -> bool {
        self.lines[v as usize].hdr.nbr & BOUNDARY != 0
    }

    fn get(&self, v: u32) -> &[Entry] {
        let l = &self.lines[v as usize];
        let h = l.hdr;
        let len = (h.nbr & !BOUNDARY) as usize;
        if h.slot == NIL {
            &l.e[..len]
        } else {
            &self.over[h.slot as usize..h.slot as usize + len]
        }
    }

    fn get_mut(&mut self, v: u32) -> &mut [Entry] {
        let l = &mut self.lines[v as usize];
        let h = l.hdr;
        let len = (h.nbr & !BOUNDARY) as usize;
        if h.slot == NIL {
            &mut l.e[..len]
        } else {
            &mut self.over[h.slot as usize..h.slot as usize + len]
        }
    }

    /// Sets `v`'s ring to `src` rotated to start at `start`.
    fn set(&mut self, v: u32, src: &[Entry], start: usize, boundary: bool) {
        let n = src.len();
        let h = self.lines[v as usize].hdr;
        let dst: &mut [Entry] = if n <= INLINE {
            &mut self.lines[v as usize].e[..n]
        } else {
            let fits = h.slot != NIL && self.over[h.slot as usize - 1].nbr as usize >= n;
            let off = if fits {
                h.slot as usize
            } else {
                let cap = (2 * n).max(16);
                self.over.push(Entry {
                    nbr: cap as u32,
                    slot: NIL,
                });
                let off = self.over.len();
                self.over.resize(off + cap, BLANK);
                off
            };
            self.lines[v as usize].hdr.slot = off as u32;
            &mut self.over[off..off + n]
        };
        // Rings are short: an element loop beats memmove calls here (and the chained
        // iterators leave no index to bounds-check).
        let (head, tail) = src.split_at(start.min(n));
        for (d, s) in dst.iter_mut().zip(tail.iter().chain(head)) {
            *d = *s;
        }
        let hdr = &mut self.lines[v as usize].hdr;
        if n <= INLINE {
            hdr.slot = NIL;
        }
        hdr.nbr = n as u32 | if boundary { BOUNDARY } else { 0 };
    }

    /// Points `v`'s entry to `from` at `to` instead; returns its position.
    #[inline]
    fn rename(&mut self, v: u32, from: u32, to: u32) -> Result<usize, SplitError> {
        let ring = self.get_mut(v);
        let k = ring
            .iter()
            .position(|x| x.nbr == from)
            .ok_or(SplitError::Inconsistent)?;
        ring[k].nbr = to;
        Ok(k)
    }

    /// Points the far ends of a split's fan at the new vertex `u` instead of `v`, except the
    /// first when it is the edge to the left wing (`has_left`), which stays with the wing's twin
    /// (`vertex_split` re-pairs it).
    #[inline(always)]
    fn redirect_fan(
        &mut self,
        fan: [&[Entry]; 2],
        has_left: bool,
        v: u32,
        u: u32,
    ) -> Result<(), SplitError> {
        for (k, e) in fan[0].iter().chain(fan[1]).enumerate() {
            if k != 0 || !has_left {
                self.rename(e.nbr, v, u)?;
            }
        }
        Ok(())
    }

    /// Inserts `e` at position `at` of `v`'s ring where it already lives (the inline line, or
    /// an overflow block with room); `false`, changing nothing, when the ring must move.
    /// A split inserts into both wings' rings; shifting a few entries in place costs a
    /// fraction of rebuilding the ring through [`Rings::set`].
    #[inline]
    fn insert_in_place(&mut self, v: u32, at: usize, e: Entry) -> bool {
        let h = self.lines[v as usize].hdr;
        let n = (h.nbr & !BOUNDARY) as usize;
        let ring: &mut [Entry] = if h.slot == NIL {
            if n + 1 > INLINE {
                return false;
            }
            &mut self.lines[v as usize].e[..n + 1]
        } else {
            let off = h.slot as usize;
            if (self.over[off - 1].nbr as usize) < n + 1 {
                return false;
            }
            &mut self.over[off..off + n + 1]
        };
        let mut k = n;
        while k > at {
            ring[k] = ring[k - 1];
            k -= 1;
        }
        ring[at] = e;
        self.lines[v as usize].hdr.nbr = h.nbr + 1;
        true
    }
}

/// The survivor's ring a split works on (see [`FlatReplay::list`]): a ring that lives in its
/// line is copied whole (one fixed-size copy, no `memmove` call), a longer one into `spill`.
#[derive(Clone, Debug)]
struct Listed {
    line: [Entry; INLINE],
    len: usize,
    inline: bool,
    spill: Vec<Entry>,
}

impl Listed {
    #[inline]
    fn as_slice(&self) -> &[Entry] {
        if self.inline {
            &self.line[..self.len]
        } else {
            &self.spill
        }
    }
}

/// Writes `seq[start..]` then `seq[..start]` (the first `len` entries of `seq`, rotated) into
/// the first `len` entries of `dst`, for `len <= INLINE`. The `start` entries that wrap are
/// first appended after `len` (usually none or a few), so the rotation is one fixed-size copy
/// of `INLINE` entries (moves, not a `memmove` call; entries past `len` are leftovers no
/// reader looks at).
#[inline(always)]
fn write_rotated(
    dst: &mut [Entry; INLINE],
    seq: &mut [Entry; 2 * INLINE + 2],
    len: usize,
    start: usize,
) {
    debug_assert!(len <= INLINE && start < len.max(1));
    for i in 0..start.min(INLINE) {
        seq[len + i] = seq[i];
    }
    dst[..INLINE].copy_from_slice(&seq[start..start + INLINE]);
}

/// Copies the run `parts[0]` then `parts[1]` (a cyclic run of a ring, in at most two pieces)
/// into `seq` from `at` on; returns the index after it.
#[inline(always)]
fn put_run(seq: &mut [Entry], at: usize, parts: [&[Entry]; 2]) -> usize {
    let mut k = at;
    for e in parts[0].iter().chain(parts[1]) {
        seq[k] = *e;
        k += 1;
    }
    k
}

fn invalid(reason: impl Into<String>) -> PmError {
    PmError::Internal(format!(
        "inconsistent progressive mesh data: {}",
        reason.into()
    ))
}

/// The base mesh and the splits applied so far, on flat arrays (vertex `i` is PM vertex `i`,
/// face `i` and half-edge slot numbers are the slots the slotmap mesh would give them).
#[derive(Clone, Debug)]
pub struct FlatReplay {
    rings: Rings,
    /// The stored half-edge of each face, in face slot order (fixed at the face's creation;
    /// [`Mesh::face_vertices`] starts at its origin). The faces' vertices are read off the
    /// rings when asked for, so a split does not touch the faces of its fan.
    face_he: Vec<u32>,
    n_base_faces: usize,
    n_halfedges: u32,
    /// The ring last listed (the entries a split works on), and whose it is; `ring_v` holds
    /// its neighbours for [`Self::ring`].
    ring: Listed,
    ring_of: u32,
    ring_v: Vec<u32>,
    scratch: Vec<Entry>,
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
        let hint = splits_hint.min(1 << 26);
        let mut face_he = vec![NIL; mesh.n_faces()];
        for f in mesh.faces() {
            face_he[f.slot()] = mesh.face_halfedges(f)[0].slot() as u32;
        }
        face_he.reserve(hint * 2);
        let mut rings = Rings {
            lines: Vec::with_capacity(base_positions.len() + hint),
            over: Vec::new(),
        };
        let mut ring = Vec::new();
        for (i, v) in mesh.vertices().enumerate() {
            let mut boundary = false;
            ring.clear();
            for (k, h) in mesh.outgoing(v).enumerate() {
                let face = mesh.face(h).is_some();
                if k == 0 {
                    boundary = !face;
                } else if !face {
                    return Err(invalid("base vertex with two boundary out-edges"));
                }
                ring.push(Entry {
                    nbr: mesh.to_vertex(h).slot() as u32,
                    slot: h.slot() as u32,
                });
            }
            rings.push_empty();
            rings.set(i as u32, &ring, 0, boundary);
        }
        let replay = FlatReplay {
            rings,
            face_he,
            n_base_faces: mesh.n_faces(),
            n_halfedges: n_he as u32,
            ring_v: Vec::new(),
            ring: Listed {
                line: [BLANK; INLINE],
                len: 0,
                inline: true,
                spill: Vec::new(),
            },
            ring_of: NIL,
            scratch: Vec::new(),
        };
        // The rings are built from the stored half-edges; the split rules need them canonical
        // (the builder promises it), so check.
        for v in 0..replay.rings.len() as u32 {
            let e = replay.rings.get(v);
            let ok = replay.rings.boundary(v)
                || e.first().is_none_or(|x| e.iter().all(|y| y.slot >= x.slot));
            if !ok {
                return Err(invalid("base mesh is not in canonical form"));
            }
        }
        Ok(replay)
    }

    /// Number of vertices so far.
    pub fn level(&self) -> usize {
        self.rings.len()
    }

    /// Number of faces of the base mesh.
    pub fn n_base_faces(&self) -> usize {
        self.n_base_faces
    }

    /// Number of faces so far.
    pub fn n_faces(&self) -> usize {
        self.face_he.len()
    }

    /// The PM indices around `v` in `Mesh::outgoing` order (counter-clockwise from the
    /// canonical half-edge; a boundary vertex starts at its boundary out-edge) — the ring the
    /// `.pyr` format indexes wings into.
    pub fn ring(&mut self, v: u32) -> Result<&[u32], PmError> {
        self.list(v)?;
        self.ring_v.clear();
        self.ring_v
            .extend(self.ring.as_slice().iter().map(|x| x.nbr));
        Ok(&self.ring_v)
    }

    /// `v`'s ring as `(neighbour, out-going half-edge slot)` entries in [`Mesh::outgoing`]
    /// order, and whether entry 0 is a boundary out-edge (no face on its left; the face left
    /// of entry `k` is `v`, entry `k`, entry `k + 1`, cyclically). Empty for a vertex that does
    /// not exist yet.
    #[inline]
    pub(crate) fn ring_entries(&self, v: u32) -> (&[Entry], bool) {
        if v as usize >= self.rings.len() {
            return (&[], false);
        }
        (self.rings.get(v), self.rings.boundary(v))
    }

    /// The length of `v`'s ring (its valence), listing the ring for a following
    /// `Self::apply_indexed` at `v`.
    pub fn valence(&mut self, v: u32) -> Result<usize, PmError> {
        self.list(v)
    }

    /// Copies `v`'s ring entries into `self.ring` (the survivor's ring a split works on).
    fn list(&mut self, v: u32) -> Result<usize, PmError> {
        if v as usize >= self.rings.len() {
            return Err(invalid(format!("survivor {v} does not exist yet")));
        }
        let line = &self.rings.lines[v as usize];
        let h = line.hdr;
        if h.slot == NIL {
            self.ring.line = line.e;
            self.ring.len = (h.nbr & !BOUNDARY) as usize;
            self.ring.inline = true;
        } else {
            self.ring.spill.clear();
            self.ring.spill.extend_from_slice(self.rings.get(v));
            self.ring.len = self.ring.spill.len();
            self.ring.inline = false;
        }
        self.ring_of = v;
        Ok(self.ring.len)
    }

    /// Cache hint for a split at `survivor` that comes `ahead` splits later: at a long
    /// distance (`ahead >= 16`) the survivor's ring line, at a shorter one the lines of its
    /// neighbours, which a split rewrites (read off the survivor's line, which the long hint
    /// fetched). A split touches five to eight rings scattered over the arrays, so replay is
    /// bound by cache misses; hinting them early overlaps the misses of consecutive splits.
    /// Only a hint: a stale or out-of-range `survivor` is harmless.
    pub(crate) fn prefetch(&self, survivor: u32, ahead: usize) {
        let lines = &self.rings.lines;
        if survivor as usize >= lines.len() {
            return;
        }
        if ahead >= 16 {
            // Both halves: a survivor's ring is longer than the first line's seven entries.
            let line = lines.as_ptr().wrapping_add(survivor as usize);
            prefetch(line);
            prefetch((line as *const u8).wrapping_add(64));
        } else {
            for e in self.rings.get(survivor) {
                prefetch(lines.as_ptr().wrapping_add(e.nbr as usize));
            }
        }
    }

    /// The hints a walk over the splits gives at split `k`: [`Self::prefetch`] for the splits
    /// 16 and 8 places ahead, whose survivors `survivor(j)` gives (`None` past the end). The
    /// encoder, the decoder and the pyramid's recording walk all replay this way.
    #[inline]
    pub(crate) fn prefetch_upcoming(&self, k: usize, survivor: impl Fn(usize) -> Option<u32>) {
        for ahead in [16, 8] {
            if let Some(s) = survivor(k + ahead) {
                self.prefetch(s, ahead);
            }
        }
    }

    /// Cache hint for reading the neighbourhood of `survivor` a few splits ahead: the first
    /// ring line and the position in `positions` of every vertex within two edges of it (read
    /// off the neighbours' lines, which [`Self::prefetch`] fetched earlier). Stencils on the
    /// rings read exactly these, scattered over the arrays. Only a hint, like
    /// [`Self::prefetch`].
    pub(crate) fn prefetch_neighbourhood<T>(&self, survivor: u32, positions: &[T]) {
        let lines = &self.rings.lines;
        if survivor as usize >= lines.len() {
            return;
        }
        for e in self.rings.get(survivor) {
            for f in self.rings.get(e.nbr) {
                prefetch(lines.as_ptr().wrapping_add(f.nbr as usize));
                prefetch(positions.as_ptr().wrapping_add(f.nbr as usize));
            }
        }
    }

    /// The valence of the vertex [`Self::ring`], [`Self::valence`] or [`Self::wing_indices`]
    /// listed last.
    pub(crate) fn listed_valence(&self) -> usize {
        self.ring.len
    }

    /// Applies `s` (which must create vertex `level()`), finding its wings in the survivor's
    /// ring. Equivalent to [`SplitReplay::apply`](super::SplitReplay::apply).
    pub(crate) fn apply(&mut self, s: &VertexSplit) -> Result<(), PmError> {
        let (il, ir) = self.wing_indices(s)?;
        self.apply_indexed(s.vertex, s.survivor, il, ir)?;
        Ok(())
    }

    /// The positions of `s`'s wings in its survivor's ring (listing the ring), for coding the
    /// split; [`Self::apply_indexed`] with the same indices then applies it.
    pub(crate) fn wing_indices(
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
        self.list(s.survivor)?;
        let ring = self.ring.as_slice();
        let find = |w: Option<u32>| match w {
            None => Ok(None),
            Some(x) => ring
                .iter()
                .position(|r| r.nbr == x)
                .map(Some)
                .ok_or_else(|| {
                    invalid(format!(
                        "split creating vertex {level}: {}",
                        SplitError::Inconsistent
                    ))
                }),
        };
        Ok((find(s.left)?, find(s.right)?))
    }

    /// Applies the split creating vertex `vertex` (which must be `level()`) at `survivor`, with
    /// wings given as indices into the survivor's ring. Returns the record.
    pub(crate) fn apply_indexed(
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
            self.list(survivor)?;
        }
        let ring = self.ring.as_slice();
        let n = ring.len();
        if il.is_some_and(|i| i >= n) || ir.is_some_and(|i| i >= n) {
            return Err(invalid(format!(
                "split creating vertex {level}: {}",
                SplitError::Inconsistent
            )));
        }
        let split = VertexSplit {
            vertex,
            survivor,
            left: il.map(|i| ring[i].nbr),
            right: ir.map(|i| ring[i].nbr),
        };
        let result = self.split(il, ir);
        self.ring_of = NIL;
        result.map_err(|e| invalid(format!("split creating vertex {level}: {e}")))?;
        Ok(split)
    }

    /// Inserts `e` in `v`'s ring just before (counter-clockwise of) its entry at `k`, leaving
    /// entry 0 (the canonical half-edge) in place: before entry 0 is the end of the list.
    #[inline]
    fn insert_before(&mut self, v: u32, k: usize, e: Entry) {
        let n = self.rings.get(v).len();
        let at = if k == 0 { n } else { k };
        if !self.rings.insert_in_place(v, at, e) {
            self.insert_moving(v, at, e);
        }
    }

    /// [`Self::insert_before`] for a ring that outgrows its storage: rebuilt elsewhere.
    #[cold]
    fn insert_moving(&mut self, v: u32, at: usize, e: Entry) {
        let ring = self.rings.get(v);
        let mut tmp = std::mem::take(&mut self.scratch);
        tmp.clear();
        tmp.extend_from_slice(&ring[..at]);
        tmp.push(e);
        tmp.extend_from_slice(&ring[at..]);
        let boundary = self.rings.boundary(v);
        self.rings.set(v, &tmp, 0, boundary);
        self.scratch = tmp;
    }

    /// `vertex_split` on the listed ring of the survivor `v`: same checks, same resulting
    /// rings, faces and slots. The fan (the ring entries that move to the new vertex) runs
    /// from the left wing (or the entry after the boundary out-edge) counter-clockwise to the
    /// right wing (exclusive; or through the boundary out-edge).
    fn split(&mut self, il: Option<usize>, ir: Option<usize>) -> Result<(), SplitError> {
        let v = self.ring_of;
        let ring = self.ring.as_slice();
        let v_boundary = self.rings.boundary(v);
        let (left, right) = check_wings(ring, v, il, ir, v_boundary)?;
        let start = il.unwrap_or(1 % ring.len());
        let m = fan_length(ring.len(), start, ir, v_boundary)?;
        let (fan, rest) = cut_fan(ring, start, m);
        let u = self.rings.len() as u32;
        let slots = SplitSlots::allocate(
            &mut self.n_halfedges,
            &mut self.face_he,
            left.is_some(),
            right.is_some(),
        );
        self.rings.redirect_fan(fan, il.is_some(), v, u)?;
        let new_rings = NewRings {
            v,
            u,
            left,
            right,
            v_boundary,
            old_first: ring[0].slot,
            fan,
            m,
            rest,
            len_u: m + 1 + usize::from(right.is_some()),
            len_v: ring.len() - m + 1 + usize::from(left.is_some()),
            slots,
        };
        if self.ring.inline && new_rings.len_u <= INLINE && new_rings.len_v <= INLINE {
            // The common case (every ring at most 15 long): both rings built on the stack and
            // written into their lines whole, with no scratch vector and no `memmove`.
            let mut seq = [BLANK; 2 * INLINE + 2];
            new_rings.push_u_line(&mut self.rings, &mut seq);
            new_rings.rewrite_v_line(&mut self.rings, &mut seq)?;
        } else {
            new_rings.push_u_ring(&mut self.rings, &mut self.scratch);
            new_rings.set_v_ring(&mut self.rings, &mut self.scratch)?;
        }
        self.link_wings(v, u, left, right, slots)
    }

    /// The wings gain an edge to u just before their edge to v; their canonical half-edge
    /// (old, or boundary) stays entry 0.
    #[inline(always)]
    fn link_wings(
        &mut self,
        v: u32,
        u: u32,
        left: Option<u32>,
        right: Option<u32>,
        slots: SplitSlots,
    ) -> Result<(), SplitError> {
        if let Some(l) = left {
            let k = self
                .rings
                .get(l)
                .iter()
                .position(|x| x.nbr == v)
                .ok_or(SplitError::Inconsistent)?;
            self.insert_before(
                l,
                k,
                Entry {
                    nbr: u,
                    slot: slots.h2,
                },
            );
        }
        if let Some(r) = right {
            // v_r's old edge to v now runs to u; the new o2 = v_r→v goes before it.
            let k = self.rings.rename(r, v, u)?;
            self.insert_before(
                r,
                k,
                Entry {
                    nbr: v,
                    slot: slots.o2,
                },
            );
        }
        Ok(())
    }

    /// The current triangles in face slot order, each starting where
    /// [`Mesh::face_vertices`] starts (what [`Mesh::to_triangles`] gives for the replayed mesh).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let mut face_of = vec![NIL; self.n_halfedges as usize];
        for (f, &h) in self.face_he.iter().enumerate() {
            face_of[h as usize] = f as u32;
        }
        let mut out = vec![[NIL; 3]; self.face_he.len()];
        for v in 0..self.rings.len() {
            let e = self.rings.get(v as u32);
            for (k, x) in e.iter().enumerate() {
                // The face left of v→nbr is (v, nbr, next neighbour counter-clockwise), listed
                // from its stored half-edge.
                let f = face_of[x.slot as usize];
                if f != NIL {
                    let next = if k + 1 == e.len() { 0 } else { k + 1 };
                    out[f as usize] = [v as u32, x.nbr, e[next].nbr];
                }
            }
        }
        out
    }

    /// The current triangles in PM indices, canonically rotated (smallest index first) and
    /// sorted.
    pub(crate) fn canonical_faces(&self) -> Vec<[u32; 3]> {
        canonical_sorted(&self.triangles(), self.level())
    }

    /// Whether the current triangles are exactly `expected`'s, as a multiset of canonically
    /// rotated triangles — [`Self::canonical_faces`]` == canonical_sorted(…)` without sorting
    /// or listing the faces: walking the rings in vertex order meets every face once at its
    /// smallest corner, already rotated, so vertex `v`'s faces are compared with bucket `v`
    /// (both a handful) while both arrays are read front to back.
    ///
    /// Large meshes are checked in two halves on two threads (the check is the longest step
    /// of a load left after the replay).
    pub(crate) fn has_faces(&self, expected: &FaceBuckets) -> bool {
        let n = self.rings.len() as u32;
        let seen = if n >= 1 << 14 {
            let mid = n / 2;
            match rayon::join(
                || self.faces_match(expected, 0..mid),
                || self.faces_match(expected, mid..n),
            ) {
                (Some(a), Some(b)) => Some(a + b),
                _ => None,
            }
        } else {
            self.faces_match(expected, 0..n)
        };
        seen == Some(expected.faces.len())
    }

    /// Whether the current mesh has the face `f`, oriented as listed (from any corner).
    pub(crate) fn has_face(&self, f: [u32; 3]) -> bool {
        let [v, a, b] = f;
        if v as usize >= self.rings.len() {
            return false;
        }
        let e = self.rings.get(v);
        let skip_first = self.rings.boundary(v);
        // The face left of v → x is (v, x, next neighbour); none left of a boundary out-edge.
        e.iter().enumerate().any(|(k, x)| {
            let next = e[if k + 1 == e.len() { 0 } else { k + 1 }].nbr;
            x.nbr == a && next == b && !(k == 0 && skip_first)
        })
    }

    /// [`Self::has_faces`] on the faces whose smallest corner is in `vertices`: how many
    /// there are, or `None` when they differ from `expected`'s buckets.
    fn faces_match(&self, expected: &FaceBuckets, vertices: std::ops::Range<u32>) -> Option<usize> {
        let mut seen = 0usize;
        // Which faces of the bucket are claimed: bits, or flags for a bucket of over 64.
        let mut claimed_big: Vec<bool> = Vec::new();
        for v in vertices {
            let e = self.rings.get(v);
            let theirs = match expected.starts.get(v as usize..v as usize + 2) {
                Some(w) => &expected.faces[w[0] as usize..w[1] as usize],
                None => &[][..],
            };
            let big = theirs.len() > 64;
            if big {
                claimed_big.clear();
                claimed_big.resize(theirs.len(), false);
            }
            let mut claimed = 0u64;
            let mut mine = 0;
            let skip_first = self.rings.boundary(v);
            for (k, x) in e.iter().enumerate() {
                // The face left of v → x (none left of a boundary out-edge, entry 0), counted
                // at its smallest corner.
                let next = e[if k + 1 == e.len() { 0 } else { k + 1 }].nbr;
                if (k == 0 && skip_first) || v > x.nbr || v > next {
                    continue;
                }
                mine += 1;
                let f = [v, x.nbr, next];
                let free = |i: usize| {
                    if big {
                        !claimed_big[i]
                    } else {
                        claimed & 1 << i == 0
                    }
                };
                match (0..theirs.len()).find(|&i| free(i) && theirs[i] == f) {
                    Some(i) if big => claimed_big[i] = true,
                    Some(i) => claimed |= 1 << i,
                    None => return None,
                }
            }
            if mine != theirs.len() {
                return None;
            }
            seen += mine;
        }
        Some(seen)
    }
}

/// Triangles canonically rotated (smallest index first) and bucketed by that index: a
/// counting sort, without ordering the faces within a bucket (about two faces per vertex).
#[derive(Clone, Debug)]
pub(crate) struct FaceBuckets {
    /// Bucket `k` is `faces[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
    faces: Vec<[u32; 3]>,
}

impl FaceBuckets {
    /// Buckets `faces` on vertices `0..n_vertices` (a face with a larger index goes to the last
    /// bucket, so any input is accepted).
    pub(crate) fn new(faces: &[[u32; 3]], n_vertices: usize) -> FaceBuckets {
        let n = n_vertices.max(1);
        let mut starts = vec![0u32; n + 1];
        let mut out = vec![[0u32; 3]; faces.len()];
        for t in faces {
            starts[bucket(t, n) + 1] += 1;
        }
        for i in 0..n {
            starts[i + 1] += starts[i];
        }
        let mut fill = starts.clone();
        for t in faces {
            let k = bucket(t, n);
            out[fill[k] as usize] = canonical(*t);
            fill[k] += 1;
        }
        FaceBuckets { starts, faces: out }
    }

    /// The faces, canonically rotated, sorted.
    pub(crate) fn into_sorted(mut self) -> Vec<[u32; 3]> {
        for w in self.starts.windows(2) {
            let b = &mut self.faces[w[0] as usize..w[1] as usize];
            if b.len() > 1 {
                b.sort_unstable();
            }
        }
        self.faces
    }
}

/// The bucket of `t` among `n` (its smallest index, clamped).
#[inline]
fn bucket(t: &[u32; 3], n: usize) -> usize {
    (t[0].min(t[1]).min(t[2]) as usize).min(n - 1)
}

/// `faces` canonically rotated (smallest index first) and sorted, for faces on vertices
/// `0..n_vertices`: a counting sort by first index, then a sort of each bucket (about two faces
/// per vertex), which is several times faster than a comparison sort of a million faces.
pub(crate) fn canonical_sorted(faces: &[[u32; 3]], n_vertices: usize) -> Vec<[u32; 3]> {
    FaceBuckets::new(faces, n_vertices).into_sorted()
}

/// The wings' vertices (from their indices in `v`'s listed ring), checked as `vertex_split`
/// checks them: at least one wing, two different wings, neither is `v`, and a missing wing
/// only at a boundary vertex.
#[inline(always)]
fn check_wings(
    ring: &[Entry],
    v: u32,
    il: Option<usize>,
    ir: Option<usize>,
    v_boundary: bool,
) -> Result<(Option<u32>, Option<u32>), SplitError> {
    if ring.is_empty() {
        return Err(SplitError::Inconsistent);
    }
    let left = il.map(|i| ring[i].nbr);
    let right = ir.map(|i| ring[i].nbr);
    if (left.is_none() && right.is_none())
        || (left.is_some() && left == right)
        || left == Some(v)
        || right == Some(v)
    {
        return Err(SplitError::Inconsistent);
    }
    if (left.is_none() || right.is_none()) && !v_boundary {
        return Err(SplitError::Inconsistent);
    }
    Ok((left, right))
}

/// The number of entries of an `n`-entry ring that move to the new vertex, counted from
/// `start`: up to the right wing's entry `ir` (exclusive), or through the boundary out-edge.
/// Only entry 0 of a boundary vertex is a boundary half-edge.
#[inline(always)]
fn fan_length(
    n: usize,
    start: usize,
    ir: Option<usize>,
    v_boundary: bool,
) -> Result<usize, SplitError> {
    let is_boundary = |k: usize| v_boundary && k == 0;
    let mut m = 0;
    let mut e = start;
    match ir {
        Some(ir) => {
            while e != ir {
                if m > n || is_boundary(e) {
                    return Err(SplitError::Inconsistent);
                }
                m += 1;
                e = if e + 1 == n { 0 } else { e + 1 };
            }
        }
        None => loop {
            if m > n {
                return Err(SplitError::Inconsistent);
            }
            m += 1;
            if is_boundary(e) {
                break;
            }
            e = if e + 1 == n { 0 } else { e + 1 };
        },
    }
    Ok(m)
}

/// The ring read from `start` on, cut into the fan (its first `m` entries) and the rest, which
/// `v` keeps; each as at most two slices. Slices rather than an index with a wrap per entry
/// (which cost more than the rest of a split's arithmetic).
#[inline(always)]
fn cut_fan(ring: &[Entry], start: usize, m: usize) -> (Run<'_>, Run<'_>) {
    let n = ring.len();
    if start + m <= n {
        (
            [&ring[start..start + m], &[][..]],
            [&ring[start + m..], &ring[..start]],
        )
    } else {
        let wrap = start + m - n;
        (
            [&ring[start..], &ring[..wrap]],
            [&ring[wrap..start], &[][..]],
        )
    }
}

/// A cyclic run of a ring, in at most two pieces.
type Run<'a> = [&'a [Entry]; 2];

/// The half-edge slots a split creates, in `vertex_split`'s insertion order (`NIL` for the
/// pair of a missing wing).
#[derive(Clone, Copy)]
struct SplitSlots {
    o: u32,
    h: u32,
    o2: u32,
    o1: u32,
    h2: u32,
    h1: u32,
}

impl SplitSlots {
    /// Takes the next slots and records the new faces' stored half-edges (`fr` then `fl`).
    #[inline(always)]
    fn allocate(
        n_halfedges: &mut u32,
        face_he: &mut Vec<u32>,
        has_left: bool,
        has_right: bool,
    ) -> SplitSlots {
        let base = *n_halfedges;
        let (o, h) = (base, base + 1);
        let mut next = base + 2;
        let (o2, o1) = if has_right {
            next += 2;
            (next - 2, next - 1)
        } else {
            (NIL, NIL)
        };
        let (h2, h1) = if has_left {
            next += 2;
            (next - 2, next - 1)
        } else {
            (NIL, NIL)
        };
        *n_halfedges = next;
        if has_right {
            face_he.push(o);
        }
        if has_left {
            face_he.push(h);
        }
        SplitSlots {
            o,
            h,
            o2,
            o1,
            h2,
            h1,
        }
    }
}

/// The two rings a split writes. u: (u→v) then the fan then (u→v_r); canonical: h without a
/// left face, the old boundary out-edge (the fan's last) without a right face, else the
/// smallest slot. v: what is left of its ring from the fan's end round to its start, then
/// (v→v_l), then (v→u); canonical: o without a right face, the unchanged boundary out-edge of
/// a boundary v, else the smallest slot.
struct NewRings<'a> {
    v: u32,
    u: u32,
    left: Option<u32>,
    right: Option<u32>,
    v_boundary: bool,
    /// The slot of `v`'s canonical half-edge before the split.
    old_first: u32,
    fan: Run<'a>,
    /// The fan's length.
    m: usize,
    rest: Run<'a>,
    len_u: usize,
    len_v: usize,
    slots: SplitSlots,
}

impl NewRings<'_> {
    /// Where u's ring starts, and whether it starts at a boundary out-edge.
    #[inline(always)]
    fn u_start(&self, ring_u: &[Entry]) -> (usize, bool) {
        match (self.left, self.right) {
            (None, _) => (0, true),
            (_, None) => (self.m, true),
            _ => (min_slot(ring_u), false),
        }
    }

    /// Where v's new ring starts.
    #[inline(always)]
    fn v_start(&self, ring_v: &[Entry]) -> Result<usize, SplitError> {
        Ok(if self.right.is_none() {
            self.len_v - 1
        } else if self.v_boundary {
            ring_v
                .iter()
                .position(|x| x.slot == self.old_first)
                .ok_or(SplitError::Inconsistent)?
        } else {
            min_slot(ring_v)
        })
    }

    /// Builds u's ring in `seq` and pushes it as a new line.
    #[inline(always)]
    fn push_u_line(&self, rings: &mut Rings, seq: &mut [Entry; 2 * INLINE + 2]) {
        seq[0] = Entry {
            nbr: self.v,
            slot: self.slots.h,
        };
        let k = put_run(seq, 1, self.fan);
        if let Some(r) = self.right {
            seq[k] = Entry {
                nbr: r,
                slot: self.slots.o1,
            };
        }
        let (u_start, u_boundary) = self.u_start(&seq[..self.len_u]);
        let mut line = Line {
            hdr: Entry {
                nbr: self.len_u as u32 | if u_boundary { BOUNDARY } else { 0 },
                slot: NIL,
            },
            e: [BLANK; INLINE],
        };
        write_rotated(&mut line.e, seq, self.len_u, u_start);
        rings.lines.push(line);
    }

    /// Builds v's new ring in `seq` and writes it over v's line.
    #[inline(always)]
    fn rewrite_v_line(
        &self,
        rings: &mut Rings,
        seq: &mut [Entry; 2 * INLINE + 2],
    ) -> Result<(), SplitError> {
        let mut k = put_run(seq, 0, self.rest);
        if let Some(l) = self.left {
            seq[k] = Entry {
                nbr: l,
                slot: self.slots.h1,
            };
            k += 1;
        }
        seq[k] = Entry {
            nbr: self.u,
            slot: self.slots.o,
        };
        let v_start = self.v_start(&seq[..self.len_v])?;
        let line = &mut rings.lines[self.v as usize];
        write_rotated(&mut line.e, seq, self.len_v, v_start);
        line.hdr.nbr = self.len_v as u32 | if self.v_boundary { BOUNDARY } else { 0 };
        Ok(())
    }

    /// [`Self::push_u_line`] for rings that may not fit a line: built in `scratch`.
    #[inline(always)]
    fn push_u_ring(&self, rings: &mut Rings, scratch: &mut Vec<Entry>) {
        scratch.clear();
        scratch.push(Entry {
            nbr: self.v,
            slot: self.slots.h,
        });
        scratch.extend_from_slice(self.fan[0]);
        scratch.extend_from_slice(self.fan[1]);
        if let Some(r) = self.right {
            scratch.push(Entry {
                nbr: r,
                slot: self.slots.o1,
            });
        }
        let (u_start, u_boundary) = self.u_start(scratch);
        rings.push_empty();
        rings.set(self.u, scratch, u_start, u_boundary);
    }

    /// [`Self::rewrite_v_line`] for rings that may not fit a line: built in `scratch`.
    #[inline(always)]
    fn set_v_ring(&self, rings: &mut Rings, scratch: &mut Vec<Entry>) -> Result<(), SplitError> {
        scratch.clear();
        scratch.extend_from_slice(self.rest[0]);
        scratch.extend_from_slice(self.rest[1]);
        if let Some(l) = self.left {
            scratch.push(Entry {
                nbr: l,
                slot: self.slots.h1,
            });
        }
        scratch.push(Entry {
            nbr: self.u,
            slot: self.slots.o,
        });
        let v_start = self.v_start(scratch)?;
        rings.set(self.v, scratch, v_start, self.v_boundary);
        Ok(())
    }
}

/// Index of the entry with the smallest half-edge slot.
fn min_slot(e: &[Entry]) -> usize {
    let Some(first) = e.first() else { return 0 };
    let (mut best, mut smallest) = (0, first.slot);
    for (k, x) in e.iter().enumerate().skip(1) {
        if x.slot < smallest {
            (best, smallest) = (k, x.slot);
        }
    }
    best
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
            for x in [Some(s.vertex), Some(s.survivor), s.left, s.right]
                .into_iter()
                .flatten()
            {
                slow.ring(x, &mut ring).unwrap();
                assert_eq!(fast.ring(x).unwrap(), &ring[..], "split {i} vertex {x}");
            }
        }
        assert_eq!(fast.triangles(), slow.mesh().to_triangles().1);
        assert_eq!(fast.canonical_faces(), slow.canonical_faces());
        // The streaming face check agrees, and notices a flipped, a missing or an extra face.
        let faces = slow.mesh().to_triangles().1;
        let n = fast.level();
        assert!(fast.has_faces(&FaceBuckets::new(&faces, n)));
        let mut flipped = faces.clone();
        flipped[faces.len() / 2].swap(1, 2);
        assert!(!fast.has_faces(&FaceBuckets::new(&flipped, n)));
        assert!(!fast.has_faces(&FaceBuckets::new(&faces[1..], n)));
        let mut extra = faces.clone();
        extra.push(faces[0]);
        assert!(!fast.has_faces(&FaceBuckets::new(&extra, n)));
        let mut renamed = faces.clone();
        renamed[0] = [renamed[0][0], renamed[0][1], (renamed[0][2] + 1) % n as u32];
        assert_eq!(
            fast.has_faces(&FaceBuckets::new(&renamed, n)),
            canonical_sorted(&renamed, n) == fast.canonical_faces()
        );
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
        // A double cone: two vertices of valence 24, rings longer than a cache line holds.
        let k = 24u32;
        let mut p = vec![DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -1.0)];
        let mut t = Vec::new();
        for i in 0..k {
            let a = i as f64 * std::f64::consts::TAU / k as f64;
            p.push(DVec3::new(a.cos(), a.sin(), 0.1 * (i % 3) as f64));
            let (x, y) = (2 + i, 2 + (i + 1) % k);
            t.push([0, x, y]);
            t.push([1, y, x]);
        }
        same_as_slotmap(&Mesh::from_triangles(&p, &t).unwrap().mesh);
    }

    #[test]
    fn face_check_handles_a_vertex_with_more_than_64_faces() {
        // A disk of 70 triangles around vertex 0: its bucket is over the 64 bits of the fast
        // claim mask.
        let k = 70u32;
        let mut p = vec![DVec3::ZERO];
        let mut t = Vec::new();
        for i in 0..k {
            let a = i as f64 * std::f64::consts::TAU / k as f64;
            p.push(DVec3::new(a.cos(), a.sin(), 0.0));
            t.push([0, 1 + i, 1 + (i + 1) % k]);
        }
        let r = FlatReplay::new(&p, &t, 0).unwrap();
        let n = p.len();
        assert!(r.has_faces(&FaceBuckets::new(&t, n)));
        let mut twice = t.clone();
        twice[69] = twice[3];
        assert!(!r.has_faces(&FaceBuckets::new(&twice, n)));
        let mut flipped = t.clone();
        flipped[65].swap(1, 2);
        assert!(!r.has_faces(&FaceBuckets::new(&flipped, n)));
    }

    #[test]
    fn face_check_in_two_halves_sees_every_face() {
        // Over 2^14 vertices: the check runs on two threads, each half of the vertex range
        // owning the faces whose smallest corner it holds.
        let (p, t) = crate::mesh::shapes::grid(140, |i, j| DVec3::new(i as f64, j as f64, 0.0));
        let n = p.len();
        assert!(n >= 1 << 14);
        let r = FlatReplay::new(&p, &t, 0).unwrap();
        assert!(r.has_faces(&FaceBuckets::new(&t, n)));
        // A face moved from one half's vertices to the other's, a face missing from each half,
        // and a duplicated face are all noticed.
        let mid = (n / 2) as u32;
        let lo = t.iter().position(|f| f.iter().all(|&x| x < mid)).unwrap();
        let hi = t.iter().position(|f| f.iter().all(|&x| x >= mid)).unwrap();
        let mut moved = t.clone();
        moved[lo] = t[hi];
        assert!(!r.has_faces(&FaceBuckets::new(&moved, n)));
        for k in [lo, hi] {
            let mut missing = t.clone();
            missing.remove(k);
            assert!(!r.has_faces(&FaceBuckets::new(&missing, n)));
        }
        let mut twice = t.clone();
        twice.push(t[hi]);
        assert!(!r.has_faces(&FaceBuckets::new(&twice, n)));
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
