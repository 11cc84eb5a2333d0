//! The first pass's cells of a mesh held in memory, cut as the streaming split cuts a file
//! ([`super::split_into_cells`]), so that every path of the partitioned build starts from the
//! same first pass whether its first pieces were made by the cell tasks or from the whole
//! working mesh.
//!
//! Steps: the input's vertices offered to the split's reservoir in input order (the same
//! generator seeded from the same counts, so the same sample); the split's cut tree from it;
//! each vertex of the repaired mesh labelled with the cell of its input vertex (a copy made by
//! the builder's repairs goes with the vertex it copies, as its cell task makes it).
//!
//! Why the same sample rather than the exact medians: the streaming split cannot see every
//! vertex before it cuts, and a first pass whose cells differed between the paths would make
//! different collapses.

use super::sample::{Reservoir, SAMPLE_SIZE};
use super::tree::{CutTree, depth_for};
use crate::pm::partition::cells::{Cells, FRAMES};
use glam::DVec3;

/// The input of a partitioned build as the first cut sees it: every input vertex's position,
/// the input's polygon count (with the vertex count, the sample's seed) and, per vertex of the
/// repaired mesh, its input vertex (`None`: the repaired mesh is the input's vertices).
pub(crate) struct InputPoints<'a> {
    pub positions: &'a [DVec3],
    pub polygons: u64,
    pub source: Option<&'a [u32]>,
}

/// The first pass's cells of the `n_vertices` vertices of the repaired mesh of `input`, in
/// blocks of `max_block`: the cells [`super::split_into_cells`] gives the same input.
pub(crate) fn first_cells(input: &InputPoints, n_vertices: usize, max_block: usize) -> Cells {
    first_cells_sampled(input, n_vertices, max_block, SAMPLE_SIZE)
}

/// [`first_cells`] from a sample of `sample_size` points, as a split told so cuts them.
pub(super) fn first_cells_sampled(
    input: &InputPoints,
    n_vertices: usize,
    max_block: usize,
    sample_size: usize,
) -> Cells {
    let tree = input_tree(input.positions, input.polygons, max_block, sample_size);
    let source = |v: usize| input.source.map_or(v as u32, |s| s[v]);
    let cell_of = (0..n_vertices)
        .map(|v| {
            let s = source(v);
            tree.locate(s, input.positions[s as usize])
        })
        .collect();
    Cells {
        cell_of,
        n_cells: 1 << tree.depth,
    }
}

/// The split's cut tree of the input `positions` of a mesh with `polygons` polygons, from a
/// sample of `sample_size` points.
fn input_tree(positions: &[DVec3], polygons: u64, max_block: usize, sample_size: usize) -> CutTree {
    let n = positions.len() as u64;
    let mut sample = Reservoir::new(sample_size, n, polygons);
    for (i, &p) in positions.iter().enumerate() {
        sample.offer(i as u32, p);
    }
    let depth = depth_for(n, sample.points.len() as u64, max_block);
    CutTree::from_sample(&mut sample.points, depth, FRAMES[0])
}
