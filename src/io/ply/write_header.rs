//! The writer's choices (position, face length and index types) and the PLY header it
//! writes.

use std::fmt::Write as _;

use super::corners::{corner_lists, table_comments};
use super::types::type_name;
use crate::io::{IoError, MeshFormat, PlyEncoding, err_invalid};
use crate::mesh::{ElementProperty, ListProperty, Materials, PolygonMesh, ScalarType};

/// The types the writer stores positions, face lengths and face indices in.
pub(super) struct Layout {
    /// `double` positions (else `float`).
    pub(super) pos_double: bool,
    /// `uchar` unless a face has more than 255 corners (then `uint`).
    pub(super) count_type: ScalarType,
    /// `int` unless there are more vertices than `int` holds (then `uint`).
    pub(super) index_type: ScalarType,
    /// The face lists of the corner attributes (before the mesh's own face lists).
    pub(super) corner_lists: Vec<ListProperty>,
    /// The mesh's comments, then those that store its tables.
    pub(super) comments: Vec<String>,
}

impl Layout {
    /// Every face list property in the order the face element holds them.
    pub(super) fn face_lists<'a>(
        &'a self,
        mesh: &'a PolygonMesh,
    ) -> impl Iterator<Item = &'a ListProperty> + 'a {
        self.corner_lists.iter().chain(&mesh.face_lists)
    }
}

impl Layout {
    /// The layout for `mesh`. Positions: `double` for f64 data, `float` for f32 data (an
    /// error if a value does not fit); untyped (or integer) positions are written as `float`
    /// when every value is an f32 value and as `double` otherwise, so the write is lossless
    /// unless the mesh says its positions are f32.
    pub(super) fn of(mesh: &PolygonMesh, materials: &Materials) -> Result<Layout, IoError> {
        let pos_double = match mesh.position_type {
            Some(ScalarType::F64) => true,
            Some(ScalarType::F32) => {
                if let Some(i) = mesh.positions.iter().position(|p| !p.as_vec3().is_finite()) {
                    return Err(err_invalid(
                        MeshFormat::Ply,
                        format!("vertex {i} does not fit in float (set position_type to F64)"),
                    ));
                }
                false
            }
            _ => mesh.positions.iter().any(|p| p.as_vec3().as_dvec3() != *p),
        };
        let max_len = mesh.faces().map(|f| f.len()).max().unwrap_or(0);
        let count_type = if max_len <= 255 {
            ScalarType::U8
        } else {
            ScalarType::U32
        };
        let index_type = if mesh.positions.len() <= i32::MAX as usize {
            ScalarType::I32
        } else {
            ScalarType::U32
        };
        let mut corner_lists = corner_lists(mesh);
        for l in &mut corner_lists {
            let longest = l.starts.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
            if longest > 255 {
                l.count_type = ScalarType::U32;
            }
        }
        let mut comments = mesh.comments.clone();
        comments.extend(table_comments(mesh, materials));
        Ok(Layout {
            pos_double,
            count_type,
            index_type,
            corner_lists,
            comments,
        })
    }
}

/// The header: format, comments, then `vertex`, `face` and the extra elements.
pub(super) fn header_text(mesh: &PolygonMesh, encoding: PlyEncoding, layout: &Layout) -> String {
    let mut h = String::new();
    h.push_str("ply\n");
    h.push_str(match encoding {
        PlyEncoding::Ascii => "format ascii 1.0\n",
        PlyEncoding::BinaryLittleEndian => "format binary_little_endian 1.0\n",
        PlyEncoding::BinaryBigEndian => "format binary_big_endian 1.0\n",
    });
    for c in &layout.comments {
        let _ = writeln!(h, "comment {c}");
    }
    push_vertex_element(&mut h, mesh, layout);
    push_face_element(&mut h, mesh, layout);
    push_extra_elements(&mut h, mesh);
    h.push_str("end_header\n");
    h
}

fn push_vertex_element(h: &mut String, mesh: &PolygonMesh, layout: &Layout) {
    let pt = if layout.pos_double { "double" } else { "float" };
    let _ = writeln!(h, "element vertex {}", mesh.positions.len());
    for c in ["x", "y", "z"] {
        let _ = writeln!(h, "property {pt} {c}");
    }
    for a in &mesh.vertex_attributes {
        let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
    }
}

fn push_face_element(h: &mut String, mesh: &PolygonMesh, layout: &Layout) {
    let _ = writeln!(h, "element face {}", mesh.n_faces());
    let _ = writeln!(
        h,
        "property list {} {} vertex_indices",
        type_name(layout.count_type),
        type_name(layout.index_type)
    );
    for l in layout.face_lists(mesh) {
        push_list_property(h, l);
    }
    for a in &mesh.face_attributes {
        let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
    }
}

fn push_extra_elements(h: &mut String, mesh: &PolygonMesh) {
    for e in &mesh.extra_elements {
        let _ = writeln!(h, "element {} {}", e.name, e.rows);
        for p in &e.properties {
            match p {
                ElementProperty::Scalar(a) => {
                    let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
                }
                ElementProperty::List(l) => push_list_property(h, l),
            }
        }
    }
}

fn push_list_property(h: &mut String, l: &ListProperty) {
    let _ = writeln!(
        h,
        "property list {} {} {}",
        type_name(l.count_type),
        type_name(l.item_type),
        l.name
    );
}
