//! Reading and writing OBJ, PLY, OFF and STL files.
//!
//! Readers produce a [`PolygonMesh`] that keeps the file's data as it is: vertex count and order
//! (unreferenced vertices included), face order, polygons (no triangulation), attribute columns
//! and PLY extra elements. Writers emit a [`PolygonMesh`] unchanged, so read → write → read is
//! bit-exact for positions, faces and attributes wherever the format can hold them.
//!
//! All readers are hand-written, bounded-allocation parsers: every count taken from a header is
//! checked against the bytes that remain before anything is allocated, and every error names
//! the place (line for text formats, byte offset for binary ones), see [`IoError`].
//!
//! Format notes (what survives and what does not):
//! - **PLY** (`ply`): everything (positions in their stored type, all scalar vertex/face
//!   properties, extra elements, comments; `obj_info` lines are kept as comments). List
//!   properties on `vertex`, and list properties other than the indices on `face`, have no
//!   place in [`PolygonMesh`] and are rejected with an error.
//! - **OBJ** (`obj`): positions, `w`, vertex colours, and texture coordinates/normals when they
//!   are consistent per vertex. `o`/`g`/`s`/`usemtl`/`mtllib`, `l`/`p` and other statements are
//!   skipped; `#` lines before the first statement become [`PolygonMesh::comments`].
//! - **OFF** (`off`): positions, `C`/`N`/`ST` vertex data, per-face colours when every face has
//!   one.
//! - **STL** (`stl`): triangles, welded by exact f32 bit equality; file normals are dropped
//!   (the writer recomputes them and fan-triangulates polygons).
//!
//! Precision: `position_type` says how positions are stored. PLY records it; for OBJ/OFF text a
//! file whose coordinates all have at most 9 significant digits is float data (`Some(F32)`),
//! otherwise double (`None`, exact f64 parses). Writers keep f32 data in f32 (shortest
//! round-trip text, or `float`), f64 data in f64, and write untyped positions as f32 only when
//! every value is an f32 value, so writing never loses precision unless the mesh says `F32`
//! (STL is always f32).

use std::fmt;
use std::path::{Path, PathBuf};

use crate::mesh::PolygonMesh;

mod atomic;
pub(crate) mod obj;
pub(crate) mod off;
pub(crate) mod ply;
pub(crate) mod stl;
mod text;

pub use atomic::write_atomic;

/// The mesh file formats meshpyr reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// Stanford PLY (`.ply`), ASCII or binary.
    Ply,
    /// Object File Format (`.off`).
    Off,
    /// Stereolithography (`.stl`), ASCII or binary.
    Stl,
}

impl MeshFormat {
    /// The format named by the path's extension (case-insensitive); a trailing `.gz` names
    /// a gzip-compressed file of the format before it (`scan.ply.gz` is PLY).
    pub fn from_path(path: &Path) -> Result<MeshFormat, IoError> {
        let inner = if is_gzip(path) {
            Path::new(path.file_stem().unwrap_or_default())
        } else {
            path
        };
        let ext = inner
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            Some("off") => Ok(MeshFormat::Off),
            Some("stl") => Ok(MeshFormat::Stl),
            _ => Err(IoError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }

    /// The usual file extension, lower case without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Ply => "ply",
            MeshFormat::Off => "off",
            MeshFormat::Stl => "stl",
        }
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Off => "OFF",
            MeshFormat::Stl => "STL",
        })
    }
}

/// PLY body encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum PlyEncoding {
    /// `format ascii 1.0`
    Ascii,
    /// `format binary_little_endian 1.0` (the default)
    #[default]
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`
    BinaryBigEndian,
}

/// Options for the writers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WriteOptions {
    /// PLY body encoding (default: binary little endian).
    pub ply_encoding: PlyEncoding,
    /// Write binary STL (default) rather than ASCII STL.
    pub stl_binary: bool,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            ply_encoding: PlyEncoding::BinaryLittleEndian,
            stl_binary: true,
        }
    }
}

/// Where in a file an error was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// No particular place (e.g. a problem with the whole file).
    None,
    /// 1-based line number (text formats and PLY headers).
    Line(u64),
    /// 0-based byte offset (binary formats).
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::None => Ok(()),
            Location::Line(l) => write!(f, "line {l}: "),
            Location::Byte(b) => write!(f, "byte {b}: "),
        }
    }
}

/// Renders an optional path as `"path: "`, or nothing.
struct PathPrefix<'a>(&'a Option<PathBuf>);

impl fmt::Display for PathPrefix<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(p) => write!(f, "{}: ", p.display()),
            None => Ok(()),
        }
    }
}

/// Errors from reading or writing mesh files. `Display` is a single line naming the file (when
/// known), the place in it and the reason, e.g.
/// `bunny.ply: byte 1234: face 17 has index 40000 but the file has 37706 vertices`.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system refused a read, write, rename, ….
    #[error("{}: {error}", path.display())]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error (part of the message, not a separate cause, so the one-line
        /// report does not repeat it).
        error: std::io::Error,
    },
    /// The file's content is malformed or unsupported.
    #[error("{}{location}{reason}", PathPrefix(path))]
    Parse {
        /// The file, when reading from a path.
        path: Option<PathBuf>,
        /// Where the problem is.
        location: Location,
        /// What is wrong (one line).
        reason: String,
    },
    /// The extension is not one of `.obj`, `.ply`, `.off`, `.stl` (optionally followed by
    /// `.gz`).
    #[error("{}: unknown mesh format (expected .obj, .ply, .off or .stl, optionally .gz)", path.display())]
    UnknownFormat {
        /// The file whose extension was not recognised.
        path: PathBuf,
    },
    /// The mesh cannot be written (broken invariants, or data the format cannot hold).
    #[error("{}cannot write {format}: {reason}", PathPrefix(path))]
    InvalidMesh {
        /// The target file, when writing to a path.
        path: Option<PathBuf>,
        /// The target format.
        format: MeshFormat,
        /// What is wrong (one line).
        reason: String,
    },
}

impl IoError {
    /// Attaches `path` to errors that do not name a file yet.
    pub(crate) fn with_path(self, p: &Path) -> IoError {
        match self {
            IoError::Parse {
                path: None,
                location,
                reason,
            } => IoError::Parse {
                path: Some(p.to_path_buf()),
                location,
                reason,
            },
            IoError::InvalidMesh {
                path: None,
                format,
                reason,
            } => IoError::InvalidMesh {
                path: Some(p.to_path_buf()),
                format,
                reason,
            },
            e => e,
        }
    }

    /// The location of a parse error, if any.
    pub fn location(&self) -> Option<Location> {
        match self {
            IoError::Parse { location, .. } => Some(*location),
            _ => None,
        }
    }
}

/// A parse error at a line.
pub(crate) fn err_line(line: u64, reason: impl Into<String>) -> IoError {
    IoError::Parse {
        path: None,
        location: Location::Line(line),
        reason: reason.into(),
    }
}

/// A parse error at a byte offset.
pub(crate) fn err_byte(byte: u64, reason: impl Into<String>) -> IoError {
    IoError::Parse {
        path: None,
        location: Location::Byte(byte),
        reason: reason.into(),
    }
}

/// A parse error without a location.
pub(crate) fn err_file(reason: impl Into<String>) -> IoError {
    IoError::Parse {
        path: None,
        location: Location::None,
        reason: reason.into(),
    }
}

/// A writer rejection.
pub(crate) fn err_invalid(format: MeshFormat, reason: impl Into<String>) -> IoError {
    IoError::InvalidMesh {
        path: None,
        format,
        reason: reason.into(),
    }
}

/// True when the path ends in `.gz` (case-insensitive): the file is gzip-compressed.
pub(crate) fn is_gzip(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// Reads a mesh file; the format comes from the extension (`.gz` files are decompressed
/// first, see [`gunzip`]).
pub fn read_mesh(path: impl AsRef<Path>) -> Result<PolygonMesh, IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let mut bytes = std::fs::read(path).map_err(|error| IoError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    if is_gzip(path) {
        bytes = gunzip(&bytes).map_err(|e| e.with_path(path))?;
    }
    read_mesh_bytes(&bytes, format).map_err(|e| e.with_path(path))
}

/// Decompresses gzip data (several concatenated members too, as `cat a.gz b.gz` makes).
///
/// Memory: DEFLATE expands at most about 1032:1, so the output is bounded by the input's size;
/// the mesh readers then check every header count against the decompressed size. A corrupt
/// or truncated stream is a parse error (with the offset into the decompressed data reached).
pub fn gunzip(bytes: &[u8]) -> Result<Vec<u8>, IoError> {
    use std::io::Read;
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(IoError::Parse {
            path: None,
            location: Location::Byte(0),
            reason: "not a gzip file (the name ends in .gz)".into(),
        });
    }
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(bytes)
        .read_to_end(&mut out)
        .map_err(|e| IoError::Parse {
            path: None,
            location: Location::None,
            reason: format!(
                "gzip data is corrupt or truncated after {} decompressed bytes: {e}",
                out.len()
            ),
        })?;
    Ok(out)
}

/// Compresses with gzip (level 6; no file name or time stamp in the header, so the same mesh
/// always gives the same bytes).
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(
        Vec::with_capacity(bytes.len() / 3),
        flate2::Compression::default(),
    );
    enc.write_all(bytes)
        .expect("writing into a Vec cannot fail");
    enc.finish().expect("writing into a Vec cannot fail")
}

/// Parses a mesh from memory.
pub fn read_mesh_bytes(bytes: &[u8], format: MeshFormat) -> Result<PolygonMesh, IoError> {
    let mesh = match format {
        MeshFormat::Obj => obj::read(bytes)?,
        MeshFormat::Ply => ply::read(bytes)?,
        MeshFormat::Off => off::read(bytes)?,
        MeshFormat::Stl => stl::read(bytes)?,
    };
    // The readers establish the invariants themselves (fuzz_read asserts it on every input);
    // debug builds re-check them.
    if cfg!(debug_assertions) {
        mesh.check().map_err(err_file)?;
    }
    Ok(mesh)
}

/// Writes a mesh atomically with default options; the format comes from the extension.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &PolygonMesh) -> Result<(), IoError> {
    write_mesh_with(path.as_ref(), mesh, &WriteOptions::default())
}

/// Writes a mesh atomically (see [`write_atomic`]); the format comes from the extension.
/// The mesh is encoded completely before the file system is touched, so a rejected mesh
/// leaves any existing file as it was.
pub fn write_mesh_with(
    path: &Path,
    mesh: &PolygonMesh,
    opts: &WriteOptions,
) -> Result<(), IoError> {
    let format = MeshFormat::from_path(path)?;
    let mut bytes = write_mesh_bytes(mesh, format, opts).map_err(|e| e.with_path(path))?;
    if is_gzip(path) {
        bytes = gzip(&bytes);
    }
    write_atomic(path, &bytes)
}

/// Encodes a mesh in memory. Fails (without panicking) on meshes that break the
/// [`PolygonMesh`] invariants or hold data the format cannot represent as given.
pub fn write_mesh_bytes(
    mesh: &PolygonMesh,
    format: MeshFormat,
    opts: &WriteOptions,
) -> Result<Vec<u8>, IoError> {
    mesh.check().map_err(|r| err_invalid(format, r))?;
    if mesh.positions.len() > u32::MAX as usize {
        return Err(err_invalid(format, "more than 2^32 - 1 vertices"));
    }
    match format {
        MeshFormat::Obj => obj::write(mesh),
        MeshFormat::Ply => ply::write(mesh, opts.ply_encoding),
        MeshFormat::Off => off::write(mesh),
        MeshFormat::Stl => stl::write(mesh, opts.stl_binary),
    }
}

/// Fuzzing and corpus-replay harness: parses `bytes` as `format`; when that succeeds, writes
/// the mesh (every PLY encoding, both STL flavours), re-reads it and asserts that writing the
/// re-read mesh gives identical bytes, and that PLY encodings agree with each other.
///
/// Panics only on a reader/writer inconsistency (a bug), never because the input is bad.
pub(crate) fn fuzz_read(format: MeshFormat, bytes: &[u8]) {
    let Ok(mesh) = read_mesh_bytes(bytes, format) else {
        return;
    };
    if let Err(e) = mesh.check() {
        panic!("the reader returned a mesh that breaks the invariants: {e}");
    }
    let option_sets: Vec<WriteOptions> = match format {
        MeshFormat::Ply => vec![
            WriteOptions {
                ply_encoding: PlyEncoding::BinaryLittleEndian,
                ..Default::default()
            },
            WriteOptions {
                ply_encoding: PlyEncoding::BinaryBigEndian,
                ..Default::default()
            },
            WriteOptions {
                ply_encoding: PlyEncoding::Ascii,
                ..Default::default()
            },
        ],
        MeshFormat::Stl => vec![
            WriteOptions::default(),
            WriteOptions {
                stl_binary: false,
                ..Default::default()
            },
        ],
        _ => vec![WriteOptions::default()],
    };
    let mut canonical: Option<Vec<u8>> = None;
    for opts in &option_sets {
        let first = write_mesh_bytes(&mesh, format, opts)
            .unwrap_or_else(|e| panic!("writing a mesh the reader accepted failed: {e}"));
        let again = read_mesh_bytes(&first, format)
            .unwrap_or_else(|e| panic!("re-reading our own output failed ({opts:?}): {e}"));
        // Geometry survives the trip bit for bit (STL output is welded on reading, and the
        // STL reader's meshes are already welded).
        let bits = |m: &PolygonMesh| -> Vec<[u64; 3]> {
            m.positions
                .iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect()
        };
        assert!(bits(&again) == bits(&mesh), "positions changed ({opts:?})");
        assert!(
            again.face_starts == mesh.face_starts && again.face_indices == mesh.face_indices,
            "faces changed ({opts:?})"
        );
        let second = write_mesh_bytes(&again, format, opts)
            .unwrap_or_else(|e| panic!("writing the re-read mesh failed: {e}"));
        assert!(
            first == second,
            "write → read → write is not byte-identical ({opts:?})"
        );
        if format != MeshFormat::Ply {
            continue;
        }
        // All PLY encodings must decode to the same mesh: compare via the LE encoding, with
        // NaN payloads made canonical (ASCII writes every NaN as `NaN`).
        let le =
            write_mesh_bytes(&canonical_nans(&again), format, &option_sets[0]).expect("re-encode");
        match &canonical {
            None => canonical = Some(le),
            Some(c) => assert!(*c == le, "PLY encodings disagree ({opts:?})"),
        }
    }
}

/// `mesh` with every NaN attribute value replaced by the canonical NaN.
fn canonical_nans(mesh: &PolygonMesh) -> PolygonMesh {
    use crate::mesh::{AttributeData, ElementProperty};
    fn fix(d: &mut AttributeData) {
        match d {
            AttributeData::F32(v) => v
                .iter_mut()
                .filter(|x| x.is_nan())
                .for_each(|x| *x = f32::NAN),
            AttributeData::F64(v) => v
                .iter_mut()
                .filter(|x| x.is_nan())
                .for_each(|x| *x = f64::NAN),
            _ => {}
        }
    }
    let mut m = mesh.clone();
    m.vertex_attributes
        .iter_mut()
        .for_each(|a| fix(&mut a.data));
    m.face_attributes.iter_mut().for_each(|a| fix(&mut a.data));
    for e in &mut m.extra_elements {
        for p in &mut e.properties {
            match p {
                ElementProperty::Scalar(a) => fix(&mut a.data),
                ElementProperty::List(l) => l
                    .items
                    .iter_mut()
                    .filter(|x| x.is_nan())
                    .for_each(|x| *x = f64::NAN),
            }
        }
    }
    m
}
