//! Wavefront OBJ reader and writer.
//!
//! Hand-written rather than built on `tobj`: tobj re-indexes vertices per model/group (its
//! `add_vertex` keeps an index map per mesh), so vertex count and order are not kept and
//! unreferenced vertices disappear, and its `LoadError` carries no line number. Here the
//! vertices are exactly the `v` lines in file order, and every error names its line.
//!
//! What is read:
//! - `v x y z [w] [r g b]`: positions (float or double, see below); `w` becomes the
//!   attribute `w` (f64, 1 where absent) when any vertex has one; colours become `red`, `green`,
//!   `blue` (f32) when every vertex has them (otherwise they are dropped).
//! - `vt u [v [w]]`, `vn x y z` and `f` corners `v`, `v/vt`, `v//vn`, `v/vt/vn` (negative indices
//!   count back from the latest element). When there are as many `vt` (`vn`) as `v` and every
//!   corner refers to the entry of its own vertex (`f 1/1/1 …`, as the writer emits per-vertex
//!   data), they become the per-vertex attributes `u`,`v` (`nx`,`ny`,`nz`, f32). Otherwise they
//!   are per corner, with their seams: the corner attribute `texcoord` (`normal`) holds every
//!   `vt` (`vn`) line as its pool and each corner's index into it
//!   ([`crate::mesh::CornerAttribute`]), so a file reads back to the same lines and indices.
//!   A third texture coordinate is dropped.
//! - `usemtl`, `g`, `o` and `s` give every face after them a material, group, object and
//!   smoothing group: the face attributes of [`crate::mesh::corners`], with the names in
//!   [`PolygonMesh::materials`], [`PolygonMesh::group_names`] and
//!   [`PolygonMesh::object_names`] in order of first use; `mtllib` files are
//!   [`crate::mesh::Materials::libraries`]. Reading from a path ([`crate::io::read_mesh`]) also
//!   reads those files for each material's `map_Kd` image; a missing file, a material no
//!   library defines or a missing image is a warning, not an error.
//! - polygons are kept as they are (no triangulation).
//! - `#` comments before the first statement become [`PolygonMesh::comments`]; `l`, `p` and
//!   other statements are skipped (lines and points are not kept). Line continuation (`\`) and
//!   CRLF are handled.
//!
//! Precision: OBJ text does not say whether it holds float or double data. When every
//! coordinate has at most 9 significant digits (and fits a float) the positions are read as
//! f32 values with `position_type = Some(F32)`, otherwise as exact f64 parses with
//! `position_type = None`. The writer uses shortest f32 formatting for f32 data (and for
//! untyped positions that are all f32 values) and shortest f64 formatting otherwise, so
//! write → read is bit-exact either way.
//!
//! The writer emits the comments, `mtllib`, `v` (with `w` and colours when those attributes
//! exist), `vt` (the `texcoord` pool, else per-vertex `u`,`v`), `vn` (the `normal` pool, else
//! per-vertex `nx`,`ny`,`nz`), and `f` lines, with `o`, `g`, `usemtl` and `s` before the faces
//! where their values change. Other attributes have no place in OBJ and are not written. A
//! mesh with materials but no library (read from a PLY file) gets one written beside it
//! ([`crate::io::write_mesh_with`]).

use super::IoError;
use crate::mesh::{Materials, PolygonMesh};

pub(super) mod mtl;
mod read;
mod statements;
mod write;

/// Reads an OBJ file.
pub(crate) fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    read::read(bytes)
}

/// Writes an OBJ file with `materials` in place of the mesh's (their paths rebased).
pub(crate) fn write(mesh: &PolygonMesh, materials: &Materials) -> Result<Vec<u8>, IoError> {
    write::write(mesh, materials)
}
