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
//! colour it is kept as face attributes `red`,`green`,`blue`[,`alpha`] (f32), otherwise face
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
pub fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let mut mesh = PolygonMesh::new();
    let mut lines = OffLines {
        lines: Lines::new(bytes, 1),
        last: 0,
    };
    let Some((hline, htoks)) = lines.next(Some(&mut mesh.comments)) else {
        return Err(err_line(lines.last.max(1), "empty file (no OFF header)"));
    };
    let (mut st, mut c, mut n) = (false, false, false);
    let count_toks: Vec<&[u8]>;
    let count_line;
    if text::parse_i64(htoks[0]).is_some() {
        // No keyword: the first line holds the counts.
        count_toks = htoks;
        count_line = hline;
    } else {
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
        if htoks.len() > 1 {
            count_toks = htoks[1..].to_vec();
            count_line = hline;
        } else {
            let Some((l, t)) = lines.next(Some(&mut mesh.comments)) else {
                return Err(err_line(
                    lines.last + 1,
                    "the file ends before the counts line",
                ));
            };
            count_toks = t;
            count_line = l;
        }
    }
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
    let left = lines.lines.rest_len() as u64 + 1;
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
    let (nv_us, nf_us) = (nv as usize, nf as usize); // bounded by the file size

    let fixed = 3 + if n { 3 } else { 0 } + if st { 2 } else { 0 };
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut colours: Vec<[f32; 4]> = Vec::new();
    let mut any_alpha = false;
    let mut uvs: Vec<[f32; 2]> = Vec::new();
    let mut tp = TextPositions::new();
    tp.reserve(nv_us);
    for i in 0..nv_us {
        let Some((line, toks)) = lines.next(None) else {
            return Err(err_line(
                lines.last + 1,
                format!("the file ends after {i} of {nv} vertices"),
            ));
        };
        let ncol = toks.len().saturating_sub(fixed);
        let ok = if c {
            toks.len() >= fixed && (ncol == 3 || ncol == 4)
        } else {
            toks.len() == fixed
        };
        if !ok {
            return Err(err_line(
                line,
                format!(
                    "vertex {i} has {} values, expected {}",
                    toks.len(),
                    if c {
                        format!("{} or {}", fixed + 3, fixed + 4)
                    } else {
                        fixed.to_string()
                    }
                ),
            ));
        }
        let mut p = [0f64; 3];
        for (o, t) in p.iter_mut().zip(&toks) {
            *o = text::parse_f64(t)
                .ok_or_else(|| err_line(line, format!("bad coordinate {}", text::show(t))))?;
        }
        if !p.iter().all(|x| x.is_finite()) {
            return Err(err_line(
                line,
                format!("vertex {i} has a non-finite coordinate"),
            ));
        }
        tp.push([toks[0], toks[1], toks[2]], p);
        let mut k = 3;
        if n {
            normals.push(floats(&toks[k..k + 3], line, "normal")?);
            k += 3;
        }
        if c {
            let mut col: [f32; 4] = floats(&toks[k..k + ncol], line, "colour")?;
            if ncol == 3 {
                col[3] = 1.0;
            } else {
                any_alpha = true;
            }
            colours.push(col);
            k += ncol;
        }
        if st {
            uvs.push(floats(&toks[k..k + 2], line, "texture coordinate")?);
        }
    }

    (mesh.positions, mesh.position_type) = tp.finish();
    let mut face_colours: Vec<[f32; 4]> = Vec::new();
    let mut all_faces_coloured = true;
    let mut any_face_alpha = false;
    mesh.face_starts.reserve(nf_us);
    for f in 0..nf_us {
        let Some((line, toks)) = lines.next(None) else {
            return Err(err_line(
                lines.last + 1,
                format!("the file ends after {f} of {nf} faces"),
            ));
        };
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
        let rest = &toks[1 + len..];
        match rest.len() {
            0 | 1 => {
                // No colour or a colour-map index: not kept.
                all_faces_coloured = false;
            }
            3 | 4 => {
                let mut col: [f32; 4] = floats(rest, line, "face colour")?;
                if rest.len() == 3 {
                    col[3] = 1.0;
                } else {
                    any_face_alpha = true;
                }
                if all_faces_coloured {
                    face_colours.push(col);
                }
            }
            k => {
                return Err(err_line(
                    line,
                    format!("face {f} has {k} values after its indices (expected a colour)"),
                ));
            }
        }
    }

    let push4 = |out: &mut Vec<Attribute>, vals: &[[f32; 4]], names: &[&str]| {
        for (k, name) in names.iter().enumerate() {
            out.push(Attribute {
                name: (*name).into(),
                data: AttributeData::F32(vals.iter().map(|c| c[k]).collect()),
            });
        }
    };
    if n {
        let n4: Vec<[f32; 4]> = normals.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
        push4(&mut mesh.vertex_attributes, &n4, &["nx", "ny", "nz"]);
    }
    if c {
        let names: &[&str] = if any_alpha {
            &["red", "green", "blue", "alpha"]
        } else {
            &["red", "green", "blue"]
        };
        push4(&mut mesh.vertex_attributes, &colours, names);
    }
    if st {
        let uv4: Vec<[f32; 4]> = uvs.iter().map(|v| [v[0], v[1], 0.0, 0.0]).collect();
        push4(&mut mesh.vertex_attributes, &uv4, &["u", "v"]);
    }
    if all_faces_coloured && nf > 0 {
        let names: &[&str] = if any_face_alpha {
            &["red", "green", "blue", "alpha"]
        } else {
            &["red", "green", "blue"]
        };
        push4(&mut mesh.face_attributes, &face_colours, names);
    }
    Ok(mesh)
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
pub fn write(mesh: &PolygonMesh) -> Result<Vec<u8>, IoError> {
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
