//! Wavefront OBJ reader and writer.
//!
//! Hand-written rather than built on `tobj`: tobj re-indexes vertices per model/group (its
//! `add_vertex` keeps an index map per mesh), so vertex count and order are not kept and
//! unreferenced vertices disappear, and its `LoadError` carries no line number. Here the
//! vertices are exactly the `v` lines in file order, and every error names its line.
//!
//! What is read:
//! - `v x y z [w] [r g b]`: positions (float or double, see below); `w` becomes the
//!   attribute `w` (f64, 1 where absent) when any vertex has one; colours become `red`, `green`,
//!   `blue` (f32) when every vertex has them (otherwise they are dropped).
//! - `vt u [v [w]]`, `vn x y z` and `f` corners `v`, `v/vt`, `v//vn`, `v/vt/vn` (negative indices
//!   count back from the latest element). Texture coordinates and normals are per corner in
//!   OBJ; they are kept as per-vertex attributes `u`,`v` and `nx`,`ny`,`nz` (f32) only when every
//!   corner has one and each vertex is always used with the same value (unreferenced vertices
//!   get 0). Otherwise positions and faces are kept exactly and the per-corner data is dropped
//!   (a known limitation: OBJ seams need a split mesh, which is the mesh builder's business).
//!   A third texture coordinate is dropped.
//! - polygons are kept as they are (no triangulation).
//! - `#` comments before the first statement become [`PolygonMesh::comments`]; `o`, `g`, `s`,
//!   `usemtl`, `mtllib`, `l`, `p` and other statements are skipped (groups, smoothing groups,
//!   materials, lines and points are not kept). Line continuation (`\`) and CRLF are handled.
//!
//! Precision: OBJ text does not say whether it holds float or double data. When every
//! coordinate has at most 9 significant digits (and fits a float) the positions are read as
//! f32 values with `position_type = Some(F32)`, otherwise as exact f64 parses with
//! `position_type = None`. The writer uses shortest f32 formatting for f32 data (and for
//! untyped positions that are all f32 values) and shortest f64 formatting otherwise, so
//! write → read is bit-exact either way.
//!
//! The writer emits the comments, `v` (with `w` and colours when those attributes exist),
//! `vt` when `u`,`v` exist, `vn` when `nx`,`ny`,`nz` exist, and `f` lines. Other attributes
//! have no place in OBJ and are not written.

use std::fmt::Write as _;

use super::text::{self, Lines, PositionFormat, TextPositions};
use super::{IoError, MeshFormat, err_invalid, err_line};
use crate::mesh::{Attribute, AttributeData, PolygonMesh};

const NONE: u32 = u32::MAX;

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

/// Per-vertex value from per-corner references, if consistent.
fn per_vertex<const N: usize>(
    nv: usize,
    corners_v: &[u32],
    corners_x: &[u32],
    values: &[[f32; N]],
) -> Option<Vec<[f32; N]>> {
    if corners_x.is_empty() {
        // No faces: a point cloud with one vt/vn per v is kept in order.
        return (nv > 0 && values.len() == nv).then(|| values.to_vec());
    }
    if corners_x.contains(&NONE) {
        return None;
    }
    let mut out: Vec<Option<[f32; N]>> = vec![None; nv];
    for (&v, &x) in corners_v.iter().zip(corners_x) {
        let val = values[x as usize];
        match &out[v as usize] {
            None => out[v as usize] = Some(val),
            Some(old) => {
                if old
                    .iter()
                    .zip(&val)
                    .any(|(a, b)| a.to_bits() != b.to_bits())
                {
                    return None;
                }
            }
        }
    }
    Some(out.into_iter().map(|o| o.unwrap_or([0.0; N])).collect())
}

/// Reads an OBJ file.
pub(crate) fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
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
            k if k.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_') => {
                // o, g, s, usemtl, mtllib, l, p, curves, … : tolerated, not kept.
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
        if let Some(uv) = per_vertex(nv, &mesh.face_indices, &self.corner_vt, &self.texcoords) {
            push_columns(&mut mesh, &uv, &["u", "v"]);
        }
        if let Some(n) = per_vertex(nv, &mesh.face_indices, &self.corner_vn, &self.normals) {
            push_columns(&mut mesh, &n, &["nx", "ny", "nz"]);
        }
        Ok(mesh)
    }
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

/// Writes an OBJ file.
pub(crate) fn write(mesh: &PolygonMesh) -> Result<Vec<u8>, IoError> {
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
    let uv = float_col(mesh, "u").zip(float_col(mesh, "v"));
    let normals = match (
        float_col(mesh, "nx"),
        float_col(mesh, "ny"),
        float_col(mesh, "nz"),
    ) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };

    let mut s = String::with_capacity(mesh.positions.len() * 30 + mesh.face_indices.len() * 8);
    for c in &mesh.comments {
        if c.contains('\n') || c.ends_with(['\r', '\\']) {
            return Err(err_invalid(
                MeshFormat::Obj,
                format!("comment {c:?} has a line break"),
            ));
        }
        let _ = writeln!(s, "# {c}");
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        s.push('v');
        for (k, c) in p.to_array().into_iter().enumerate() {
            s.push(' ');
            pf.push(&mut s, i, k, c);
        }
        if let Some(w) = w {
            s.push(' ');
            push_attr(&mut s, w, i);
        }
        if let Some(cols) = &colours {
            for c in cols {
                s.push(' ');
                push_attr(&mut s, c, i);
            }
        }
        s.push('\n');
    }
    if let Some((u, v)) = uv {
        for i in 0..mesh.positions.len() {
            s.push_str("vt ");
            push_attr(&mut s, u, i);
            s.push(' ');
            push_attr(&mut s, v, i);
            s.push('\n');
        }
    }
    if let Some(n) = &normals {
        for i in 0..mesh.positions.len() {
            s.push_str("vn");
            for c in n {
                s.push(' ');
                push_attr(&mut s, c, i);
            }
            s.push('\n');
        }
    }
    for (f, face) in mesh.faces().enumerate() {
        if face.is_empty() {
            return Err(err_invalid(
                MeshFormat::Obj,
                format!("face {f} has no vertices"),
            ));
        }
        s.push('f');
        for &v in face {
            let k = v as u64 + 1;
            let _ = match (uv.is_some(), normals.is_some()) {
                (false, false) => write!(s, " {k}"),
                (true, false) => write!(s, " {k}/{k}"),
                (false, true) => write!(s, " {k}//{k}"),
                (true, true) => write!(s, " {k}/{k}/{k}"),
            };
        }
        s.push('\n');
    }
    Ok(s.into_bytes())
}
