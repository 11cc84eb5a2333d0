//! The OBJ reader: statements into a [`PolygonMesh`] (see the module docs of `obj`).

use super::statements::FaceState;
use crate::io::text::{self, Lines, TextPositions};
use crate::io::{IoError, err_line};
use crate::mesh::corners::{NORMAL, TEXCOORD};
use crate::mesh::{Attribute, AttributeData, CornerAttribute, NO_VALUE, PolygonMesh};

const NONE: u32 = NO_VALUE;

/// One resolved face corner reference kind.
struct IndexSpace {
    /// Number of elements defined so far.
    count: u64,
    /// Largest positive (forward-capable) index seen and its line, validated at the end.
    max: Option<(u64, u64)>,
    what: &'static str,
    plural: &'static str,
}

impl IndexSpace {
    fn new(what: &'static str, plural: &'static str) -> Self {
        IndexSpace {
            count: 0,
            max: None,
            what,
            plural,
        }
    }

    /// Resolves a 1-based or negative OBJ index to a 0-based one.
    fn resolve(&mut self, tok: &[u8], line: u64) -> Result<u32, IoError> {
        let i = text::parse_i64(tok).ok_or_else(|| {
            err_line(line, format!("bad {} index {}", self.what, text::show(tok)))
        })?;
        if i > 0 {
            let i = i as u64;
            if i > u32::MAX as u64 - 1 {
                return Err(err_line(
                    line,
                    format!("{} index {i} is too large", self.what),
                ));
            }
            if self.max.is_none_or(|(m, _)| i > m) {
                self.max = Some((i, line));
            }
            Ok((i - 1) as u32)
        } else if i < 0 {
            let back = i.unsigned_abs();
            if back > self.count {
                return Err(err_line(
                    line,
                    format!(
                        "relative {} index {i} points before the first of {} {}",
                        self.what, self.count, self.plural
                    ),
                ));
            }
            Ok((self.count - back) as u32)
        } else {
            Err(err_line(
                line,
                format!("{} index 0 (OBJ indices start at 1)", self.what),
            ))
        }
    }

    fn check(&self) -> Result<(), IoError> {
        if let Some((m, line)) = self.max
            && m > self.count
        {
            return Err(err_line(
                line,
                format!(
                    "{} index {m} but the file has {} {}",
                    self.what, self.count, self.plural
                ),
            ));
        }
        Ok(())
    }
}

/// Joins `\`-continued lines; yields (first line number, logical line).
fn logical_lines(bytes: &[u8]) -> impl Iterator<Item = (u64, std::borrow::Cow<'_, [u8]>)> {
    let mut lines = Lines::new(bytes, 1);
    std::iter::from_fn(move || {
        let (n, l) = lines.next()?;
        if l.last() != Some(&b'\\') {
            return Some((n, std::borrow::Cow::Borrowed(l)));
        }
        let mut buf = l[..l.len() - 1].to_vec();
        buf.push(b' ');
        for (_, next) in lines.by_ref() {
            if next.last() == Some(&b'\\') {
                buf.extend_from_slice(&next[..next.len() - 1]);
                buf.push(b' ');
            } else {
                buf.extend_from_slice(next);
                break;
            }
        }
        Some((n, std::borrow::Cow::Owned(buf)))
    })
}

fn parse_floats<const N: usize>(
    toks: &[&[u8]],
    line: u64,
    what: &str,
) -> Result<[f32; N], IoError> {
    let mut out = [0f32; N];
    for (o, t) in out.iter_mut().zip(toks) {
        *o = text::parse_f32(t)
            .ok_or_else(|| err_line(line, format!("bad {what} value {}", text::show(t))))?;
    }
    Ok(out)
}

/// True when `vt` (or `vn`) entry `k` belongs to vertex `k` exactly: as many entries as
/// vertices and every corner refers to the entry of its vertex (what the writer emits for
/// per-vertex attributes), so per-vertex columns write back to the same file.
fn is_per_vertex(nv: usize, corners_v: &[u32], corners_x: &[u32], n_values: usize) -> bool {
    n_values == nv && nv > 0 && corners_v == corners_x
}

/// The per-corner pool of `vt` or `vn` values with the corners' indices.
fn corner_attribute<const N: usize>(
    name: &str,
    columns: &[&str],
    values: &[[f32; N]],
    indices: Vec<u32>,
) -> CornerAttribute {
    CornerAttribute {
        name: name.into(),
        columns: columns
            .iter()
            .enumerate()
            .map(|(k, c)| Attribute {
                name: (*c).into(),
                data: AttributeData::F32(values.iter().map(|x| x[k]).collect()),
            })
            .collect(),
        indices,
    }
}

/// Reads an OBJ file.
pub(super) fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let mut reader = ObjReader::new();
    for (line, l) in logical_lines(bytes) {
        reader.read_line(line, &l)?;
    }
    reader.finish()
}

/// What the statements read so far have given.
struct ObjReader {
    mesh: PolygonMesh,
    tp: TextPositions,
    /// Vertex colours, while every vertex has one.
    colours: Vec<[f32; 3]>,
    all_coloured: bool,
    /// `w` of the vertices that have one.
    ws: Vec<(u32, f64)>,
    texcoords: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    /// Per face corner, its texture coordinate and normal (`NONE` when it has none).
    corner_vt: Vec<u32>,
    corner_vn: Vec<u32>,
    vs: IndexSpace,
    vts: IndexSpace,
    vns: IndexSpace,
    /// Materials, groups, objects and smoothing groups of the faces.
    state: FaceState,
    /// No statement yet: comments are kept.
    in_preamble: bool,
}

impl ObjReader {
    fn new() -> Self {
        ObjReader {
            mesh: PolygonMesh::new(),
            tp: TextPositions::new(),
            colours: Vec::new(),
            all_coloured: true,
            ws: Vec::new(),
            texcoords: Vec::new(),
            normals: Vec::new(),
            corner_vt: Vec::new(),
            corner_vn: Vec::new(),
            vs: IndexSpace::new("vertex", "vertices"),
            vts: IndexSpace::new("texture coordinate", "texture coordinates"),
            vns: IndexSpace::new("normal", "normals"),
            state: FaceState::default(),
            in_preamble: true,
        }
    }

    /// One logical line: a statement, a comment or nothing.
    #[inline]
    fn read_line(&mut self, line: u64, l: &[u8]) -> Result<(), IoError> {
        let (data, comment) = match l.iter().position(|&b| b == b'#') {
            Some(i) => (&l[..i], Some(&l[i + 1..])),
            None => (l, None),
        };
        let toks: Vec<&[u8]> = text::tokens(data).collect();
        let Some((&kw, args)) = toks.split_first() else {
            if self.in_preamble
                && let Some(c) = comment
            {
                let c = c.strip_prefix(b" ").unwrap_or(c);
                self.mesh
                    .comments
                    .push(String::from_utf8_lossy(text::strip_cr(c)).into_owned());
            }
            return Ok(());
        };
        self.in_preamble = false;
        match kw {
            b"v" => self.read_vertex(line, args),
            b"vt" => self.read_texcoord(line, args),
            b"vn" => self.read_normal(line, args),
            b"f" => self.read_face(line, args),
            b"usemtl" | b"mtllib" | b"g" | b"o" | b"s" => self.state.statement(line, kw, args),
            k if k.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_') => {
                // l, p, curves, … : tolerated, not kept.
                Ok(())
            }
            k => Err(err_line(
                line,
                format!("unknown statement {}", text::show(k)),
            )),
        }
    }

    /// `v x y z [w] [r g b]`.
    #[inline]
    fn read_vertex(&mut self, line: u64, args: &[&[u8]]) -> Result<(), IoError> {
        let n = args.len();
        if !matches!(n, 3 | 4 | 6 | 7) {
            return Err(err_line(
                line,
                format!("a v line needs x y z [w] [r g b], found {n} values"),
            ));
        }
        let mut p = [0f64; 3];
        for (o, t) in p.iter_mut().zip(args) {
            *o = text::parse_f64(t)
                .ok_or_else(|| err_line(line, format!("bad coordinate {}", text::show(t))))?;
        }
        let idx = self.tp.len();
        if !p.iter().all(|c| c.is_finite()) {
            return Err(err_line(
                line,
                format!("vertex {} has a non-finite coordinate", idx + 1),
            ));
        }
        if idx >= u32::MAX as usize {
            return Err(err_line(line, "more than 2^32 - 1 vertices"));
        }
        self.tp.push([args[0], args[1], args[2]], p);
        self.vs.count += 1;
        if n == 4 || n == 7 {
            let w = text::parse_f64(args[3])
                .ok_or_else(|| err_line(line, format!("bad w {}", text::show(args[3]))))?;
            self.ws.push((idx as u32, w));
        }
        if n >= 6 {
            let c: [f32; 3] = parse_floats(&args[n - 3..], line, "colour")?;
            if self.all_coloured {
                self.colours.push(c);
            }
        } else {
            self.all_coloured = false;
            self.colours = Vec::new();
        }
        Ok(())
    }

    /// `vt u [v [w]]`.
    #[inline]
    fn read_texcoord(&mut self, line: u64, args: &[&[u8]]) -> Result<(), IoError> {
        if !(1..=3).contains(&args.len()) {
            return Err(err_line(line, "a vt line needs 1 to 3 values"));
        }
        let mut uv: [f32; 2] = [0.0; 2];
        let vals: [f32; 3] = parse_floats(args, line, "texture coordinate")?;
        uv.copy_from_slice(&vals[..2]);
        if args.len() == 1 {
            uv[1] = 0.0;
        }
        self.texcoords.push(uv);
        self.vts.count += 1;
        Ok(())
    }

    /// `vn x y z`.
    #[inline]
    fn read_normal(&mut self, line: u64, args: &[&[u8]]) -> Result<(), IoError> {
        if args.len() != 3 {
            return Err(err_line(line, "a vn line needs 3 values"));
        }
        self.normals.push(parse_floats(args, line, "normal")?);
        self.vns.count += 1;
        Ok(())
    }

    /// `f` with corners `v`, `v/vt`, `v//vn` or `v/vt/vn`.
    #[inline]
    fn read_face(&mut self, line: u64, args: &[&[u8]]) -> Result<(), IoError> {
        if args.is_empty() {
            return Err(err_line(line, "a face without vertices"));
        }
        for corner in args {
            let mut parts = corner.split(|&b| b == b'/');
            let v = parts.next().unwrap_or(b"");
            let vt = parts.next().filter(|t| !t.is_empty());
            let vn = parts.next().filter(|t| !t.is_empty());
            if parts.next().is_some() {
                return Err(err_line(
                    line,
                    format!("bad face corner {}", text::show(corner)),
                ));
            }
            self.mesh.face_indices.push(self.vs.resolve(v, line)?);
            self.corner_vt.push(match vt {
                Some(t) => self.vts.resolve(t, line)?,
                None => NONE,
            });
            self.corner_vn.push(match vn {
                Some(t) => self.vns.resolve(t, line)?,
                None => NONE,
            });
        }
        let len = u32::try_from(self.mesh.face_indices.len())
            .map_err(|_| err_line(line, "more than 2^32 - 1 face corners"))?;
        self.state.face(self.mesh.face_starts.len() as u32 - 1);
        self.mesh.face_starts.push(len);
        Ok(())
    }

    /// Checks forward references, then turns the per-vertex and per-corner data into
    /// attributes.
    fn finish(self) -> Result<PolygonMesh, IoError> {
        self.vs.check()?;
        self.vts.check()?;
        self.vns.check()?;
        let mut mesh = self.mesh;
        (mesh.positions, mesh.position_type) = self.tp.finish();
        let nv = mesh.positions.len();
        push_w(&mut mesh, self.ws);
        if self.all_coloured && nv > 0 {
            push_columns(&mut mesh, &self.colours, &["red", "green", "blue"]);
        }
        let corners_v = &mesh.face_indices;
        let (vt_per_vertex, vn_per_vertex) = (
            is_per_vertex(nv, corners_v, &self.corner_vt, self.texcoords.len()),
            is_per_vertex(nv, corners_v, &self.corner_vn, self.normals.len()),
        );
        let (any_vt, any_vn) = (has_any(&self.corner_vt), has_any(&self.corner_vn));
        if vt_per_vertex {
            push_columns(&mut mesh, &self.texcoords, &["u", "v"]);
        } else if any_vt {
            let a = corner_attribute(TEXCOORD, &["u", "v"], &self.texcoords, self.corner_vt);
            mesh.corner_attributes.push(a);
        }
        if vn_per_vertex {
            push_columns(&mut mesh, &self.normals, &["nx", "ny", "nz"]);
        } else if any_vn {
            let a = corner_attribute(NORMAL, &["nx", "ny", "nz"], &self.normals, self.corner_vn);
            mesh.corner_attributes.push(a);
        }
        self.state.finish(&mut mesh);
        Ok(mesh)
    }
}

/// True when some corner refers to a value.
fn has_any(indices: &[u32]) -> bool {
    indices.iter().any(|&i| i != NONE)
}

/// The attribute `w` (1 where a vertex has none), when any vertex has one.
fn push_w(mesh: &mut PolygonMesh, ws: Vec<(u32, f64)>) {
    if ws.is_empty() {
        return;
    }
    let mut w = vec![1.0f64; mesh.positions.len()];
    for (i, x) in ws {
        w[i as usize] = x;
    }
    mesh.vertex_attributes.push(Attribute {
        name: "w".into(),
        data: AttributeData::F64(w),
    });
}

/// One f32 vertex attribute per name, column `k` from component `k` of `vals`.
fn push_columns<const N: usize>(mesh: &mut PolygonMesh, vals: &[[f32; N]], names: &[&str]) {
    for (k, name) in names.iter().enumerate() {
        mesh.vertex_attributes.push(Attribute {
            name: (*name).into(),
            data: AttributeData::F32(vals.iter().map(|c| c[k]).collect()),
        });
    }
}
