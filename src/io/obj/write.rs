//! The OBJ writer (see the module docs of `obj`).

use std::fmt::Write as _;

use crate::io::text::{self, PositionFormat};
use crate::io::{IoError, MeshFormat, err_invalid};
use crate::mesh::corners::{
    GROUP_ATTRIBUTE, MATERIAL_ATTRIBUTE, NORMAL, OBJECT_ATTRIBUTE, SMOOTHING_ATTRIBUTE, TEXCOORD,
};
use crate::mesh::{AttributeData, CornerAttribute, Materials, NO_VALUE, PolygonMesh};

/// A float-typed vertex attribute column, or `None`.
fn float_col<'a>(mesh: &'a PolygonMesh, name: &str) -> Option<&'a AttributeData> {
    mesh.vertex_attribute(name)
        .map(|a| &a.data)
        .filter(|d| matches!(d, AttributeData::F32(_) | AttributeData::F64(_)))
}

fn push_attr(out: &mut String, d: &AttributeData, i: usize) {
    match d {
        AttributeData::F32(v) => text::push_f32(out, v[i]),
        AttributeData::U8(v) => text::push_f32(out, v[i] as f32 / 255.0),
        _ => text::push_f64(out, d.get_f64(i)),
    }
}

/// Where a corner's `vt` or `vn` comes from: the vertex's own row (per-vertex columns) or a
/// corner attribute's pool.
enum Source<'a> {
    None,
    PerVertex(Vec<&'a AttributeData>),
    Corners(&'a CornerAttribute),
}

impl<'a> Source<'a> {
    /// The corner attribute `corner` when its columns are numbers in the count OBJ needs,
    /// else the per-vertex columns `columns` when all exist.
    fn of(mesh: &'a PolygonMesh, corner: &str, columns: &[&str]) -> Source<'a> {
        if let Some(a) = mesh.corner_attribute(corner)
            && a.columns.len() == columns.len()
        {
            return Source::Corners(a);
        }
        let cols: Vec<&AttributeData> = columns.iter().filter_map(|c| float_col(mesh, c)).collect();
        if cols.len() == columns.len() {
            Source::PerVertex(cols)
        } else {
            Source::None
        }
    }

    /// The `vt`/`vn` lines.
    fn push_pool(&self, s: &mut String, keyword: &str, n_vertices: usize) {
        let (cols, rows): (Vec<&AttributeData>, usize) = match self {
            Source::None => return,
            Source::PerVertex(c) => (c.clone(), n_vertices),
            Source::Corners(a) => (a.columns.iter().map(|c| &c.data).collect(), a.pool_len()),
        };
        for i in 0..rows {
            s.push_str(keyword);
            for c in &cols {
                s.push(' ');
                push_attr(s, c, i);
            }
            s.push('\n');
        }
    }

    /// The 1-based index corner `corner` (of vertex `v`) refers to, or 0 for none.
    fn index(&self, corner: usize, v: u32) -> u64 {
        match self {
            Source::None => 0,
            Source::PerVertex(_) => v as u64 + 1,
            Source::Corners(a) => match a.indices[corner] {
                NO_VALUE => 0,
                i => i as u64 + 1,
            },
        }
    }
}

/// Writes an OBJ file; `materials` replaces the mesh's (its paths rebased for the output's
/// folder).
pub(crate) fn write(mesh: &PolygonMesh, materials: &Materials) -> Result<Vec<u8>, IoError> {
    let mut s = String::with_capacity(mesh.positions.len() * 30 + mesh.face_indices.len() * 8);
    push_comments(&mut s, mesh)?;
    for lib in &materials.libraries {
        push_statement(&mut s, "mtllib", lib)?;
    }
    push_vertices(&mut s, mesh)?;
    let uv = Source::of(mesh, TEXCOORD, &["u", "v"]);
    let normals = Source::of(mesh, NORMAL, &["nx", "ny", "nz"]);
    uv.push_pool(&mut s, "vt", mesh.n_vertices());
    normals.push_pool(&mut s, "vn", mesh.n_vertices());
    let mut statements = Statements::new(mesh, materials);
    for (f, face) in mesh.faces().enumerate() {
        if face.is_empty() {
            return Err(err_invalid(
                MeshFormat::Obj,
                format!("face {f} has no vertices"),
            ));
        }
        statements.push_changes(&mut s, f)?;
        s.push('f');
        let first = mesh.face_starts[f] as usize;
        for (k, &v) in face.iter().enumerate() {
            let _ = write!(s, " {}", v as u64 + 1);
            match (uv.index(first + k, v), normals.index(first + k, v)) {
                (0, 0) => {}
                (t, 0) => {
                    let _ = write!(s, "/{t}");
                }
                (0, n) => {
                    let _ = write!(s, "//{n}");
                }
                (t, n) => {
                    let _ = write!(s, "/{t}/{n}");
                }
            }
        }
        s.push('\n');
    }
    Ok(s.into_bytes())
}

/// The comments as `#` lines.
fn push_comments(s: &mut String, mesh: &PolygonMesh) -> Result<(), IoError> {
    for c in &mesh.comments {
        if c.contains('\n') || c.ends_with(['\r', '\\']) {
            return Err(err_invalid(
                MeshFormat::Obj,
                format!("comment {c:?} has a line break"),
            ));
        }
        let _ = writeln!(s, "# {c}");
    }
    Ok(())
}

/// `kw name` on a line of its own. A name ending in a backslash gets a space after it, so that
/// it does not continue the line; names with line breaks or `#` cannot be written.
fn push_statement(s: &mut String, kw: &str, name: &str) -> Result<(), IoError> {
    if name.is_empty() || name.contains(['\n', '\r', '#']) {
        return Err(err_invalid(
            MeshFormat::Obj,
            format!("{kw} {name:?} cannot be written on an OBJ line"),
        ));
    }
    let gap = if name.ends_with('\\') { " " } else { "" };
    let _ = writeln!(s, "{kw} {name}{gap}");
    Ok(())
}

/// The `v` lines, with `w` and colours when those attributes exist.
fn push_vertices(s: &mut String, mesh: &PolygonMesh) -> Result<(), IoError> {
    let pf = PositionFormat::new(mesh)
        .map_err(|i| err_invalid(MeshFormat::Obj, format!("vertex {i} does not fit in float")))?;
    let w = float_col(mesh, "w");
    let colour_cols: Vec<&AttributeData> = ["red", "green", "blue"]
        .iter()
        .filter_map(|n| {
            mesh.vertex_attribute(n).map(|a| &a.data).filter(|d| {
                matches!(
                    d,
                    AttributeData::F32(_) | AttributeData::F64(_) | AttributeData::U8(_)
                )
            })
        })
        .collect();
    let colours = (colour_cols.len() == 3).then_some(colour_cols);
    for (i, p) in mesh.positions.iter().enumerate() {
        s.push('v');
        for (k, c) in p.to_array().into_iter().enumerate() {
            s.push(' ');
            pf.push(s, i, k, c);
        }
        if let Some(w) = w {
            s.push(' ');
            push_attr(s, w, i);
        }
        if let Some(cols) = &colours {
            for c in cols {
                s.push(' ');
                push_attr(s, c, i);
            }
        }
        s.push('\n');
    }
    Ok(())
}

/// The `o`, `g`, `usemtl` and `s` statements before the faces where their values change.
struct Statements<'a> {
    /// Per slot: the face attribute, its name table (none for `s`) and the keyword.
    slots: Vec<(&'a AttributeData, Option<Vec<&'a str>>, &'static str)>,
    /// The values written last (`None` before the first face).
    last: Vec<Option<i64>>,
}

impl<'a> Statements<'a> {
    fn new(mesh: &'a PolygonMesh, materials: &'a Materials) -> Self {
        let names = |v: &'a [String]| -> Option<Vec<&'a str>> {
            Some(v.iter().map(String::as_str).collect())
        };
        let material_names = Some(materials.list.iter().map(|m| m.name.as_str()).collect());
        let wanted = [
            (OBJECT_ATTRIBUTE, names(&mesh.object_names), "o"),
            (GROUP_ATTRIBUTE, names(&mesh.group_names), "g"),
            (MATERIAL_ATTRIBUTE, material_names, "usemtl"),
            (SMOOTHING_ATTRIBUTE, None, "s"),
        ];
        let slots: Vec<_> = wanted
            .into_iter()
            .filter_map(|(attr, table, kw)| {
                let a = mesh.face_attribute(attr)?;
                // A material, group or object that no face has writes nothing, so that the
                // file reads back to what it writes again.
                let useful = table.is_none() || (0..a.data.len()).any(|f| a.data.get_f64(f) >= 0.0);
                useful.then_some((&a.data, table, kw))
            })
            .collect();
        let last = vec![None; slots.len()];
        Statements { slots, last }
    }

    /// The statements face `f` needs before it.
    fn push_changes(&mut self, s: &mut String, f: usize) -> Result<(), IoError> {
        for (k, (data, table, kw)) in self.slots.iter().enumerate() {
            let value = data.get_f64(f) as i64;
            let value = if table.is_some() {
                value.max(-1)
            } else {
                value
            };
            // The first face always gets the statement, so the attribute exists on reading
            // even when every face has the value of none.
            if self.last[k] == Some(value) {
                continue;
            }
            self.last[k] = Some(value);
            match (table, value) {
                (None, 0) => s.push_str("s off\n"),
                (None, n) => {
                    let _ = writeln!(s, "s {n}");
                }
                // Back to none: the statement without a name, which the reader reads so.
                (Some(_), i) if i < 0 => {
                    let _ = writeln!(s, "{kw}");
                }
                (Some(t), i) => {
                    let name = match t.get(i as usize) {
                        Some(name) => name.to_string(),
                        None => format!("{}{i}", if *kw == "usemtl" { "material" } else { kw }),
                    };
                    push_statement(s, kw, &name)?;
                }
            }
        }
        Ok(())
    }
}
