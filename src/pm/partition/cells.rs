//! The spatial split of a partitioned build: the vertices cut into `2^depth` cells of nearly
//! equal size by a k-d tree, each cut at the median of the longest side of its part's
//! bounding box.
//!
//! Steps: find the smallest depth at which `⌈V / 2^depth⌉` fits the block size; then cut each
//! part in two at its median (the first half gets `⌊n/2⌋` vertices) until that depth. All
//! leaves are at the same depth, so the merge tree is a complete binary tree whose node `k` at
//! level `j` covers cells `k·2^j .. (k+1)·2^j`, and cell sizes differ by at most one.
//!
//! Why so: a median cut on the longest side keeps parts compact (short borders for their
//! size); equal depths keep every round of the merge working on blocks of the same size.
//! Ties are broken by vertex index with a total order on the coordinates, so the cut depends
//! on nothing but the positions (not on a sort's stability or the number of threads).

use crate::mesh::BoundingBox;
use glam::DVec3;

/// The cells: each vertex's cell (`u32::MAX` for the vertices not in `vertices`) and the tree
/// depth (there are `2^depth` cells).
pub(crate) struct Cells {
    pub cell_of: Vec<u32>,
    pub depth: u32,
}

/// Splits `vertices` (indices into `positions`) into cells of at most `max_block` vertices.
pub(crate) fn split_cells(positions: &[DVec3], mut vertices: Vec<u32>, max_block: usize) -> Cells {
    let max_block = max_block.max(1);
    let mut depth = 0u32;
    while vertices.len().div_ceil(1 << depth) > max_block {
        depth += 1;
    }
    let mut cell_of = vec![u32::MAX; positions.len()];
    cut(positions, &mut vertices, depth, 0, &mut cell_of);
    Cells { cell_of, depth }
}

/// Cuts `part` (the vertices of cells `first .. first + 2^depth`) in two at its median until
/// `depth` is used up, then labels it.
fn cut(positions: &[DVec3], part: &mut [u32], depth: u32, first: u32, cell_of: &mut [u32]) {
    if depth == 0 || part.len() < 2 {
        for &v in part.iter() {
            cell_of[v as usize] = first;
        }
        return;
    }
    let axis = longest_axis(positions, part);
    let key = |v: &u32| positions[*v as usize][axis];
    let by_axis = |a: &u32, b: &u32| key(a).total_cmp(&key(b)).then(a.cmp(b));
    let mid = part.len() / 2;
    part.select_nth_unstable_by(mid, by_axis);
    let (low, high) = part.split_at_mut(mid);
    let half = 1u32 << (depth - 1);
    cut(positions, low, depth - 1, first, cell_of);
    cut(positions, high, depth - 1, first + half, cell_of);
}

/// The axis (0, 1, 2) along which `part`'s bounding box is longest (the first on ties).
fn longest_axis(positions: &[DVec3], part: &[u32]) -> usize {
    let Some(b) = BoundingBox::of(part.iter().map(|&v| positions[v as usize])) else {
        return 0;
    };
    let size = b.max - b.min;
    let mut axis = 0;
    for k in 1..3 {
        if size[k] > size[axis] {
            axis = k;
        }
    }
    axis
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> Vec<DVec3> {
        (0..n).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect()
    }

    #[test]
    fn cells_are_balanced_and_no_larger_than_the_block() {
        let p = line(103);
        let cells = split_cells(&p, (0..103).collect(), 10);
        assert_eq!(cells.depth, 4);
        let mut sizes = vec![0usize; 16];
        for &c in &cells.cell_of {
            sizes[c as usize] += 1;
        }
        assert!(sizes.iter().all(|&s| (6..=7).contains(&s)), "{sizes:?}");
    }

    #[test]
    fn cells_follow_the_longest_side_in_order() {
        let p = line(40);
        let cells = split_cells(&p, (0..40).collect(), 10);
        // Cells are contiguous runs along the line, in tree order.
        for w in cells.cell_of.windows(2) {
            assert!(w[0] <= w[1]);
        }
    }

    #[test]
    fn equal_positions_are_split_by_index() {
        let p = vec![DVec3::ONE; 9];
        let cells = split_cells(&p, (0..9).rev().collect(), 3);
        assert_eq!(cells.depth, 2);
        assert_eq!(cells.cell_of, vec![0, 0, 1, 1, 2, 2, 3, 3, 3]);
    }

    #[test]
    fn a_mesh_that_fits_is_one_cell() {
        let p = line(5);
        let cells = split_cells(&p, vec![0, 2, 4], 3);
        assert_eq!(cells.depth, 0);
        assert_eq!(cells.cell_of, vec![0, u32::MAX, 0, u32::MAX, 0]);
    }
}
