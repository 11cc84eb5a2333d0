//! The `ATTR` section: what a mesh file holds besides positions and polygons (the position
//! type, vertex and face attributes, extra elements with their scalar and list properties, and
//! comments), coded so that writing the restored mesh gives back the user's file exactly.

use crate::format::FormatError;
use crate::format::varint::{ByteReader, put_uvarint};
use crate::mesh::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, PolygonMesh, ScalarType,
};

use super::corrupt;

/// The code of a scalar type in the file (0 stands for none where a type is optional).
fn scalar_code(t: ScalarType) -> u8 {
    match t {
        ScalarType::I8 => 1,
        ScalarType::U8 => 2,
        ScalarType::I16 => 3,
        ScalarType::U16 => 4,
        ScalarType::I32 => 5,
        ScalarType::U32 => 6,
        ScalarType::F32 => 7,
        ScalarType::F64 => 8,
    }
}

fn scalar_of(code: u8) -> Option<ScalarType> {
    Some(match code {
        1 => ScalarType::I8,
        2 => ScalarType::U8,
        3 => ScalarType::I16,
        4 => ScalarType::U16,
        5 => ScalarType::I32,
        6 => ScalarType::U32,
        7 => ScalarType::F32,
        8 => ScalarType::F64,
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------------------
// Writing

/// `ATTR`: the position type, the vertex and face attributes, the extra elements and the
/// comments of `m`.
pub(super) fn encode_attributes(m: &PolygonMesh) -> Vec<u8> {
    let mut out = Vec::new();
    out.push(m.position_type.map_or(0, scalar_code));
    for list in [&m.vertex_attributes, &m.face_attributes] {
        put_uvarint(&mut out, list.len() as u64);
        for a in list {
            put_attribute(&mut out, a);
        }
    }
    put_uvarint(&mut out, m.extra_elements.len() as u64);
    for e in &m.extra_elements {
        put_element(&mut out, e);
    }
    put_uvarint(&mut out, m.comments.len() as u64);
    for c in &m.comments {
        put_str(&mut out, c);
    }
    out
}

/// An extra element: name, rows, then each property tagged 0 (scalar) or 1 (list).
fn put_element(out: &mut Vec<u8>, e: &ExtraElement) {
    put_str(out, &e.name);
    put_uvarint(out, e.rows as u64);
    put_uvarint(out, e.properties.len() as u64);
    for p in &e.properties {
        match p {
            ElementProperty::Scalar(a) => {
                out.push(0);
                put_attribute(out, a);
            }
            ElementProperty::List(l) => {
                out.push(1);
                put_list_property(out, l);
            }
        }
    }
}

/// A list property: name, count and item types, the row starts as deltas, then the items as
/// f64.
pub(super) fn put_list_property(out: &mut Vec<u8>, l: &ListProperty) {
    put_str(out, &l.name);
    out.push(scalar_code(l.count_type));
    out.push(scalar_code(l.item_type));
    let mut prev = 0u32;
    for &s in &l.starts {
        put_uvarint(out, u64::from(s.wrapping_sub(prev)));
        prev = s;
    }
    for x in &l.items {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

pub(super) fn put_attribute(out: &mut Vec<u8>, a: &Attribute) {
    put_str(out, &a.name);
    put_column(out, &a.data);
}

fn put_column(out: &mut Vec<u8>, d: &AttributeData) {
    out.push(scalar_code(d.scalar_type()));
    match d {
        AttributeData::I8(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::U8(v) => out.extend_from_slice(v),
        AttributeData::I16(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::U16(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::I32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::U32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::F32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::F64(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
    }
}

pub(super) fn put_str(out: &mut Vec<u8>, s: &str) {
    put_uvarint(out, s.len() as u64);
    out.extend_from_slice(s.as_bytes());
}

// ---------------------------------------------------------------------------------------------
// Reading

/// Reads `ATTR` into `m`, whose positions and polygons are already there (they give the
/// attributes' row counts).
pub(super) fn decode_attributes(
    r: &mut ByteReader<'_>,
    m: &mut PolygonMesh,
) -> Result<(), FormatError> {
    m.position_type = read_position_type(r)?;
    m.vertex_attributes = read_attributes(r, m.positions.len())?;
    m.face_attributes = read_attributes(r, m.n_faces())?;
    let n_el = r.count(r.remaining() as u64 / 3, "element count")?;
    for _ in 0..n_el {
        let e = read_element(r)?;
        m.extra_elements.push(e);
    }
    let n_c = r.count(r.remaining() as u64, "comment count")?;
    for _ in 0..n_c {
        m.comments.push(read_str(r)?);
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in ATTR"));
    }
    Ok(())
}

fn read_position_type(r: &mut ByteReader<'_>) -> Result<Option<ScalarType>, FormatError> {
    let at = r.offset();
    let [pt] = r.array("position type")?;
    Ok(match pt {
        0 => None,
        c => Some(scalar_of(c).ok_or_else(|| corrupt(at, "unknown position type"))?),
    })
}

/// A list of attributes with `rows` values each.
fn read_attributes(r: &mut ByteReader<'_>, rows: usize) -> Result<Vec<Attribute>, FormatError> {
    let count = r.count(r.remaining() as u64 / 2, "attribute count")?;
    let mut list = Vec::with_capacity(count);
    for _ in 0..count {
        list.push(read_attribute(r, rows)?);
    }
    Ok(list)
}

fn read_element(r: &mut ByteReader<'_>) -> Result<ExtraElement, FormatError> {
    let name = read_str(r)?;
    let rows = r.count(u64::from(u32::MAX), "element rows")?;
    let n_prop = r.count(r.remaining() as u64 / 2, "property count")?;
    let mut properties = Vec::with_capacity(n_prop);
    for _ in 0..n_prop {
        let at = r.offset();
        let [kind] = r.array("property kind")?;
        match kind {
            0 => properties.push(ElementProperty::Scalar(read_attribute(r, rows)?)),
            1 => properties.push(ElementProperty::List(read_list_property(r, rows)?)),
            k => return Err(corrupt(at, format!("unknown property kind {k}"))),
        }
    }
    Ok(ExtraElement {
        name,
        rows,
        properties,
    })
}

pub(super) fn read_list_property(
    r: &mut ByteReader<'_>,
    rows: usize,
) -> Result<ListProperty, FormatError> {
    let name = read_str(r)?;
    let count_type = read_scalar_type(r)?;
    let item_type = read_scalar_type(r)?;
    if rows >= r.remaining() {
        return Err(FormatError::Truncated {
            offset: r.offset(),
            what: "list offsets".into(),
        });
    }
    let mut starts = Vec::with_capacity(rows + 1);
    let mut s = 0u64;
    for _ in 0..=rows {
        s += r.count(u64::from(u32::MAX), "list offset")? as u64;
        if s > u64::from(u32::MAX) {
            return Err(corrupt(r.offset(), "list offsets overflow"));
        }
        starts.push(s as u32);
    }
    let n_items = s as usize;
    let bytes = r.take(
        n_items
            .checked_mul(8)
            .ok_or_else(|| corrupt(r.offset(), "list too large"))?,
        "list items",
    )?;
    let items = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
        .collect();
    Ok(ListProperty {
        name,
        count_type,
        item_type,
        starts,
        items,
    })
}

pub(super) fn read_attribute(
    r: &mut ByteReader<'_>,
    rows: usize,
) -> Result<Attribute, FormatError> {
    let name = read_str(r)?;
    let data = read_column(r, rows)?;
    Ok(Attribute { name, data })
}

fn read_column(r: &mut ByteReader<'_>, rows: usize) -> Result<AttributeData, FormatError> {
    let t = read_scalar_type(r)?;
    let bytes = r.take(
        rows.checked_mul(t.size())
            .ok_or_else(|| corrupt(r.offset(), "column too large"))?,
        "attribute values",
    )?;
    macro_rules! col {
        ($v:ident, $ty:ty) => {
            AttributeData::$v(
                bytes
                    .chunks_exact(std::mem::size_of::<$ty>())
                    .map(|c| <$ty>::from_le_bytes(c.try_into().unwrap_or_default()))
                    .collect(),
            )
        };
    }
    Ok(match t {
        ScalarType::I8 => col!(I8, i8),
        ScalarType::U8 => AttributeData::U8(bytes.to_vec()),
        ScalarType::I16 => col!(I16, i16),
        ScalarType::U16 => col!(U16, u16),
        ScalarType::I32 => col!(I32, i32),
        ScalarType::U32 => col!(U32, u32),
        ScalarType::F32 => col!(F32, f32),
        ScalarType::F64 => col!(F64, f64),
    })
}

fn read_scalar_type(r: &mut ByteReader<'_>) -> Result<ScalarType, FormatError> {
    let at = r.offset();
    let [c] = r.array("scalar type")?;
    scalar_of(c).ok_or_else(|| corrupt(at, format!("unknown scalar type {c}")))
}

pub(super) fn read_str(r: &mut ByteReader<'_>) -> Result<String, FormatError> {
    let n = r.count(r.remaining() as u64, "string length")?;
    let at = r.offset();
    let b = r.take(n, "string")?;
    String::from_utf8(b.to_vec()).map_err(|_| corrupt(at, "string is not UTF-8"))
}
