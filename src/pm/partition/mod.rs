//! The partitioned build of the progressive mesh: the same half-edge collapses, decided in
//! spatial blocks of bounded size with their borders pinned, pass by pass, the cells cut
//! differently in consecutive passes so that no border stays pinned (`docs/partitioned.md`).
//! The systems that scale mesh simplification work in blocks (Nexus's `nxsbuild`,
//! meshoptimizer's clusterlod); Nexus moves its cut planes from level to level so that one
//! level's borders lie inside the next level's cells, and Hoppe's view-dependent refinement
//! (SIGGRAPH 1998) builds a large terrain's progressive mesh as a hierarchy of such block
//! refinements.
//!
//! Steps ([`decimate_in_blocks`]):
//! 1. the whole mesh's quadrics, once (a vertex's quadric sums its whole star's planes);
//! 2. while the mesh has more vertices than a block holds, one pass:
//!    - its vertices cut into cells of at most the block size along the axes of the pass's
//!      frame, the frames taking turns (`cells.rs`); the first pass's cells are the streaming
//!      split's, cut at a sample's medians and drawn alike from the input in memory
//!      (`stream/first.rs`), its faces in the order of the split's pieces, so that every path
//!      (in memory, through files from the whole mesh or from the file's cells) makes the same
//!      first pass;
//!    - the faces sorted into the cells' blocks; a face across cells pins its vertices
//!      (`split.rs`);
//!    - every block collects its candidates, one cost cut is taken over all of them, every
//!      block collapses under it (`lockstep.rs`, `block.rs`);
//!    - the blocks' collapses interleaved by cost (`order.rs`), the whole mesh put back
//!      together from the blocks' faces and the faces across cells;
//! 3. the mesh that fits one block decimated to the base as one block, nothing pinned
//!    (`block.rs`), relaxing the rules where nothing else moves, as the one-process build
//!    ends.
//!
//! The collapse sequence, passes in order, is put into PM order like the one-process build's.
//! A vertex pinned in one pass is at a border of the pass's cells; the next pass's cells cross
//! those borders, so it is free there unless it also lies at a border of those — near the few
//! spots where a border of one frame crosses one of the other.
//!
//! A textured scan keeps its seams: every face carries its corners' wedges through the passes
//! as it carries its vertices, each task gets the wedges of its faces with their texture
//! coordinates and attribute quadrics and decides its collapses with the one-process seam rule
//! and cost, and the attribute quadrics its collapses merge are written back as the geometric
//! quadrics are (`docs/seams.md`, "Partitioned builds").
//!
//! Results depend on the input and the block size only: each task is a function of its
//! inputs, the tasks of a pass are collected in cell order, and the merge breaks ties by cell.

mod block;
mod cells;
mod contents;
mod lockstep;
mod order;
#[cfg(test)]
mod pyramid_commutes;
pub mod runner;
mod split;
pub mod stream;
pub mod task_memory;
pub mod taskfile;
pub mod tasks;
mod through_files;

use super::PmError;
use super::attribute_quadric::AttributeQuadric;
use super::decimate::passes::Turns;
use super::decimate::{Collapse, DecimateParams, FlatMesh, SeamFloor, initial_quadrics};
use super::progressive::Decimated;
use super::seams::Seams;
use crate::progress::Progress;
use block::{BlockResult, BlockSeams, BlockTask, VertexQuadric, decimate_block};
use cells::{Cells, FRAMES};
pub(crate) use contents::read_any;
use glam::{DVec2, DVec3};
use lockstep::Whole;
use rayon::prelude::*;
pub(crate) use stream::{InputPoints, first_cells};
pub(crate) use through_files::decimate_through_files;

/// Decimates `flat` in blocks of at most `max_block` vertices, keeping the texture seams of
/// `seams` when there are any (see the module docs). The first pass takes the cells `first`
/// (the streaming split's, [`stream::first_cells`]).
pub(crate) fn decimate_in_blocks(
    flat: FlatMesh,
    params: &DecimateParams,
    max_block: usize,
    (seams, first): (Option<Seams>, Cells),
    progress: &dyn Progress,
) -> Result<Decimated, PmError> {
    let merge = order::merge_by_cost;
    decimate_in_blocks_merged(flat, params, max_block, (seams, first), progress, merge)
}

/// [`decimate_in_blocks`] with each pass's collapses interleaved by `merge` (given the blocks'
/// sequences in cell order; any interleaving keeping each block's order is a valid sequence,
/// "Why the concatenated records are a valid progressive mesh").
fn decimate_in_blocks_merged(
    flat: FlatMesh,
    params: &DecimateParams,
    max_block: usize,
    (seams, first): (Option<Seams>, Cells),
    progress: &dyn Progress,
    merge: fn(Vec<Vec<Collapse>>) -> Vec<Collapse>,
) -> Result<Decimated, PmError> {
    let quadric = initial_quadrics(&flat, params.boundary_weight);
    let positions = flat.positions();
    let mut faces = flat.triangles();
    let mut wedges = WholeWedges::of(seams, &flat);
    in_cell_order(&mut faces, &mut wedges.faces, &first.cell_of);
    let mut first = Some(first);
    let mut vertices = flat.survivors();
    drop(flat);
    let mut quadrics: Vec<VertexQuadric> = (0..positions.len())
        .map(|v| VertexQuadric {
            planes: quadric.faces[v],
            rim: quadric.rim(v as u32).copied(),
        })
        .collect();
    drop(quadric);
    let input = Input {
        positions: &positions,
        input_faces: faces.len(),
        params,
    };
    let start = vertices.len();
    let stop_at = max_block.max(params.target_vertices);
    let mut collapses = Vec::new();
    let mut passes = Vec::new();
    let mut turns = Turns::START;
    let mut pass = 0;
    // Keeping seams, passes without the cut take no collapse far dearer than those made under
    // one, as in one process (`SEAM_FLOOR_COST_FACTOR`, docs/seams.md), nor does the last block.
    let mut floor = SeamFloor::default();
    while vertices.len() > stop_at && faces.len() > params.target_faces && turns.idle < FRAMES.len()
    {
        let frame = &FRAMES[pass % FRAMES.len()];
        pass += 1;
        let cells = match first.take() {
            Some(cells) => cells,
            None => cells::split_cells(&positions, vertices, max_block, frame),
        };
        let split = split::split_faces(&faces, &wedges.faces, &cells.cell_of, cells.n_cells);
        drop(cells);
        let mut block_wedges = split.inside_wedges.into_iter();
        let blocks: Vec<_> = (split.inside)
            .into_iter()
            .map(|f| (f, block_wedges.next()))
            .collect();
        let tasks: Vec<BlockTask> = blocks
            .into_par_iter()
            .map(|(f, w)| {
                let seams = wedges.block(w);
                input.task(f, &quadrics, |v| split.pinned[v as usize], false, seams)
            })
            .collect();
        let whole = Whole {
            input_faces: input.input_faces,
            faces: faces.len(),
            use_goal: turns.use_goal,
            cap: floor.cap(wedges.keeps_seams() && !turns.use_goal),
        };
        let (results, cut) = lockstep::pass_in_step(tasks, &whole, params);
        faces = split.across;
        wedges.faces = split.across_wedges;
        let first_new = collapses.len();
        let made = gather(
            results,
            (&mut quadrics, &mut faces, &mut wedges),
            &mut collapses,
            merge,
        );
        if turns.use_goal {
            floor.took(&collapses[first_new..]);
        }
        passes.push((made, pinned_of(&split.pinned)));
        vertices = vertices_of(&faces);
        // When no frame's cells find anything, the mesh goes to the last block as it is.
        turns.after(made > 0, cut, params.max_error_sq);
        progress.update((start - vertices.len()) as f64 / start.max(1) as f64);
    }
    let last_wedges = std::mem::take(&mut wedges.faces);
    let last_seams = wedges.block(Some(last_wedges));
    let mut last = input.task(faces, &quadrics, |_| false, true, last_seams);
    last.seam_floor = floor;
    let (result, stop) = decimate_block(last);
    passes.push((result.collapses.len(), Vec::new()));
    collapses.extend(result.collapses);
    progress.update(1.0);
    Ok(Decimated {
        collapses,
        survivors: vertices_of(&result.faces),
        n_base_faces: result.faces.len(),
        stop,
        passes,
    })
}

/// The vertices `pinned` marks, ascending.
fn pinned_of(pinned: &[bool]) -> Vec<u32> {
    (0..pinned.len() as u32)
        .filter(|&v| pinned[v as usize])
        .collect()
}

/// Puts `faces` (and their corners' `wedges`, face for face, when there are any) in the order
/// of the first pass's pieces: by the cell `cell_of` gives their first vertex, keeping their
/// order within a cell. The cell tasks write each cell's piece so (a face goes to the cell of
/// its first vertex, in triangle order), and the order of the faces is what breaks the ties
/// between a block's candidates, so every path's first pass sees the same blocks.
fn in_cell_order(faces: &mut Vec<[u32; 3]>, wedges: &mut Vec<[u32; 3]>, cell_of: &[u32]) {
    let order = cell_order(faces.len(), |t| faces[t][0], cell_of);
    *faces = order.iter().map(|&i| faces[i as usize]).collect();
    if !wedges.is_empty() {
        *wedges = order.iter().map(|&i| wedges[i as usize]).collect();
    }
}

/// The order [`in_cell_order`] puts `n_faces` faces in, as face indices, given each face's
/// first vertex: by the cell of that vertex, in face order within a cell (a stable sort).
pub(crate) fn cell_order(
    n_faces: usize,
    first_vertex: impl Fn(usize) -> u32,
    cell_of: &[u32],
) -> Vec<u32> {
    let mut order: Vec<u32> = (0..n_faces as u32).collect();
    order.sort_by_key(|&t| cell_of[first_vertex(t as usize) as usize]);
    order
}

/// Takes a pass's results into the whole mesh: their quadrics into `quadrics`, their faces
/// after `faces` (and their wedges into `wedges`), their collapses interleaved by `merge`
/// after `collapses`; returns how many.
fn gather(
    results: Vec<BlockResult>,
    (quadrics, faces, wedges): (&mut [VertexQuadric], &mut Vec<[u32; 3]>, &mut WholeWedges),
    collapses: &mut Vec<Collapse>,
    merge: fn(Vec<Vec<Collapse>>) -> Vec<Collapse>,
) -> usize {
    let mut made = Vec::with_capacity(results.len());
    for r in results {
        for &(v, q) in &r.quadrics {
            quadrics[v as usize] = q;
        }
        faces.extend_from_slice(&r.faces);
        if wedges.keeps_seams() {
            wedges.faces.extend_from_slice(&r.wedges);
            for &(w, q) in &r.wedge_quadrics {
                wedges.quadrics[w as usize] = q;
            }
        }
        made.push(r.collapses);
    }
    let made = merge(made);
    let n = made.len();
    collapses.extend(made);
    n
}

/// A textured scan's seams across the passes: the wedges of the current faces' corners, face
/// for face, and per wedge (the whole mesh's numbering) its texture coordinates and attribute
/// quadric, the latter written back after every pass as the vertices' quadrics are. Without
/// seams everything is empty and the tasks get none.
struct WholeWedges {
    seams: bool,
    faces: Vec<[u32; 3]>,
    uv: Vec<DVec2>,
    quadrics: Vec<AttributeQuadric>,
    scale: f64,
}

impl WholeWedges {
    /// The wedges of `seams` on the live triangles of `flat` (in [`FlatMesh::triangles`]'
    /// order), or none.
    fn of(seams: Option<Seams>, flat: &FlatMesh) -> WholeWedges {
        match seams {
            Some(s) => {
                let faces = s.live_wedges(flat);
                let (uv, quadrics, scale) = s.wedge_tables();
                WholeWedges {
                    seams: true,
                    faces,
                    uv,
                    quadrics,
                    scale,
                }
            }
            None => WholeWedges {
                seams: false,
                faces: Vec::new(),
                uv: Vec::new(),
                quadrics: Vec::new(),
                scale: 0.0,
            },
        }
    }

    fn keeps_seams(&self) -> bool {
        self.seams
    }

    /// The seams of the block whose faces' corners have the wedges `faces` (`None` without).
    fn block(&self, faces: Option<Vec<[u32; 3]>>) -> Option<BlockSeams> {
        let faces = faces.filter(|_| self.seams)?;
        let mut ids: Vec<u32> = faces.iter().flatten().copied().collect();
        ids.sort_unstable();
        ids.dedup();
        Some(BlockSeams {
            uv: pick(&self.uv, &ids),
            quadrics: pick(&self.quadrics, &ids),
            wedges: faces,
            ids,
            scale: self.scale,
        })
    }
}

/// The rows `ids` of `table`, or nothing from an empty table.
fn pick<T: Copy>(table: &[T], ids: &[u32]) -> Vec<T> {
    if table.is_empty() {
        Vec::new()
    } else {
        ids.iter().map(|&w| table[w as usize]).collect()
    }
}

/// What every task of a build reads from.
struct Input<'a> {
    positions: &'a [DVec3],
    input_faces: usize,
    params: &'a DecimateParams,
}

impl Input<'_> {
    /// The task of the block `faces`, whose vertices are pinned where `pinned` says.
    fn task(
        &self,
        faces: Vec<[u32; 3]>,
        quadrics: &[VertexQuadric],
        pinned: impl Fn(u32) -> bool,
        last: bool,
        seams: Option<BlockSeams>,
    ) -> BlockTask {
        let vertices = vertices_of(&faces);
        BlockTask {
            positions: vertices
                .iter()
                .map(|&v| self.positions[v as usize])
                .collect(),
            quadrics: vertices.iter().map(|&v| quadrics[v as usize]).collect(),
            pinned: vertices.iter().map(|&v| pinned(v)).collect(),
            faces,
            vertices,
            input_faces: self.input_faces,
            params: *self.params,
            last,
            seams,
            seam_floor: SeamFloor::default(),
        }
    }
}

/// The vertices of `faces`, ascending.
fn vertices_of(faces: &[[u32; 3]]) -> Vec<u32> {
    let mut v: Vec<u32> = faces.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    v
}
