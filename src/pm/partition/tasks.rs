//! The tasks of one pass of a partitioned build as functions of files (`docs/partitioned.md`,
//! "Running the passes through files"): each reads task files and writes one or two, and
//! nothing else, so that a task can run on any worker that sees the files and a task run twice
//! writes the same bytes.
//!
//! A pass, in rounds (the driver, `through_files.rs`, runs each round's tasks on rayon):
//! 1. [`split`]: one piece of the whole mesh → its faces across cells (a piece of the next
//!    state) and its faces and vertex records sorted into the pass's cells;
//!    [`concat`] then joins the faces across cells into one piece;
//! 2. [`gather`]: one cell's shares of every routed piece → the cell's block input, and the
//!    records of the cell's pinned vertices (a piece of the next state);
//! 3. [`candidates`]: one block input → its candidate costs;
//! 4. the cut, over all blocks' costs: [`cost_histogram`] per block, summed by the driver;
//! 5. [`collapse`]: one block input and the cut → the block's result (a piece of the next
//!    state: the faces afterwards and the records of the free survivors, with the collapses);
//! 6. [`assemble`]: the pass's results → its collapses interleaved by cost.
//!
//! The last block is [`finish`]: the whole mesh as one block, nothing pinned, to the end.
//! Rounds 3 and 5 both build the block's working mesh and collect its candidates: a task
//! keeps nothing in memory between rounds.

use super::block::{BlockTask, decimate_block, working_mesh};
use super::contents::{self, BlockOutput, Bucket, PassInfo, Record};
use super::order::merge_by_cost;
use super::taskfile::BlockFileError;
use crate::pm::decimate::passes::Stepper;
use crate::pm::decimate::{DecimateParams, rim_scale_at_level};
use std::path::{Path, PathBuf};

/// Round 1: sorts the piece `piece` into the cells of the pass `pass`: the faces whose three
/// vertices lie in one cell, and the vertex records, go to that cell's share of `routed_out`;
/// the faces across cells go, in order, to the piece `across_out`, and pin their vertices
/// (listed in their cells' shares).
pub fn split(
    pass: &Path,
    piece: &Path,
    across_out: &Path,
    routed_out: &Path,
) -> Result<(), BlockFileError> {
    let info = contents::read_pass_info(pass)?;
    let labels = contents::read_labels(pass, &info)?;
    let (faces, records) = contents::read_piece(piece)?;
    let cell_of = |v: u32| match labels.cell(v)? {
        Some(c) => Ok(c as usize),
        None => {
            let what = format!("vertex {v} is not in the mesh of this pass");
            Err(BlockFileError::new(piece, 0, what))
        }
    };
    let mut buckets = vec![Bucket::default(); info.n_cells as usize];
    let mut across = Vec::new();
    for f in faces {
        let [a, b, c] = [cell_of(f[0])?, cell_of(f[1])?, cell_of(f[2])?];
        if a == b && b == c {
            buckets[a].faces.push(f);
        } else {
            across.push(f);
            for (v, k) in f.into_iter().zip([a, b, c]) {
                buckets[k].pins.push(v);
            }
        }
    }
    for r in records {
        buckets[cell_of(r.vertex)?].records.push(r);
    }
    for b in &mut buckets {
        b.pins.sort_unstable();
        b.pins.dedup();
    }
    contents::write_piece(across_out, &across, &[])?;
    contents::write_routed(routed_out, &buckets)
}

/// After round 1: the pieces `pieces` joined in order into the one piece `out` (the faces across
/// the pass's cells, so that the next state has one piece of them, not one per piece).
pub fn concat(pieces: &[PathBuf], out: &Path) -> Result<(), BlockFileError> {
    let mut faces = Vec::new();
    let mut records = Vec::new();
    for p in pieces {
        let (f, r) = contents::read_piece(p)?;
        faces.extend(f);
        records.extend(r);
    }
    records.sort_unstable_by_key(|r: &Record| r.vertex);
    if let Some(w) = records.windows(2).find(|w| w[0].vertex == w[1].vertex) {
        let what = format!("vertex {} has two records among the pieces", w[0].vertex);
        return Err(BlockFileError::new(out, 0, what));
    }
    contents::write_piece(out, &faces, &records)
}

/// Round 2: cell `cell`'s shares of the routed pieces `routed` (in the order of the whole
/// mesh's pieces) → the block input `input_out` (the cell's faces in that order, the records of
/// their vertices, which of them are pinned) and the piece `held_out` (the records of the
/// cell's pinned vertices, which the block's result does not carry).
pub fn gather(
    routed: &[PathBuf],
    cell: u32,
    input_out: &Path,
    held_out: &Path,
) -> Result<(), BlockFileError> {
    let mut faces = Vec::new();
    let mut records: Vec<Record> = Vec::new();
    let mut pins = Vec::new();
    for path in routed {
        let b = contents::read_routed(path, cell)?;
        faces.extend(b.faces);
        records.extend(b.records);
        pins.extend(b.pins);
    }
    records.sort_unstable_by_key(|r| r.vertex);
    if let Some(w) = records.windows(2).find(|w| w[0].vertex == w[1].vertex) {
        let what = format!(
            "vertex {} has two records among the routed pieces",
            w[0].vertex
        );
        return Err(BlockFileError::new(input_out, 0, what));
    }
    pins.sort_unstable();
    pins.dedup();
    let record = |v: u32| {
        let i = records
            .binary_search_by_key(&v, |r| r.vertex)
            .map_err(|_| {
                let what =
                    format!("vertex {v} of cell {cell} has no record among the routed pieces");
                BlockFileError::new(input_out, 0, what)
            })?;
        Ok::<Record, BlockFileError>(records[i])
    };
    let held = pins
        .iter()
        .map(|&v| record(v))
        .collect::<Result<Vec<_>, _>>()?;
    contents::write_piece(held_out, &[], &held)?;
    let vertices = super::vertices_of(&faces);
    let block = Bucket {
        records: vertices
            .iter()
            .map(|&v| record(v))
            .collect::<Result<_, _>>()?,
        pins: vertices
            .iter()
            .copied()
            .filter(|v| pins.binary_search(v).is_ok())
            .collect(),
        faces,
    };
    contents::write_input(input_out, &block)
}

/// The decimator's view of a block input.
fn task(info: &PassInfo, block: Bucket) -> BlockTask {
    let mut pinned = vec![false; block.records.len()];
    for v in &block.pins {
        if let Ok(i) = block.records.binary_search_by_key(v, |r| r.vertex) {
            pinned[i] = true;
        }
    }
    BlockTask {
        faces: block.faces,
        vertices: block.records.iter().map(|r| r.vertex).collect(),
        positions: block.records.iter().map(|r| r.position).collect(),
        quadrics: block.records.iter().map(|r| r.quadric).collect(),
        pinned,
        input_faces: info.input_faces as usize,
        params: info.params,
        last: info.last,
        seams: None,
        seam_floor: Default::default(),
    }
}

/// A block's pass with its candidates collected (rounds 3 and 5), and the positions of its
/// vertices (for the records of its result).
fn stepper(
    pass: &Path,
    input: &Path,
) -> Result<(PassInfo, Stepper, super::block::Block, Vec<Record>), BlockFileError> {
    let info = contents::read_pass_info(pass)?;
    let block = contents::read_input(input)?;
    let records = block.records.clone();
    let (b, mesh, quadric, seams) = working_mesh(task(&info, block));
    let mut stepper = Stepper::new(mesh, quadric, seams);
    let rim_scale = rim_scale_at_level(info.whole_faces as usize, info.input_faces as usize);
    stepper.collect(rim_scale, info.params.max_error_sq);
    Ok((info, stepper, b, records))
}

/// Round 3: the candidate costs of the block input `input` in the pass `pass`, written
/// ascending to `costs_out`; returns how many.
pub fn candidates(pass: &Path, input: &Path, costs_out: &Path) -> Result<u64, BlockFileError> {
    let (_, stepper, _, _) = stepper(pass, input)?;
    let mut keys: Vec<u64> = stepper.costs().map(contents::cost_key).collect();
    keys.sort_unstable();
    contents::write_costs(costs_out, &keys)?;
    Ok(keys.len() as u64)
}

/// Bits of a cost key one [`cost_histogram`] resolves.
pub const HISTOGRAM_BITS: u32 = 16;

/// Round 4, one step of an exact selection over all blocks' costs: of the costs in `costs`
/// whose key (the cost's bits in `f64::total_cmp` order) has the `64 − shift − 16` high bits
/// `prefix`, how many have each value of the next 16 bits (`shift` is 48, 32, 16 or 0).
pub fn cost_histogram(costs: &Path, prefix: u64, shift: u32) -> Result<Vec<u64>, BlockFileError> {
    let keys = contents::read_costs(costs)?;
    let mut bins = vec![0u64; 1 << HISTOGRAM_BITS];
    let high = shift + HISTOGRAM_BITS;
    let lo = prefix.checked_shl(high).unwrap_or(0);
    let first = keys.partition_point(|&k| k < lo);
    for &k in &keys[first..] {
        if k.checked_shr(high).unwrap_or(0) != prefix {
            break;
        }
        bins[((k >> shift) & 0xffff) as usize] += 1;
    }
    Ok(bins)
}

/// One round of [`cost_histogram`] over a list of costs files with the same prefix and shift:
/// one histogram per file, in order.
pub type HistogramRound<'a> =
    dyn Fn(&[PathBuf], u64, u32) -> Result<Vec<Vec<u64>>, BlockFileError> + 'a;

/// The `k`-th smallest (from 0) of the costs in `costs` in `f64::total_cmp` order, by four
/// rounds of [`cost_histogram`] (`histogram` runs one round's tasks); `None` when there are
/// not more than `k`.
pub fn select_cost(
    costs: &[PathBuf],
    k: u64,
    histogram: &HistogramRound,
) -> Result<Option<f64>, BlockFileError> {
    let mut prefix = 0u64;
    let mut rank = k;
    for shift in [48, 32, 16, 0] {
        let parts = histogram(costs, prefix, shift)?;
        let mut bins = vec![0u64; 1 << HISTOGRAM_BITS];
        for p in &parts {
            for (b, n) in bins.iter_mut().zip(p) {
                *b += n;
            }
        }
        let mut below = 0;
        let Some(bin) = bins.iter().position(|&n| {
            below += n;
            below > rank
        }) else {
            return Ok(None);
        };
        rank -= below - bins[bin];
        prefix = prefix << HISTOGRAM_BITS | bin as u64;
    }
    Ok(Some(contents::key_cost(prefix)))
}

/// Round 5: the block input `input` of the pass `pass` collapsed under the cost cut `cut` in
/// cost order, a survivor locked until the pass ends; its result to `result_out`. Returns how
/// many collapses it made.
pub fn collapse(
    pass: &Path,
    input: &Path,
    cut: f64,
    result_out: &Path,
) -> Result<u64, BlockFileError> {
    let (info, mut stepper, block, records) = stepper(pass, input)?;
    let whole = info.whole_faces as usize;
    let legality = info
        .params
        .legality
        .at_level(whole, info.input_faces as usize);
    let block_params = DecimateParams {
        target_vertices: 0,
        target_faces: 0,
        ..info.params
    };
    stepper.perform(cut, legality, &block_params);
    let (collapses, mesh, quadric, seams) = stepper.finish();
    let result = block.result(collapses, &mesh, &quadric, seams.as_ref());
    write_result(result_out, &result, &records, None)?;
    Ok(result.collapses.len() as u64)
}

fn write_result(
    path: &Path,
    result: &super::block::BlockResult,
    records: &[Record],
    stop: Option<&crate::pm::Stop>,
) -> Result<(), BlockFileError> {
    let position = |v: u32| {
        let i = records
            .binary_search_by_key(&v, |r| r.vertex)
            .expect("a survivor has a record");
        records[i].position
    };
    let survivors: Vec<Record> = (result.quadrics.iter())
        .map(|&(vertex, quadric)| Record {
            vertex,
            position: position(vertex),
            quadric,
        })
        .collect();
    let out = BlockOutput {
        collapses: &result.collapses,
        faces: &result.faces,
        records: &survivors,
        stop,
    };
    contents::write_result(path, &out)
}

/// Round 6: the collapses of the pass's results `results` (in cell order) interleaved by
/// cost, cheapest head first, ties to the lower cell, written to `sequence_out`; returns how
/// many. `n_vertices` bounds the vertex indices read.
pub fn assemble(
    results: &[PathBuf],
    n_vertices: u64,
    sequence_out: &Path,
) -> Result<u64, BlockFileError> {
    let blocks = (results.iter())
        .map(|r| contents::read_collapses(r, n_vertices))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = merge_by_cost(blocks);
    contents::write_sequence(sequence_out, &merged)?;
    Ok(merged.len() as u64)
}

/// The last block: the input `input` of the one-cell pass `pass`, nothing pinned, decimated
/// to the end with the rules relaxed where nothing else moves; its result, with why it
/// stopped, to `result_out`.
pub fn finish(pass: &Path, input: &Path, result_out: &Path) -> Result<(), BlockFileError> {
    let info = contents::read_pass_info(pass)?;
    if !info.last {
        return Err(BlockFileError::new(pass, 0, "not the last block's pass"));
    }
    let block = contents::read_input(input)?;
    let records = block.records.clone();
    let (result, stop) = decimate_block(task(&info, block));
    write_result(result_out, &result, &records, Some(&stop))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pm::legality::Legality;

    fn pass_info(n_cells: u32, n_vertices: u64) -> PassInfo {
        PassInfo {
            pass: 0,
            n_cells,
            last: false,
            n_vertices,
            input_faces: 1,
            whole_faces: 1,
            params: DecimateParams {
                target_vertices: 0,
                target_faces: 0,
                max_error_sq: f64::INFINITY,
                legality: Legality::default(),
                boundary_weight: 1.0,
            },
        }
    }

    #[test]
    fn a_split_task_sorts_by_the_labels_it_looks_up_and_names_the_byte_of_a_label_of_no_cell() {
        let dir = std::env::temp_dir().join(format!("meshpyr-labels-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (pass, piece) = (dir.join("pass"), dir.join("piece"));
        let (across, routed) = (dir.join("across"), dir.join("routed"));
        // Vertices 0..3 in cell 1, vertex 3 outside the mesh, vertex 4 labelled with cell 7 of 2.
        contents::write_pass(&pass, &pass_info(2, 5), &[1, 1, 1, NO_CELL, 7]).unwrap();
        contents::write_piece(&piece, &[[0, 1, 2]], &[]).unwrap();
        split(&pass, &piece, &across, &routed).unwrap();
        let cells = contents::read_routed(&routed, 1).unwrap();
        assert_eq!(cells.faces, vec![[0, 1, 2]]);
        contents::write_piece(&piece, &[[0, 1, 4]], &[]).unwrap();
        let e = split(&pass, &piece, &across, &routed)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cell 7 of 2") && e.contains("pass"), "{e}");
        contents::write_piece(&piece, &[[0, 1, 3]], &[]).unwrap();
        let e = split(&pass, &piece, &across, &routed)
            .unwrap_err()
            .to_string();
        assert!(e.contains("vertex 3 is not in the mesh"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    const NO_CELL: u32 = u32::MAX;

    #[test]
    fn the_histogram_selection_is_the_kth_cost_in_total_order() {
        let dir = std::env::temp_dir().join(format!("meshpyr-select-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut all = vec![-0.0, 0.0, -1e-300, 3.5, 3.5, f64::INFINITY, 1e-310];
        all.extend((0..300).map(|i| ((i * 7919) % 257) as f64 * 0.125 - 2.0));
        let files: Vec<PathBuf> = (all.chunks(50).enumerate())
            .map(|(i, part)| {
                let mut keys: Vec<u64> = part.iter().map(|&c| contents::cost_key(c)).collect();
                keys.sort_unstable();
                let f = dir.join(format!("costs{i}"));
                contents::write_costs(&f, &keys).unwrap();
                f
            })
            .collect();
        let round = |c: &[PathBuf], prefix, shift| -> Result<Vec<Vec<u64>>, BlockFileError> {
            c.iter().map(|f| cost_histogram(f, prefix, shift)).collect()
        };
        let mut sorted = all.clone();
        sorted.sort_by(f64::total_cmp);
        for k in [0, 1, 2, 3, 100, 306, 307] {
            let got = select_cost(&files, k as u64, &round).unwrap();
            assert_eq!(
                got.map(f64::to_bits),
                sorted.get(k).map(|c| c.to_bits()),
                "k = {k}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
