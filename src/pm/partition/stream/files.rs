//! The files of the streaming split (`formats/blocks.md`, "Cell files"): the cells' record
//! files, written through one bounded buffer per cell, read back whole with their checks, and
//! the manifest, a task file of kind 8.
//!
//! Why flat record files for the cells rather than task files: a task file's table precedes
//! its sections and carries their checksums, so it is written whole; a cell's files grow by
//! appends from a bounded buffer while the input streams by. Their checksums go to the
//! manifest instead, computed as the bytes are appended.

use super::super::taskfile::{self, BlockFileError, Kind, Section, TaskFile};
use crate::mesh::BoundingBox;
use glam::DVec3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Bytes of every record of a cell file.
pub(super) const RECORD: usize = 32;

/// One cut of the tree: the frame axis, and the median point's coordinate along it and index;
/// a vertex is on the upper side when its `(coordinate, index)` is not below `(value, index)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cut {
    /// The frame axis (0, 1, 2).
    pub axis: u32,
    /// The median point's input index (`u32::MAX` with an infinite value: no cut).
    pub index: u32,
    /// The median point's coordinate along the axis.
    pub value: f64,
}

/// One cell's files as the manifest describes them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CellEntry {
    /// Records of `c{k}.vert`: the cell's vertices.
    pub vertices: u64,
    /// Records of `c{k}.face`: the triangles with a vertex in the cell.
    pub faces: u64,
    /// Records of `c{k}.border`: the other cells' vertices those triangles use.
    pub border: u64,
    /// CRC-32 of `c{k}.vert`, `c{k}.face`, `c{k}.border`.
    pub crc: [u32; 3],
}

/// What the streaming split wrote (the file `manifest`, `formats/blocks.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The input's vertices.
    pub input_vertices: u64,
    /// The input's polygons.
    pub polygons: u64,
    /// The triangles of the fan triangulation, those with a repeated vertex left out.
    pub triangles: u64,
    /// The triangles left out for a repeated vertex.
    pub dropped_triangles: u64,
    /// The sample's capacity and how many vertices it held.
    pub sample: (u64, u64),
    /// The bounding box of all vertices (`None` without vertices).
    pub bounds: Option<BoundingBox>,
    /// The bounding box of the vertices with triangles: its centre is the origin of the
    /// decimator's frame, in which the cell tasks write positions and quadrics.
    pub used_bounds: Option<BoundingBox>,
    /// Which of the partitioned build's frames the cuts follow (0: the model's axes).
    pub frame: u32,
    /// The tree's depth (`2^depth` cells).
    pub depth: u32,
    /// The cuts in heap order.
    pub cuts: Vec<Cut>,
    /// The cells' files.
    pub cells: Vec<CellEntry>,
}

const SPLT: [u8; 4] = *b"SPLT";
const TREE: [u8; 4] = *b"TREE";
const CELL: [u8; 4] = *b"CELL";
const SPLT_LEN: usize = 152;

fn bounds_bytes(out: &mut Vec<u8>, b: &Option<BoundingBox>) {
    let (min, max) = match b {
        Some(b) => (b.min, b.max),
        None => (DVec3::INFINITY, DVec3::NEG_INFINITY),
    };
    for x in min.to_array().into_iter().chain(max.to_array()) {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

impl Manifest {
    /// Writes the manifest to `path` (under a temporary name, then renamed).
    pub(super) fn write(&self, path: &Path) -> Result<(), BlockFileError> {
        let mut s = Vec::with_capacity(SPLT_LEN);
        for x in [
            self.input_vertices,
            self.polygons,
            self.triangles,
            self.dropped_triangles,
        ] {
            s.extend_from_slice(&x.to_le_bytes());
        }
        s.extend_from_slice(&self.depth.to_le_bytes());
        s.extend_from_slice(&self.frame.to_le_bytes());
        s.extend_from_slice(&self.sample.0.to_le_bytes());
        s.extend_from_slice(&self.sample.1.to_le_bytes());
        bounds_bytes(&mut s, &self.bounds);
        bounds_bytes(&mut s, &self.used_bounds);
        let mut t = Vec::with_capacity(16 * self.cuts.len());
        for c in &self.cuts {
            t.extend_from_slice(&c.axis.to_le_bytes());
            t.extend_from_slice(&c.index.to_le_bytes());
            t.extend_from_slice(&c.value.to_le_bytes());
        }
        let mut c = Vec::with_capacity(40 * self.cells.len());
        for e in &self.cells {
            for x in [e.vertices, e.faces, e.border] {
                c.extend_from_slice(&x.to_le_bytes());
            }
            for x in e.crc.into_iter().chain([0]) {
                c.extend_from_slice(&x.to_le_bytes());
            }
        }
        let section = |tag, bytes| Section {
            tag,
            cell: 0,
            bytes,
        };
        let sections = [section(SPLT, s), section(TREE, t), section(CELL, c)];
        taskfile::write(path, Kind::Manifest, &sections)
    }

    /// Reads the manifest at `path`, refusing anything inconsistent with the file and the byte.
    pub fn read(path: &Path) -> Result<Manifest, BlockFileError> {
        let mut f = TaskFile::open(path, &[Kind::Manifest])?;
        let (s, at) = f.section(SPLT, 0)?.unwrap_or_default();
        if s.len() != SPLT_LEN {
            return Err(f.error(at, format!("SPLT is {} bytes, not {SPLT_LEN}", s.len())));
        }
        let mut r = Fields(&s);
        let [input_vertices, polygons, triangles, dropped_triangles] = [(); 4].map(|_| r.u64());
        let (depth, frame) = (r.u32(), r.u32());
        let sample = (r.u64(), r.u64());
        let bounds = r.bounds();
        let used_bounds = r.bounds();
        if depth > 31 || frame > 1 {
            return Err(f.error(
                at + 32,
                format!("depth {depth} or frame {frame} out of range"),
            ));
        }
        let (t, at) = f.section(TREE, 0)?.unwrap_or_default();
        let n_cuts = (1usize << depth) - 1;
        if t.len() != 16 * n_cuts {
            return Err(f.error(at, format!("TREE is {} bytes for {n_cuts} cuts", t.len())));
        }
        let mut r = Fields(&t);
        let cuts: Vec<Cut> = (0..n_cuts)
            .map(|_| Cut {
                axis: r.u32(),
                index: r.u32(),
                value: r.f64(),
            })
            .collect();
        if let Some(i) = cuts.iter().position(|c| c.axis > 2 || c.value.is_nan()) {
            return Err(f.error(at + 16 * i as u64, "a cut with no axis or no value"));
        }
        let (c, at) = f.section(CELL, 0)?.unwrap_or_default();
        if c.len() != 40 << depth {
            return Err(f.error(
                at,
                format!("CELL is {} bytes for {} cells", c.len(), 1 << depth),
            ));
        }
        let mut r = Fields(&c);
        let cells = (0..1usize << depth)
            .map(|_| {
                let [vertices, faces, border] = [(); 3].map(|_| r.u64());
                let crc = [(); 3].map(|_| r.u32());
                let _reserved = r.u32();
                CellEntry {
                    vertices,
                    faces,
                    border,
                    crc,
                }
            })
            .collect();
        Ok(Manifest {
            input_vertices,
            polygons,
            triangles,
            dropped_triangles,
            sample,
            bounds,
            used_bounds,
            frame,
            depth,
            cuts,
            cells,
        })
    }
}

/// Little-endian fields of a section, in order (the caller checked the length).
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (head, rest) = self.0.split_at(N);
        self.0 = rest;
        head.try_into().expect("N bytes")
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
    fn bounds(&mut self) -> Option<BoundingBox> {
        let min = DVec3::new(self.f64(), self.f64(), self.f64());
        let max = DVec3::new(self.f64(), self.f64(), self.f64());
        (min.is_finite() && max.is_finite() && min.cmple(max).all())
            .then_some(BoundingBox { min, max })
    }
}

/// The names of cell `k`'s files in `dir`.
pub(super) fn cell_paths(dir: &Path, k: usize) -> [PathBuf; 3] {
    ["vert", "face", "border"].map(|ext| dir.join(format!("c{k}.{ext}")))
}

/// A vertex record: input index u32, reserved u32, position (input frame) f64 × 3.
pub(super) fn vertex_record(index: u32, p: DVec3) -> [u8; RECORD] {
    let mut r = [0u8; RECORD];
    r[..4].copy_from_slice(&index.to_le_bytes());
    for (k, x) in p.to_array().into_iter().enumerate() {
        r[8 + 8 * k..16 + 8 * k].copy_from_slice(&x.to_le_bytes());
    }
    r
}

/// A triangle of a cell's `face` file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct FaceRecord {
    /// Its place in the triangulation (its triangle, and corners `3t..3t + 3`).
    pub triangle: u64,
    /// The input polygon it comes from.
    pub polygon: u64,
    /// Its input vertices, in the polygon's order.
    pub vertices: [u32; 3],
    /// The cell that owns it (of its first vertex).
    pub owner: u32,
}

impl FaceRecord {
    pub(super) fn bytes(&self) -> [u8; RECORD] {
        let mut r = [0u8; RECORD];
        r[..8].copy_from_slice(&self.triangle.to_le_bytes());
        r[8..16].copy_from_slice(&self.polygon.to_le_bytes());
        for (k, v) in self.vertices.into_iter().chain([self.owner]).enumerate() {
            r[16 + 4 * k..20 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        r
    }

    fn parse(r: &[u8]) -> FaceRecord {
        let word = |k: usize| u32::from_le_bytes(r[k..k + 4].try_into().expect("4 bytes"));
        FaceRecord {
            triangle: u64::from_le_bytes(r[..8].try_into().expect("8 bytes")),
            polygon: u64::from_le_bytes(r[8..16].try_into().expect("8 bytes")),
            vertices: [word(16), word(20), word(24)],
            owner: word(28),
        }
    }
}

/// One cell's file being appended to through a bounded buffer, its checksum kept as it grows.
struct Appended {
    path: PathBuf,
    buffer: Vec<u8>,
    crc: crc32fast::Hasher,
    records: u64,
}

/// The files of one kind (`vert`, `face` or `border`) of every cell, each behind a buffer of
/// at most `limit` bytes; written under the name `NAME.part`, renamed by [`Self::finish`].
pub(super) struct CellWriters {
    files: Vec<Appended>,
    limit: usize,
}

/// The temporary name a split file is written under before its rename.
pub(super) fn part(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".part");
    path.with_file_name(name)
}

/// A failed write of a split file `path`.
pub(super) fn write_error(path: &Path, e: std::io::Error) -> BlockFileError {
    BlockFileError::new(path, 0, format!("cannot write: {e}"))
}

impl CellWriters {
    /// Empty files at `paths` (their `.part` names), one per cell.
    pub(super) fn create(paths: Vec<PathBuf>, limit: usize) -> Result<CellWriters, BlockFileError> {
        let mut files = Vec::with_capacity(paths.len());
        for path in paths {
            let p = part(&path);
            std::fs::File::create(&p).map_err(|e| write_error(&p, e))?;
            files.push(Appended {
                path,
                buffer: Vec::new(),
                crc: crc32fast::Hasher::new(),
                records: 0,
            });
        }
        Ok(CellWriters {
            files,
            limit: limit.max(RECORD),
        })
    }

    /// Appends `record` to cell `k`'s file.
    pub(super) fn push(&mut self, k: usize, record: &[u8; RECORD]) -> Result<(), BlockFileError> {
        let limit = self.limit;
        let f = &mut self.files[k];
        if f.buffer.len() + RECORD > limit {
            flush(f)?;
        }
        f.buffer.extend_from_slice(record);
        f.records += 1;
        Ok(())
    }

    /// Flushes every buffer and renames the files into place; returns each file's record
    /// count and checksum.
    pub(super) fn finish(mut self) -> Result<Vec<(u64, u32)>, BlockFileError> {
        let mut out = Vec::with_capacity(self.files.len());
        for f in &mut self.files {
            flush(f)?;
            std::fs::rename(part(&f.path), &f.path).map_err(|e| write_error(&f.path, e))?;
            out.push((f.records, f.crc.clone().finalize()));
        }
        Ok(out)
    }
}

fn flush(f: &mut Appended) -> Result<(), BlockFileError> {
    if f.buffer.is_empty() {
        return Ok(());
    }
    let p = part(&f.path);
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(&p)
        .map_err(|e| write_error(&p, e))?;
    file.write_all(&f.buffer).map_err(|e| write_error(&p, e))?;
    f.crc.update(&f.buffer);
    f.buffer.clear();
    Ok(())
}

/// Removes the files a failed split made, complete or `.part`.
pub(super) fn remove_made(paths: impl IntoIterator<Item = PathBuf>) {
    for p in paths {
        let _ = std::fs::remove_file(part(&p));
        let _ = std::fs::remove_file(&p);
    }
}

/// The whole of a cell file, checked against the manifest's record count and checksum.
fn read_checked(path: &Path, records: u64, crc: u32) -> Result<Vec<u8>, BlockFileError> {
    let bytes = std::fs::read(path)
        .map_err(|e| BlockFileError::new(path, 0, format!("cannot read: {e}")))?;
    let want = records.saturating_mul(RECORD as u64);
    if bytes.len() as u64 != want {
        let what = format!("{} bytes where the manifest says {want}", bytes.len());
        return Err(BlockFileError::new(
            path,
            bytes.len().min(want as usize) as u64,
            what,
        ));
    }
    if crc32fast::hash(&bytes) != crc {
        return Err(BlockFileError::new(
            path,
            0,
            "checksum mismatch with the manifest",
        ));
    }
    Ok(bytes)
}

/// The vertices of a `vert` or `border` file: strictly ascending indices, finite positions.
pub(super) fn read_vertices(
    path: &Path,
    records: u64,
    crc: u32,
) -> Result<Vec<(u32, DVec3)>, BlockFileError> {
    let bytes = read_checked(path, records, crc)?;
    let mut out: Vec<(u32, DVec3)> = Vec::with_capacity(records as usize);
    for (i, r) in bytes.chunks_exact(RECORD).enumerate() {
        let mut f = Fields(r);
        let index = f.u32();
        let _reserved = f.u32();
        let p = DVec3::new(f.f64(), f.f64(), f.f64());
        if out.last().is_some_and(|l| l.0 >= index) || !p.is_finite() {
            let what = format!("vertex {index} out of order or not finite");
            return Err(BlockFileError::new(path, (i * RECORD) as u64, what));
        }
        out.push((index, p));
    }
    Ok(out)
}

/// The triangles of a `face` file: strictly ascending, three distinct vertices, owner below
/// `cells`.
pub(super) fn read_faces(
    path: &Path,
    entry: &CellEntry,
    cells: u32,
) -> Result<Vec<FaceRecord>, BlockFileError> {
    let bytes = read_checked(path, entry.faces, entry.crc[1])?;
    let mut out: Vec<FaceRecord> = Vec::with_capacity(entry.faces as usize);
    for (i, r) in bytes.chunks_exact(RECORD).enumerate() {
        let f = FaceRecord::parse(r);
        let [a, b, c] = f.vertices;
        let ordered = out.last().is_none_or(|l| l.triangle < f.triangle);
        if !ordered || a == b || b == c || a == c || f.owner >= cells {
            let what = format!("triangle {} is out of order or malformed", f.triangle);
            return Err(BlockFileError::new(path, (i * RECORD) as u64, what));
        }
        out.push(f);
    }
    Ok(out)
}
