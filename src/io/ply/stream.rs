//! A PLY file read in chunks of rows, vertices then faces, never as a whole mesh: the reader
//! of the streaming split of a scan into cell files (`docs/partitioned.md`, "Splitting a scan
//! into cell files in one pass").
//!
//! Steps: the header is parsed as [`super::read`] parses it; the body is walked element by
//! element in file order with the same plans, room checks and decoders (the binary fast paths
//! and the value-by-value reader), a chunk of rows at a time, and each chunk of positions or
//! faces is handed to the caller and dropped. Other elements are decoded and dropped (binary
//! ones of fixed stride are skipped). Errors are the reader's, with the file's path, the byte
//! or line, and the element's row (not the chunk's).
//!
//! Why a memory map: the decoders read a byte slice; mapping the file gives them one without
//! reading it into memory, and the pages already decoded can be dropped by the kernel, so the
//! process holds a chunk of rows at a time. The file must not change while it is read, which
//! is what any reader of a file assumes.
//!
//! A file whose faces come before its vertices cannot be read in one pass (a face's vertices
//! have no position yet): it is refused with a message that says so.

use super::fast::{float_positions, read_faces_fast, row_stride, scalar_columns};
use super::header::{ElementDef, Header, parse_header};
use super::plan::{Out, Plan, Role, plan_element};
use super::reader::{BodyReader, positions, vertex_count};
use super::rows::read_rows;
use crate::io::{IoError, err_line};
use crate::mesh::{AttributeData, ScalarType};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// An open PLY file, its header parsed.
pub(crate) struct PlyStream {
    path: PathBuf,
    map: Option<memmap2::Mmap>,
    header: Header,
    nv: u64,
}

/// One chunk of a streamed read.
pub(crate) enum Rows<'a> {
    /// Positions of the vertices `first..first + positions.len()`.
    Vertices { first: u64, positions: &'a [DVec3] },
    /// The polygons `first..`: polygon `i` of the chunk has the indices
    /// `indices[starts[i]..starts[i + 1]]` (each below the vertex count).
    Faces {
        first: u64,
        starts: &'a [u32],
        indices: &'a [u32],
    },
}

impl PlyStream {
    /// Opens `path` and parses its header.
    pub(crate) fn open(path: &Path) -> Result<PlyStream, IoError> {
        let io = |error| IoError::Io {
            path: path.to_path_buf(),
            error,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        // SAFETY: the mapping is only read, through byte slices that the decoders bound-check;
        // the module docs state that the file must not change while it is read.
        let map = match len {
            0 => None,
            _ => Some(unsafe { memmap2::Mmap::map(&file) }.map_err(io)?),
        };
        let bytes: &[u8] = map.as_deref().unwrap_or(&[]);
        let header = parse_header(bytes).map_err(|e| e.with_path(path))?;
        let nv = vertex_count(&header).map_err(|e| e.with_path(path))?;
        Ok(PlyStream {
            path: path.to_path_buf(),
            map,
            header,
            nv,
        })
    }

    /// The number of vertices the header announces.
    pub(crate) fn n_vertices(&self) -> u64 {
        self.nv
    }

    /// The number of polygons the header announces.
    pub(crate) fn n_faces(&self) -> u64 {
        let face = self.header.elements.iter().find(|e| e.name == "face");
        face.map_or(0, |e| e.count)
    }

    /// Walks the body to the end of the faces, handing `each` the vertices, then the faces,
    /// `chunk` rows at a time; stops at the first error (the reader's, or `each`'s).
    pub(crate) fn read<E: From<IoError>>(
        &self,
        chunk: usize,
        mut each: impl FnMut(Rows) -> Result<(), E>,
    ) -> Result<(), E> {
        let bytes: &[u8] = self.map.as_deref().unwrap_or(&[]);
        let mut walk = BodyReader::new(bytes, &self.header, self.nv);
        let mut seen_vertices = false;
        for el in &self.header.elements {
            let role = Role::of(el);
            if role == Role::Face && !seen_vertices {
                let what = "the faces come before the vertices: a streamed read needs the \
                            vertices first";
                return Err(err_line(el.line, what).with_path(&self.path).into());
            }
            walk.element(el, &role, chunk.max(1), &mut each)
                .map_err(|e| e.map_io(&self.path))?;
            seen_vertices |= role == Role::Vertex;
            if role == Role::Face {
                break;
            }
        }
        Ok(())
    }
}

/// An error of a streamed read: the reader's (without the path yet) or the caller's.
enum Failed<E> {
    Read(IoError),
    Caller(E),
}

impl<E: From<IoError>> Failed<E> {
    fn map_io(self, path: &Path) -> E {
        match self {
            Failed::Read(e) => e.with_path(path).into(),
            Failed::Caller(e) => e,
        }
    }
}

impl<E> From<IoError> for Failed<E> {
    fn from(e: IoError) -> Self {
        Failed::Read(e)
    }
}

/// The streamed walk uses the whole-file reader's state (`BodyReader`): its sources, its room
/// check and its face context, with chunked decoding of its own below.
impl BodyReader<'_> {
    /// Decodes the rows of `el` chunk by chunk, handing vertices and faces to `each`.
    fn element<E>(
        &mut self,
        el: &ElementDef,
        role: &Role,
        chunk: usize,
        each: &mut impl FnMut(Rows) -> Result<(), E>,
    ) -> Result<(), Failed<E>> {
        let plans = plan_element(el, role)?;
        if plans.is_empty() {
            return Ok(());
        }
        let rows = self.check_room(el, &plans)?;
        let all_scalar = plans.iter().all(|p| matches!(p, Plan::Scalar { .. }));
        if !self.ascii && all_scalar && *role != Role::Vertex {
            // Nothing to check in such rows: the reader keeps them verbatim.
            self.bin.pos += rows * row_stride(&plans);
            return Ok(());
        }
        let mut first = 0;
        while first < rows {
            let n = chunk.min(rows - first);
            let rows = match *role {
                Role::Vertex => {
                    let p = self.vertices(el, &plans, all_scalar, (first, n))?;
                    Some(Chunk::Vertices(p))
                }
                Role::Face => {
                    self.faces(el, &plans, (first, n))?;
                    Some(Chunk::Faces)
                }
                Role::Extra => {
                    self.rows(el, &plans, (first, n))?;
                    None
                }
            };
            let handed = match &rows {
                Some(Chunk::Vertices(p)) => each(Rows::Vertices {
                    first: first as u64,
                    positions: p,
                }),
                Some(Chunk::Faces) => each(Rows::Faces {
                    first: first as u64,
                    starts: &self.ctx.face_starts,
                    indices: &self.ctx.face_indices,
                }),
                None => Ok(()),
            };
            handed.map_err(Failed::Caller)?;
            first += n;
        }
        Ok(())
    }

    /// The positions of `n` vertex rows from row `first`.
    fn vertices(
        &mut self,
        el: &ElementDef,
        plans: &[Plan],
        all_scalar: bool,
        (first, n): (usize, usize),
    ) -> Result<Vec<DVec3>, IoError> {
        if !self.ascii && all_scalar {
            let stride = row_stride(plans);
            let start = self.bin.pos;
            let block = &self.bytes[start..start + n * stride];
            let fast = float_positions(el, block, stride, (start, first), self.big)?;
            let decoded = fast.is_some();
            let outs = scalar_columns(plans, block, stride, (start, first), self.big, decoded)?;
            self.bin.pos += n * stride;
            return Ok(match fast {
                Some(p) => p,
                None => xyz(el, outs),
            });
        }
        let outs = self.rows(el, plans, (first, n))?;
        Ok(xyz(el, outs))
    }

    /// The polygons of `n` face rows from row `first`, left in the context.
    fn faces(
        &mut self,
        el: &ElementDef,
        plans: &[Plan],
        (first, n): (usize, usize),
    ) -> Result<(), IoError> {
        self.ctx.face_starts.clear();
        self.ctx.face_starts.push(0);
        self.ctx.face_indices.clear();
        match *plans {
            [
                Plan::Indices {
                    count,
                    item: item @ (ScalarType::I32 | ScalarType::U32),
                },
            ] if !self.ascii && !self.big => {
                let pos = self.bin.pos;
                self.bin.pos =
                    read_faces_fast(self.bytes, pos, (first, n), count, item, &mut self.ctx)?;
            }
            _ => {
                self.rows(el, plans, (first, n))?;
            }
        }
        Ok(())
    }

    /// `n` rows from row `first`, value by value.
    fn rows(
        &mut self,
        el: &ElementDef,
        plans: &[Plan],
        rows: (usize, usize),
    ) -> Result<Vec<Out>, IoError> {
        match self.ascii {
            true => read_rows(&mut self.asc, el, plans, rows, &mut self.ctx),
            false => read_rows(&mut self.bin, el, plans, rows, &mut self.ctx),
        }
    }
}

/// A decoded chunk, before it is handed on.
enum Chunk {
    Vertices(Vec<DVec3>),
    Faces,
}

/// The positions from the decoded columns `x`, `y`, `z`.
fn xyz(el: &ElementDef, outs: Vec<Out>) -> Vec<DVec3> {
    let mut cols: [Option<AttributeData>; 3] = [None, None, None];
    for (p, out) in el.props.iter().zip(outs) {
        let Out::Col(data) = out else { continue };
        if let Some(k) = ["x", "y", "z"].iter().position(|c| *c == p.name) {
            cols[k] = Some(data);
        }
    }
    match cols {
        [Some(x), Some(y), Some(z)] => positions(&x, &y, &z),
        _ => unreachable!("plan_element requires x, y and z on the vertex element"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{IoError, Location, PlyEncoding};
    use crate::mesh::{Materials, PolygonMesh};

    fn mesh() -> PolygonMesh {
        let positions = (0..30)
            .map(|i| DVec3::new(i as f64 * 0.25, (i % 7) as f64, (i * i % 11) as f64 * 0.5))
            .collect();
        let mut m = PolygonMesh::from_triangles(positions, &[]);
        for i in 0..20u32 {
            match i % 3 {
                0 => m.push_face(&[i, i + 1, i + 2, i + 5]),
                _ => m.push_face(&[i, i + 3, i + 7]),
            }
        }
        m
    }

    fn streamed(path: &Path, chunk: usize) -> Result<(Vec<DVec3>, Vec<Vec<u32>>), IoError> {
        let (mut p, mut f) = (Vec::new(), Vec::new());
        let stream = PlyStream::open(path)?;
        {
            stream.read(chunk, |rows| {
                match rows {
                    Rows::Vertices { first, positions } => {
                        assert_eq!(first as usize, p.len());
                        p.extend_from_slice(positions);
                    }
                    Rows::Faces {
                        first,
                        starts,
                        indices,
                    } => {
                        assert_eq!(first as usize, f.len());
                        for w in starts.windows(2) {
                            f.push(indices[w[0] as usize..w[1] as usize].to_vec());
                        }
                    }
                }
                Ok::<(), IoError>(())
            })?;
        }
        Ok((p, f))
    }

    fn write(dir: &Path, name: &str, m: &PolygonMesh, encoding: PlyEncoding) -> PathBuf {
        let bytes = super::super::write(m, &Materials::default(), encoding).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    #[test]
    fn every_encoding_and_chunk_size_streams_what_the_whole_file_reader_reads() {
        let dir = tempfile::tempdir().unwrap();
        let m = mesh();
        for (k, encoding) in [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ]
        .into_iter()
        .enumerate()
        {
            let path = write(dir.path(), &format!("m{k}.ply"), &m, encoding);
            let whole = super::super::read(&std::fs::read(&path).unwrap()).unwrap();
            let faces: Vec<Vec<u32>> = whole.faces().map(|f| f.to_vec()).collect();
            for chunk in [1, 4, 7, 1000] {
                let (p, f) = streamed(&path, chunk).unwrap();
                assert_eq!(p, whole.positions, "{encoding:?} chunk {chunk}");
                assert_eq!(f, faces, "{encoding:?} chunk {chunk}");
            }
        }
    }

    #[test]
    fn a_damaged_row_is_reported_with_the_file_the_place_and_the_elements_row() {
        let dir = tempfile::tempdir().unwrap();
        let m = mesh();
        let path = write(dir.path(), "a.ply", &m, PlyEncoding::Ascii);
        let text = std::fs::read_to_string(&path).unwrap();
        // Face 13 (the 14th face line) gets an index past the vertices.
        let body = text.find("end_header\n").unwrap() + "end_header\n".len();
        let mut lines: Vec<String> = text[body..].lines().map(String::from).collect();
        lines[30 + 13] = "3 0 1 99".into();
        let bad = format!("{}{}\n", &text[..body], lines.join("\n"));
        std::fs::write(&path, bad).unwrap();
        let e = streamed(&path, 4).unwrap_err();
        let IoError::Parse {
            path: Some(p),
            location,
            reason,
        } = &e
        else {
            panic!("{e}")
        };
        assert_eq!(p, &path);
        assert!(matches!(location, Location::Line(_)), "{e}");
        assert!(reason.contains("face 13 "), "{e}");
    }

    #[test]
    fn every_truncation_of_a_binary_file_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(
            dir.path(),
            "b.ply",
            &mesh(),
            PlyEncoding::BinaryLittleEndian,
        );
        let good = std::fs::read(&path).unwrap();
        let cut = dir.path().join("cut.ply");
        for n in (0..good.len()).step_by(7) {
            std::fs::write(&cut, &good[..n]).unwrap();
            let e = streamed(&cut, 3).unwrap_err();
            assert!(e.to_string().starts_with(&cut.display().to_string()), "{e}");
        }
    }

    #[test]
    fn other_elements_around_the_faces_are_passed_over() {
        let dir = tempfile::tempdir().unwrap();
        let head = "ply\nformat FORMAT 1.0\nelement edge 1\nproperty int a\nproperty int b\n\
                    element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                    element note 2\nproperty list uchar int ids\nproperty double w\n\
                    element face 2\nproperty list uchar int vertex_indices\n\
                    element tail 1\nproperty uchar k\nend_header\n";
        let ascii = "0 1\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 5 6 0.5\n0 1.5\n3 0 1 2\n4 0 2 3 1\n7\n";
        let mut binary = head.replace("FORMAT", "binary_little_endian").into_bytes();
        for x in [0i32, 1] {
            binary.extend(x.to_le_bytes());
        }
        for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
            p.iter().for_each(|c| binary.extend(c.to_le_bytes()));
        }
        for (ids, w) in [(vec![5i32, 6], 0.5f64), (vec![], 1.5)] {
            binary.push(ids.len() as u8);
            ids.iter().for_each(|i| binary.extend(i.to_le_bytes()));
            binary.extend(w.to_le_bytes());
        }
        for f in [vec![0i32, 1, 2], vec![0, 2, 3, 1]] {
            binary.push(f.len() as u8);
            f.iter().for_each(|i| binary.extend(i.to_le_bytes()));
        }
        binary.push(7);
        let a = dir.path().join("a.ply");
        std::fs::write(&a, head.replace("FORMAT", "ascii") + ascii).unwrap();
        let b = dir.path().join("b.ply");
        std::fs::write(&b, binary).unwrap();
        for path in [a, b] {
            let (p, f) = streamed(&path, 1).unwrap();
            assert_eq!(p.len(), 4);
            assert_eq!(p[2], DVec3::new(1.0, 1.0, 0.0));
            assert_eq!(f, vec![vec![0, 1, 2], vec![0, 2, 3, 1]]);
        }
    }

    #[test]
    fn faces_before_vertices_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.ply");
        let text = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n\
                    element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                    end_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n";
        std::fs::write(&path, text).unwrap();
        let e = streamed(&path, 8).unwrap_err();
        assert!(e.to_string().contains("vertices first"), "{e}");
    }
}
