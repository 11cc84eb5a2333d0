//! PLY reader and writer (ASCII, binary little endian, binary big endian).
//!
//! Hand-written rather than built on `ply-rs-bw`, for three reasons: speed (the binary path
//! decodes fixed-layout vertex rows column by column and has a tight loop for the common
//! `list uchar int vertex_indices` face layout, with no per-element maps), bounded allocation
//! (every element count is checked against the bytes that remain before anything is
//! allocated) and error locations (byte offsets for binary bodies, lines for ASCII).
//!
//! Mapping onto [`PolygonMesh`]:
//! - `vertex`: `x`,`y`,`z` (any scalar type; `position_type` records it) become positions, every
//!   other scalar property becomes a vertex attribute in file order.
//! - `face`: the list `vertex_indices` (or `vertex_index`) gives the polygons; other scalar
//!   properties become face attributes.
//! - other elements are kept verbatim in `extra_elements`; `comment` and `obj_info` lines are
//!   kept in `comments` (an `obj_info` line becomes the comment `obj_info …`).
//! - list properties on `vertex`, and on `face` other than the indices, cannot be represented
//!   and are rejected with an error.
//!
//! The writer emits `vertex` (`float` positions unless `position_type` is `F64`, or the values
//! do not fit in `float`), then `face` (`list uchar int vertex_indices`, or `uint` counts for
//! polygons with more than 255 corners), then the extra elements.

use std::fmt::Write as _;

use glam::DVec3;

use super::text::{self, Lines};
use super::{IoError, MeshFormat, PlyEncoding, err_byte, err_invalid, err_line};
use crate::mesh::{
    Attribute, AttributeData, ElementProperty, ExtraElement, ListProperty, PolygonMesh, ScalarType,
};

// ---------------------------------------------------------------------------------------------
// Header
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq)]
enum PropKind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

#[derive(Debug)]
struct PropDef {
    name: String,
    kind: PropKind,
}

#[derive(Debug)]
struct ElementDef {
    name: String,
    count: u64,
    props: Vec<PropDef>,
    line: u64,
}

struct Header {
    encoding: PlyEncoding,
    elements: Vec<ElementDef>,
    comments: Vec<String>,
    /// Byte offset of the body.
    body: usize,
    /// Line number of the first body line (ASCII).
    body_line: u64,
}

fn parse_type(name: &[u8]) -> Option<ScalarType> {
    Some(match name {
        b"char" | b"int8" => ScalarType::I8,
        b"uchar" | b"uint8" => ScalarType::U8,
        b"short" | b"int16" => ScalarType::I16,
        b"ushort" | b"uint16" => ScalarType::U16,
        b"int" | b"int32" => ScalarType::I32,
        b"uint" | b"uint32" => ScalarType::U32,
        b"float" | b"float32" => ScalarType::F32,
        b"double" | b"float64" => ScalarType::F64,
        _ => return None,
    })
}

fn type_name(t: ScalarType) -> &'static str {
    match t {
        ScalarType::I8 => "char",
        ScalarType::U8 => "uchar",
        ScalarType::I16 => "short",
        ScalarType::U16 => "ushort",
        ScalarType::I32 => "int",
        ScalarType::U32 => "uint",
        ScalarType::F32 => "float",
        ScalarType::F64 => "double",
    }
}

fn is_int(t: ScalarType) -> bool {
    !matches!(t, ScalarType::F32 | ScalarType::F64)
}

/// Text after a header keyword: one separating whitespace character removed.
fn keyword_rest<'a>(line: &'a [u8], keyword: &[u8]) -> Option<&'a [u8]> {
    let start = line.iter().position(|b| !b.is_ascii_whitespace())?;
    let l = &line[start..];
    let rest = l.strip_prefix(keyword)?;
    match rest.first() {
        None => Some(rest),
        Some(b) if b.is_ascii_whitespace() => Some(&rest[1..]),
        Some(_) => None,
    }
}

fn parse_header(bytes: &[u8]) -> Result<Header, IoError> {
    let mut pos = 0usize;
    let mut line_no = 0u64;
    let mut encoding = None;
    let mut elements: Vec<ElementDef> = Vec::new();
    let mut comments = Vec::new();
    loop {
        line_no += 1;
        let Some(nl) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err_line(
                line_no,
                if line_no == 1 {
                    "not a PLY file (no header line)"
                } else {
                    "the header has no end_header line"
                },
            ));
        };
        let line = text::strip_cr(&bytes[pos..pos + nl]);
        pos += nl + 1;
        let mut toks = text::tokens(line);
        let kw = toks.next().unwrap_or(b"");
        if line_no == 1 {
            if line != b"ply" && kw != b"ply" {
                return Err(err_line(1, "not a PLY file (first line is not `ply`)"));
            }
            continue;
        }
        match kw {
            b"format" => {
                if encoding.is_some() {
                    return Err(err_line(line_no, "second format line"));
                }
                encoding = Some(match toks.next() {
                    Some(b"ascii") => PlyEncoding::Ascii,
                    Some(b"binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some(b"binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(err_line(
                            line_no,
                            format!("unknown format {}", text::show(other.unwrap_or(b""))),
                        ));
                    }
                });
            }
            b"comment" | b"obj_info" => {
                let rest = keyword_rest(line, kw).unwrap_or(b"");
                let rest = String::from_utf8_lossy(rest);
                if kw == b"comment" {
                    comments.push(rest.into_owned());
                } else {
                    comments.push(format!("obj_info {rest}"));
                }
            }
            b"element" => {
                let (Some(name), Some(count), None) = (toks.next(), toks.next(), toks.next())
                else {
                    return Err(err_line(line_no, "expected `element <name> <count>`"));
                };
                let count: u64 = std::str::from_utf8(count)
                    .ok()
                    .and_then(|c| c.parse().ok())
                    .ok_or_else(|| {
                        err_line(line_no, format!("bad element count {}", text::show(count)))
                    })?;
                let name = String::from_utf8_lossy(name).into_owned();
                if elements.iter().any(|e| e.name == name) {
                    return Err(err_line(line_no, format!("element {name:?} defined twice")));
                }
                elements.push(ElementDef {
                    name,
                    count,
                    props: Vec::new(),
                    line: line_no,
                });
            }
            b"property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(err_line(line_no, "property before any element"));
                };
                let t = toks.next().unwrap_or(b"");
                let kind = if t == b"list" {
                    let ct = toks.next().unwrap_or(b"");
                    let it = toks.next().unwrap_or(b"");
                    let count = parse_type(ct).ok_or_else(|| {
                        err_line(line_no, format!("unknown type {}", text::show(ct)))
                    })?;
                    let item = parse_type(it).ok_or_else(|| {
                        err_line(line_no, format!("unknown type {}", text::show(it)))
                    })?;
                    if !is_int(count) {
                        return Err(err_line(line_no, "list count type must be an integer type"));
                    }
                    PropKind::List { count, item }
                } else {
                    PropKind::Scalar(parse_type(t).ok_or_else(|| {
                        err_line(line_no, format!("unknown type {}", text::show(t)))
                    })?)
                };
                let (Some(name), None) = (toks.next(), toks.next()) else {
                    return Err(err_line(line_no, "expected `property <type> <name>`"));
                };
                let name = String::from_utf8_lossy(name).into_owned();
                if el.props.iter().any(|p| p.name == name) {
                    return Err(err_line(
                        line_no,
                        format!("property {name:?} defined twice in element {:?}", el.name),
                    ));
                }
                el.props.push(PropDef { name, kind });
            }
            b"end_header" => break,
            b"" => {}
            other => {
                return Err(err_line(
                    line_no,
                    format!("unknown header line {}", text::show(other)),
                ));
            }
        }
    }
    let encoding = encoding.ok_or_else(|| err_line(line_no, "the header has no format line"))?;
    Ok(Header {
        encoding,
        elements,
        comments,
        body: pos,
        body_line: line_no + 1,
    })
}

// ---------------------------------------------------------------------------------------------
// Body sources
// ---------------------------------------------------------------------------------------------

/// What the reader does with one property of an element.
#[derive(Clone, Copy)]
enum Plan {
    /// Scalar into a column; `finite` checks positions.
    Scalar { t: ScalarType, finite: bool },
    /// Face indices.
    Indices { count: ScalarType, item: ScalarType },
    /// Opaque list.
    List { count: ScalarType, item: ScalarType },
}

/// Output of one property.
enum Out {
    Col(AttributeData),
    List(ListProperty),
    Indices,
}

fn empty_col(t: ScalarType, cap: usize) -> AttributeData {
    match t {
        ScalarType::I8 => AttributeData::I8(Vec::with_capacity(cap)),
        ScalarType::U8 => AttributeData::U8(Vec::with_capacity(cap)),
        ScalarType::I16 => AttributeData::I16(Vec::with_capacity(cap)),
        ScalarType::U16 => AttributeData::U16(Vec::with_capacity(cap)),
        ScalarType::I32 => AttributeData::I32(Vec::with_capacity(cap)),
        ScalarType::U32 => AttributeData::U32(Vec::with_capacity(cap)),
        ScalarType::F32 => AttributeData::F32(Vec::with_capacity(cap)),
        ScalarType::F64 => AttributeData::F64(Vec::with_capacity(cap)),
    }
}

/// A stream of property values (binary or ASCII).
trait Source {
    fn err(&self, reason: String) -> IoError;
    /// Starts a row (ASCII: moves to the next non-blank line).
    fn begin_row(&mut self, what: &dyn Fn() -> String) -> Result<(), IoError>;
    /// Ends a row (ASCII: no values may be left on the line).
    fn end_row(&mut self) -> Result<(), IoError>;
    /// Reads a scalar of the column's type and appends it.
    fn push_scalar(&mut self, col: &mut AttributeData) -> Result<(), IoError>;
    /// Reads an integer of type `t` (exact).
    fn int(&mut self, t: ScalarType) -> Result<i64, IoError>;
    /// Reads a value of type `t` widened to f64 (exact).
    fn num(&mut self, t: ScalarType) -> Result<f64, IoError>;
    /// Fails unless `n` items of type `t` can still follow (bounds list allocations).
    fn check_items(&self, n: u64, t: ScalarType) -> Result<(), IoError>;
}

struct Bin<'a> {
    data: &'a [u8],
    pos: usize,
    /// Start of the value read last (errors about a value point at it).
    last: usize,
    big: bool,
}

impl Bin<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], IoError> {
        self.last = self.pos;
        match self.data.get(self.pos..self.pos + N) {
            Some(s) => {
                self.pos += N;
                let mut a = [0u8; N];
                a.copy_from_slice(s);
                Ok(a)
            }
            None => Err(err_byte(
                self.pos as u64,
                "the file ends in the middle of the data",
            )),
        }
    }
}

macro_rules! rd {
    ($self:ident, $t:ty) => {{
        let b = $self.take::<{ std::mem::size_of::<$t>() }>()?;
        if $self.big {
            <$t>::from_be_bytes(b)
        } else {
            <$t>::from_le_bytes(b)
        }
    }};
}

impl Source for Bin<'_> {
    fn err(&self, reason: String) -> IoError {
        err_byte(self.last as u64, reason)
    }
    fn begin_row(&mut self, _what: &dyn Fn() -> String) -> Result<(), IoError> {
        Ok(())
    }
    fn end_row(&mut self) -> Result<(), IoError> {
        Ok(())
    }
    fn push_scalar(&mut self, col: &mut AttributeData) -> Result<(), IoError> {
        match col {
            AttributeData::I8(v) => v.push(rd!(self, i8)),
            AttributeData::U8(v) => v.push(rd!(self, u8)),
            AttributeData::I16(v) => v.push(rd!(self, i16)),
            AttributeData::U16(v) => v.push(rd!(self, u16)),
            AttributeData::I32(v) => v.push(rd!(self, i32)),
            AttributeData::U32(v) => v.push(rd!(self, u32)),
            AttributeData::F32(v) => v.push(rd!(self, f32)),
            AttributeData::F64(v) => v.push(rd!(self, f64)),
        }
        Ok(())
    }
    fn int(&mut self, t: ScalarType) -> Result<i64, IoError> {
        Ok(match t {
            ScalarType::I8 => rd!(self, i8) as i64,
            ScalarType::U8 => rd!(self, u8) as i64,
            ScalarType::I16 => rd!(self, i16) as i64,
            ScalarType::U16 => rd!(self, u16) as i64,
            ScalarType::I32 => rd!(self, i32) as i64,
            ScalarType::U32 => rd!(self, u32) as i64,
            _ => return Err(self.err("expected an integer type".into())),
        })
    }
    fn num(&mut self, t: ScalarType) -> Result<f64, IoError> {
        Ok(match t {
            ScalarType::F32 => rd!(self, f32) as f64,
            ScalarType::F64 => rd!(self, f64),
            _ => self.int(t)? as f64,
        })
    }
    fn check_items(&self, n: u64, t: ScalarType) -> Result<(), IoError> {
        let need = n.saturating_mul(t.size() as u64);
        let left = (self.data.len() - self.pos) as u64;
        if need > left {
            return Err(self.err(format!(
                "a list of {n} items needs {need} bytes but only {left} remain"
            )));
        }
        Ok(())
    }
}

struct Ascii<'a> {
    lines: Lines<'a>,
    line_no: u64,
    toks: Vec<&'a [u8]>,
    next: usize,
}

impl<'a> Ascii<'a> {
    fn tok(&mut self) -> Result<&'a [u8], IoError> {
        match self.toks.get(self.next) {
            Some(t) => {
                self.next += 1;
                Ok(t)
            }
            None => Err(self.err("the line has too few values for its element".into())),
        }
    }
}

impl Source for Ascii<'_> {
    fn err(&self, reason: String) -> IoError {
        err_line(self.line_no, reason)
    }
    fn begin_row(&mut self, what: &dyn Fn() -> String) -> Result<(), IoError> {
        loop {
            match self.lines.next() {
                Some((n, l)) => {
                    self.line_no = n;
                    self.toks.clear();
                    self.toks.extend(text::tokens(l));
                    self.next = 0;
                    if !self.toks.is_empty() {
                        return Ok(());
                    }
                }
                None => {
                    return Err(err_line(
                        self.line_no + 1,
                        format!("the file ends before {}", what()),
                    ));
                }
            }
        }
    }
    fn end_row(&mut self) -> Result<(), IoError> {
        if self.next < self.toks.len() {
            return Err(self.err(format!(
                "the line has {} values, more than its element defines",
                self.toks.len()
            )));
        }
        Ok(())
    }
    fn push_scalar(&mut self, col: &mut AttributeData) -> Result<(), IoError> {
        let tok = self.tok()?;
        let bad = |s: &Self, t: ScalarType| {
            s.err(format!(
                "{} is not a valid {}",
                text::show(tok),
                type_name(t)
            ))
        };
        let t = col.scalar_type();
        match col {
            AttributeData::F32(v) => v.push(text::parse_f32(tok).ok_or_else(|| bad(self, t))?),
            AttributeData::F64(v) => v.push(text::parse_f64(tok).ok_or_else(|| bad(self, t))?),
            _ => {
                let x = text::parse_i64(tok).ok_or_else(|| bad(self, t))?;
                let ok = match col {
                    AttributeData::I8(v) => i8::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::U8(v) => u8::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::I16(v) => i16::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::U16(v) => u16::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::I32(v) => i32::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::U32(v) => u32::try_from(x).map(|x| v.push(x)).is_ok(),
                    _ => false,
                };
                if !ok {
                    return Err(bad(self, t));
                }
            }
        }
        Ok(())
    }
    fn int(&mut self, t: ScalarType) -> Result<i64, IoError> {
        let tok = self.tok()?;
        let x = text::parse_i64(tok);
        let ok = match (t, x) {
            (ScalarType::I8, Some(x)) => i8::try_from(x).is_ok(),
            (ScalarType::U8, Some(x)) => u8::try_from(x).is_ok(),
            (ScalarType::I16, Some(x)) => i16::try_from(x).is_ok(),
            (ScalarType::U16, Some(x)) => u16::try_from(x).is_ok(),
            (ScalarType::I32, Some(x)) => i32::try_from(x).is_ok(),
            (ScalarType::U32, Some(x)) => u32::try_from(x).is_ok(),
            _ => false,
        };
        match x {
            Some(x) if ok => Ok(x),
            _ => Err(self.err(format!(
                "{} is not a valid {}",
                text::show(tok),
                type_name(t)
            ))),
        }
    }
    fn num(&mut self, t: ScalarType) -> Result<f64, IoError> {
        match t {
            ScalarType::F32 | ScalarType::F64 => {
                let tok = self.tok()?;
                let x = if t == ScalarType::F32 {
                    text::parse_f32(tok).map(|x| x as f64)
                } else {
                    text::parse_f64(tok)
                };
                x.ok_or_else(|| {
                    self.err(format!(
                        "{} is not a valid {}",
                        text::show(tok),
                        type_name(t)
                    ))
                })
            }
            _ => Ok(self.int(t)? as f64),
        }
    }
    fn check_items(&self, n: u64, _t: ScalarType) -> Result<(), IoError> {
        let left = (self.toks.len() - self.next) as u64;
        if n > left {
            return Err(self.err(format!(
                "a list of {n} items but only {left} values remain on the line"
            )));
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

/// Element kinds with a meaning for the mesh.
#[derive(PartialEq)]
enum Role {
    Vertex,
    Face,
    Extra,
}

fn plan_element(el: &ElementDef, role: &Role) -> Result<Vec<Plan>, IoError> {
    let mut plans = Vec::with_capacity(el.props.len());
    let mut have_indices = false;
    for p in &el.props {
        let plan = match (p.kind, role) {
            (PropKind::Scalar(t), Role::Vertex) => Plan::Scalar {
                t,
                finite: matches!(p.name.as_str(), "x" | "y" | "z"),
            },
            (PropKind::Scalar(t), _) => Plan::Scalar { t, finite: false },
            (PropKind::List { count, item }, Role::Face)
                if !have_indices
                    && matches!(p.name.as_str(), "vertex_indices" | "vertex_index") =>
            {
                if !is_int(item) {
                    return Err(err_line(
                        el.line,
                        format!("face list {} must have an integer item type", p.name),
                    ));
                }
                have_indices = true;
                Plan::Indices { count, item }
            }
            (PropKind::List { count, item }, Role::Extra) => Plan::List { count, item },
            (PropKind::List { .. }, _) => {
                return Err(err_line(
                    el.line,
                    format!(
                        "list property {:?} on element {:?} is not supported",
                        p.name, el.name
                    ),
                ));
            }
        };
        plans.push(plan);
    }
    match role {
        Role::Vertex => {
            for c in ["x", "y", "z"] {
                if !el.props.iter().any(|p| p.name == c) {
                    return Err(err_line(el.line, format!("the vertex element has no {c}")));
                }
            }
        }
        Role::Face if !have_indices => {
            return Err(err_line(
                el.line,
                "the face element has no vertex_indices list",
            ));
        }
        _ => {}
    }
    Ok(plans)
}

/// Minimum bytes one row needs (binary: exact sizes; ASCII: one character and one separator
/// per value), used to reject absurd counts before allocating.
fn min_row_bytes(plans: &[Plan], ascii: bool) -> u64 {
    plans
        .iter()
        .map(|p| match (p, ascii) {
            (_, true) => 2,
            (Plan::Scalar { t, .. }, false) => t.size() as u64,
            (Plan::Indices { count, .. } | Plan::List { count, .. }, false) => count.size() as u64,
        })
        .sum()
}

/// State shared by all elements while reading a body.
struct Ctx {
    nv: u64,
    face_starts: Vec<u32>,
    face_indices: Vec<u32>,
}

/// Reads the rows of one element, value by value (all encodings, all layouts).
fn read_rows(
    src: &mut dyn Source,
    el: &ElementDef,
    plans: &[Plan],
    rows: usize,
    ctx: &mut Ctx,
) -> Result<Vec<Out>, IoError> {
    let mut outs: Vec<Out> = plans
        .iter()
        .map(|p| match *p {
            Plan::Scalar { t, .. } => Out::Col(empty_col(t, rows)),
            Plan::Indices { .. } => Out::Indices,
            Plan::List { count, item } => Out::List(ListProperty {
                name: String::new(),
                count_type: count,
                item_type: item,
                starts: {
                    let mut s = Vec::with_capacity(rows + 1);
                    s.push(0);
                    s
                },
                items: Vec::new(),
            }),
        })
        .collect();
    for (k, p) in el.props.iter().enumerate() {
        if let Out::List(l) = &mut outs[k] {
            l.name = p.name.clone();
        }
    }
    let is_face = plans.iter().any(|p| matches!(p, Plan::Indices { .. }));
    if is_face {
        ctx.face_starts.reserve(rows + 1);
    }
    for row in 0..rows {
        src.begin_row(&|| format!("{} {row} of {}", el.name, el.count))?;
        for (plan, out) in plans.iter().zip(outs.iter_mut()) {
            match (*plan, out) {
                (Plan::Scalar { finite, .. }, Out::Col(col)) => {
                    src.push_scalar(col)?;
                    if finite {
                        let x = col.get_f64(col.len() - 1);
                        if !x.is_finite() {
                            return Err(
                                src.err(format!("vertex {row} has a non-finite coordinate"))
                            );
                        }
                    }
                }
                (Plan::Indices { count, item }, Out::Indices) => {
                    let n = src.int(count)?;
                    if n < 0 {
                        return Err(src.err(format!("face {row} has a negative length {n}")));
                    }
                    src.check_items(n as u64, item)?;
                    for _ in 0..n {
                        let i = src.int(item)?;
                        if i < 0 {
                            return Err(src.err(format!("face {row} has negative index {i}")));
                        }
                        if i as u64 >= ctx.nv {
                            return Err(src.err(format!(
                                "face {row} has index {i} but the file has {} vertices",
                                ctx.nv
                            )));
                        }
                        ctx.face_indices.push(i as u32);
                    }
                    let len = u32::try_from(ctx.face_indices.len())
                        .map_err(|_| src.err("more than 2^32 - 1 face indices".into()))?;
                    ctx.face_starts.push(len);
                }
                (Plan::List { count, item }, Out::List(l)) => {
                    let n = src.int(count)?;
                    if n < 0 {
                        return Err(src.err(format!(
                            "{} {row}: list {:?} has a negative length {n}",
                            el.name, l.name
                        )));
                    }
                    src.check_items(n as u64, item)?;
                    for _ in 0..n {
                        l.items.push(src.num(item)?);
                    }
                    let len = u32::try_from(l.items.len())
                        .map_err(|_| src.err("more than 2^32 - 1 list items".into()))?;
                    l.starts.push(len);
                }
                _ => unreachable!("plans and outputs are built together"),
            }
        }
        src.end_row()?;
    }
    Ok(outs)
}

/// Decodes one fixed-offset scalar column of a fixed-stride binary block.
fn column(block: &[u8], stride: usize, off: usize, t: ScalarType, big: bool) -> AttributeData {
    macro_rules! col {
        ($ty:ty, $var:ident) => {{
            const N: usize = std::mem::size_of::<$ty>();
            AttributeData::$var(
                block
                    .chunks_exact(stride)
                    .map(|r| {
                        let mut a = [0u8; N];
                        a.copy_from_slice(&r[off..off + N]);
                        if big {
                            <$ty>::from_be_bytes(a)
                        } else {
                            <$ty>::from_le_bytes(a)
                        }
                    })
                    .collect(),
            )
        }};
    }
    match t {
        ScalarType::I8 => col!(i8, I8),
        ScalarType::U8 => col!(u8, U8),
        ScalarType::I16 => col!(i16, I16),
        ScalarType::U16 => col!(u16, U16),
        ScalarType::I32 => col!(i32, I32),
        ScalarType::U32 => col!(u32, U32),
        ScalarType::F32 => col!(f32, F32),
        ScalarType::F64 => col!(f64, F64),
    }
}

/// Fast path: binary little-endian face element whose only property is
/// `list <uchar|ushort|uint|…> <int|uint> vertex_indices`.
fn read_faces_fast(
    data: &[u8],
    mut pos: usize,
    rows: usize,
    count: ScalarType,
    item: ScalarType,
    ctx: &mut Ctx,
) -> Result<usize, IoError> {
    let csize = count.size();
    let nv = ctx.nv;
    let signed = item == ScalarType::I32;
    let left = data.len() - pos;
    ctx.face_starts.reserve(rows + 1);
    ctx.face_indices
        .reserve((rows.saturating_mul(3)).min(left / 4));
    for f in 0..rows {
        let Some(cb) = data.get(pos..pos + csize) else {
            return Err(err_byte(
                pos as u64,
                "the file ends in the middle of the faces",
            ));
        };
        let n: i64 = match count {
            ScalarType::U8 => cb[0] as i64,
            ScalarType::I8 => cb[0] as i8 as i64,
            ScalarType::U16 => u16::from_le_bytes([cb[0], cb[1]]) as i64,
            ScalarType::I16 => i16::from_le_bytes([cb[0], cb[1]]) as i64,
            ScalarType::U32 => u32::from_le_bytes([cb[0], cb[1], cb[2], cb[3]]) as i64,
            _ => i32::from_le_bytes([cb[0], cb[1], cb[2], cb[3]]) as i64,
        };
        if n < 0 {
            return Err(err_byte(
                pos as u64,
                format!("face {f} has a negative length {n}"),
            ));
        }
        pos += csize;
        let end = (n as u64)
            .checked_mul(4)
            .and_then(|b| b.checked_add(pos as u64))
            .filter(|&e| e <= data.len() as u64)
            .ok_or_else(|| {
                err_byte(
                    pos as u64,
                    format!("face {f} has {n} indices, more than the rest of the file holds"),
                )
            })? as usize;
        for (k, c) in data[pos..end].chunks_exact(4).enumerate() {
            let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if v as u64 >= nv || (signed && v > i32::MAX as u32) {
                let at = (pos + 4 * k) as u64;
                return Err(if signed && v > i32::MAX as u32 {
                    err_byte(at, format!("face {f} has negative index {}", v as i32))
                } else {
                    err_byte(
                        at,
                        format!("face {f} has index {v} but the file has {nv} vertices"),
                    )
                });
            }
            ctx.face_indices.push(v);
        }
        pos = end;
        let len = u32::try_from(ctx.face_indices.len())
            .map_err(|_| err_byte(pos as u64, "more than 2^32 - 1 face indices"))?;
        ctx.face_starts.push(len);
    }
    Ok(pos)
}

/// Reads a PLY file (any encoding).
pub fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let header = parse_header(bytes)?;
    let ascii = header.encoding == PlyEncoding::Ascii;
    let big = header.encoding == PlyEncoding::BinaryBigEndian;

    let roles: Vec<Role> = header
        .elements
        .iter()
        .map(|e| match e.name.as_str() {
            "vertex" => Role::Vertex,
            "face" => Role::Face,
            _ => Role::Extra,
        })
        .collect();
    let vertex_el = header.elements.iter().find(|e| e.name == "vertex");
    let nv = match vertex_el {
        Some(e) => e.count,
        None => {
            return Err(err_line(
                header.body_line - 1,
                "the file has no vertex element",
            ));
        }
    };
    if nv > u32::MAX as u64 {
        return Err(err_line(
            vertex_el.map_or(0, |e| e.line),
            format!("{nv} vertices is more than 2^32 - 1"),
        ));
    }

    let mut mesh = PolygonMesh::new();
    mesh.comments = header.comments;
    let mut ctx = Ctx {
        nv,
        face_starts: vec![0],
        face_indices: Vec::new(),
    };

    let mut bin = Bin {
        data: bytes,
        pos: header.body,
        last: header.body,
        big,
    };
    let mut asc = Ascii {
        lines: Lines::new(&bytes[header.body..], header.body_line),
        line_no: header.body_line - 1,
        toks: Vec::new(),
        next: 0,
    };

    for (el, role) in header.elements.iter().zip(&roles) {
        let plans = plan_element(el, role)?;
        if plans.is_empty() {
            // An element without properties occupies no bytes; only its row count is kept.
            mesh.extra_elements.push(ExtraElement {
                name: el.name.clone(),
                rows: usize::try_from(el.count).map_err(|_| {
                    err_line(el.line, format!("element count {} is too large", el.count))
                })?,
                properties: Vec::new(),
            });
            continue;
        }
        // Reject counts the rest of the file cannot hold, before allocating anything.
        let left = if ascii {
            // Rows are separated by line breaks; the last one may lack its own.
            asc.lines.rest_len() as u64 + 1
        } else {
            (bytes.len() - bin.pos) as u64
        };
        let need = el.count.saturating_mul(min_row_bytes(&plans, ascii));
        if need > left {
            let what = format!(
                "element {:?} claims {} rows (at least {need} bytes) but only {left} bytes remain",
                el.name, el.count
            );
            return Err(if ascii {
                err_line(el.line, what)
            } else {
                err_byte(bin.pos as u64, what)
            });
        }
        let rows = el.count as usize; // fits: bounded by the file size above

        let all_scalar = plans.iter().all(|p| matches!(p, Plan::Scalar { .. }));
        let outs = if !ascii && all_scalar {
            // Fixed-stride block: decode column by column.
            let stride: usize = plans
                .iter()
                .map(|p| match p {
                    Plan::Scalar { t, .. } => t.size(),
                    _ => 0,
                })
                .sum();
            let block = &bytes[bin.pos..bin.pos + rows * stride];
            let start = bin.pos;
            let mut off = 0;
            let mut outs = Vec::with_capacity(plans.len());
            for plan in &plans {
                let Plan::Scalar { t, finite } = *plan else {
                    unreachable!()
                };
                let col = column(block, stride, off, t, big);
                if finite {
                    for i in 0..col.len() {
                        if !col.get_f64(i).is_finite() {
                            return Err(err_byte(
                                (start + i * stride + off) as u64,
                                format!("vertex {i} has a non-finite coordinate"),
                            ));
                        }
                    }
                }
                outs.push(Out::Col(col));
                off += t.size();
            }
            bin.pos += rows * stride;
            outs
        } else if !ascii
            && !big
            && plans.len() == 1
            && matches!(
                plans[0],
                Plan::Indices {
                    item: ScalarType::I32 | ScalarType::U32,
                    ..
                }
            )
        {
            let Plan::Indices { count, item } = plans[0] else {
                unreachable!()
            };
            bin.pos = read_faces_fast(bytes, bin.pos, rows, count, item, &mut ctx)?;
            vec![Out::Indices]
        } else if ascii {
            read_rows(&mut asc, el, &plans, rows, &mut ctx)?
        } else {
            read_rows(&mut bin, el, &plans, rows, &mut ctx)?
        };

        match role {
            Role::Vertex => {
                let mut xyz: [Option<AttributeData>; 3] = [None, None, None];
                for (p, out) in el.props.iter().zip(outs) {
                    let Out::Col(data) = out else { continue };
                    match p.name.as_str() {
                        "x" => xyz[0] = Some(data),
                        "y" => xyz[1] = Some(data),
                        "z" => xyz[2] = Some(data),
                        _ => mesh.vertex_attributes.push(Attribute {
                            name: p.name.clone(),
                            data,
                        }),
                    }
                }
                let [Some(x), Some(y), Some(z)] = xyz else {
                    unreachable!("checked by plan_element")
                };
                mesh.position_type = Some(position_type(&x, &y, &z));
                mesh.positions = positions(&x, &y, &z);
            }
            Role::Face => {
                for (p, out) in el.props.iter().zip(outs) {
                    if let Out::Col(data) = out {
                        mesh.face_attributes.push(Attribute {
                            name: p.name.clone(),
                            data,
                        });
                    }
                }
            }
            Role::Extra => {
                let properties = el
                    .props
                    .iter()
                    .zip(outs)
                    .map(|(p, out)| match out {
                        Out::Col(data) => ElementProperty::Scalar(Attribute {
                            name: p.name.clone(),
                            data,
                        }),
                        Out::List(l) => ElementProperty::List(l),
                        Out::Indices => unreachable!("extra elements have no indices"),
                    })
                    .collect();
                mesh.extra_elements.push(ExtraElement {
                    name: el.name.clone(),
                    rows,
                    properties,
                });
            }
        }
    }
    mesh.face_starts = ctx.face_starts;
    mesh.face_indices = ctx.face_indices;
    Ok(mesh)
}

fn position_type(x: &AttributeData, y: &AttributeData, z: &AttributeData) -> ScalarType {
    let (a, b, c) = (x.scalar_type(), y.scalar_type(), z.scalar_type());
    if a == b && b == c {
        a
    } else if [a, b, c].contains(&ScalarType::F64) {
        ScalarType::F64
    } else {
        ScalarType::F32
    }
}

fn positions(x: &AttributeData, y: &AttributeData, z: &AttributeData) -> Vec<DVec3> {
    match (x, y, z) {
        (AttributeData::F32(x), AttributeData::F32(y), AttributeData::F32(z)) => x
            .iter()
            .zip(y)
            .zip(z)
            .map(|((&x, &y), &z)| DVec3::new(x as f64, y as f64, z as f64))
            .collect(),
        (AttributeData::F64(x), AttributeData::F64(y), AttributeData::F64(z)) => x
            .iter()
            .zip(y)
            .zip(z)
            .map(|((&x, &y), &z)| DVec3::new(x, y, z))
            .collect(),
        _ => (0..x.len())
            .map(|i| DVec3::new(x.get_f64(i), y.get_f64(i), z.get_f64(i)))
            .collect(),
    }
}

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------

fn check_name(name: &str, what: &str) -> Result<(), IoError> {
    if name.is_empty() || name.bytes().any(|b| b.is_ascii_whitespace()) {
        return Err(err_invalid(
            MeshFormat::Ply,
            format!("{what} name {name:?} is empty or contains whitespace"),
        ));
    }
    Ok(())
}

fn check_unique<'a>(
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
fn fits(x: f64, t: ScalarType) -> bool {
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

fn max_count(t: ScalarType) -> u64 {
    match t {
        ScalarType::I8 => i8::MAX as u64,
        ScalarType::U8 => u8::MAX as u64,
        ScalarType::I16 => i16::MAX as u64,
        ScalarType::U16 => u16::MAX as u64,
        ScalarType::I32 => i32::MAX as u64,
        _ => u32::MAX as u64,
    }
}

fn validate(mesh: &PolygonMesh) -> Result<(), IoError> {
    for c in &mesh.comments {
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
        mesh.face_attributes.iter().map(|a| a.name.as_str()),
        &["vertex_indices"],
        "face attribute",
    )?;
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
                ElementProperty::List(l) => {
                    if !is_int(l.count_type) {
                        return Err(bad(&format!("{} has a non-integer count type", l.name)));
                    }
                    if l.starts.len() != e.rows + 1
                        || l.starts[0] != 0
                        || *l.starts.last().unwrap_or(&0) as usize != l.items.len()
                        || l.starts
                            .windows(2)
                            .any(|w| w[0] > w[1] || (w[1] - w[0]) as u64 > max_count(l.count_type))
                    {
                        return Err(bad(&format!("list {} has inconsistent offsets", l.name)));
                    }
                    if let Some(x) = l.items.iter().find(|&&x| !fits(x, l.item_type)) {
                        return Err(bad(&format!(
                            "list {} holds {x}, which is not a valid {}",
                            l.name,
                            type_name(l.item_type)
                        )));
                    }
                }
            }
        }
    }
    Ok(())
}

/// Appends one value of `col` (row `i`) to a binary body.
fn put_bin(out: &mut Vec<u8>, col: &AttributeData, i: usize, big: bool) {
    macro_rules! put {
        ($v:expr) => {
            if big {
                out.extend_from_slice(&$v.to_be_bytes())
            } else {
                out.extend_from_slice(&$v.to_le_bytes())
            }
        };
    }
    match col {
        AttributeData::I8(v) => put!(v[i]),
        AttributeData::U8(v) => put!(v[i]),
        AttributeData::I16(v) => put!(v[i]),
        AttributeData::U16(v) => put!(v[i]),
        AttributeData::I32(v) => put!(v[i]),
        AttributeData::U32(v) => put!(v[i]),
        AttributeData::F32(v) => put!(v[i]),
        AttributeData::F64(v) => put!(v[i]),
    }
}

/// Appends one value of `col` (row `i`) as text.
fn put_txt(out: &mut String, col: &AttributeData, i: usize) {
    match col {
        AttributeData::F32(v) => text::push_f32(out, v[i]),
        AttributeData::F64(v) => text::push_f64(out, v[i]),
        _ => {
            let _ = write!(out, "{}", col.get_f64(i) as i64);
        }
    }
}

/// Appends `x` (exactly representable in `t`) in type `t`.
fn put_num_bin(out: &mut Vec<u8>, x: f64, t: ScalarType, big: bool) {
    macro_rules! put {
        ($v:expr) => {
            if big {
                out.extend_from_slice(&$v.to_be_bytes())
            } else {
                out.extend_from_slice(&$v.to_le_bytes())
            }
        };
    }
    match t {
        ScalarType::I8 => put!(x as i8),
        ScalarType::U8 => put!(x as u8),
        ScalarType::I16 => put!(x as i16),
        ScalarType::U16 => put!(x as u16),
        ScalarType::I32 => put!(x as i32),
        ScalarType::U32 => put!(x as u32),
        ScalarType::F32 => put!(x as f32),
        ScalarType::F64 => put!(x),
    }
}

fn put_num_txt(out: &mut String, x: f64, t: ScalarType) {
    match t {
        ScalarType::F32 => text::push_f32(out, x as f32),
        ScalarType::F64 => text::push_f64(out, x),
        _ => {
            let _ = write!(out, "{}", x as i64);
        }
    }
}

/// Writes a PLY file.
pub fn write(mesh: &PolygonMesh, encoding: PlyEncoding) -> Result<Vec<u8>, IoError> {
    validate(mesh)?;
    let nv = mesh.positions.len();
    let nf = mesh.n_faces();
    // Positions: keep double for double input; float otherwise, unless a value would overflow.
    let pos_double = match mesh.position_type {
        Some(ScalarType::F64) => true,
        None => mesh.positions.iter().any(|p| !p.as_vec3().is_finite()),
        Some(_) => {
            if let Some(i) = mesh.positions.iter().position(|p| !p.as_vec3().is_finite()) {
                return Err(err_invalid(
                    MeshFormat::Ply,
                    format!("vertex {i} does not fit in float (set position_type to F64)"),
                ));
            }
            false
        }
    };
    let max_len = mesh.faces().map(|f| f.len()).max().unwrap_or(0);
    let count_type = if max_len <= 255 {
        ScalarType::U8
    } else {
        ScalarType::U32
    };
    let index_type = if nv <= i32::MAX as usize {
        ScalarType::I32
    } else {
        ScalarType::U32
    };

    let mut h = String::new();
    h.push_str("ply\n");
    h.push_str(match encoding {
        PlyEncoding::Ascii => "format ascii 1.0\n",
        PlyEncoding::BinaryLittleEndian => "format binary_little_endian 1.0\n",
        PlyEncoding::BinaryBigEndian => "format binary_big_endian 1.0\n",
    });
    for c in &mesh.comments {
        let _ = writeln!(h, "comment {c}");
    }
    let pt = if pos_double { "double" } else { "float" };
    let _ = writeln!(h, "element vertex {nv}");
    for c in ["x", "y", "z"] {
        let _ = writeln!(h, "property {pt} {c}");
    }
    for a in &mesh.vertex_attributes {
        let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
    }
    let _ = writeln!(h, "element face {nf}");
    let _ = writeln!(
        h,
        "property list {} {} vertex_indices",
        type_name(count_type),
        type_name(index_type)
    );
    for a in &mesh.face_attributes {
        let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
    }
    for e in &mesh.extra_elements {
        let _ = writeln!(h, "element {} {}", e.name, e.rows);
        for p in &e.properties {
            match p {
                ElementProperty::Scalar(a) => {
                    let _ = writeln!(h, "property {} {}", type_name(a.data.scalar_type()), a.name);
                }
                ElementProperty::List(l) => {
                    let _ = writeln!(
                        h,
                        "property list {} {} {}",
                        type_name(l.count_type),
                        type_name(l.item_type),
                        l.name
                    );
                }
            }
        }
    }
    h.push_str("end_header\n");

    match encoding {
        PlyEncoding::Ascii => {
            let mut s = h;
            let prec = if pos_double {
                text::TextPrecision::F64
            } else {
                text::TextPrecision::F32
            };
            for (i, p) in mesh.positions.iter().enumerate() {
                for (k, c) in p.to_array().into_iter().enumerate() {
                    if k > 0 {
                        s.push(' ');
                    }
                    let _ = prec.push(&mut s, c);
                }
                for a in &mesh.vertex_attributes {
                    s.push(' ');
                    put_txt(&mut s, &a.data, i);
                }
                s.push('\n');
            }
            for (f, face) in mesh.faces().enumerate() {
                let _ = write!(s, "{}", face.len());
                for &v in face {
                    let _ = write!(s, " {v}");
                }
                for a in &mesh.face_attributes {
                    s.push(' ');
                    put_txt(&mut s, &a.data, f);
                }
                s.push('\n');
            }
            for e in &mesh.extra_elements {
                if e.properties.is_empty() {
                    continue;
                }
                for r in 0..e.rows {
                    for (k, p) in e.properties.iter().enumerate() {
                        if k > 0 {
                            s.push(' ');
                        }
                        match p {
                            ElementProperty::Scalar(a) => put_txt(&mut s, &a.data, r),
                            ElementProperty::List(l) => {
                                let items =
                                    &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
                                let _ = write!(s, "{}", items.len());
                                for &x in items {
                                    s.push(' ');
                                    put_num_txt(&mut s, x, l.item_type);
                                }
                            }
                        }
                    }
                    s.push('\n');
                }
            }
            Ok(s.into_bytes())
        }
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let big = encoding == PlyEncoding::BinaryBigEndian;
            let mut out = h.into_bytes();
            let vsize = if pos_double { 24 } else { 12 }
                + mesh
                    .vertex_attributes
                    .iter()
                    .map(|a| a.data.scalar_type().size())
                    .sum::<usize>();
            out.reserve(nv * vsize + nf + mesh.face_indices.len() * 4);
            for (i, p) in mesh.positions.iter().enumerate() {
                for c in p.to_array() {
                    if pos_double {
                        put_num_bin(&mut out, c, ScalarType::F64, big);
                    } else {
                        put_num_bin(&mut out, c, ScalarType::F32, big);
                    }
                }
                for a in &mesh.vertex_attributes {
                    put_bin(&mut out, &a.data, i, big);
                }
            }
            for (f, face) in mesh.faces().enumerate() {
                put_num_bin(&mut out, face.len() as f64, count_type, big);
                for &v in face {
                    if big {
                        out.extend_from_slice(&v.to_be_bytes());
                    } else {
                        out.extend_from_slice(&v.to_le_bytes());
                    }
                }
                for a in &mesh.face_attributes {
                    put_bin(&mut out, &a.data, f, big);
                }
            }
            for e in mesh
                .extra_elements
                .iter()
                .filter(|e| !e.properties.is_empty())
            {
                for r in 0..e.rows {
                    for p in &e.properties {
                        match p {
                            ElementProperty::Scalar(a) => put_bin(&mut out, &a.data, r, big),
                            ElementProperty::List(l) => {
                                let items =
                                    &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
                                put_num_bin(&mut out, items.len() as f64, l.count_type, big);
                                for &x in items {
                                    put_num_bin(&mut out, x, l.item_type, big);
                                }
                            }
                        }
                    }
                }
            }
            Ok(out)
        }
    }
}
