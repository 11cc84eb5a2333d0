//! The `CRNR` section (2.2): what a textured input holds besides `ATTR`, i.e. its corner
//! attributes (pools and per-corner indices), its other face lists, its materials with the
//! files they name, and its group and object names (see [`crate::mesh::corners`]). Written
//! only for an input that has any of them, and marked required: a 2.1 reader refuses such a
//! file rather than restoring the mesh without its texture.

use crate::format::FormatError;
use crate::format::varint::{ByteReader, put_uvarint};
use crate::mesh::{CornerAttribute, Material, NO_VALUE, PolygonMesh};

use super::attributes::{
    put_attribute, put_list_property, put_str, read_attribute, read_list_property, read_str,
};
use super::corrupt;

/// True when the input has something for `CRNR`.
pub(super) fn has_corner_data(m: &PolygonMesh) -> bool {
    !m.corner_attributes.is_empty()
        || !m.face_lists.is_empty()
        || !m.materials.is_empty()
        || !m.group_names.is_empty()
        || !m.object_names.is_empty()
}

/// `CRNR`: corner attributes, face lists, material libraries and materials, the folder their
/// paths start from, group and object names.
pub(super) fn encode_corners(m: &PolygonMesh) -> Vec<u8> {
    let mut out = Vec::new();
    put_uvarint(&mut out, m.corner_attributes.len() as u64);
    for a in &m.corner_attributes {
        put_str(&mut out, &a.name);
        put_uvarint(&mut out, a.pool_len() as u64);
        put_uvarint(&mut out, a.columns.len() as u64);
        for c in &a.columns {
            put_attribute(&mut out, c);
        }
        // Index + 1, 0 for none: neighbouring corners mostly share nearby rows, so small
        // varints.
        for &i in &a.indices {
            put_uvarint(&mut out, if i == NO_VALUE { 0 } else { u64::from(i) + 1 });
        }
    }
    put_uvarint(&mut out, m.face_lists.len() as u64);
    for l in &m.face_lists {
        put_list_property(&mut out, l);
    }
    put_strs(&mut out, &m.materials.libraries);
    put_uvarint(&mut out, m.materials.list.len() as u64);
    for mat in &m.materials.list {
        put_str(&mut out, &mat.name);
        put_optional(&mut out, mat.texture.as_deref());
    }
    let folder = m.materials.folder.as_ref().map(|f| f.to_string_lossy());
    put_optional(&mut out, folder.as_deref());
    put_strs(&mut out, &m.group_names);
    put_strs(&mut out, &m.object_names);
    out
}

fn put_strs(out: &mut Vec<u8>, list: &[String]) {
    put_uvarint(out, list.len() as u64);
    for s in list {
        put_str(out, s);
    }
}

fn put_optional(out: &mut Vec<u8>, s: Option<&str>) {
    match s {
        None => out.push(0),
        Some(s) => {
            out.push(1);
            put_str(out, s);
        }
    }
}

/// Reads `CRNR` into `m`, whose polygons are already there (they give the row counts).
pub(super) fn decode_corners(
    r: &mut ByteReader<'_>,
    m: &mut PolygonMesh,
) -> Result<(), FormatError> {
    let n = r.count(r.remaining() as u64 / 3, "corner attribute count")?;
    for _ in 0..n {
        let a = read_corner_attribute(r, m.face_indices.len())?;
        m.corner_attributes.push(a);
    }
    let n = r.count(r.remaining() as u64 / 3, "face list count")?;
    for _ in 0..n {
        let l = read_list_property(r, m.n_faces())?;
        m.face_lists.push(l);
    }
    m.materials.libraries = read_strs(r)?;
    let n = r.count(r.remaining() as u64 / 2, "material count")?;
    for _ in 0..n {
        let name = read_str(r)?;
        let texture = read_optional(r)?;
        m.materials.list.push(Material { name, texture });
    }
    m.materials.folder = read_optional(r)?.map(Into::into);
    m.group_names = read_strs(r)?;
    m.object_names = read_strs(r)?;
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in CRNR"));
    }
    Ok(())
}

fn read_corner_attribute(
    r: &mut ByteReader<'_>,
    corners: usize,
) -> Result<CornerAttribute, FormatError> {
    let name = read_str(r)?;
    let pool = r.count(r.remaining() as u64, "corner pool length")?;
    let n_cols = r.count(r.remaining() as u64 / 2, "corner column count")?;
    let mut columns = Vec::with_capacity(n_cols);
    for _ in 0..n_cols {
        columns.push(read_attribute(r, pool)?);
    }
    if corners > r.remaining() {
        return Err(FormatError::Truncated {
            offset: r.offset(),
            what: "corner indices".into(),
        });
    }
    let mut indices = Vec::with_capacity(corners);
    for _ in 0..corners {
        let at = r.offset();
        let i = r.count(pool as u64, "corner index")?;
        indices.push(match i {
            0 => NO_VALUE,
            i => u32::try_from(i - 1).map_err(|_| corrupt(at, "corner index too large"))?,
        });
    }
    Ok(CornerAttribute {
        name,
        columns,
        indices,
    })
}

fn read_strs(r: &mut ByteReader<'_>) -> Result<Vec<String>, FormatError> {
    let n = r.count(r.remaining() as u64, "name count")?;
    (0..n).map(|_| read_str(r)).collect()
}

fn read_optional(r: &mut ByteReader<'_>) -> Result<Option<String>, FormatError> {
    let at = r.offset();
    match r.array::<1>("optional string")? {
        [0] => Ok(None),
        [1] => Ok(Some(read_str(r)?)),
        [k] => Err(corrupt(at, format!("bad optional string tag {k}"))),
    }
}
