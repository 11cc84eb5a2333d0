//! STL reader and writer (binary and ASCII).
//!
//! STL stores independent triangles, so the reader welds corners whose f32 coordinates are
//! bit-identical (first-occurrence order; `-0.0` and `0.0` stay distinct). Positions are f32
//! (`position_type = Some(F32)`). The stored facet normals are dropped (the writer recomputes
//! them). A binary file's per-triangle "attribute byte count" is kept as the face attribute
//! `attribute` (u16) when any triangle has a non-zero value; the 80-byte header is not kept.
//!
//! Detection: a file is binary when its size is exactly `84 + 50·n` for the count `n` it
//! declares (some binary files begin with `solid`), ASCII when it starts with `solid`, and
//! binary otherwise (trailing bytes after the declared triangles are ignored).
//!
//! The writer emits binary by default (or ASCII), one facet per triangle with its normal
//! computed from the f32 corners; polygons with more than three corners are fan-triangulated
//! (STL only has triangles) and faces with fewer than three corners are skipped.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use glam::{DVec3, Vec3};

use super::text::{self, Lines};
use super::{IoError, MeshFormat, err_byte, err_file, err_invalid, err_line};
use crate::mesh::{Attribute, AttributeData, PolygonMesh, ScalarType};

/// Welds bit-identical corners.
struct Welder {
    map: HashMap<[u32; 3], u32>,
    mesh: PolygonMesh,
}

impl Welder {
    fn new(cap: usize) -> Self {
        let mut mesh = PolygonMesh::new();
        mesh.position_type = Some(ScalarType::F32);
        mesh.face_starts.reserve(cap + 1);
        mesh.face_indices.reserve(cap * 3);
        Welder {
            map: HashMap::with_capacity(cap),
            mesh,
        }
    }

    fn vertex(&mut self, p: [f32; 3]) -> u32 {
        let key = p.map(f32::to_bits);
        match self.map.entry(key) {
            Entry::Occupied(e) => *e.get(),
            Entry::Vacant(e) => {
                let i = self.mesh.positions.len() as u32;
                self.mesh.positions.push(Vec3::from_array(p).as_dvec3());
                *e.insert(i)
            }
        }
    }

    fn triangle(&mut self, t: [[f32; 3]; 3]) {
        for p in t {
            let i = self.vertex(p);
            self.mesh.face_indices.push(i);
        }
        self.mesh
            .face_starts
            .push(self.mesh.face_indices.len() as u32);
    }
}

/// The triangle count of a binary STL file whose head is `head` and length `len`, detected as
/// [`read`] does; `None` for ASCII STL (or a binary file whose count does not match its size,
/// which the reader rejects).
pub(crate) fn binary_triangles(head: &[u8], len: u64) -> Option<u64> {
    let declared = u32::from_le_bytes(head.get(80..84)?.try_into().ok()?) as u64;
    (84 + 50 * declared == len).then_some(declared)
}

/// Reads an STL file (binary or ASCII, detected from the content).
pub(crate) fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let declared = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let exact = declared.is_some_and(|n| 84 + 50 * n == bytes.len() as u64);
    let starts_solid = {
        let start = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(bytes.len());
        bytes[start..].starts_with(b"solid")
    };
    if exact || !starts_solid {
        read_binary(bytes)
    } else {
        read_ascii(bytes)
    }
}

fn read_binary(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    if bytes.len() < 84 {
        return Err(err_file(format!(
            "not an STL file ({} bytes: too short for binary STL and no `solid` keyword)",
            bytes.len()
        )));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    let need = 84 + 50 * n;
    if need > bytes.len() as u64 {
        return Err(err_byte(
            80,
            format!(
                "binary STL declares {n} triangles ({need} bytes) but the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    let n = n as usize; // bounded by the file size
    let mut w = Welder::new(n);
    let mut attrs: Vec<u16> = Vec::with_capacity(n);
    for (t, rec) in bytes[84..84 + 50 * n].chunks_exact(50).enumerate() {
        let f = |k: usize| f32::from_le_bytes([rec[k], rec[k + 1], rec[k + 2], rec[k + 3]]);
        let mut tri = [[0f32; 3]; 3];
        for (c, corner) in tri.iter_mut().enumerate() {
            for (d, x) in corner.iter_mut().enumerate() {
                *x = f(12 + 12 * c + 4 * d);
                if !x.is_finite() {
                    return Err(err_byte(
                        (84 + 50 * t + 12 + 12 * c + 4 * d) as u64,
                        format!("triangle {t} has a non-finite coordinate"),
                    ));
                }
            }
        }
        w.triangle(tri);
        attrs.push(u16::from_le_bytes([rec[48], rec[49]]));
    }
    if attrs.iter().any(|&a| a != 0) {
        w.mesh.face_attributes.push(Attribute {
            name: "attribute".into(),
            data: AttributeData::U16(attrs),
        });
    }
    Ok(w.mesh)
}

/// Token stream with line numbers.
struct Toks<'a> {
    lines: Lines<'a>,
    cur: Vec<&'a [u8]>,
    next: usize,
    line: u64,
}

impl<'a> Toks<'a> {
    fn next(&mut self) -> Option<&'a [u8]> {
        while self.next >= self.cur.len() {
            let (n, l) = self.lines.next()?;
            self.line = n;
            self.cur.clear();
            self.cur.extend(text::tokens(l));
            self.next = 0;
        }
        self.next += 1;
        Some(self.cur[self.next - 1])
    }

    /// Skips the rest of the current line (a solid's name).
    fn skip_line(&mut self) {
        self.next = self.cur.len();
    }

    fn expect(&mut self, kw: &[u8]) -> Result<(), IoError> {
        match self.next() {
            Some(t) if t.eq_ignore_ascii_case(kw) => Ok(()),
            Some(t) => Err(err_line(
                self.line,
                format!(
                    "expected `{}`, found {}",
                    String::from_utf8_lossy(kw),
                    text::show(t)
                ),
            )),
            None => Err(err_line(
                self.line,
                format!(
                    "the file ends where `{}` was expected",
                    String::from_utf8_lossy(kw)
                ),
            )),
        }
    }

    fn float(&mut self) -> Result<f32, IoError> {
        match self.next() {
            Some(t) => text::parse_f32(t)
                .ok_or_else(|| err_line(self.line, format!("bad number {}", text::show(t)))),
            None => Err(err_line(
                self.line,
                "the file ends in the middle of a facet",
            )),
        }
    }
}

fn read_ascii(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let mut t = Toks {
        lines: Lines::new(bytes, 1),
        cur: Vec::new(),
        next: 0,
        line: 1,
    };
    let mut w = Welder::new(0);
    let mut facets = 0usize;
    let mut open_solid = false;
    while let Some(tok) = t.next() {
        if !open_solid {
            if !tok.eq_ignore_ascii_case(b"solid") {
                return Err(err_line(
                    t.line,
                    format!("expected `solid`, found {}", text::show(tok)),
                ));
            }
            t.skip_line();
            open_solid = true;
            continue;
        }
        if tok.eq_ignore_ascii_case(b"endsolid") {
            t.skip_line();
            open_solid = false;
            continue;
        }
        if !tok.eq_ignore_ascii_case(b"facet") {
            return Err(err_line(
                t.line,
                format!("expected `facet` or `endsolid`, found {}", text::show(tok)),
            ));
        }
        t.expect(b"normal")?;
        for _ in 0..3 {
            t.float()?; // the stored normal is not kept
        }
        t.expect(b"outer")?;
        t.expect(b"loop")?;
        let mut tri = [[0f32; 3]; 3];
        for corner in tri.iter_mut() {
            t.expect(b"vertex")?;
            for x in corner.iter_mut() {
                *x = t.float()?;
                if !x.is_finite() {
                    return Err(err_line(
                        t.line,
                        format!("facet {facets} has a non-finite coordinate"),
                    ));
                }
            }
        }
        t.expect(b"endloop")?;
        t.expect(b"endfacet")?;
        if w.mesh.face_indices.len() + 3 > u32::MAX as usize {
            return Err(err_line(t.line, "too many facets"));
        }
        w.triangle(tri);
        facets += 1;
    }
    // A missing final `endsolid` is tolerated (many exporters forget it).
    Ok(w.mesh)
}

/// Fan triangles of the mesh (with their face index).
fn triangles(mesh: &PolygonMesh) -> impl Iterator<Item = (usize, [u32; 3])> + '_ {
    mesh.faces().enumerate().flat_map(|(f, face)| {
        (2..face.len().max(2)).map(move |k| (f, [face[0], face[k - 1], face[k]]))
    })
}

/// Writes an STL file (binary or ASCII).
pub(crate) fn write(mesh: &PolygonMesh, binary: bool) -> Result<Vec<u8>, IoError> {
    let pos: Vec<Vec3> = mesh.positions.iter().map(|p: &DVec3| p.as_vec3()).collect();
    if let Some(i) = pos.iter().position(|p| !p.is_finite()) {
        return Err(err_invalid(
            MeshFormat::Stl,
            format!("vertex {i} does not fit in float"),
        ));
    }
    let attr = mesh
        .face_attributes
        .iter()
        .find(|a| a.name == "attribute" && a.data.scalar_type() == ScalarType::U16);
    let normal = |t: [u32; 3]| {
        let [a, b, c] = t.map(|i| pos[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    if binary {
        let n = mesh.n_triangles();
        let n32 = u32::try_from(n)
            .map_err(|_| err_invalid(MeshFormat::Stl, "more than 2^32 - 1 triangles"))?;
        let mut out = Vec::with_capacity(84 + 50 * n);
        let mut header = [b' '; 80];
        header[..19].copy_from_slice(b"meshpyr binary STL ");
        out.extend_from_slice(&header);
        out.extend_from_slice(&n32.to_le_bytes());
        for (f, t) in triangles(mesh) {
            for v in std::iter::once(normal(t)).chain(t.map(|i| pos[i as usize])) {
                for c in v.to_array() {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            let a = attr.map_or(0, |a| a.data.get_f64(f) as u16);
            out.extend_from_slice(&a.to_le_bytes());
        }
        Ok(out)
    } else {
        let mut s = String::from("solid meshpyr\n");
        let put3 = |s: &mut String, v: Vec3| {
            for c in v.to_array() {
                s.push(' ');
                text::push_f32(s, c);
            }
        };
        for (_, t) in triangles(mesh) {
            s.push_str("facet normal");
            put3(&mut s, normal(t));
            s.push_str("\n outer loop\n");
            for i in t {
                s.push_str("  vertex");
                put3(&mut s, pos[i as usize]);
                s.push('\n');
            }
            s.push_str(" endloop\nendfacet\n");
        }
        s.push_str("endsolid meshpyr\n");
        Ok(s.into_bytes())
    }
}
