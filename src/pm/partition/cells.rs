//! The spatial split of one pass of a partitioned build: the vertices cut into `2^depth` cells
//! of nearly equal size by a k-d tree, each cut at the median of the longest side of its
//! part's bounding box, measured along the axes of one of [`FRAMES`].
//!
//! Steps: find the smallest depth at which `⌈V / 2^depth⌉` fits the block size; then cut each
//! part in two at its median (the first half gets `⌊n/2⌋` vertices) until that depth, so cell
//! sizes differ by at most one.
//!
//! Why so: a median cut on the longest side keeps parts compact (short borders for their
//! size). The passes take the frames in turn: the second frame's axes are parallel to none of
//! the first's, so its cut planes cross the first's instead of running along them, and a
//! vertex at a border of one pass lies inside a cell in the next (Nexus moves its cut planes
//! from level to level for the same reason). Ties are broken by vertex index with a total
//! order on the coordinates, so the cut depends on nothing but the positions (not on a sort's
//! stability or the number of threads).

use crate::mesh::BoundingBox;
use glam::DVec3;

/// Orthonormal frames whose axes the cuts follow, one per pass in turn: the model's axes, and
/// those turned by 60° about the diagonal `(1, 1, 1)`, an exact rational rotation whose axes
/// make angles of 48° to 71° with the model's.
pub(crate) const FRAMES: [[DVec3; 3]; 2] = [
    [DVec3::X, DVec3::Y, DVec3::Z],
    [
        DVec3::new(2.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0),
        DVec3::new(2.0 / 3.0, 2.0 / 3.0, -1.0 / 3.0),
        DVec3::new(-1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0),
    ],
];

/// The cells: each vertex's cell (`u32::MAX` for the vertices not in `vertices`) and their
/// number (`2^depth`).
pub(crate) struct Cells {
    pub cell_of: Vec<u32>,
    pub n_cells: usize,
}

/// Splits `vertices` (indices into `positions`) into cells of at most `max_block` vertices,
/// cutting along the axes of `frame`.
pub(crate) fn split_cells(
    positions: &[DVec3],
    mut vertices: Vec<u32>,
    max_block: usize,
    frame: &[DVec3; 3],
) -> Cells {
    let max_block = max_block.max(1);
    let mut depth = 0u32;
    while vertices.len().div_ceil(1 << depth) > max_block {
        depth += 1;
    }
    let mut cell_of = vec![u32::MAX; positions.len()];
    let along = |v: u32, axis: usize| positions[v as usize].dot(frame[axis]);
    cut(&along, &mut vertices, depth, 0, &mut cell_of);
    Cells {
        cell_of,
        n_cells: 1 << depth,
    }
}

/// [`split_cells`] of the points `points`, given in ascending vertex order: the same cells
/// (ties go to the lower index either way), labelled by position in `points`.
pub(crate) fn split_cells_of(points: &[DVec3], max_block: usize, frame: &[DVec3; 3]) -> Cells {
    let max_block = max_block.max(1);
    let mut depth = 0u32;
    while points.len().div_ceil(1 << depth) > max_block {
        depth += 1;
    }
    let mut cell_of = vec![u32::MAX; points.len()];
    let along = |v: u32, axis: usize| points[v as usize].dot(frame[axis]);
    let mut part: Vec<u32> = (0..points.len() as u32).collect();
    cut(&along, &mut part, depth, 0, &mut cell_of);
    Cells {
        cell_of,
        n_cells: 1 << depth,
    }
}

/// Cuts `part` (the vertices of cells `first .. first + 2^depth`) in two at its median until
/// `depth` is used up, then labels it. `along(v, axis)` is `v`'s coordinate on a frame axis.
fn cut(
    along: &impl Fn(u32, usize) -> f64,
    part: &mut [u32],
    depth: u32,
    first: u32,
    cell_of: &mut [u32],
) {
    if depth == 0 || part.len() < 2 {
        for &v in part.iter() {
            cell_of[v as usize] = first;
        }
        return;
    }
    let axis = longest_axis(along, part);
    let by_axis = |a: &u32, b: &u32| along(*a, axis).total_cmp(&along(*b, axis)).then(a.cmp(b));
    let mid = part.len() / 2;
    part.select_nth_unstable_by(mid, by_axis);
    let (low, high) = part.split_at_mut(mid);
    let half = 1u32 << (depth - 1);
    cut(along, low, depth - 1, first, cell_of);
    cut(along, high, depth - 1, first + half, cell_of);
}

/// The axis (0, 1, 2) along which `part`'s bounding box is longest (the first on ties).
fn longest_axis(along: &impl Fn(u32, usize) -> f64, part: &[u32]) -> usize {
    let point = |v: u32| DVec3::new(along(v, 0), along(v, 1), along(v, 2));
    longest_axis_of(part.iter().map(|&v| point(v)))
}

/// The axis (0, 1, 2) along which the bounding box of `points` is longest (the first on ties;
/// 0 for no points): the cut rule of the passes' cells and of the streaming split's tree.
pub(super) fn longest_axis_of(points: impl Iterator<Item = DVec3>) -> usize {
    let Some(b) = BoundingBox::of(points) else {
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
        let cells = split_cells(&p, (0..103).collect(), 10, &FRAMES[0]);
        assert_eq!(cells.n_cells, 16);
        let mut sizes = vec![0usize; 16];
        for &c in &cells.cell_of {
            sizes[c as usize] += 1;
        }
        assert!(sizes.iter().all(|&s| (6..=7).contains(&s)), "{sizes:?}");
    }

    #[test]
    fn cells_follow_the_longest_side_in_order() {
        let p = line(40);
        let cells = split_cells(&p, (0..40).collect(), 10, &FRAMES[0]);
        // Cells are contiguous runs along the line, in tree order.
        for w in cells.cell_of.windows(2) {
            assert!(w[0] <= w[1]);
        }
    }

    #[test]
    fn equal_positions_are_split_by_index() {
        let p = vec![DVec3::ONE; 9];
        let cells = split_cells(&p, (0..9).rev().collect(), 3, &FRAMES[1]);
        assert_eq!(cells.n_cells, 4);
        assert_eq!(cells.cell_of, vec![0, 0, 1, 1, 2, 2, 3, 3, 3]);
    }

    #[test]
    fn cells_of_the_current_points_are_the_cells_of_their_vertices() {
        let p: Vec<DVec3> = (0..500)
            .map(|i| {
                let t = i as f64;
                DVec3::new((t * 0.37).sin(), (t * 0.11).cos(), (t * 0.05).floor())
            })
            .collect();
        let vertices: Vec<u32> = (0..500).filter(|v| v % 3 != 1).collect();
        for frame in &FRAMES {
            let whole = split_cells(&p, vertices.clone(), 40, frame);
            let points: Vec<DVec3> = vertices.iter().map(|&v| p[v as usize]).collect();
            let current = split_cells_of(&points, 40, frame);
            assert_eq!(current.n_cells, whole.n_cells);
            for (i, &v) in vertices.iter().enumerate() {
                assert_eq!(current.cell_of[i], whole.cell_of[v as usize]);
            }
        }
    }

    #[test]
    fn a_mesh_that_fits_is_one_cell() {
        let p = line(5);
        let cells = split_cells(&p, vec![0, 2, 4], 3, &FRAMES[0]);
        assert_eq!(cells.n_cells, 1);
        assert_eq!(cells.cell_of, vec![0, u32::MAX, 0, u32::MAX, 0]);
    }
}
