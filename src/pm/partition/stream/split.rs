//! [`split_into_cells`]: steps 1–5 of the streaming split (the module docs of `stream`), one
//! read of the input.

use super::SplitError;
use super::files::{
    CellEntry, CellWriters, FaceRecord, Manifest, RECORD, cell_paths, part, read_faces,
    remove_made, vertex_record, write_error,
};
use super::sample::Reservoir;
use super::tree::{CutTree, depth_for};
use crate::io::ply::stream::{PlyStream, Rows};
use crate::mesh::BoundingBox;
use crate::pm::partition::cells::FRAMES;
use crate::pm::partition::taskfile::BlockFileError;
use glam::DVec3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// How the streaming split cuts and buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitOptions {
    /// The block size: a cell holds at most about this many vertices (exactly at most when the
    /// sample holds every vertex; within the sample's error otherwise).
    pub block_vertices: usize,
    /// Bytes of the write buffer of each cell file (at least one 32-byte record).
    pub buffer_bytes: usize,
    /// Capacity of the reservoir sample the cuts are taken from (32 bytes a point).
    pub sample_size: usize,
}

impl SplitOptions {
    /// Cells of `block_vertices`, 64 KiB buffers and a sample of 4M points (128 MB), enough for
    /// cells within a few per cent of the block size on meshes of billions of vertices.
    pub fn new(block_vertices: usize) -> SplitOptions {
        SplitOptions {
            block_vertices,
            buffer_bytes: 64 << 10,
            sample_size: super::sample::SAMPLE_SIZE,
        }
    }
}

/// Rows decoded at a time.
const CHUNK_ROWS: usize = 1 << 16;

/// Splits the PLY file `input` (uncompressed, vertices before faces) into cell files in `dir` (which must exist; the names are in
/// `formats/blocks.md`, "Cell files") and writes `dir/manifest`, which it returns.
///
/// The files depend on the input's vertices and faces only (not on its encoding, nor on the
/// buffer size): a split run twice writes the same bytes. Every file is written under a
/// temporary name and renamed once complete; on error every file it made is removed. Memory
/// is bounded by the sample, the tree and one buffer per cell (the module docs of `stream`).
pub fn split_into_cells(
    input: &Path,
    dir: &Path,
    options: &SplitOptions,
) -> Result<Manifest, SplitError> {
    let stream = PlyStream::open(input)?;
    let mut made: Vec<PathBuf> = Vec::new();
    let result = split(&stream, input, dir, options, &mut made);
    if result.is_err() {
        remove_made(made);
    }
    result
}

fn split(
    stream: &PlyStream,
    input: &Path,
    dir: &Path,
    options: &SplitOptions,
    made: &mut Vec<PathBuf>,
) -> Result<Manifest, SplitError> {
    let (nv, nf) = (stream.n_vertices(), stream.n_faces());
    let positions_path = dir.join("positions.f64");
    made.push(positions_path.clone());
    let part = part(&positions_path);
    let file = std::fs::File::create(&part).map_err(|e| write_error(&part, e))?;
    let mut s = Splitter {
        dir,
        options,
        made,
        positions_path,
        positions: Some(std::io::BufWriter::with_capacity(
            options.buffer_bytes.max(RECORD),
            file,
        )),
        bounds: None,
        sample: Some(Reservoir::new(options.sample_size, nv, nf)),
        faces: None,
    };
    stream.read(CHUNK_ROWS, |rows| match rows {
        Rows::Vertices { first, positions } => s.vertices(first, positions),
        Rows::Faces {
            first,
            starts,
            indices,
        } => s.faces()?.triangles(input, first, starts, indices),
    })?;
    s.faces()?;
    let Splitter {
        positions_path,
        bounds,
        faces,
        ..
    } = s;
    let Faces {
        tree,
        sampled,
        paths,
        vert,
        labels,
        writers,
        counts,
    } = faces.expect("made by faces()");
    drop(labels);
    let face = writers.finish()?;
    let mut cells: Vec<CellEntry> = (0..paths.len())
        .map(|k| CellEntry {
            vertices: vert[k].0,
            faces: face[k].0,
            border: 0,
            crc: [vert[k].1, face[k].1, 0],
        })
        .collect();
    let used_bounds = borders(&positions_path, &paths, &mut cells, options)?;
    let manifest = Manifest {
        input_vertices: nv,
        polygons: counts.polygons,
        triangles: counts.triangles,
        dropped_triangles: counts.dropped,
        sample: (options.sample_size.max(1) as u64, sampled),
        bounds,
        used_bounds,
        frame: 0,
        depth: tree.depth,
        cuts: tree.cuts,
        cells,
    };
    manifest.write(&dir.join("manifest"))?;
    Ok(manifest)
}

/// The split while the input streams by: steps 1 on the vertices, 2 and 3 when the first face
/// comes (or the input ends), 4 on the faces.
struct Splitter<'a> {
    dir: &'a Path,
    options: &'a SplitOptions,
    made: &'a mut Vec<PathBuf>,
    positions_path: PathBuf,
    /// Step 1's writer of `positions.f64`, until the first face.
    positions: Option<std::io::BufWriter<std::fs::File>>,
    bounds: Option<BoundingBox>,
    sample: Option<Reservoir>,
    /// Step 4's state, from the first face on.
    faces: Option<Faces>,
}

/// What step 4 works with: the tree, the cells' files and the labels, and what it counted.
struct Faces {
    tree: CutTree,
    sampled: u64,
    paths: Vec<[PathBuf; 3]>,
    /// Each `vert` file's record count and checksum.
    vert: Vec<(u64, u32)>,
    labels: Option<memmap2::Mmap>,
    writers: CellWriters,
    counts: Counts,
}

impl Splitter<'_> {
    /// Step 1: a chunk of positions to `positions.f64` (24 bytes a vertex), the bounding box
    /// and the sample.
    fn vertices(&mut self, first: u64, positions: &[DVec3]) -> Result<(), SplitError> {
        let part = part(&self.positions_path);
        let (Some(w), Some(sample)) = (&mut self.positions, &mut self.sample) else {
            let what = "vertices after the faces";
            return Err(BlockFileError::new(&part, 0, what).into());
        };
        for (i, &p) in positions.iter().enumerate() {
            let bytes: Vec<u8> = p.to_array().iter().flat_map(|x| x.to_le_bytes()).collect();
            w.write_all(&bytes).map_err(|e| write_error(&part, e))?;
            let b = self
                .bounds
                .map_or(BoundingBox { min: p, max: p }, |b| b.including(p));
            self.bounds = Some(b);
            sample.offer((first + i as u64) as u32, p);
        }
        Ok(())
    }

    /// Steps 2 and 3 once, when the vertices end; then step 4's state.
    fn faces(&mut self) -> Result<&mut Faces, SplitError> {
        if self.faces.is_none() {
            let part = part(&self.positions_path);
            if let Some(mut w) = self.positions.take() {
                w.flush().map_err(|e| write_error(&part, e))?;
            }
            std::fs::rename(&part, &self.positions_path)
                .map_err(|e| write_error(&self.positions_path, e))?;
            let mut sample = self.sample.take().expect("taken once");
            let sampled = sample.points.len() as u64;
            let nv = std::fs::metadata(&self.positions_path).map_or(0, |m| m.len() / 24);
            let depth = depth_for(nv, sampled, self.options.block_vertices);
            let tree = CutTree::from_sample(&mut sample.points, depth, FRAMES[0]);
            drop(sample);
            let dir = self.dir;
            let labels_path = dir.join("cell_of.u32");
            self.made.push(labels_path.clone());
            let paths: Vec<[PathBuf; 3]> =
                (0..1usize << depth).map(|k| cell_paths(dir, k)).collect();
            self.made.extend(paths.iter().flatten().cloned());
            let vert = labels(
                &self.positions_path,
                &labels_path,
                &tree,
                &paths,
                self.options,
            )?;
            let face_paths = paths.iter().map(|p| p[1].clone()).collect();
            let writers = CellWriters::create(face_paths, self.options.buffer_bytes)?;
            self.faces = Some(Faces {
                tree,
                sampled,
                paths,
                vert,
                labels: map(&labels_path)?,
                writers,
                counts: Counts {
                    polygons: 0,
                    triangles: 0,
                    dropped: 0,
                },
            });
        }
        Ok(self.faces.as_mut().expect("made above"))
    }
}

/// A read-only map of a file this split wrote (`None` when it is empty).
fn map(path: &Path) -> Result<Option<memmap2::Mmap>, BlockFileError> {
    let failed = |e: std::io::Error| BlockFileError::new(path, 0, format!("cannot read: {e}"));
    let file = std::fs::File::open(path).map_err(failed)?;
    if file.metadata().map_err(failed)?.len() == 0 {
        return Ok(None);
    }
    // SAFETY: the file is one this split wrote in its own folder and renamed into place; it
    // is not written again while the map lives.
    Ok(Some(unsafe { memmap2::Mmap::map(&file) }.map_err(failed)?))
}

/// The position of vertex `v` in a map of `positions.f64`.
fn position_at(positions: &[u8], v: u32) -> DVec3 {
    let at = 24 * v as usize;
    let x = |k: usize| f64::from_le_bytes(positions[at + k..at + k + 8].try_into().expect("8"));
    DVec3::new(x(0), x(8), x(16))
}

/// Step 3: every vertex's cell to `cell_of.u32` and the vertex to its cell's `vert` file;
/// returns each `vert` file's record count and checksum.
fn labels(
    positions_path: &Path,
    out: &Path,
    tree: &CutTree,
    paths: &[[PathBuf; 3]],
    options: &SplitOptions,
) -> Result<Vec<(u64, u32)>, BlockFileError> {
    let positions = map(positions_path)?;
    let positions: &[u8] = positions.as_deref().unwrap_or(&[]);
    let part = part(out);
    let file = std::fs::File::create(&part).map_err(|e| write_error(&part, e))?;
    let mut w = std::io::BufWriter::with_capacity(options.buffer_bytes.max(RECORD), file);
    let vert_paths = paths.iter().map(|p| p[0].clone()).collect();
    let mut cells = CellWriters::create(vert_paths, options.buffer_bytes)?;
    for v in 0..(positions.len() / 24) as u32 {
        let p = position_at(positions, v);
        let k = tree.locate(v, p);
        w.write_all(&k.to_le_bytes())
            .map_err(|e| write_error(&part, e))?;
        cells.push(k as usize, &vertex_record(v, p))?;
    }
    w.flush().map_err(|e| write_error(&part, e))?;
    drop(w);
    std::fs::rename(&part, out).map_err(|e| write_error(out, e))?;
    cells.finish()
}

/// What step 4 counted.
struct Counts {
    polygons: u64,
    triangles: u64,
    dropped: u64,
}

impl Faces {
    /// Step 4: a chunk of polygons fan-triangulated as the mesh builder does, each triangle to
    /// the `face` file of every cell holding one of its vertices.
    fn triangles(
        &mut self,
        input: &Path,
        first: u64,
        starts: &[u32],
        indices: &[u32],
    ) -> Result<(), SplitError> {
        let labels: &[u8] = self.labels.as_deref().unwrap_or(&[]);
        let cell_of = |v: u32| {
            let at = 4 * v as usize;
            u32::from_le_bytes(labels[at..at + 4].try_into().expect("4 bytes"))
        };
        // The builder numbers corners 3t..3t + 3 in 32 bits.
        let max_triangles = (u32::MAX / 3) as u64;
        let counts = &mut self.counts;
        for (i, w) in starts.windows(2).enumerate() {
            let polygon = first + i as u64;
            let poly = &indices[w[0] as usize..w[1] as usize];
            counts.polygons += 1;
            for k in 1..poly.len().saturating_sub(1) {
                let t = [poly[0], poly[k], poly[k + 1]];
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    counts.dropped += 1;
                    continue;
                }
                if counts.triangles >= max_triangles {
                    let what = format!("polygon {polygon}: more than {max_triangles} triangles");
                    return Err(BlockFileError::new(input, 0, what).into());
                }
                let cells = t.map(cell_of);
                let record = FaceRecord {
                    triangle: counts.triangles,
                    polygon,
                    vertices: t,
                    owner: cells[0],
                }
                .bytes();
                counts.triangles += 1;
                for (j, &k) in cells.iter().enumerate() {
                    if !cells[..j].contains(&k) {
                        self.writers.push(k as usize, &record)?;
                    }
                }
            }
        }
        Ok(())
    }
}

/// Step 5: each cell's `border` file (the positions of the other cells' vertices its triangles
/// use, ascending), its count and checksum in `cells`; returns the bounding box of the
/// vertices with triangles.
fn borders(
    positions_path: &Path,
    paths: &[[PathBuf; 3]],
    cells: &mut [CellEntry],
    options: &SplitOptions,
) -> Result<Option<BoundingBox>, BlockFileError> {
    let positions = map(positions_path)?;
    let positions: &[u8] = positions.as_deref().unwrap_or(&[]);
    let mut used: Option<BoundingBox> = None;
    let n_cells = cells.len() as u32;
    for (k, entry) in cells.iter_mut().enumerate() {
        let faces = read_faces(&paths[k][1], entry, n_cells)?;
        let own = super::files::read_vertices(&paths[k][0], entry.vertices, entry.crc[0])?;
        let is_own = |v: u32| own.binary_search_by_key(&v, |x| x.0).is_ok();
        let mut border: Vec<u32> = Vec::new();
        for f in &faces {
            for v in f.vertices {
                if is_own(v) {
                    let p = position_at(positions, v);
                    used = Some(used.map_or(BoundingBox { min: p, max: p }, |b| b.including(p)));
                } else {
                    border.push(v);
                }
            }
        }
        border.sort_unstable();
        border.dedup();
        let mut w = CellWriters::create(vec![paths[k][2].clone()], options.buffer_bytes)?;
        for v in border {
            w.push(0, &vertex_record(v, position_at(positions, v)))?;
        }
        let [(n, crc)] = <[(u64, u32); 1]>::try_from(w.finish()?).expect("one file");
        entry.border = n;
        entry.crc[2] = crc;
    }
    Ok(used)
}
