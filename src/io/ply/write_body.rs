//! The PLY body: vertex rows, face rows, then the rows of the extra elements, as text or as
//! binary in either byte order.

use std::fmt::Write as _;

use super::write_header::Layout;
use crate::io::text;
use crate::mesh::{AttributeData, ElementProperty, ListProperty, PolygonMesh, ScalarType};

/// Appends the bytes of the number `$v` to `$out`, big endian when `$big`.
macro_rules! put_endian {
    ($out:expr, $big:expr, $v:expr) => {
        if $big {
            $out.extend_from_slice(&$v.to_be_bytes())
        } else {
            $out.extend_from_slice(&$v.to_le_bytes())
        }
    };
}

/// Appends the ASCII body of `mesh` to its header `s`.
pub(super) fn ascii_body(mut s: String, mesh: &PolygonMesh, layout: &Layout) -> String {
    push_ascii_vertices(&mut s, mesh, layout);
    push_ascii_faces(&mut s, mesh, layout);
    push_ascii_extra_elements(&mut s, mesh);
    s
}

/// Appends the binary body of `mesh` to its header `out` (big endian when `big`).
pub(super) fn binary_body(
    mut out: Vec<u8>,
    mesh: &PolygonMesh,
    layout: &Layout,
    big: bool,
) -> Vec<u8> {
    let vsize = if layout.pos_double { 24 } else { 12 }
        + mesh
            .vertex_attributes
            .iter()
            .map(|a| a.data.scalar_type().size())
            .sum::<usize>();
    out.reserve(mesh.positions.len() * vsize + mesh.n_faces() + mesh.face_indices.len() * 4);
    push_binary_vertices(&mut out, mesh, layout, big);
    push_binary_faces(&mut out, mesh, layout, big);
    push_binary_extra_elements(&mut out, mesh, big);
    out
}

fn push_ascii_vertices(s: &mut String, mesh: &PolygonMesh, layout: &Layout) {
    let prec = if layout.pos_double {
        text::TextPrecision::F64
    } else {
        text::TextPrecision::F32
    };
    for (i, p) in mesh.positions.iter().enumerate() {
        for (k, c) in p.to_array().into_iter().enumerate() {
            if k > 0 {
                s.push(' ');
            }
            let _ = prec.push(s, c);
        }
        for a in &mesh.vertex_attributes {
            s.push(' ');
            put_txt(s, &a.data, i);
        }
        s.push('\n');
    }
}

fn push_ascii_faces(s: &mut String, mesh: &PolygonMesh, layout: &Layout) {
    for (f, face) in mesh.faces().enumerate() {
        let _ = write!(s, "{}", face.len());
        for &v in face {
            let _ = write!(s, " {v}");
        }
        for l in layout.face_lists(mesh) {
            s.push(' ');
            put_list_txt(s, l, f);
        }
        for a in &mesh.face_attributes {
            s.push(' ');
            put_txt(s, &a.data, f);
        }
        s.push('\n');
    }
}

/// Elements without properties have no rows in the body.
fn push_ascii_extra_elements(s: &mut String, mesh: &PolygonMesh) {
    for e in &mesh.extra_elements {
        if e.properties.is_empty() {
            continue;
        }
        for r in 0..e.rows {
            for (k, p) in e.properties.iter().enumerate() {
                if k > 0 {
                    s.push(' ');
                }
                match p {
                    ElementProperty::Scalar(a) => put_txt(s, &a.data, r),
                    ElementProperty::List(l) => put_list_txt(s, l, r),
                }
            }
            s.push('\n');
        }
    }
}

fn push_binary_vertices(out: &mut Vec<u8>, mesh: &PolygonMesh, layout: &Layout, big: bool) {
    for (i, p) in mesh.positions.iter().enumerate() {
        for c in p.to_array() {
            if layout.pos_double {
                put_num_bin(out, c, ScalarType::F64, big);
            } else {
                put_num_bin(out, c, ScalarType::F32, big);
            }
        }
        for a in &mesh.vertex_attributes {
            put_bin(out, &a.data, i, big);
        }
    }
}

fn push_binary_faces(out: &mut Vec<u8>, mesh: &PolygonMesh, layout: &Layout, big: bool) {
    for (f, face) in mesh.faces().enumerate() {
        put_num_bin(out, face.len() as f64, layout.count_type, big);
        for &v in face {
            if big {
                out.extend_from_slice(&v.to_be_bytes());
            } else {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        for l in layout.face_lists(mesh) {
            put_list_bin(out, l, f, big);
        }
        for a in &mesh.face_attributes {
            put_bin(out, &a.data, f, big);
        }
    }
}

/// Elements without properties have no rows in the body.
fn push_binary_extra_elements(out: &mut Vec<u8>, mesh: &PolygonMesh, big: bool) {
    for e in mesh
        .extra_elements
        .iter()
        .filter(|e| !e.properties.is_empty())
    {
        for r in 0..e.rows {
            for p in &e.properties {
                match p {
                    ElementProperty::Scalar(a) => put_bin(out, &a.data, r, big),
                    ElementProperty::List(l) => put_list_bin(out, l, r, big),
                }
            }
        }
    }
}

/// Appends row `r` of a list property as text: its length, then its items.
#[inline]
fn put_list_txt(s: &mut String, l: &ListProperty, r: usize) {
    let items = &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
    let _ = write!(s, "{}", items.len());
    for &x in items {
        s.push(' ');
        put_num_txt(s, x, l.item_type);
    }
}

/// Appends row `r` of a list property to a binary body.
#[inline]
fn put_list_bin(out: &mut Vec<u8>, l: &ListProperty, r: usize, big: bool) {
    let items = &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
    put_num_bin(out, items.len() as f64, l.count_type, big);
    for &x in items {
        put_num_bin(out, x, l.item_type, big);
    }
}

/// Appends one value of `col` (row `i`) to a binary body.
fn put_bin(out: &mut Vec<u8>, col: &AttributeData, i: usize, big: bool) {
    macro_rules! put {
        ($v:expr) => {
            put_endian!(out, big, $v)
        };
    }
    match col {
        AttributeData::I8(v) => put!(v[i]),
        AttributeData::U8(v) => put!(v[i]),
        AttributeData::I16(v) => put!(v[i]),
        AttributeData::U16(v) => put!(v[i]),
        AttributeData::I32(v) => put!(v[i]),
        AttributeData::U32(v) => put!(v[i]),
        AttributeData::F32(v) => put!(v[i]),
        AttributeData::F64(v) => put!(v[i]),
    }
}

/// Appends one value of `col` (row `i`) as text.
fn put_txt(out: &mut String, col: &AttributeData, i: usize) {
    match col {
        AttributeData::F32(v) => text::push_f32(out, v[i]),
        AttributeData::F64(v) => text::push_f64(out, v[i]),
        _ => {
            let _ = write!(out, "{}", col.get_f64(i) as i64);
        }
    }
}

/// Appends `x` (exactly representable in `t`) in type `t`.
fn put_num_bin(out: &mut Vec<u8>, x: f64, t: ScalarType, big: bool) {
    macro_rules! put {
        ($v:expr) => {
            put_endian!(out, big, $v)
        };
    }
    match t {
        ScalarType::I8 => put!(x as i8),
        ScalarType::U8 => put!(x as u8),
        ScalarType::I16 => put!(x as i16),
        ScalarType::U16 => put!(x as u16),
        ScalarType::I32 => put!(x as i32),
        ScalarType::U32 => put!(x as u32),
        ScalarType::F32 => put!(x as f32),
        ScalarType::F64 => put!(x),
    }
}

fn put_num_txt(out: &mut String, x: f64, t: ScalarType) {
    match t {
        ScalarType::F32 => text::push_f32(out, x as f32),
        ScalarType::F64 => text::push_f64(out, x),
        _ => {
            let _ = write!(out, "{}", x as i64);
        }
    }
}
