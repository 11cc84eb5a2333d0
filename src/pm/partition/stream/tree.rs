//! The cut tree of the streaming split: a k-d tree cut at the medians of a sample, which
//! labels every vertex of the mesh with its cell.
//!
//! Steps: the depth is the smallest at which the expected cell, with a margin for the sample's
//! error, fits the block size (exact when the sample is the whole mesh); each part of the
//! sample is cut at its median along the longest side of its bounding box in the frame, as the
//! partitioned build cuts its cells (`cells.rs`); a vertex goes to the upper side of a cut when
//! its `(coordinate, index)` is not below the median point's, a total order, so every vertex
//! has one cell and a sample point the cell the sample's cut gave it. Cells are numbered as
//! the leaves of the tree in heap order (lower side first), as `cells.rs` numbers them.

use super::super::cells::longest_axis_of;
use super::files::Cut;
use glam::DVec3;

/// The tree: its depth, its frame and its `2^depth - 1` cuts in heap order (node `n` at
/// `n - 1`, its sides `2n` and `2n + 1`).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct CutTree {
    pub depth: u32,
    pub frame: [DVec3; 3],
    pub cuts: Vec<Cut>,
}

/// A cut that sends everything to its lower side (a part of the sample too small to cut).
const NO_CUT: Cut = Cut {
    axis: 0,
    index: u32::MAX,
    value: f64::INFINITY,
};

/// The depth for `n` vertices in cells of at most `max_block`, cut from `sampled` of them:
/// a cell of the tree holds about `sampled / 2^d` sample points, and its true size differs
/// from `n / 2^d` by a few times `sqrt(2^d / sampled)` of it, which the margin covers.
pub(super) fn depth_for(n: u64, sampled: u64, max_block: usize) -> u32 {
    let max_block = max_block.max(1) as f64;
    let mut depth = 0u32;
    loop {
        let cells = (1u64 << depth) as f64;
        let expected = (n as f64 / cells).ceil();
        let margin = match sampled >= n {
            true => 0.0,
            false => 3.0 * (cells / sampled.max(1) as f64).sqrt(),
        };
        if expected * (1.0 + margin) <= max_block || depth >= 31 {
            return depth;
        }
        depth += 1;
    }
}

impl CutTree {
    /// The tree of `depth` cut from `sample` (which it reorders) along the axes of `frame`.
    pub(super) fn from_sample(sample: &mut [(u32, DVec3)], depth: u32, frame: [DVec3; 3]) -> Self {
        let mut tree = CutTree {
            depth,
            frame,
            cuts: vec![NO_CUT; (1usize << depth) - 1],
        };
        tree.cut(sample, 1, depth);
        tree
    }

    fn along(&self, p: DVec3, axis: usize) -> f64 {
        p.dot(self.frame[axis])
    }

    fn cut(&mut self, part: &mut [(u32, DVec3)], node: usize, depth: u32) {
        if depth == 0 || part.len() < 2 {
            return;
        }
        let axis = self.longest_axis(part);
        let key = |a: &(u32, DVec3)| (self.along(a.1, axis), a.0);
        let by_axis = |a: &(u32, DVec3), b: &(u32, DVec3)| {
            let (ka, kb) = (key(a), key(b));
            ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
        };
        let mid = part.len() / 2;
        part.select_nth_unstable_by(mid, by_axis);
        let (value, index) = key(&part[mid]);
        self.cuts[node - 1] = Cut {
            axis: axis as u32,
            index,
            value,
        };
        let (low, high) = part.split_at_mut(mid);
        self.cut(low, 2 * node, depth - 1);
        self.cut(high, 2 * node + 1, depth - 1);
    }

    /// The axis along which `part`'s bounding box is longest (the first on ties).
    fn longest_axis(&self, part: &[(u32, DVec3)]) -> usize {
        let point = |p: DVec3| DVec3::new(self.along(p, 0), self.along(p, 1), self.along(p, 2));
        longest_axis_of(part.iter().map(|x| point(x.1)))
    }

    /// The cell of vertex `index` at `p`.
    pub(super) fn locate(&self, index: u32, p: DVec3) -> u32 {
        let mut node = 1usize;
        for _ in 0..self.depth {
            let c = &self.cuts[node - 1];
            let x = self.along(p, c.axis as usize);
            let high = x.total_cmp(&c.value).then(index.cmp(&c.index)).is_ge();
            node = 2 * node + high as usize;
        }
        (node - (1usize << self.depth)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pm::partition::cells::{FRAMES, split_cells_of};

    #[test]
    fn a_tree_cut_from_every_vertex_gives_the_cells_of_the_exact_medians() {
        let points: Vec<DVec3> = (0..500u32)
            .map(|i| {
                let f = i as f64;
                DVec3::new(
                    (f * 0.37).sin() * 3.0,
                    (f * 0.11).cos(),
                    (i % 13) as f64 * 0.2,
                )
            })
            .collect();
        let exact = split_cells_of(&points, 40, &FRAMES[0]);
        let depth = depth_for(500, 500, 40);
        assert_eq!(1usize << depth, exact.n_cells);
        let mut sample: Vec<(u32, DVec3)> = (0..500).map(|i| (i, points[i as usize])).collect();
        let tree = CutTree::from_sample(&mut sample, depth, FRAMES[0]);
        for (i, p) in points.iter().enumerate() {
            assert_eq!(tree.locate(i as u32, *p), exact.cell_of[i], "vertex {i}");
        }
    }

    #[test]
    fn a_sampled_tree_is_deeper_and_its_cells_stay_near_the_block_size() {
        let n = 20_000u32;
        let points: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new((i % 200) as f64, (i / 200) as f64, ((i * 7) % 5) as f64))
            .collect();
        let mut sample: Vec<(u32, DVec3)> = (0..n)
            .step_by(10)
            .map(|i| (i, points[i as usize]))
            .collect();
        let depth = depth_for(n as u64, sample.len() as u64, 1000);
        assert!(depth >= 5);
        let tree = CutTree::from_sample(&mut sample, depth, FRAMES[0]);
        let mut sizes = vec![0usize; 1 << depth];
        for (i, p) in points.iter().enumerate() {
            sizes[tree.locate(i as u32, *p) as usize] += 1;
        }
        assert!(sizes.iter().all(|&s| s > 0 && s <= 1000), "{sizes:?}");
    }
}
