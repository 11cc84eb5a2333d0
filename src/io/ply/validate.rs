//! What the writer checks before writing: names PLY can hold, consistent extra elements.

use super::types::{is_int, type_name};
use super::write_header::Layout;
use crate::io::{IoError, MeshFormat, err_invalid};
use crate::mesh::{ElementProperty, ListProperty, PolygonMesh, ScalarType};

pub(super) fn check_name(name: &str, what: &str) -> Result<(), IoError> {
    if name.is_empty() || name.bytes().any(|b| b.is_ascii_whitespace()) {
        return Err(err_invalid(
            MeshFormat::Ply,
            format!("{what} name {name:?} is empty or contains whitespace"),
        ));
    }
    Ok(())
}

pub(super) fn check_unique<'a>(
    names: impl Iterator<Item = &'a str>,
    reserved: &[&str],
    what: &str,
) -> Result<(), IoError> {
    let mut seen: Vec<&str> = reserved.to_vec();
    for n in names {
        check_name(n, what)?;
        if seen.contains(&n) {
            return Err(err_invalid(
                MeshFormat::Ply,
                format!("{what} name {n:?} is used twice"),
            ));
        }
        seen.push(n);
    }
    Ok(())
}

/// Checks that `x` is exactly representable in `t` (list items are stored as f64).
pub(super) fn fits(x: f64, t: ScalarType) -> bool {
    let int_in = |lo: f64, hi: f64| x.fract() == 0.0 && x >= lo && x <= hi;
    match t {
        ScalarType::I8 => int_in(i8::MIN as f64, i8::MAX as f64),
        ScalarType::U8 => int_in(0.0, u8::MAX as f64),
        ScalarType::I16 => int_in(i16::MIN as f64, i16::MAX as f64),
        ScalarType::U16 => int_in(0.0, u16::MAX as f64),
        ScalarType::I32 => int_in(i32::MIN as f64, i32::MAX as f64),
        ScalarType::U32 => int_in(0.0, u32::MAX as f64),
        ScalarType::F32 => x.is_nan() || (x as f32) as f64 == x,
        ScalarType::F64 => true,
    }
}

pub(super) fn max_count(t: ScalarType) -> u64 {
    match t {
        ScalarType::I8 => i8::MAX as u64,
        ScalarType::U8 => u8::MAX as u64,
        ScalarType::I16 => i16::MAX as u64,
        ScalarType::U16 => u16::MAX as u64,
        ScalarType::I32 => i32::MAX as u64,
        _ => u32::MAX as u64,
    }
}

/// A list property of `rows` rows that PLY can hold as its types say.
fn check_list(l: &ListProperty, rows: usize) -> Result<(), String> {
    if !is_int(l.count_type) {
        return Err(format!("{} has a non-integer count type", l.name));
    }
    if l.starts.len() != rows + 1
        || l.starts[0] != 0
        || *l.starts.last().unwrap_or(&0) as usize != l.items.len()
        || l.starts
            .windows(2)
            .any(|w| w[0] > w[1] || (w[1] - w[0]) as u64 > max_count(l.count_type))
    {
        return Err(format!("list {} has inconsistent offsets", l.name));
    }
    if let Some(x) = l.items.iter().find(|&&x| !fits(x, l.item_type)) {
        return Err(format!(
            "list {} holds {x}, which is not a valid {}",
            l.name,
            type_name(l.item_type)
        ));
    }
    Ok(())
}

pub(super) fn validate(mesh: &PolygonMesh, layout: &Layout) -> Result<(), IoError> {
    for c in &layout.comments {
        if c.contains('\n') || c.ends_with('\r') {
            return Err(err_invalid(
                MeshFormat::Ply,
                format!("comment {c:?} contains a line break"),
            ));
        }
    }
    check_unique(
        mesh.vertex_attributes.iter().map(|a| a.name.as_str()),
        &["x", "y", "z"],
        "vertex attribute",
    )?;
    check_unique(
        mesh.face_attributes
            .iter()
            .map(|a| a.name.as_str())
            .chain(layout.face_lists(mesh).map(|l| l.name.as_str())),
        &["vertex_indices"],
        "face property",
    )?;
    for l in layout.face_lists(mesh) {
        check_list(l, mesh.n_faces())
            .map_err(|what| err_invalid(MeshFormat::Ply, format!("face {what}")))?;
    }
    check_unique(
        mesh.extra_elements.iter().map(|e| e.name.as_str()),
        &["vertex", "face"],
        "element",
    )?;
    for e in &mesh.extra_elements {
        check_unique(
            e.properties.iter().map(|p| match p {
                ElementProperty::Scalar(a) => a.name.as_str(),
                ElementProperty::List(l) => l.name.as_str(),
            }),
            &[],
            "property",
        )?;
        for p in &e.properties {
            let bad =
                |what: &str| err_invalid(MeshFormat::Ply, format!("element {:?}: {what}", e.name));
            match p {
                ElementProperty::Scalar(a) => {
                    if a.data.len() != e.rows {
                        return Err(bad(&format!("{} has {} rows", a.name, a.data.len())));
                    }
                }
                ElementProperty::List(l) => check_list(l, e.rows).map_err(|w| bad(&w))?,
            }
        }
    }
    Ok(())
}
