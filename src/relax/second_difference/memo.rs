//! The memos that let one batch of stencils (the 1-ring of a split) compute each edge flap
//! once: a small direct-mapped table keyed by edge, on the half-edge mesh ([`FlapCache`]) and
//! on the rings of the flat replay ([`RingFlapCache`], one per thread, kept between batches).

use super::{SecondDifference, Steering};
use crate::mesh::{HalfedgeId, Mesh, SlotIndex, VertexId};
use crate::pm::FlatReplay;
use glam::DVec3;

/// A small direct-mapped memo of edge flaps for one batch of stencils (an edge enters the
/// stencils of up to four vertices of a 1-ring). Keys are whole (a slot, a vertex pair), so
/// a collision just recomputes. [`Self::clear`] starts a new batch by bumping a generation
/// rather than rewriting the 7 KB of entries.
pub(super) struct BatchMemo<K, V> {
    tags: [K; BATCH_MEMO_SIZE],
    /// The batch each entry was computed in; entries of older batches are empty.
    generations: [u32; BATCH_MEMO_SIZE],
    generation: u32,
    values: [Option<V>; BATCH_MEMO_SIZE],
}

const BATCH_MEMO_SIZE: usize = 128;

impl<K: Copy + PartialEq, V: Copy> BatchMemo<K, V> {
    /// An empty memo (every entry is of generation 0, which no batch has, so the initial
    /// tag `unused` can be any key).
    pub(super) fn new(unused: K) -> Self {
        Self {
            tags: [unused; BATCH_MEMO_SIZE],
            generations: [0; BATCH_MEMO_SIZE],
            generation: 1,
            values: [None; BATCH_MEMO_SIZE],
        }
    }

    /// Empties the memo for a new batch.
    pub(super) fn clear(&mut self) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.generations = [0; BATCH_MEMO_SIZE];
            self.generation = 1;
        }
    }

    /// The value of `key` (whose hash is `hash`), computed by `compute` unless the memo holds
    /// it.
    #[inline]
    fn get(&mut self, key: K, hash: u64, compute: impl FnOnce() -> Option<V>) -> Option<&V> {
        // Fibonacci hashing: neighbouring keys spread over the table.
        let at = (hash.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            >> (64 - BATCH_MEMO_SIZE.trailing_zeros())) as usize;
        if self.tags[at] != key || self.generations[at] != self.generation {
            self.tags[at] = key;
            self.generations[at] = self.generation;
            self.values[at] = compute();
        }
        self.values[at].as_ref()
    }
}

/// Flaps on the half-edge mesh, keyed by the slot of the edge's canonical half-edge.
pub(super) type FlapCache = BatchMemo<u32, ([VertexId; 4], [f64; 4])>;

impl FlapCache {
    /// The flap of `h`, from the memo when its edge was seen in this batch.
    #[inline]
    pub(super) fn flap(
        &mut self,
        op: &SecondDifference,
        mesh: &Mesh,
        geometry: &[DVec3],
        h: HalfedgeId,
        steering: Option<&Steering>,
    ) -> Option<([VertexId; 4], [f64; 4])> {
        let (canonical, flipped) = canonical_halfedge(mesh, h);
        let key = canonical.slot() as u32;
        let flap = self.get(key, key.into(), || {
            op.canonical_flap(mesh, geometry, canonical, steering)
        })?;
        Some(orient_flap(*flap, flipped))
    }
}

/// The half-edge of `h`'s edge with the smaller slot, and whether it runs against `h`.
#[inline]
pub(super) fn canonical_halfedge(mesh: &Mesh, h: HalfedgeId) -> (HalfedgeId, bool) {
    let t = mesh.twin(h);
    if t.slot() < h.slot() {
        (t, true)
    } else {
        (h, false)
    }
}

/// A flap computed along the canonical half-edge, seen from its twin when `flipped`: `j1, j2`
/// and `l1, l2` swap, with their coefficients.
#[inline]
pub(super) fn orient_flap(
    (v, c): ([VertexId; 4], [f64; 4]),
    flipped: bool,
) -> ([VertexId; 4], [f64; 4]) {
    if flipped {
        ([v[1], v[0], v[3], v[2]], [c[1], c[0], c[3], c[2]])
    } else {
        (v, c)
    }
}

/// A flap on rings along its canonical half-edge: `[j1, j2, l1, l2]` and their coefficients.
/// Seen from the other half-edge, `j1, j2` and `l1, l2` swap: position `p` there is position
/// `p ^ 1` here.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RingFlap {
    pub(super) v: [u32; 4],
    pub(super) c: [f64; 4],
}

/// Flaps on rings, keyed by the edge's two vertices.
pub(super) type RingFlapCache = BatchMemo<u64, RingFlap>;

thread_local! {
    /// Each thread's flap memo for [`RingStencils::ring_stencils`], kept between batches (one
    /// per split in the analysis) so that starting a batch costs a generation bump, not a
    /// fresh 7 KB memo.
    pub(super) static RING_FLAPS: std::cell::RefCell<RingFlapCache> =
        std::cell::RefCell::new(RingFlapCache::new(u64::MAX));
}

impl RingFlapCache {
    /// The flap of edge `a`–`b` and 1 when it is seen flipped along `a → b` (`ka`: where `b`
    /// is in `a`'s ring, when known).
    #[inline(always)]
    pub(super) fn flap(
        &mut self,
        op: &SecondDifference,
        replay: &FlatReplay,
        geometry: &[DVec3],
        (a, b, ka): (u32, u32, Option<usize>),
        steering: Option<&Steering>,
    ) -> Option<(&RingFlap, usize)> {
        let key = (a.min(b) as u64) << 32 | a.max(b) as u64;
        let f = self.get(key, key, || {
            op.ring_flap(replay, geometry, a, b, ka, steering)
        })?;
        Some((f, (f.v[0] != a) as usize))
    }
}
