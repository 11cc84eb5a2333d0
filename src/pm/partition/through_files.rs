//! The partitioned build with every pass run through task files in a scratch directory
//! (`docs/partitioned.md`, "Running the passes through files"): the same passes, cells, cut
//! and collapses as [`super::decimate_in_blocks`], so the same hierarchy bit for bit, but each
//! round's tasks read and write only files (`tasks.rs`), as the tasks of a distributed engine
//! would.
//!
//! Steps:
//! 1. the whole mesh's quadrics, written with the faces (in the first pass's cell order) and
//!    positions as the first pieces, or the cell pieces of the streaming split taken as they
//!    are ([`decimate_from_pieces`]);
//! 2. per pass: the cells cut from the current vertices' positions (read from the pieces) and
//!    written with the pass's parameters (the first pass's given, or read off the cell
//!    pieces); then the rounds of `tasks.rs` — split, gather,
//!    candidates, the exact cut, collapse, assemble — the next state being the faces across
//!    cells, the blocks' results and the cells' pinned records;
//! 3. the last block from the last state, as one cell;
//! 4. the passes' collapse sequences read back in order.
//!
//! The directory is removed at the end, and on error.

use super::cells::{Cells, FRAMES, split_cells_of};
use super::contents::{self, PassInfo, Record};
use super::runner::{Task, TaskOutput, TaskRunner};
use super::taskfile::BlockFileError;
use super::tasks;
use super::{VertexQuadric, vertices_of};
use crate::pm::PmError;
use crate::pm::decimate::passes::{Turns, cut_at, pass_goal};
use crate::pm::decimate::{Collapse, DecimateParams, FlatMesh, initial_quadrics};
use crate::pm::progressive::Decimated;
use crate::progress::Progress;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// A scratch directory, removed when dropped.
pub(super) struct Scratch(pub(super) PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
        crate::io::atomic::forget_scratch_folder(&self.0);
    }
}

impl Scratch {
    fn file(&self, name: String) -> PathBuf {
        self.0.join(name)
    }
}

/// Runs `f` over `0..n` on rayon, results in order, the first error returned.
fn round<T: Send>(
    n: usize,
    f: impl Fn(usize) -> Result<T, BlockFileError> + Sync + Send,
) -> Result<Vec<T>, BlockFileError> {
    (0..n).into_par_iter().map(f).collect()
}

/// Decimates `flat` in blocks of at most `max_block` vertices, every pass through task files in
/// a new directory under `scratch`, each round's tasks run by `runner`; the first pass takes
/// the cells `first` (the streaming split's, `stream::first_cells`).
pub(crate) fn decimate_through_files(
    flat: FlatMesh,
    params: &DecimateParams,
    (max_block, first): (usize, Cells),
    scratch: &Path,
    runner: &dyn TaskRunner,
    progress: &dyn Progress,
) -> Result<Decimated, PmError> {
    let driver = Driver {
        runner,
        dir: &Scratch(unique_dir(scratch)?),
        max_block,
    };
    let counts = (flat.n_vertex_slots() as u64, flat.n_faces() as u64);
    let state = first_pieces(flat, params, (max_block, &first.cell_of), driver.dir)?;
    let first = FirstCut::Labels(first);
    Ok(driver.run(state, (counts, first), params, progress)?)
}

/// [`decimate_through_files`] from first pieces made elsewhere: the cell pieces of the
/// streaming split (`stream::cell_pieces`), one per cell in cell order, whose vertices are
/// numbered below `n_vertices` (the repaired mesh's vertex count) and whose faces together are
/// the whole mesh's. The first pass's cells are the pieces: a vertex is in the cell of the
/// piece holding its record. The pieces are consumed: the first pass removes them once it has
/// split them.
pub(crate) fn decimate_from_pieces(
    pieces: Vec<PathBuf>,
    n_vertices: u64,
    params: &DecimateParams,
    max_block: usize,
    scratch: &Path,
    runner: &dyn TaskRunner,
    progress: &dyn Progress,
) -> Result<Decimated, PmError> {
    let driver = Driver {
        runner,
        dir: &Scratch(unique_dir(scratch)?),
        max_block,
    };
    let mut state = State {
        pieces,
        faces: 0,
        vertices: 0,
    };
    count(&mut state)?;
    let counts = (n_vertices, state.faces as u64);
    Ok(driver.run(state, (counts, FirstCut::ByPiece), params, progress)?)
}

/// Where the first pass's cells come from.
enum FirstCut {
    /// Given, per vertex.
    Labels(Cells),
    /// The cell of each vertex is the index of the first piece holding its record.
    ByPiece,
}

/// What every step of the driver uses.
struct Driver<'a> {
    runner: &'a dyn TaskRunner,
    dir: &'a Scratch,
    max_block: usize,
}

/// The counts a round's tasks hand back, in order.
fn counts(outputs: Vec<TaskOutput>) -> Vec<u64> {
    let count = |o| match o {
        TaskOutput::Count(n) => n,
        _ => 0,
    };
    outputs.into_iter().map(count).collect()
}

/// A new directory under `scratch`, named by the process and a counter, registered to be removed
/// if a signal ends the process before its [`Scratch`] does.
pub(super) fn unique_dir(scratch: &Path) -> Result<PathBuf, PmError> {
    let failed = |e: std::io::Error| {
        BlockFileError::new(scratch, 0, format!("cannot make a scratch directory: {e}"))
    };
    std::fs::create_dir_all(scratch).map_err(|e| PmError::from(failed(e)))?;
    for n in 0.. {
        let dir = scratch.join(format!("meshpyr-blocks-{}-{n}", std::process::id()));
        match std::fs::create_dir(&dir) {
            Ok(()) => {
                crate::io::atomic::register_scratch_folder(&dir);
                return Ok(dir);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(failed(e).into()),
        }
    }
    unreachable!("a free name among u64 counters")
}

/// The state of the whole mesh between passes: the pieces, in the order of its face list.
struct State {
    pieces: Vec<PathBuf>,
    faces: usize,
    vertices: usize,
}

impl Driver<'_> {
    /// The passes from the first state `state` of a mesh of `n_vertices` vertex slots and
    /// `input_faces` faces, the first pass's cells from `first`.
    fn run(
        &self,
        mut state: State,
        ((n_vertices, input_faces), first): ((u64, u64), FirstCut),
        params: &DecimateParams,
        progress: &dyn Progress,
    ) -> Result<Decimated, BlockFileError> {
        let (dir, max_block) = (self.dir, self.max_block);
        let start = state.vertices;
        let stop_at = max_block.max(params.target_vertices);
        let mut sequences = Vec::new();
        let (mut turns, mut pass) = (Turns::START, 0u32);
        let mut first = Some(first);
        while state.vertices > stop_at
            && state.faces > params.target_faces
            && turns.idle < FRAMES.len()
        {
            let frame = &FRAMES[pass as usize % FRAMES.len()];
            let info = PassInfo {
                pass,
                n_cells: 0,
                last: false,
                n_vertices,
                input_faces,
                whole_faces: state.faces as u64,
                params: *params,
            };
            let pass_file = match first.take() {
                Some(FirstCut::Labels(cells)) => write_cells(info, cells, dir)?,
                Some(FirstCut::ByPiece) => piece_cells(&state, info, dir)?,
                None => cut_cells(&state, info, |p| split_cells_of(p, max_block, frame), dir)?,
            };
            let blocks = self.split_and_gather(&pass_file, &mut state)?;
            let pinned = pinned_vertices(&blocks.held)?;
            let costs: Vec<PathBuf> = (0..blocks.inputs.len())
                .map(|k| dir.file(format!("p{pass}.costs{k}")))
                .collect();
            let round = (blocks.inputs.iter().zip(&costs)).map(|(input, out)| Task::Candidates {
                pass: pass_file.clone(),
                input: input.clone(),
                costs_out: out.clone(),
            });
            self.runner.run_round(round.collect())?;
            let goal = pass_goal(state.faces, params.target_faces) as u64;
            let nth = match turns.use_goal {
                true => tasks::select_cost(&costs, goal, &|c, prefix, shift| {
                    self.histograms(c, prefix, shift)
                })?,
                false => None,
            };
            let cut = cut_at(nth, params.max_error_sq);
            remove(&costs);
            let results: Vec<PathBuf> = (0..blocks.inputs.len())
                .map(|k| dir.file(format!("p{pass}.result{k}")))
                .collect();
            let round = (blocks.inputs.iter().zip(&results)).map(|(input, out)| Task::Collapse {
                pass: pass_file.clone(),
                input: input.clone(),
                cut,
                result_out: out.clone(),
            });
            self.runner.run_round(round.collect())?;
            remove(&blocks.inputs);
            remove(&[pass_file]);
            let sequence = dir.file(format!("p{pass}.sequence"));
            let assemble = Task::Assemble {
                results: results.clone(),
                n_vertices,
                sequence_out: sequence.clone(),
            };
            let made = counts(self.runner.run_round(vec![assemble])?)[0];
            sequences.push((sequence, pinned));
            state.pieces = [vec![blocks.across], results, blocks.held].concat();
            count(&mut state)?;
            pass += 1;
            turns.after(made > 0, cut, params.max_error_sq);
            progress.update((start - state.vertices) as f64 / start.max(1) as f64);
        }
        let info = PassInfo {
            pass,
            n_cells: 1,
            last: true,
            n_vertices,
            input_faces,
            whole_faces: state.faces as u64,
            params: *params,
        };
        let pass_file = cut_cells(
            &state,
            info,
            |p| Cells {
                cell_of: vec![0; p.len()],
                n_cells: 1,
            },
            dir,
        )?;
        let blocks = self.split_and_gather(&pass_file, &mut state)?;
        let last = dir.file("last.result".into());
        let finish = Task::Finish {
            pass: pass_file,
            input: blocks.inputs[0].clone(),
            result_out: last.clone(),
        };
        self.runner.run_round(vec![finish])?;
        let mut collapses: Vec<Collapse> = Vec::new();
        let mut passes = Vec::new();
        for (s, pinned) in sequences.into_iter().chain([(last.clone(), Vec::new())]) {
            let made = contents::read_collapses(&s, n_vertices)?;
            passes.push((made.len(), pinned));
            collapses.extend(made);
        }
        let (faces, _) = contents::read_piece(&last)?;
        let stop = contents::read_stop(&last)?;
        progress.update(1.0);
        Ok(Decimated {
            collapses,
            survivors: vertices_of(&faces),
            n_base_faces: faces.len(),
            stop,
            passes,
        })
    }

    /// One round of [`tasks::cost_histogram`] over `costs`.
    fn histograms(
        &self,
        costs: &[PathBuf],
        prefix: u64,
        shift: u32,
    ) -> Result<Vec<Vec<u64>>, BlockFileError> {
        let round = costs.iter().map(|c| Task::CostHistogram {
            costs: c.clone(),
            prefix,
            shift,
        });
        let bins = |o| match o {
            TaskOutput::Histogram(b) => b,
            _ => Vec::new(),
        };
        Ok(self
            .runner
            .run_round(round.collect())?
            .into_iter()
            .map(bins)
            .collect())
    }
}

/// The whole mesh's faces, positions and initial quadrics as pieces: the faces in the order of
/// the first pass's cells (`cell_of`, [`super::cell_order`]), cut into runs of
/// about a block's faces, the records of the vertices with faces in runs of a block's
/// vertices. Each run's faces and records are made by the task that writes them, from the
/// working mesh and the quadrics, so that the driver never holds the whole mesh's records
/// (216 B per vertex) nor copies of its faces and positions beside the working mesh (only the
/// faces' order, 4 B a face).
fn first_pieces(
    flat: FlatMesh,
    params: &DecimateParams,
    (max_block, cell_of): (usize, &[u32]),
    dir: &Scratch,
) -> Result<State, BlockFileError> {
    let quadric = initial_quadrics(&flat, params.boundary_weight);
    let vertices = flat.survivors();
    // The working mesh is fresh, so its triangles are the live ones and runs of its triangle
    // slots are runs of its face list.
    let faces = flat.n_faces();
    debug_assert_eq!(faces, flat.triangles().len());
    let record = |v: u32| Record {
        vertex: v,
        position: flat.position(v),
        quadric: VertexQuadric {
            planes: quadric.faces[v as usize],
            rim: quadric.rim(v).copied(),
        },
    };
    let order = super::cell_order(faces, |t| flat.triangle(t)[0], cell_of);
    let face_run = 2 * max_block.max(1);
    let vertex_runs: Vec<_> = vertices.chunks(max_block.max(1)).collect();
    let n = faces.div_ceil(face_run).max(vertex_runs.len());
    let pieces = round(n, |i| {
        let out = dir.file(format!("first.piece{i}"));
        let run = &order[(i * face_run).min(faces)..((i + 1) * face_run).min(faces)];
        let f: Vec<[u32; 3]> = run.iter().map(|&t| flat.triangle(t as usize)).collect();
        let v = vertex_runs.get(i).copied().unwrap_or_default();
        let records: Vec<Record> = v.iter().map(|&v| record(v)).collect();
        contents::write_piece(&out, &f, &records)?;
        Ok(out)
    })?;
    Ok(State {
        pieces,
        faces,
        vertices: vertices.len(),
    })
}

/// The state's face and vertex counts from its pieces' section tables.
fn count(state: &mut State) -> Result<(), BlockFileError> {
    let counts = round(state.pieces.len(), |i| {
        contents::piece_counts(&state.pieces[i])
    })?;
    state.faces = counts.iter().map(|c| c.0 as usize).sum();
    state.vertices = counts.iter().map(|c| c.1 as usize).sum();
    Ok(())
}

/// The pass's cells `cells` (per vertex) written with `info` to the pass's file.
fn write_cells(mut info: PassInfo, cells: Cells, dir: &Scratch) -> Result<PathBuf, BlockFileError> {
    info.n_cells = cells.n_cells as u32;
    let out = dir.file(format!("p{}.pass", info.pass));
    contents::write_pass(&out, &info, &cells.cell_of)?;
    Ok(out)
}

/// The pass's cells read off the state's pieces, one cell per piece (each vertex in the cell
/// of the piece holding its record), written with `info` to the pass's file.
fn piece_cells(state: &State, info: PassInfo, dir: &Scratch) -> Result<PathBuf, BlockFileError> {
    let parts = piece_positions(state)?;
    let n_cells = parts.len();
    let in_piece = parts.iter().enumerate();
    let pairs = in_piece.flat_map(|(k, part)| part.iter().map(move |&(v, _)| (v, k as u32)));
    let cell_of = labels(info.n_vertices, pairs, dir)?;
    write_cells(info, Cells { cell_of, n_cells }, dir)
}

/// The pass's cells from the current vertices' positions (`cells_of` labels positions given
/// in ascending vertex order), written with `info` to the pass's file.
fn cut_cells(
    state: &State,
    info: PassInfo,
    cells_of: impl Fn(&[glam::DVec3]) -> Cells,
    dir: &Scratch,
) -> Result<PathBuf, BlockFileError> {
    let mut points: Vec<(u32, glam::DVec3)> =
        piece_positions(state)?.into_iter().flatten().collect();
    points.sort_unstable_by_key(|p| p.0);
    let positions: Vec<glam::DVec3> = points.iter().map(|p| p.1).collect();
    let cells = cells_of(&positions);
    drop(positions);
    let pairs = points.iter().map(|p| p.0).zip(cells.cell_of);
    let cell_of = labels(info.n_vertices, pairs, dir)?;
    write_cells(info, Cells { cell_of, ..cells }, dir)
}

/// Every piece's records' vertices and positions, piece by piece.
fn piece_positions(state: &State) -> Result<Vec<Vec<(u32, glam::DVec3)>>, BlockFileError> {
    round(state.pieces.len(), |i| {
        contents::read_positions(&state.pieces[i])
    })
}

/// One label per vertex of `n_vertices` from `(vertex, cell)` pairs, `u32::MAX` for a vertex
/// without one; a vertex out of range is an error naming the scratch folder.
fn labels(
    n_vertices: u64,
    pairs: impl Iterator<Item = (u32, u32)>,
    dir: &Scratch,
) -> Result<Vec<u32>, BlockFileError> {
    let mut labels = vec![u32::MAX; n_vertices as usize];
    for (v, c) in pairs {
        let what = || BlockFileError::new(&dir.0, 0, format!("vertex {v} out of range"));
        *labels.get_mut(v as usize).ok_or_else(what)? = c;
    }
    Ok(labels)
}

/// The blocks of a pass, as files.
struct Blocks {
    inputs: Vec<PathBuf>,
    across: PathBuf,
    held: Vec<PathBuf>,
}

impl Driver<'_> {
    /// Rounds 1 and 2: the state's pieces split into the pass's cells and gathered into block
    /// inputs; the consumed pieces are removed.
    fn split_and_gather(
        &self,
        pass_file: &Path,
        state: &mut State,
    ) -> Result<Blocks, BlockFileError> {
        let dir = self.dir;
        let info = contents::read_pass_info(pass_file)?;
        let p = info.pass;
        let n = state.pieces.len();
        let across_parts: Vec<PathBuf> = (0..n)
            .map(|i| dir.file(format!("p{p}.across{i}")))
            .collect();
        let routed: Vec<PathBuf> = (0..n)
            .map(|i| dir.file(format!("p{p}.routed{i}")))
            .collect();
        let round = (0..n).map(|i| Task::Split {
            pass: pass_file.to_path_buf(),
            piece: state.pieces[i].clone(),
            across_out: across_parts[i].clone(),
            routed_out: routed[i].clone(),
        });
        self.runner.run_round(round.collect())?;
        remove(&state.pieces);
        let across = dir.file(format!("p{p}.across"));
        let concat = Task::Concat {
            pieces: across_parts.clone(),
            out: across.clone(),
        };
        self.runner.run_round(vec![concat])?;
        remove(&across_parts);
        let cells = info.n_cells;
        let inputs: Vec<PathBuf> = (0..cells)
            .map(|k| dir.file(format!("p{p}.input{k}")))
            .collect();
        let held: Vec<PathBuf> = (0..cells)
            .map(|k| dir.file(format!("p{p}.held{k}")))
            .collect();
        let round = (0..cells as usize).map(|k| Task::Gather {
            routed: routed.clone(),
            cell: k as u32,
            input_out: inputs[k].clone(),
            held_out: held[k].clone(),
        });
        self.runner.run_round(round.collect())?;
        remove(&routed);
        Ok(Blocks {
            inputs,
            across,
            held,
        })
    }
}

/// The vertices pinned in a pass, ascending: those of its cells' held pieces (`tasks::gather`
/// writes there the records of each cell's pinned vertices).
fn pinned_vertices(held: &[PathBuf]) -> Result<Vec<u32>, BlockFileError> {
    let parts = round(held.len(), |k| contents::read_positions(&held[k]))?;
    let mut pinned: Vec<u32> = parts.into_iter().flatten().map(|(v, _)| v).collect();
    pinned.sort_unstable();
    Ok(pinned)
}

fn remove(files: &[PathBuf]) {
    for f in files {
        let _ = std::fs::remove_file(f);
    }
}
