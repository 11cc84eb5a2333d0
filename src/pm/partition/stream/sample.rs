//! A deterministic reservoir sample of the vertices, drawn while they stream by.
//!
//! Algorithm R: the first `size` vertices fill the reservoir; vertex `i` after them replaces a
//! uniformly drawn slot `j ∈ 0..=i` when `j < size`. Every vertex ends in the sample with
//! probability `size / n`, in one pass and `size` slots, without knowing `n`.
//!
//! Why a fixed generator seeded from the mesh's counts: the cut tree is built from the sample,
//! so the cells are a function of the sample; a split must write the same files every time, and
//! the same files for the same mesh in any encoding (ASCII and binary PLY differ in length, not
//! in counts), so neither the clock, nor the file's length, nor a library's generator (whose
//! stream may change between versions) may seed it.

use glam::DVec3;

/// The reservoir's capacity unless a split is told otherwise: 4M points (128 MB), enough for
/// cells within a few per cent of the block size on meshes of billions of vertices. The
/// in-memory paths draw the same sample, so it is one number for both.
pub(crate) const SAMPLE_SIZE: usize = 4 << 20;

/// The reservoir: `(input index, position)` per slot.
pub(super) struct Reservoir {
    size: usize,
    seen: u64,
    state: u64,
    pub(super) points: Vec<(u32, DVec3)>,
}

impl Reservoir {
    /// An empty reservoir of `size` slots for a mesh of `vertices` vertices and `faces` faces.
    pub(super) fn new(size: usize, vertices: u64, faces: u64) -> Reservoir {
        Reservoir {
            size: size.max(1),
            seen: 0,
            state: vertices.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ faces.rotate_left(32),
            points: Vec::new(),
        }
    }

    /// Offers vertex `index` at `p`.
    pub(super) fn offer(&mut self, index: u32, p: DVec3) {
        let i = self.seen;
        self.seen += 1;
        if self.points.len() < self.size {
            self.points.push((index, p));
            return;
        }
        // `j` uniform in 0..=i by a multiply-shift of a 64-bit draw (bias below 2^-32).
        let j = ((self.next() as u128 * (i as u128 + 1)) >> 64) as usize;
        if j < self.size {
            self.points[j] = (index, p);
        }
    }

    /// SplitMix64.
    fn next(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_mesh_is_sampled_whole_and_a_large_one_evenly_and_the_same_every_time() {
        let mut all = Reservoir::new(100, 50, 0);
        for i in 0..50 {
            all.offer(i, DVec3::ZERO);
        }
        assert_eq!(all.points.len(), 50);
        let draw = || {
            let mut r = Reservoir::new(1000, 100_000, 7);
            for i in 0..100_000 {
                r.offer(i, DVec3::ZERO);
            }
            r.points.iter().map(|p| p.0).collect::<Vec<_>>()
        };
        let a = draw();
        assert_eq!(a, draw());
        // Each tenth of the stream holds about a tenth of the sample.
        let mut tenths = [0usize; 10];
        for &i in &a {
            tenths[(i / 10_000) as usize] += 1;
        }
        assert!(
            tenths.iter().all(|&n| (60..=140).contains(&n)),
            "{tenths:?}"
        );
    }
}
