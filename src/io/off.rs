//! OFF (Object File Format) reader and writer.
//!
//! Accepted headers: `OFF`, `COFF`, `NOFF`, `CNOFF`, `STOFF` and their combinations
//! (`[ST][C][N]OFF`), optionally followed by the counts on the same line; a file without a
//! header keyword that starts directly with the counts is accepted too. `4OFF`, `nOFF` and
//! `OFF BINARY` are rejected with an error. `#` starts a comment anywhere; comments before the
//! counts line are kept in [`PolygonMesh::comments`]. Blank lines and CRLF are fine. Each
//! vertex and each face is one line.
//!
//! Vertex lines are `x y z [nx ny nz] [r g b [a]] [u v]` as the header announces; positions are
//! float or double data as described in [`super::obj`] (at most 9 significant digits per
//! coordinate: f32 with `position_type = Some(F32)`; otherwise exact f64, `None`), normals become `nx`,`ny`,`nz`, colours `red`,
//! `green`,`blue` (and `alpha` when any vertex has one, 1 elsewhere), texture coordinates
//! `u`,`v`, all f32. Face lines are `n i1 … in [colour]`; when every face carries an RGB(A)
//! colour it is kept as face attributes `red`,`green`,`blue` (and `alpha`) (f32), otherwise face
//! colours (including colour-map indices) are dropped. The edge count is ignored.

use std::fmt::Write as _;

use super::text::{self, Lines, PositionFormat, TextPositions};
use super::{IoError, MeshFormat, err_invalid, err_line};
use crate::mesh::{Attribute, AttributeData, PolygonMesh};

/// Significant lines: comments removed, blank lines skipped.
struct OffLines<'a> {
    lines: Lines<'a>,
    last: u64,
}

impl<'a> OffLines<'a> {
    /// Next non-blank line: (line number, tokens, comment text if the line had one).
    fn next(&mut self, comments: Option<&mut Vec<String>>) -> Option<(u64, Vec<&'a [u8]>)> {
        let mut comments = comments;
        for (n, l) in self.lines.by_ref() {
            self.last = n;
            let (data, comment) = match l.iter().position(|&b| b == b'#') {
                Some(i) => (&l[..i], Some(&l[i + 1..])),
                None => (l, None),
            };
            if let (Some(c), Some(out)) = (comment, comments.as_deref_mut()) {
                let c = c.strip_prefix(b" ").unwrap_or(c);
                out.push(String::from_utf8_lossy(c).into_owned());
            }
            let toks: Vec<&[u8]> = text::tokens(data).collect();
            if !toks.is_empty() {
                return Some((n, toks));
            }
        }
        None
    }
}

fn parse_count(tok: &[u8], line: u64) -> Result<u64, IoError> {
    text::parse_i64(tok)
        .filter(|&c| c >= 0)
        .map(|c| c as u64)
        .ok_or_else(|| err_line(line, format!("bad count {}", text::show(tok))))
}

fn floats<const N: usize>(toks: &[&[u8]], line: u64, what: &str) -> Result<[f32; N], IoError> {
    let mut out = [0f32; N];
    for (o, t) in out.iter_mut().zip(toks) {
        *o = text::parse_f32(t)
            .ok_or_else(|| err_line(line, format!("bad {what} value {}", text::show(t))))?;
    }
    Ok(out)
}

/// Reads an OFF file.
pub(crate) fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let mut mesh = PolygonMesh::new();
    let mut lines = OffLines {
        lines: Lines::new(bytes, 1),
        last: 0,
    };
    let header = read_header(&mut lines, &mut mesh.comments, 0)?;
    let (positions, vertices) = read_vertices(&mut lines, &header)?;
    (mesh.positions, mesh.position_type) = positions.finish();
    let face_colours = read_faces(&mut lines, &header, &mut mesh)?;
    push_vertex_attributes(&mut mesh, &header, &vertices);
    push_face_colours(&mut mesh, &header, face_colours);
    Ok(mesh)
}

/// What the header announces: the optional vertex data (`ST`, `C`, `N`) and the counts.
struct OffHeader {
    uvs: bool,
    colours: bool,
    normals: bool,
    nv: u64,
    nf: u64,
}

impl OffHeader {
    /// The number of values every vertex line has besides a colour.
    fn fixed_values(&self) -> usize {
        3 + if self.normals { 3 } else { 0 } + if self.uvs { 2 } else { 0 }
    }
}

/// The vertex and face counts of an OFF file's header, from the head of the file, for an
/// estimate before the body is read; `file_len` is the whole file's length when known. `None`
/// when the header is malformed or the file cannot hold the counts (the reader says why).
pub(crate) fn header_counts(head: &[u8], file_len: Option<u64>) -> Option<(u64, u64)> {
    let mut lines = OffLines {
        lines: Lines::new(head, 1),
        last: 0,
    };
    // The bytes after the head count as room for the counts (all of them when unknown).
    let beyond = file_len.map_or(u64::MAX / 2, |l| l.saturating_sub(head.len() as u64));
    let header = read_header(&mut lines, &mut Vec::new(), beyond).ok()?;
    Some((header.nv, header.nf))
}

/// The keyword line (if any) and the counts line; comments before the counts are kept.
/// `beyond`: bytes of the file after `lines`' text (0 when `lines` hold the whole file).
fn read_header(
    lines: &mut OffLines,
    comments: &mut Vec<String>,
    beyond: u64,
) -> Result<OffHeader, IoError> {
    let Some((hline, htoks)) = lines.next(Some(comments)) else {
        return Err(err_line(lines.last.max(1), "empty file (no OFF header)"));
    };
    let ((uvs, colours, normals), count_line, count_toks) = if text::parse_i64(htoks[0]).is_some() {
        // No keyword: the first line holds the counts.
        ((false, false, false), hline, htoks)
    } else {
        let flags = parse_keyword(&htoks, hline)?;
        if htoks.len() > 1 {
            (flags, hline, htoks[1..].to_vec())
        } else {
            let Some((l, t)) = lines.next(Some(comments)) else {
                return Err(err_line(
                    lines.last + 1,
                    "the file ends before the counts line",
                ));
            };
            (flags, l, t)
        }
    };
    let rest = (lines.lines.rest_len() as u64).saturating_add(beyond);
    let (nv, nf) = parse_counts(&count_toks, count_line, rest)?;
    Ok(OffHeader {
        uvs,
        colours,
        normals,
        nv,
        nf,
    })
}

/// `[ST][C][N]OFF` (and an optional `BINARY`, rejected): whether vertices have texture
/// coordinates, colours and normals.
fn parse_keyword(htoks: &[&[u8]], hline: u64) -> Result<(bool, bool, bool), IoError> {
    let (mut st, mut c, mut n) = (false, false, false);
    let mut kw = htoks[0];
    if let Some(r) = kw.strip_prefix(b"ST") {
        st = true;
        kw = r;
    }
    if let Some(r) = kw.strip_prefix(b"C") {
        c = true;
        kw = r;
    }
    if let Some(r) = kw.strip_prefix(b"N") {
        n = true;
        kw = r;
    }
    if kw.starts_with(b"4") || kw.starts_with(b"n") {
        return Err(err_line(
            hline,
            "4OFF / nOFF (non-3D) files are not supported",
        ));
    }
    if kw != b"OFF" {
        return Err(err_line(
            hline,
            format!("not an OFF file (header {})", text::show(htoks[0])),
        ));
    }
    if htoks.get(1) == Some(&&b"BINARY"[..]) {
        return Err(err_line(hline, "binary OFF is not supported"));
    }
    Ok((st, c, n))
}

/// `vertices faces [edges]`, checked against the `rest_len` bytes that follow.
fn parse_counts(
    count_toks: &[&[u8]],
    count_line: u64,
    rest_len: u64,
) -> Result<(u64, u64), IoError> {
    if !(2..=3).contains(&count_toks.len()) {
        return Err(err_line(
            count_line,
            "expected the counts line `vertices faces [edges]`",
        ));
    }
    let nv = parse_count(count_toks[0], count_line)?;
    let nf = parse_count(count_toks[1], count_line)?;
    if let Some(e) = count_toks.get(2) {
        parse_count(e, count_line)?;
    }
    // Each vertex line needs at least "0 0 0\n", each face line "0\n".
    let left = rest_len.saturating_add(1);
    let need = nv.saturating_mul(6).saturating_add(nf.saturating_mul(2));
    if need > left {
        return Err(err_line(
            count_line,
            format!("the counts claim {nv} vertices and {nf} faces but only {left} bytes follow"),
        ));
    }
    if nv > u32::MAX as u64 {
        return Err(err_line(count_line, "more than 2^32 - 1 vertices"));
    }
    Ok((nv, nf))
}

/// The vertex lines' data besides positions, in file order.
struct VertexData {
    normals: Vec<[f32; 3]>,
    colours: Vec<[f32; 4]>,
    any_alpha: bool,
    uvs: Vec<[f32; 2]>,
}

fn read_vertices(
    lines: &mut OffLines,
    h: &OffHeader,
) -> Result<(TextPositions, VertexData), IoError> {
    let mut positions = TextPositions::new();
    let mut data = VertexData {
        normals: Vec::new(),
        colours: Vec::new(),
        any_alpha: false,
        uvs: Vec::new(),
    };
    let nv = h.nv;
    positions.reserve(nv as usize); // bounded by the file size
    for i in 0..nv as usize {
        let Some((line, toks)) = lines.next(None) else {
            return Err(err_line(
                lines.last + 1,
                format!("the file ends after {i} of {nv} vertices"),
            ));
        };
        data.push_line(&mut positions, h, i, line, &toks)?;
    }
    Ok((positions, data))
}

impl VertexData {
    /// Vertex `i`: `x y z [nx ny nz] [r g b [a]] [u v]`.
    #[inline]
    fn push_line(
        &mut self,
        positions: &mut TextPositions,
        h: &OffHeader,
        i: usize,
        line: u64,
        toks: &[&[u8]],
    ) -> Result<(), IoError> {
        let ncol = check_vertex_values(h, i, line, toks.len())?;
        let p = parse_position(i, line, toks)?;
        positions.push([toks[0], toks[1], toks[2]], p);
        let mut k = 3;
        if h.normals {
            self.normals.push(floats(&toks[k..k + 3], line, "normal")?);
            k += 3;
        }
        if h.colours {
            let mut col: [f32; 4] = floats(&toks[k..k + ncol], line, "colour")?;
            if ncol == 3 {
                col[3] = 1.0;
            } else {
                self.any_alpha = true;
            }
            self.colours.push(col);
            k += ncol;
        }
        if h.uvs {
            self.uvs
                .push(floats(&toks[k..k + 2], line, "texture coordinate")?);
        }
        Ok(())
    }
}

/// Checks that vertex `i` has the values the header announces; returns its colour's length.
#[inline]
fn check_vertex_values(h: &OffHeader, i: usize, line: u64, n: usize) -> Result<usize, IoError> {
    let fixed = h.fixed_values();
    let ncol = n.saturating_sub(fixed);
    let ok = if h.colours {
        n >= fixed && (ncol == 3 || ncol == 4)
    } else {
        n == fixed
    };
    if !ok {
        return Err(err_line(
            line,
            format!(
                "vertex {i} has {n} values, expected {}",
                if h.colours {
                    format!("{} or {}", fixed + 3, fixed + 4)
                } else {
                    fixed.to_string()
                }
            ),
        ));
    }
    Ok(ncol)
}

/// The (finite) position of vertex `i`, its line's first three values.
#[inline]
fn parse_position(i: usize, line: u64, toks: &[&[u8]]) -> Result<[f64; 3], IoError> {
    let mut p = [0f64; 3];
    for (o, t) in p.iter_mut().zip(toks) {
        *o = text::parse_f64(t)
            .ok_or_else(|| err_line(line, format!("bad coordinate {}", text::show(t))))?;
    }
    if !p.iter().all(|x| x.is_finite()) {
        return Err(err_line(
            line,
            format!("vertex {i} has a non-finite coordinate"),
        ));
    }
    Ok(p)
}

/// Per-face colours, kept only when every face has one.
struct FaceColours {
    colours: Vec<[f32; 4]>,
    all: bool,
    any_alpha: bool,
}

/// Reads the face lines into `mesh`; returns their colours.
fn read_faces(
    lines: &mut OffLines,
    h: &OffHeader,
    mesh: &mut PolygonMesh,
) -> Result<FaceColours, IoError> {
    let mut colours = FaceColours {
        colours: Vec::new(),
        all: true,
        any_alpha: false,
    };
    let nf = h.nf;
    mesh.face_starts.reserve(nf as usize); // bounded by the file size
    for f in 0..nf as usize {
        let Some((line, toks)) = lines.next(None) else {
            return Err(err_line(
                lines.last + 1,
                format!("the file ends after {f} of {nf} faces"),
            ));
        };
        let len = push_face(mesh, h.nv, f, line, &toks)?;
        colours.push_line_rest(f, line, &toks[1 + len..])?;
    }
    Ok(colours)
}

/// Face `f`: `n i1 … in`, indices checked against the `nv` vertices; returns `n`.
#[inline]
fn push_face(
    mesh: &mut PolygonMesh,
    nv: u64,
    f: usize,
    line: u64,
    toks: &[&[u8]],
) -> Result<usize, IoError> {
    let len = text::parse_i64(toks[0])
        .filter(|&l| l >= 0)
        .ok_or_else(|| err_line(line, format!("bad face length {}", text::show(toks[0]))))?
        as u64;
    let have = toks.len() as u64 - 1;
    if len > have {
        return Err(err_line(
            line,
            format!("face {f} claims {len} vertices but the line has {have} values"),
        ));
    }
    let len = len as usize;
    for t in &toks[1..=len] {
        let i = text::parse_i64(t)
            .ok_or_else(|| err_line(line, format!("bad vertex index {}", text::show(t))))?;
        if i < 0 {
            return Err(err_line(line, format!("face {f} has negative index {i}")));
        }
        if i as u64 >= nv {
            return Err(err_line(
                line,
                format!("face {f} has index {i} but the file has {nv} vertices"),
            ));
        }
        mesh.face_indices.push(i as u32);
    }
    let total = u32::try_from(mesh.face_indices.len())
        .map_err(|_| err_line(line, "more than 2^32 - 1 face indices"))?;
    mesh.face_starts.push(total);
    Ok(len)
}

impl FaceColours {
    /// The values after face `f`'s indices: nothing, a colour-map index, or an RGB(A) colour.
    #[inline]
    fn push_line_rest(&mut self, f: usize, line: u64, rest: &[&[u8]]) -> Result<(), IoError> {
        match rest.len() {
            0 | 1 => {
                // No colour or a colour-map index: not kept.
                self.all = false;
            }
            3 | 4 => {
                let mut col: [f32; 4] = floats(rest, line, "face colour")?;
                if rest.len() == 3 {
                    col[3] = 1.0;
                } else {
                    self.any_alpha = true;
                }
                if self.all {
                    self.colours.push(col);
                }
            }
            k => {
                return Err(err_line(
                    line,
                    format!("face {f} has {k} values after its indices (expected a colour)"),
                ));
            }
        }
        Ok(())
    }
}

/// Normals, colours and texture coordinates as the vertex attributes `nx`,`ny`,`nz`,
/// `red`,`green`,`blue`[,`alpha`] and `u`,`v`.
fn push_vertex_attributes(mesh: &mut PolygonMesh, h: &OffHeader, v: &VertexData) {
    if h.normals {
        let n4: Vec<[f32; 4]> = v.normals.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
        push_columns(&mut mesh.vertex_attributes, &n4, &["nx", "ny", "nz"]);
    }
    if h.colours {
        push_columns(
            &mut mesh.vertex_attributes,
            &v.colours,
            colour_names(v.any_alpha),
        );
    }
    if h.uvs {
        let uv4: Vec<[f32; 4]> = v.uvs.iter().map(|v| [v[0], v[1], 0.0, 0.0]).collect();
        push_columns(&mut mesh.vertex_attributes, &uv4, &["u", "v"]);
    }
}

/// Face colours as the face attributes `red`,`green`,`blue`[,`alpha`] when every face has one.
fn push_face_colours(mesh: &mut PolygonMesh, h: &OffHeader, c: FaceColours) {
    if c.all && h.nf > 0 {
        push_columns(
            &mut mesh.face_attributes,
            &c.colours,
            colour_names(c.any_alpha),
        );
    }
}

fn colour_names(alpha: bool) -> &'static [&'static str] {
    if alpha {
        &["red", "green", "blue", "alpha"]
    } else {
        &["red", "green", "blue"]
    }
}

/// One f32 column per name, column `k` from component `k` of `vals`.
fn push_columns(out: &mut Vec<Attribute>, vals: &[[f32; 4]], names: &[&str]) {
    for (k, name) in names.iter().enumerate() {
        out.push(Attribute {
            name: (*name).into(),
            data: AttributeData::F32(vals.iter().map(|c| c[k]).collect()),
        });
    }
}

/// Columns for a group of attribute names, if all exist with a usable type.
fn cols<'a>(
    attrs: &'a [Attribute],
    names: &[&str],
    allow_u8: bool,
) -> Option<Vec<&'a AttributeData>> {
    names
        .iter()
        .map(|n| {
            attrs
                .iter()
                .find(|a| a.name == *n)
                .map(|a| &a.data)
                .filter(|d| {
                    matches!(d, AttributeData::F32(_) | AttributeData::F64(_))
                        || (allow_u8 && matches!(d, AttributeData::U8(_)))
                })
        })
        .collect()
}

fn push_val(s: &mut String, d: &AttributeData, i: usize) {
    match d {
        AttributeData::F32(v) => text::push_f32(s, v[i]),
        AttributeData::F64(v) => text::push_f64(s, v[i]),
        _ => {
            let _ = write!(s, "{}", d.get_f64(i));
        }
    }
}

/// Colour columns: RGB plus alpha when present.
fn colour_cols(attrs: &[Attribute]) -> Option<Vec<&AttributeData>> {
    let mut c = cols(attrs, &["red", "green", "blue"], true)?;
    if let Some(a) = cols(attrs, &["alpha"], true) {
        c.extend(a);
    }
    Some(c)
}

/// Writes an OFF file (`[ST][C][N]OFF` as the attributes require).
pub(crate) fn write(mesh: &PolygonMesh) -> Result<Vec<u8>, IoError> {
    let pf = PositionFormat::new(mesh)
        .map_err(|i| err_invalid(MeshFormat::Off, format!("vertex {i} does not fit in float")))?;
    let normals = cols(&mesh.vertex_attributes, &["nx", "ny", "nz"], false);
    let colours = colour_cols(&mesh.vertex_attributes);
    let uvs = cols(&mesh.vertex_attributes, &["u", "v"], false);
    let fcolours = colour_cols(&mesh.face_attributes);

    let mut s = String::with_capacity(mesh.positions.len() * 30 + mesh.face_indices.len() * 8);
    if uvs.is_some() {
        s.push_str("ST");
    }
    if colours.is_some() {
        s.push('C');
    }
    if normals.is_some() {
        s.push('N');
    }
    s.push_str("OFF\n");
    for c in &mesh.comments {
        if c.contains('\n') || c.ends_with('\r') {
            return Err(err_invalid(
                MeshFormat::Off,
                format!("comment {c:?} has a line break"),
            ));
        }
        let _ = writeln!(s, "# {c}");
    }
    let _ = writeln!(s, "{} {} 0", mesh.positions.len(), mesh.n_faces());
    for (i, p) in mesh.positions.iter().enumerate() {
        for (k, c) in p.to_array().into_iter().enumerate() {
            if k > 0 {
                s.push(' ');
            }
            pf.push(&mut s, i, k, c);
        }
        for group in [&normals, &colours, &uvs].into_iter().flatten() {
            for d in group {
                s.push(' ');
                push_val(&mut s, d, i);
            }
        }
        s.push('\n');
    }
    for (f, face) in mesh.faces().enumerate() {
        let _ = write!(s, "{}", face.len());
        for &v in face {
            let _ = write!(s, " {v}");
        }
        if let Some(fc) = &fcolours {
            for d in fc {
                s.push(' ');
                push_val(&mut s, d, f);
            }
        }
        s.push('\n');
    }
    Ok(s.into_bytes())
}
