//! [`hierarchy_from_cells`]: the partitioned build through files, its first pieces written by
//! the streaming split and the cell tasks instead of from the whole working mesh.
//!
//! Steps: split the file into cells ([`split_into_cells`]) in a new folder under the scratch
//! folder; the cell tasks' pieces ([`cell_pieces`]); the passes from them, as the file path
//! runs them (`through_files.rs`); then the hierarchy put into PM order from the input read
//! whole and repaired by the builder, whose vertices the pieces number alike (the copies after
//! the input's, in the builder's order), so the collapses apply to it as they are.
//!
//! Why the assembly still reads the input whole: the PM numbers vertices by their collapse and
//! keeps the input's faces in order, which the pieces (faces in cell order) do not hold; a pass
//! over the sequence files in reverse would remove that (`docs/partitioned.md`).

use super::SplitError;
use super::rounds::cell_pieces_by;
use super::split::{SplitOptions, split_into_cells};
use crate::mesh::{BoundingBox, CornerTable, PolygonMesh, SourceMap};
use crate::pm::partition::runner::RayonRunner;
use crate::pm::partition::through_files::{Scratch, decimate_from_pieces, unique_dir};
use crate::pm::progressive::{decimate_params, triangles_of};
use crate::pm::{PmError, PmOptions, ProgressiveMesh};
use crate::progress::Progress;
use std::path::Path;

/// The progressive mesh of the PLY file `input` (uncompressed) built in blocks through files, the first pass
/// starting from the streaming split's cells: `opts.block_vertices` is the block size and
/// `opts.block_scratch` the folder the files go to (a new folder in it, removed at the end),
/// both required; `opts.block_runner` runs the passes' tasks (this process's threads without
/// one). Returns the hierarchy and the map back onto the input, as
/// [`ProgressiveMesh::from_polygons`].
///
/// The hierarchy is the bytes of the partitioned build of the same input in memory or through
/// files from the whole mesh (`PmOptions::block_scratch`): those take the first pass's cells
/// from the same sample and its faces in the same order. Texture seams are not kept (as on the
/// file path). A scan whose repair is not local (a component that cannot be oriented, a
/// multi-edge) is refused with [`SplitError::NotLocal`].
pub fn hierarchy_from_cells(
    input: &Path,
    opts: &PmOptions,
    progress: &dyn Progress,
) -> Result<(ProgressiveMesh, SourceMap), SplitError> {
    let passed = decimate_from_cells(input, opts, progress)?;
    let mesh = crate::io::read_mesh(input)?;
    Ok(assemble_from_cells(&mesh, passed)?)
}

/// The passes of a build from cells: the collapses, the repaired mesh's vertex count and the
/// bounding-box diagonal the options were made relative to.
pub(crate) struct FromCells {
    decimated: crate::pm::progressive::Decimated,
    n_vertices: u64,
    diagonal: f64,
}

/// The streaming split of `input`, the cell tasks and the passes from their pieces, as
/// [`hierarchy_from_cells`] runs them; nothing of the whole mesh is held.
pub(crate) fn decimate_from_cells(
    input: &Path,
    opts: &PmOptions,
    progress: &dyn Progress,
) -> Result<FromCells, SplitError> {
    let (Some(max_block), Some(scratch)) = (opts.block_vertices, &opts.block_scratch) else {
        let what = "a build from cells needs block_vertices and block_scratch";
        return Err(PmError::InvalidOption(what.into()).into());
    };
    // The options are checked before the work (the bound is relative, so any diagonal does).
    decimate_params(opts, 1.0)?;
    let dir = Scratch(unique_dir(scratch)?);
    let cells = dir.0.join("cells");
    let made = |e: std::io::Error| {
        let what = format!("cannot make a folder: {e}");
        SplitError::File(super::BlockFileError::new(&cells, 0, what))
    };
    std::fs::create_dir(&cells).map_err(made)?;
    let manifest = split_into_cells(input, &cells, &SplitOptions::new(max_block))?;
    let runner = opts
        .block_runner
        .as_ref()
        .map_or(&RayonRunner as &dyn super::super::runner::TaskRunner, |r| {
            &*r.0
        });
    let (pieces, copies) = cell_pieces_by(&cells, opts.boundary_weight, &dir.0, runner)?;
    let _ = std::fs::remove_dir_all(&cells);
    let diagonal = manifest.bounds.map_or(0.0, |b| b.diagonal());
    let params = decimate_params(opts, diagonal)?;
    let decimated = decimate_from_pieces(
        pieces,
        copies.n_vertices,
        &params,
        max_block,
        &dir.0,
        runner,
        progress,
    )?;
    Ok(FromCells {
        decimated,
        n_vertices: copies.n_vertices,
        diagonal,
    })
}

/// The hierarchy of the passes `passed` put into PM order from `mesh`, the input they were
/// run on, repaired by the builder (whose vertices the pieces number alike).
pub(crate) fn assemble_from_cells(
    mesh: &PolygonMesh,
    passed: FromCells,
) -> Result<(ProgressiveMesh, SourceMap), PmError> {
    let repaired = CornerTable::from_polygons(mesh)?;
    let source = repaired.source.vertex_source.as_slice();
    if source.len() as u64 != passed.n_vertices {
        let what = format!(
            "the cells number {} vertices, the builder {}",
            passed.n_vertices,
            source.len()
        );
        return Err(PmError::Internal(what));
    }
    let positions = source.iter().map(|&s| mesh.positions[s as usize]);
    if BoundingBox::of(positions).map_or(0.0, |b| b.diagonal()) != passed.diagonal {
        let what = "the input changed while it was built";
        return Err(PmError::Internal(what.into()));
    }
    let mut corner_vertex = repaired.corners.corner_vertex;
    let mut referenced = vec![false; source.len()];
    for &v in &corner_vertex {
        referenced[v as usize] = true;
    }
    let isolated: Vec<u32> = (0..source.len() as u32)
        .filter(|&v| !referenced[v as usize])
        .collect();
    let faces = move |mesh_to_pm: &[u32]| {
        for v in &mut corner_vertex {
            *v = mesh_to_pm[*v as usize];
        }
        triangles_of(corner_vertex)
    };
    let position = |v: u32| mesh.positions[source[v as usize] as usize];
    let n = source.len();
    let pm =
        ProgressiveMesh::from_decimation(passed.decimated, (n, n), &isolated, position, faces)?;
    Ok((pm, repaired.source))
}
