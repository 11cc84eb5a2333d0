//! Writing a mesh as PLY: the header and the ASCII or binary body.

use std::fmt::Write as _;

use super::types::type_name;
use super::validate::validate;
use crate::io::text;
use crate::io::{IoError, MeshFormat, PlyEncoding, err_invalid};
use crate::mesh::{AttributeData, ElementProperty, PolygonMesh, ScalarType};

/// Appends one value of `col` (row `i`) to a binary body.
pub(super) fn put_bin(out: &mut Vec<u8>, col: &AttributeData, i: usize, big: bool) {
    macro_rules! put {
        ($v:expr) => {
            if big {
                out.extend_from_slice(&$v.to_be_bytes())
            } else {
                out.extend_from_slice(&$v.to_le_bytes())
            }
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
pub(super) fn put_txt(out: &mut String, col: &AttributeData, i: usize) {
    match col {
        AttributeData::F32(v) => text::push_f32(out, v[i]),
        AttributeData::F64(v) => text::push_f64(out, v[i]),
        _ => {
            let _ = write!(out, "{}", col.get_f64(i) as i64);
        }
    }
}

/// Appends `x` (exactly representable in `t`) in type `t`.
pub(super) fn put_num_bin(out: &mut Vec<u8>, x: f64, t: ScalarType, big: bool) {
    macro_rules! put {
        ($v:expr) => {
            if big {
                out.extend_from_slice(&$v.to_be_bytes())
            } else {
                out.extend_from_slice(&$v.to_le_bytes())
            }
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

pub(super) fn put_num_txt(out: &mut String, x: f64, t: ScalarType) {
    match t {
        ScalarType::F32 => text::push_f32(out, x as f32),
        ScalarType::F64 => text::push_f64(out, x),
        _ => {
            let _ = write!(out, "{}", x as i64);
        }
    }
}

/// Writes a PLY file.
pub fn write(mesh: &PolygonMesh, encoding: PlyEncoding) -> Result<Vec<u8>, IoError> {
    validate(mesh)?;
    let nv = mesh.positions.len();
    let nf = mesh.n_faces();
    // Positions: keep double for double input; float otherwise, unless a value would overflow.
    // Positions: `double` for f64 data, `float` for f32 data; untyped (or integer) positions
    // are written as `float` when every value is an f32 value and as `double` otherwise, so
    // the write is lossless unless the mesh says its positions are f32.
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
    let index_type = if nv <= i32::MAX as usize {
        ScalarType::I32
    } else {
        ScalarType::U32
    };

    let mut h = String::new();
    h.push_str("ply\n");
    h.push_str(match encoding {
        PlyEncoding::Ascii => "format ascii 1.0\n",
        PlyEncoding::BinaryLittleEndian => "format binary_little_endian 1.0\n",
        PlyEncoding::BinaryBigEndian => "format binary_big_endian 1.0\n",
    });
    for c in &mesh.comments {
        let _ = writeln!(h, "comment {c}");
    }
    let pt = if pos_double { "double" } else { "float" };
    let _ = writeln!(h, "element vertex {nv}");
    for c in ["x", "y", "z"] {
        let _ = writeln!(h, "property {pt} {c}");
    }
    for a in &mesh.vertex_attributes {
        let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
    }
    let _ = writeln!(h, "element face {nf}");
    let _ = writeln!(
        h,
        "property list {} {} vertex_indices",
        type_name(count_type),
        type_name(index_type)
    );
    for a in &mesh.face_attributes {
        let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
    }
    for e in &mesh.extra_elements {
        let _ = writeln!(h, "element {} {}", e.name, e.rows);
        for p in &e.properties {
            match p {
                ElementProperty::Scalar(a) => {
                    let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
                }
                ElementProperty::List(l) => {
                    let _ = writeln!(
                        h,
                        "property list {} {} {}",
                        type_name(l.count_type),
                        type_name(l.item_type),
                        l.name
                    );
                }
            }
        }
    }
    h.push_str("end_header\n");

    match encoding {
        PlyEncoding::Ascii => {
            let mut s = h;
            let prec = if pos_double {
                text::TextPrecision::F64
            } else {
                text::TextPrecision::F32
            };
            for (i, p) in mesh.positions.iter().enumerate() {
                for (k, c) in p.to_array().into_iter().enumerate() {
                    if k > 0 {
                        s.push(' ');
                    }
                    let _ = prec.push(&mut s, c);
                }
                for a in &mesh.vertex_attributes {
                    s.push(' ');
                    put_txt(&mut s, &a.data, i);
                }
                s.push('\n');
            }
            for (f, face) in mesh.faces().enumerate() {
                let _ = write!(s, "{}", face.len());
                for &v in face {
                    let _ = write!(s, " {v}");
                }
                for a in &mesh.face_attributes {
                    s.push(' ');
                    put_txt(&mut s, &a.data, f);
                }
                s.push('\n');
            }
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
                            ElementProperty::Scalar(a) => put_txt(&mut s, &a.data, r),
                            ElementProperty::List(l) => {
                                let items =
                                    &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
                                let _ = write!(s, "{}", items.len());
                                for &x in items {
                                    s.push(' ');
                                    put_num_txt(&mut s, x, l.item_type);
                                }
                            }
                        }
                    }
                    s.push('\n');
                }
            }
            Ok(s.into_bytes())
        }
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let big = encoding == PlyEncoding::BinaryBigEndian;
            let mut out = h.into_bytes();
            let vsize = if pos_double { 24 } else { 12 }
                + mesh
                    .vertex_attributes
                    .iter()
                    .map(|a| a.data.scalar_type().size())
                    .sum::<usize>();
            out.reserve(nv * vsize + nf + mesh.face_indices.len() * 4);
            for (i, p) in mesh.positions.iter().enumerate() {
                for c in p.to_array() {
                    if pos_double {
                        put_num_bin(&mut out, c, ScalarType::F64, big);
                    } else {
                        put_num_bin(&mut out, c, ScalarType::F32, big);
                    }
                }
                for a in &mesh.vertex_attributes {
                    put_bin(&mut out, &a.data, i, big);
                }
            }
            for (f, face) in mesh.faces().enumerate() {
                put_num_bin(&mut out, face.len() as f64, count_type, big);
                for &v in face {
                    if big {
                        out.extend_from_slice(&v.to_be_bytes());
                    } else {
                        out.extend_from_slice(&v.to_le_bytes());
                    }
                }
                for a in &mesh.face_attributes {
                    put_bin(&mut out, &a.data, f, big);
                }
            }
            for e in mesh
                .extra_elements
                .iter()
                .filter(|e| !e.properties.is_empty())
            {
                for r in 0..e.rows {
                    for p in &e.properties {
                        match p {
                            ElementProperty::Scalar(a) => put_bin(&mut out, &a.data, r, big),
                            ElementProperty::List(l) => {
                                let items =
                                    &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
                                put_num_bin(&mut out, items.len() as f64, l.count_type, big);
                                for &x in items {
                                    put_num_bin(&mut out, x, l.item_type, big);
                                }
                            }
                        }
                    }
                }
            }
            Ok(out)
        }
    }
}
