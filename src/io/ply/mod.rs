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
//!   properties become face attributes.
//! - other elements are kept verbatim in `extra_elements`; `comment` and `obj_info` lines are
//!   kept in `comments` (an `obj_info` line becomes the comment `obj_info …`).
//! - list properties on `vertex`, and on `face` other than the indices, cannot be represented
//!   and are rejected with an error.
//!
//! The writer emits `vertex` (`double` positions when `position_type` is `F64`, `float` when it
//! is `F32`; otherwise `float` if every coordinate is an f32 value and `double` if not), then `face` (`list uchar int vertex_indices`, or `uint` counts for
//! polygons with more than 255 corners), then the extra elements.

use super::IoError;
use crate::mesh::PolygonMesh;
use header::parse_header;
use reader::{BodyReader, vertex_count};

mod fast;
mod header;
mod plan;
mod reader;
mod rows;
mod source;
mod types;
mod validate;
mod writer;

/// Reads a PLY file (any encoding).
pub fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let header = parse_header(bytes)?;
    let nv = vertex_count(&header)?;
    let mut body = BodyReader::new(bytes, &header, nv);
    let mut mesh = PolygonMesh::new();
    mesh.comments = header.comments;
    for el in &header.elements {
        body.read_element(el, &mut mesh)?;
    }
    body.finish(&mut mesh);
    Ok(mesh)
}

pub use writer::write;
