//! What PLY files store of a textured mesh: per-corner face lists (`texcoord`, MeshLab's
//! layout: `u v` for each corner of the face, in corner order) and the header comments that
//! name textures (`TextureFile`, indexed by the face property `texnumber`) and the names of
//! materials, groups and objects (`meshpyr material|group|object|mtllib NAME`, so that an OBJ
//! converted to PLY and back keeps them).
//!
//! Corner values are read into a pool without repeats (first use first), which is what an
//! OBJ writes as `vt` lines; a face whose list is empty has no values. A face with some
//! corners valued and others not cannot be written as a list: its missing values are written
//! as 0.

use std::collections::HashMap;

use smallvec::SmallVec;

use super::rows::corner_list_width;
use super::types::empty_col;
use crate::mesh::corners::{NORMAL, TEXCOORD};
use crate::mesh::{Attribute, CornerAttribute, ListProperty, Material, NO_VALUE, PolygonMesh};

/// The corner attribute a face list read as `name` becomes, and its column names.
fn corner_name(list: &str, width: usize) -> (String, Vec<String>) {
    match list {
        "texcoord" => (TEXCOORD.into(), vec!["u".into(), "v".into()]),
        "corner_normal" => (NORMAL.into(), ["nx", "ny", "nz"].map(String::from).to_vec()),
        _ => {
            let cols = (0..width).map(|k| format!("{list}_{k}")).collect();
            (list.to_string(), cols)
        }
    }
}

/// The face list with this corner attribute's values (inverse of [`corner_name`]).
fn list_name(a: &CornerAttribute) -> String {
    match a.name.as_str() {
        TEXCOORD => "texcoord".into(),
        NORMAL => "corner_normal".into(),
        n if n.starts_with("corner_") => n.into(),
        n => format!("corner_{n}"),
    }
}

/// Moves the per-corner face lists of a mesh just read into corner attributes.
pub(super) fn lists_to_corners(mesh: &mut PolygonMesh) {
    for l in std::mem::take(&mut mesh.face_lists) {
        match corner_list_width(&l.name).and_then(|_| width(&l, &mesh.face_starts)) {
            Some(w) => {
                let a = corner_attribute(&l, w, &mesh.face_starts);
                mesh.corner_attributes.push(a);
            }
            None => mesh.face_lists.push(l),
        }
    }
}

/// Values per corner when every valued face has the same number (the reader checked that
/// each list holds a whole number per corner).
fn width(l: &ListProperty, face_starts: &[u32]) -> Option<usize> {
    let mut w = None;
    for f in 0..face_starts.len() - 1 {
        let len = (l.starts[f + 1] - l.starts[f]) as usize;
        let corners = (face_starts[f + 1] - face_starts[f]) as usize;
        if len == 0 || corners == 0 {
            continue;
        }
        match w {
            None => w = Some(len / corners),
            Some(k) if k * corners == len => {}
            Some(_) => return None,
        }
    }
    w.or(corner_list_width(&l.name).flatten())
        .or(Some(1))
        .filter(|&k| k > 0)
}

/// The pool (each distinct value once, in order of first use) and the corners' indices.
fn corner_attribute(l: &ListProperty, width: usize, face_starts: &[u32]) -> CornerAttribute {
    let (name, col_names) = corner_name(&l.name, width);
    let corners = *face_starts.last().unwrap_or(&0) as usize;
    let mut indices = vec![NO_VALUE; corners];
    let mut pool: Vec<&[f64]> = Vec::new();
    // Keys inline up to four values: a scan has millions of corners.
    let mut seen: HashMap<SmallVec<[u64; 4]>, u32> = HashMap::new();
    for f in 0..face_starts.len() - 1 {
        let items = &l.items[l.starts[f] as usize..l.starts[f + 1] as usize];
        for (k, value) in items.chunks_exact(width).enumerate() {
            let key: SmallVec<[u64; 4]> = value.iter().map(|x| x.to_bits()).collect();
            let next = pool.len() as u32;
            let row = *seen.entry(key).or_insert_with(|| {
                pool.push(value);
                next
            });
            indices[face_starts[f] as usize + k] = row;
        }
    }
    let columns = col_names
        .into_iter()
        .enumerate()
        .map(|(k, name)| {
            let mut data = empty_col(l.item_type, pool.len());
            for v in &pool {
                data.push_f64(v[k]);
            }
            Attribute { name, data }
        })
        .collect();
    CornerAttribute {
        name,
        columns,
        indices,
    }
}

/// The face lists the writer emits for the mesh's corner attributes, with their item types.
pub(super) fn corner_lists(mesh: &PolygonMesh) -> Vec<ListProperty> {
    mesh.corner_attributes
        .iter()
        .map(|a| {
            let width = a.columns.len();
            let mut starts = Vec::with_capacity(mesh.n_faces() + 1);
            starts.push(0u32);
            let mut items = Vec::with_capacity(a.indices.len() * width);
            for f in 0..mesh.n_faces() {
                let corners =
                    &a.indices[mesh.face_starts[f] as usize..mesh.face_starts[f + 1] as usize];
                if corners.iter().any(|&i| i != NO_VALUE) {
                    for &i in corners {
                        for c in &a.columns {
                            items.push(if i == NO_VALUE {
                                0.0
                            } else {
                                c.data.get_f64(i as usize)
                            });
                        }
                    }
                }
                starts.push(items.len() as u32);
            }
            let item_type = a
                .columns
                .first()
                .map_or(crate::mesh::ScalarType::F32, |c| c.data.scalar_type());
            ListProperty {
                name: list_name(a),
                count_type: crate::mesh::ScalarType::U8,
                item_type,
                starts,
                items,
            }
        })
        .collect()
}

/// Takes the comments that name textures, materials, groups and objects out of `comments`
/// into the mesh's tables.
pub(super) fn comments_to_tables(mesh: &mut PolygonMesh) {
    let mut textures: Vec<Option<String>> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    mesh.comments.retain(|c| {
        let (kw, rest) = c.split_once(' ').unwrap_or((c.as_str(), ""));
        match (kw, rest.split_once(' ')) {
            ("TextureFile", _) => textures.push((!rest.is_empty()).then(|| rest.to_string())),
            ("meshpyr", Some(("material", n))) => names.push(n.into()),
            ("meshpyr", Some(("mtllib", n))) => mesh.materials.libraries.push(n.into()),
            ("meshpyr", Some(("group", n))) => mesh.group_names.push(n.into()),
            ("meshpyr", Some(("object", n))) => mesh.object_names.push(n.into()),
            _ => return true,
        }
        false
    });
    let n = textures.len().max(names.len());
    mesh.materials.list = (0..n)
        .map(|i| {
            let texture = textures.get(i).cloned().flatten();
            let name = names
                .get(i)
                .cloned()
                .unwrap_or_else(|| material_name(i, &texture));
            Material { name, texture }
        })
        .collect();
}

/// A material name for a PLY texture: the image's file stem, one word.
fn material_name(i: usize, texture: &Option<String>) -> String {
    let stem = texture
        .as_deref()
        .and_then(|t| std::path::Path::new(t).file_stem())
        .map(|s| s.to_string_lossy().replace(char::is_whitespace, "_"))
        .filter(|s| !s.is_empty());
    stem.unwrap_or_else(|| format!("material{i}"))
}

/// The header comments that store the tables ([`comments_to_tables`] reads them back).
pub(super) fn table_comments(
    mesh: &PolygonMesh,
    materials: &crate::mesh::Materials,
) -> Vec<String> {
    let mut out = Vec::new();
    for m in &materials.list {
        out.push(format!(
            "TextureFile {}",
            m.texture.as_deref().unwrap_or("")
        ));
    }
    let derived = materials
        .list
        .iter()
        .enumerate()
        .all(|(i, m)| m.name == material_name(i, &m.texture));
    if !derived {
        out.extend(
            materials
                .list
                .iter()
                .map(|m| format!("meshpyr material {}", m.name)),
        );
    }
    out.extend(
        materials
            .libraries
            .iter()
            .map(|l| format!("meshpyr mtllib {l}")),
    );
    out.extend(
        mesh.group_names
            .iter()
            .map(|g| format!("meshpyr group {g}")),
    );
    out.extend(
        mesh.object_names
            .iter()
            .map(|o| format!("meshpyr object {o}")),
    );
    out
}
