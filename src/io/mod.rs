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
//!   properties, face list properties (`texcoord` per corner), `TextureFile` comments as
//!   materials, extra elements, comments; `obj_info` lines are kept as comments). List
//!   properties on `vertex` have no place in [`PolygonMesh`] and are rejected with an error.
//! - **OBJ** (`obj`): positions, `w`, vertex colours, texture coordinates and normals (per
//!   vertex when the file indexes them so, else per corner with their pools and seams),
//!   `mtllib`/`usemtl` materials, `g`/`o`/`s` groups. `l`/`p` and other statements are skipped;
//!   `#` lines before the first statement become [`PolygonMesh::comments`].
//! - Textured meshes: see [`crate::mesh::corners`] for the model and `references` (below) for
//!   the files they name: referenced, never copied; rebased when written elsewhere; missing
//!   ones are warnings of [`read_mesh_reporting`]. [`texture_data_not_held`] says what OFF and
//!   STL cannot hold.
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

use crate::mesh::{Materials, PolygonMesh};

pub(crate) mod atomic;
mod fuzz;
mod gz;
pub(crate) mod obj;
pub(crate) mod off;
pub(crate) mod ply;
mod references;
pub(crate) mod stl;
mod text;

#[doc(hidden)]
pub use atomic::hold_writes_for_tests;
pub use atomic::{exit_removing_temporary_files, write_atomic, write_atomic_with};
pub(crate) use fuzz::fuzz_read;
pub(crate) use gz::head_of_gz;
pub use gz::{gunzip, gzip};

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

/// Reads a mesh file; the format comes from the extension. `.gz` files are decompressed as a
/// stream, dropping the comments the reader would discard, so a small file that inflates to
/// gigabytes of comment text reads in little memory. The warnings of
/// [`read_mesh_reporting`] (missing material libraries and images) are dropped.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<PolygonMesh, IoError> {
    Ok(read_mesh_reporting(path)?.0)
}

/// [`read_mesh`], with a line for each file the mesh names that is missing: a material
/// library, an image, or a material no library defines (see [`crate::mesh::Materials`]).
pub fn read_mesh_reporting(path: impl AsRef<Path>) -> Result<(PolygonMesh, Vec<String>), IoError> {
    let path = path.as_ref();
    if path.is_dir() {
        return Err(IoError::Io {
            path: path.to_path_buf(),
            error: std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a directory, not a mesh file",
            ),
        });
    }
    let format = MeshFormat::from_path(path)?;
    let bytes = if is_gzip(path) {
        gz::read_gz_file(path, format)?
    } else {
        std::fs::read(path).map_err(|error| IoError::Io {
            path: path.to_path_buf(),
            error,
        })?
    };
    let mut mesh = read_mesh_bytes(&bytes, format).map_err(|e| e.with_path(path))?;
    let warnings = references::resolve(&mut mesh, path, format);
    Ok((mesh, warnings))
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

/// What of `mesh`'s texture side (per-corner data, materials, groups, per-face lists) a file
/// of `format` cannot hold: one line, or `None` when it holds all of it. OBJ holds all but the
/// per-face lists; PLY all; OFF and STL none.
pub fn texture_data_not_held(mesh: &PolygonMesh, format: MeshFormat) -> Option<String> {
    let mut what = Vec::new();
    let plain = matches!(format, MeshFormat::Off | MeshFormat::Stl);
    if plain {
        what.extend(
            mesh.corner_attributes
                .iter()
                .map(|a| format!("per-corner {}", a.name)),
        );
        if !mesh.materials.is_empty() {
            what.push("materials".to_string());
        }
        if !mesh.group_names.is_empty() || !mesh.object_names.is_empty() {
            what.push("groups".to_string());
        }
    }
    if format != MeshFormat::Ply {
        what.extend(
            mesh.face_lists
                .iter()
                .map(|l| format!("face list {}", l.name)),
        );
    }
    (!what.is_empty()).then(|| {
        format!(
            "{format} cannot hold the mesh's {}; they are not written",
            what.join(", ")
        )
    })
}

/// Writes a mesh atomically with default options; the format comes from the extension.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &PolygonMesh) -> Result<(), IoError> {
    write_mesh_with(path.as_ref(), mesh, &WriteOptions::default())
}

/// Writes a mesh atomically (see [`write_atomic`]); the format comes from the extension.
/// The mesh is encoded completely before the file system is touched, so a rejected mesh
/// leaves any existing file as it was.
///
/// Material libraries and images are referenced, not copied: relative references are
/// rewritten to reach the same files from `path`'s folder. An OBJ output of a mesh with
/// materials but no library (read from PLY) gets `NAME.mtl` written beside it.
pub fn write_mesh_with(
    path: &Path,
    mesh: &PolygonMesh,
    opts: &WriteOptions,
) -> Result<(), IoError> {
    let format = MeshFormat::from_path(path)?;
    let mut materials = references::rebased(&mesh.materials, path);
    let sidecar = match format {
        MeshFormat::Obj => references::sidecar_library(&materials, path),
        _ => None,
    };
    if let Some((file, _)) = &sidecar {
        let name = file.file_name().unwrap_or_default().to_string_lossy();
        materials.libraries.push(name.into_owned());
    }
    let mut bytes = encode(mesh, &materials, format, opts).map_err(|e| e.with_path(path))?;
    if is_gzip(path) {
        bytes = gzip(&bytes);
    }
    if let Some((file, text)) = sidecar {
        write_atomic(&file, text.as_bytes())?;
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
    encode(mesh, &mesh.materials, format, opts)
}

/// [`write_mesh_bytes`] for bytes whose file's folder is not known (a download): relative
/// references to material libraries and images are written absolute (from the folder the
/// mesh was read from), so that they reach the same files wherever the bytes are saved on
/// this machine. A mesh with materials but no library (read from PLY) gets no `mtllib` in an
/// OBJ: there is no file beside it to hold one.
pub fn write_mesh_bytes_detached(
    mesh: &PolygonMesh,
    format: MeshFormat,
    opts: &WriteOptions,
) -> Result<Vec<u8>, IoError> {
    encode(mesh, &references::anchored(&mesh.materials), format, opts)
}

/// [`write_mesh_bytes`] with `materials` in place of the mesh's.
fn encode(
    mesh: &PolygonMesh,
    materials: &Materials,
    format: MeshFormat,
    opts: &WriteOptions,
) -> Result<Vec<u8>, IoError> {
    mesh.check().map_err(|r| err_invalid(format, r))?;
    if mesh.positions.len() > u32::MAX as usize {
        return Err(err_invalid(format, "more than 2^32 - 1 vertices"));
    }
    match format {
        MeshFormat::Obj => obj::write(mesh, materials),
        MeshFormat::Ply => ply::write(mesh, materials, opts.ply_encoding),
        MeshFormat::Off => off::write(mesh),
        MeshFormat::Stl => stl::write(mesh, opts.stl_binary),
    }
}
