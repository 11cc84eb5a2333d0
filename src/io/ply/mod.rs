//! PLY reader and writer (ASCII, binary little endian, binary big endian).
//!
//! Hand-written rather than built on `ply-rs-bw`, for three reasons: speed (the binary path
//! decodes fixed-layout vertex rows column by column and has a tight loop for the common
//! `list uchar int vertex_indices` face layout, with no per-element maps), bounded allocation
//! (every element count is checked against the bytes that remain before anything is
//! allocated) and error locations (byte offsets for binary bodies, lines for ASCII).
//!
//! Mapping onto [`PolygonMesh`]:
//! - `vertex`: `x`,`y`,`z` (any scalar type; `position_type` records it when all three agree)
//!   become positions, every
//!   other scalar property becomes a vertex attribute in file order.
//! - `face`: the list `vertex_indices` (or `vertex_index`) gives the polygons; other scalar
//!   properties become face attributes; `texcoord` (two values per corner) becomes the corner
//!   attribute `texcoord` and other lists are kept in `face_lists` (see `corners` for them and
//!   for the `TextureFile` comments).
//! - other elements are kept verbatim in `extra_elements`; `comment` and `obj_info` lines are
//!   kept in `comments` (an `obj_info` line becomes the comment `obj_info …`).
//! - list properties on `vertex` cannot be represented and are rejected with an error.
//!
//! The writer emits `vertex` (`double` positions when `position_type` is `F64`, `float` when it
//! is `F32`; otherwise `float` if every coordinate is an f32 value and `double` if not), then
//! `face` (`list uchar int vertex_indices`, or `uint` counts for polygons with more than 255
//! corners; then the corner lists, the face lists and the scalar face properties), then the
//! extra elements.
//!
//! Layout of the module: [`read()`] parses the header (`header`), checks the vertex count and
//! reads element by element (`reader`: a plan per property from `plan`, then the binary fast
//! paths of `fast` or the value-by-value reader of `rows` over the sources of `source`).
//! [`write()`] validates the mesh (`validate`), chooses the stored types and writes the header
//! (`write_header`), then the body (`write_body`). `types` holds the PLY type names.

use super::{IoError, PlyEncoding};
use crate::mesh::{Materials, PolygonMesh};
use corners::comments_to_tables;
use header::parse_header;
use reader::{BodyReader, vertex_count};
use validate::validate;
use write_body::{ascii_body, binary_body};
use write_header::{Layout, header_text};

mod corners;
mod fast;
mod header;
mod plan;
mod reader;
mod rows;
mod source;
pub(crate) mod stream;
mod types;
mod validate;
mod write_body;
mod write_header;

/// Reads a PLY file (any encoding).
pub(crate) fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let header = parse_header(bytes)?;
    let nv = vertex_count(&header)?;
    let mut body = BodyReader::new(bytes, &header, nv);
    let mut mesh = PolygonMesh::new();
    mesh.comments = header.comments;
    for el in &header.elements {
        body.read_element(el, &mut mesh)?;
    }
    body.finish(&mut mesh);
    comments_to_tables(&mut mesh);
    Ok(mesh)
}

/// The vertex and face counts a PLY header announces, from the head of the file (which must
/// hold the whole header), for an estimate before the body is read. `None` when the header is
/// malformed, or when `body_len` (the file's length, when known) cannot hold the rows the
/// counts claim: the reader then says what is wrong.
pub(crate) fn header_counts(head: &[u8], file_len: Option<u64>) -> Option<(u64, u64)> {
    let header = parse_header(head).ok()?;
    let nv = vertex_count(&header).ok()?;
    if let Some(len) = file_len {
        let ascii = header.encoding == PlyEncoding::Ascii;
        let mut need = 0u64;
        for el in &header.elements {
            let plans = plan::plan_element(el, &plan::Role::of(el)).ok()?;
            need = need.saturating_add(el.count.saturating_mul(plan::min_row_bytes(&plans, ascii)));
        }
        // ASCII: the last row may lack its line break.
        if need > len.saturating_sub(header.body as u64) + u64::from(ascii) {
            return None;
        }
    }
    let nf = header
        .elements
        .iter()
        .find(|e| e.name == "face")
        .map_or(0, |e| e.count);
    Some((nv, nf))
}

/// Writes a PLY file with `materials` in place of the mesh's (their paths rebased).
pub(crate) fn write(
    mesh: &PolygonMesh,
    materials: &Materials,
    encoding: PlyEncoding,
) -> Result<Vec<u8>, IoError> {
    let layout = Layout::of(mesh, materials)?;
    validate(mesh, &layout)?;
    let header = header_text(mesh, encoding, &layout);
    Ok(match encoding {
        PlyEncoding::Ascii => ascii_body(header, mesh, &layout).into_bytes(),
        PlyEncoding::BinaryLittleEndian => binary_body(header.into_bytes(), mesh, &layout, false),
        PlyEncoding::BinaryBigEndian => binary_body(header.into_bytes(), mesh, &layout, true),
    })
}
