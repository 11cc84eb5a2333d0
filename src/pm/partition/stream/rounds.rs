//! The cell tasks as tasks of a runner (`runner.rs`), so that a scheduler runs them where it
//! runs the passes' tasks (`meshpyr.dask`: on its workers): each reads the split's folder and
//! the driver's small files, and writes one file; nothing but a count comes back.
//!
//! Rounds ([`cell_pieces_by`]):
//! 1. **patches** (a task per cell, [`patches_task`]): the cell's patches to a round file;
//! 2. **orientation** (driver): every cell's patches read back and joined ([`orient`]); each
//!    cell's flips to the flips file, one section per cell;
//! 3. **fans** (a task per cell, [`fans_task`]): the cell's extra fans to a round file;
//! 4. **copies** (driver): every cell's fans numbered ([`number_copies`]), to the copies file;
//! 5. **pieces** (a task per cell, [`piece_task`]): the cell's first piece.
//!
//! A task that finds a repair its cell cannot make writes the refusal to its output instead
//! (the cell file, the record, which repair): a refusal is an answer about the input, not a
//! failure of the task, and a runner that retries failed tasks would only find it again. The
//! driver turns the first refusal, in cell order, into [`SplitError::NotLocal`].
//!
//! The round files are task files of kind 9 (`formats/blocks.md`, "Cell rounds"): sections of
//! little-endian `u64` words, each section's layout given by its tag.

use super::cell::{Copies, ExtraFan, cell_fans, cell_piece, number_copies};
use super::files::Manifest;
use super::orient::{CellPatches, Flips, cell_patches, orient};
use super::{GlobalRepair, SplitError};
use crate::pm::partition::runner::{Task, TaskOutput, TaskRunner};
use crate::pm::partition::taskfile::{self, BlockFileError, Kind, Section, TaskFile};
use std::path::{Path, PathBuf};

/// A cell's patches: four words a patch (parity-0 and parity-1 counts, first triangle or
/// `u64::MAX`, its parity).
pub(super) const PATCHES: [u8; 4] = *b"PTCH";
/// A cell's shared triangles: three words each (triangle, patch, parity).
pub(super) const SHARED: [u8; 4] = *b"SHRD";
/// A cell's flips (the section's cell is the cell): a word a patch, 0 or 1.
pub(super) const FLIPS: [u8; 4] = *b"FLIP";
/// A cell's extra fans: per fan its corner count, then its corners ascending.
pub(super) const FANS: [u8; 4] = *b"FANS";
/// The copies: the repaired mesh's vertex count, then `(corner, vertex)` pairs by corner.
pub(super) const COPIES: [u8; 4] = *b"COPY";
/// A refusal: the repair (0 orientation, 1 multi-edge), the record's byte, then the cell
/// file's path and the message as UTF-8, each after its length in bytes.
const REFUSED: [u8; 4] = *b"RFSD";

/// A section of `words`.
pub(super) fn words_section(tag: [u8; 4], cell: u32, words: &[u64]) -> Section {
    let bytes = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    Section { tag, cell, bytes }
}

/// The words of section `tag` of `cell` in `f`, and the section's offset; an error naming
/// the file when it has none or a partial word.
pub(super) fn read_words(
    f: &mut TaskFile,
    tag: [u8; 4],
    cell: u32,
) -> Result<(Vec<u64>, u64), BlockFileError> {
    let Some((bytes, at)) = f.section(tag, cell)? else {
        return Err(f.error(0, format!("no section {}", taskfile::tag_name(tag))));
    };
    if bytes.len() % 8 != 0 {
        return Err(f.error(at, "a section of words with a partial word"));
    }
    let words = bytes.chunks_exact(8);
    let words = words.map(|w| u64::from_le_bytes(w.try_into().expect("8 bytes")));
    Ok((words.collect(), at))
}

/// Opens the round file `path`.
pub(super) fn open_round(path: &Path) -> Result<TaskFile, BlockFileError> {
    TaskFile::open(path, &[Kind::CellRound])
}

/// Writes `sections` as a round file to `path`.
fn write_round(path: &Path, sections: &[Section]) -> Result<(), BlockFileError> {
    taskfile::write(path, Kind::CellRound, sections)
}

/// Writes `result`'s sections to `out`, or its refusal; any other error is the task's.
fn write_or_refuse(out: &Path, result: Result<Vec<Section>, SplitError>) -> Result<(), SplitError> {
    match result {
        Ok(sections) => Ok(write_round(out, &sections)?),
        Err(SplitError::NotLocal {
            path,
            offset,
            repair,
            what,
        }) => Ok(write_round(out, &[refusal(&path, offset, repair, &what)])?),
        Err(e) => Err(e),
    }
}

fn refusal(path: &Path, offset: u64, repair: GlobalRepair, what: &str) -> Section {
    let mut bytes = Vec::new();
    let code: u64 = match repair {
        GlobalRepair::Orientation => 0,
        GlobalRepair::MultiEdge => 1,
    };
    bytes.extend_from_slice(&code.to_le_bytes());
    bytes.extend_from_slice(&offset.to_le_bytes());
    for s in [path.to_string_lossy().as_bytes(), what.as_bytes()] {
        bytes.extend_from_slice(&(s.len() as u64).to_le_bytes());
        bytes.extend_from_slice(s);
    }
    Section {
        tag: REFUSED,
        cell: 0,
        bytes,
    }
}

/// The refusal written to `f`, if it holds one.
fn refusal_in(f: &mut TaskFile) -> Result<Option<SplitError>, BlockFileError> {
    let Some((bytes, at)) = f.section(REFUSED, 0)? else {
        return Ok(None);
    };
    let damaged = || f.error(at, "a damaged refusal");
    let word = |i: usize| {
        let b = bytes.get(i..i + 8)?;
        Some(u64::from_le_bytes(b.try_into().ok()?))
    };
    let text = |i: usize| -> Option<(String, usize)> {
        let n = usize::try_from(word(i)?).ok()?;
        let s = bytes.get(i + 8..(i + 8).checked_add(n)?)?;
        Some((String::from_utf8_lossy(s).into_owned(), i + 8 + n))
    };
    let repair = match word(0) {
        Some(0) => GlobalRepair::Orientation,
        Some(1) => GlobalRepair::MultiEdge,
        _ => return Err(damaged()),
    };
    let offset = word(8).ok_or_else(damaged)?;
    let (path, next) = text(16).ok_or_else(damaged)?;
    let (what, _) = text(next).ok_or_else(damaged)?;
    Ok(Some(SplitError::NotLocal {
        path: PathBuf::from(path),
        offset,
        repair,
        what,
    }))
}

/// Round 1 as a task: cell `cell`'s patches (from the split in `cells`) to the round file
/// `out`, or its refusal.
pub fn patches_task(cells: &Path, cell: u32, out: &Path) -> Result<(), SplitError> {
    let manifest = Manifest::read(&cells.join("manifest"))?;
    let patches = cell_patches(cells, &manifest, cell);
    write_or_refuse(out, patches.map(|p| p.sections()))
}

/// Round 3 as a task: cell `cell`'s extra fans, its triangles flipped as the flips file
/// `flips` says, to the round file `out`, or its refusal.
pub fn fans_task(cells: &Path, cell: u32, flips: &Path, out: &Path) -> Result<(), SplitError> {
    let manifest = Manifest::read(&cells.join("manifest"))?;
    let flips = Flips::read_cell(&mut open_round(flips)?, cell)?;
    let fans = cell_fans(cells, &manifest, cell, &flips).map(|fans| {
        let mut words = Vec::new();
        for f in fans {
            words.push(f.corners.len() as u64);
            words.extend(f.corners.iter().map(|&c| c as u64));
        }
        vec![words_section(FANS, 0, &words)]
    });
    write_or_refuse(out, fans)
}

/// Round 5 as a task: cell `cell`'s first piece to `out` (a piece), flipped by `flips` and
/// numbered by `copies` (the driver's files), with `boundary_weight` on the boundary planes;
/// or its refusal, written to `out` as a round file. Returns the piece's faces (0 refused).
pub fn piece_task(
    cells: &Path,
    cell: u32,
    (flips, copies): (&Path, &Path),
    boundary_weight: f64,
    out: &Path,
) -> Result<u64, SplitError> {
    let manifest = Manifest::read(&cells.join("manifest"))?;
    let flips = Flips::read_cell(&mut open_round(flips)?, cell)?;
    let copies = Copies::read(&mut open_round(copies)?)?;
    match cell_piece(
        cells,
        &manifest,
        cell,
        (&flips, &copies),
        boundary_weight,
        out,
    ) {
        Ok(counts) => Ok(counts.faces),
        Err(e @ SplitError::NotLocal { .. }) => write_or_refuse(out, Err(e)).map(|()| 0),
        Err(e) => Err(e),
    }
}

/// The cell tasks over every cell of the split in `cells`, each round run by `runner`, the
/// driver's and the rounds' files in `cells`: the first pieces `out_dir/first.piece{k}` in
/// cell order and the copies. On a refusal (the first in cell order) or an error, no piece is
/// left.
pub(crate) fn cell_pieces_by(
    cells: &Path,
    boundary_weight: f64,
    out_dir: &Path,
    runner: &dyn TaskRunner,
) -> Result<(Vec<PathBuf>, Copies), SplitError> {
    let manifest = Manifest::read(&cells.join("manifest"))?;
    let n = manifest.cells.len() as u32;
    let pieces: Vec<PathBuf> = (0..n)
        .map(|k| out_dir.join(format!("first.piece{k}")))
        .collect();
    let made = rounds(cells, n, boundary_weight, &pieces, runner);
    if made.is_err() {
        for p in &pieces {
            let _ = std::fs::remove_file(p);
        }
    }
    made.map(|copies| (pieces, copies))
}

fn rounds(
    cells: &Path,
    n: u32,
    boundary_weight: f64,
    pieces: &[PathBuf],
    runner: &dyn TaskRunner,
) -> Result<Copies, SplitError> {
    let named =
        |name: &str| -> Vec<PathBuf> { (0..n).map(|k| cells.join(format!("{name}{k}"))).collect() };
    let patch_files = named("patches");
    let round = (0..n).map(|k| Task::CellPatches {
        cells: cells.to_path_buf(),
        cell: k,
        patches_out: patch_files[k as usize].clone(),
    });
    runner.run_round(round.collect())?;
    let mut patches = Vec::with_capacity(n as usize);
    for p in &patch_files {
        let mut f = open_round(p)?;
        refused(&mut f)?;
        patches.push(CellPatches::read(&mut f)?);
    }
    let flips = orient(cells, &patches)?;
    drop(patches);
    let flips_file = cells.join("flips");
    write_round(&flips_file, &flips.sections())?;
    let fan_files = named("fans");
    let round = (0..n).map(|k| Task::CellFans {
        cells: cells.to_path_buf(),
        cell: k,
        flips: flips_file.clone(),
        fans_out: fan_files[k as usize].clone(),
    });
    runner.run_round(round.collect())?;
    let mut fans = Vec::new();
    for p in &fan_files {
        let mut f = open_round(p)?;
        refused(&mut f)?;
        fans.extend(read_fans(&mut f)?);
    }
    let copies = number_copies(read_input_vertices(cells)?, fans)?;
    let copies_file = cells.join("copies");
    write_round(&copies_file, &[copies.section()])?;
    let round = (0..n).map(|k| Task::CellPiece {
        cells: cells.to_path_buf(),
        cell: k,
        flips: flips_file.clone(),
        copies: copies_file.clone(),
        boundary_weight,
        piece_out: pieces[k as usize].clone(),
    });
    runner.run_round(round.collect())?;
    for p in pieces {
        if let Ok(mut f) = open_round(p) {
            refused(&mut f)?;
        }
    }
    Ok(copies)
}

/// The input's vertex count from the split's manifest.
fn read_input_vertices(cells: &Path) -> Result<u64, SplitError> {
    Ok(Manifest::read(&cells.join("manifest"))?.input_vertices)
}

/// The refusal in round file `f` as an error.
fn refused(f: &mut TaskFile) -> Result<(), SplitError> {
    match refusal_in(f)? {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The extra fans of a fans round file.
fn read_fans(f: &mut TaskFile) -> Result<Vec<ExtraFan>, BlockFileError> {
    let (words, at) = read_words(f, FANS, 0)?;
    let mut out = Vec::new();
    let mut i = 0;
    while i < words.len() {
        let bad = |what: &str| f.error(at + 8 * i as u64, what.to_string());
        let n = usize::try_from(words[i]).map_err(|_| bad("a fan's length out of range"))?;
        let corners = words
            .get(i + 1..(i + 1).saturating_add(n))
            .ok_or_else(|| bad("a fan past the section's end"))?;
        let corners: Vec<u32> = corners
            .iter()
            .map(|&c| u32::try_from(c).map_err(|_| bad("a corner out of range")))
            .collect::<Result<_, _>>()?;
        if corners.is_empty() || !corners.is_sorted() {
            return Err(bad(
                "a fan without corners or with its corners out of order",
            ));
        }
        out.push(ExtraFan {
            first: corners[0],
            corners,
        });
        i += 1 + n;
    }
    Ok(out)
}

/// A cell task's failure as the runner reports it: the file and byte of a file error, else
/// the message against the cell's folder.
pub(crate) fn task_error(cells: &Path, e: SplitError) -> BlockFileError {
    match e {
        SplitError::File(e) => e,
        e => BlockFileError::new(cells, 0, e.to_string()),
    }
}

/// What a cell task hands back.
pub(crate) fn run(task: &Task) -> Option<Result<TaskOutput, BlockFileError>> {
    let (cells, done) = match task {
        Task::CellPatches {
            cells,
            cell,
            patches_out,
        } => (
            cells,
            patches_task(cells, *cell, patches_out).map(|()| TaskOutput::Written),
        ),
        Task::CellFans {
            cells,
            cell,
            flips,
            fans_out,
        } => (
            cells,
            fans_task(cells, *cell, flips, fans_out).map(|()| TaskOutput::Written),
        ),
        Task::CellPiece {
            cells,
            cell,
            flips,
            copies,
            boundary_weight,
            piece_out,
        } => (
            cells,
            piece_task(cells, *cell, (flips, copies), *boundary_weight, piece_out)
                .map(TaskOutput::Count),
        ),
        _ => return None,
    };
    Some(done.map_err(|e| task_error(cells, e)))
}

/// Reads the round file `path` with every reader of round files, for the fuzz target.
pub(crate) fn read_any_round(path: &Path) {
    if let Ok(mut f) = open_round(path) {
        let _ = refusal_in(&mut f);
        let _ = CellPatches::read(&mut f);
        for k in 0..4 {
            let _ = Flips::read_cell(&mut f, k);
        }
        let _ = read_fans(&mut f);
        let _ = Copies::read(&mut f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damaged_round_files_are_errors_naming_the_file_and_the_byte() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("round");
        let check = |sections: &[Section], needle: &str| {
            write_round(&path, sections).unwrap();
            let mut f = open_round(&path).unwrap();
            let errors = [
                CellPatches::read(&mut f).err(),
                Flips::read_cell(&mut f, 0).err(),
                read_fans(&mut f).err(),
                Copies::read(&mut f).err(),
            ];
            let e = errors
                .into_iter()
                .flatten()
                .find(|e| e.what.contains(needle));
            let e = e.unwrap_or_else(|| panic!("no error with {needle:?}"));
            assert_eq!(e.path, path);
            // Past the header and the table: the byte of the section or of its record.
            assert!(e.offset >= 24 + 32 * sections.len() as u64, "{e}");
        };
        check(
            &[
                words_section(PATCHES, 0, &[1, 2, 3, 2]),
                words_section(SHARED, 0, &[]),
            ],
            "parity",
        );
        check(
            &[
                words_section(PATCHES, 0, &[]),
                words_section(SHARED, 0, &[9, 0, 0]),
            ],
            "no patch",
        );
        check(&[words_section(FLIPS, 0, &[0, 1, 7])], "flip other than");
        check(&[words_section(FANS, 0, &[3, 5, 4, 6])], "out of order");
        check(&[words_section(FANS, 0, &[4, 5, 6])], "past the section");
        check(&[words_section(COPIES, 0, &[10, 3, 11])], "copy past");
        check(&[words_section(COPIES, 0, &[])], "no vertex count");
        let mut partial = words_section(FANS, 0, &[1, 2]);
        partial.bytes.pop();
        check(&[partial], "partial word");
    }

    #[test]
    fn a_refusal_reads_back_as_it_was_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("round");
        let cell = Path::new("cells/c3.face");
        let what = "a component cannot be oriented";
        write_round(&path, &[refusal(cell, 96, GlobalRepair::Orientation, what)]).unwrap();
        let e = refusal_in(&mut open_round(&path).unwrap())
            .unwrap()
            .unwrap();
        let SplitError::NotLocal {
            path: p,
            offset,
            repair,
            what: w,
        } = e
        else {
            panic!("{e}")
        };
        assert_eq!(
            (p.as_path(), offset, repair, w.as_str()),
            (cell, 96, GlobalRepair::Orientation, what)
        );
        let mut damaged = refusal(cell, 96, GlobalRepair::MultiEdge, what);
        damaged.bytes.truncate(20);
        write_round(&path, &[damaged]).unwrap();
        let e = refusal_in(&mut open_round(&path).unwrap()).unwrap_err();
        assert!(e.what.contains("damaged refusal"), "{e}");
    }
}
