//! The PLY header: format line, comments, elements and their properties.

use super::types::{is_int, parse_type};
use crate::io::text;
use crate::io::{IoError, PlyEncoding, err_line};
use crate::mesh::ScalarType;

/// A property's type: a scalar, or a list with its count and item types.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum PropKind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

/// One `property` line.
#[derive(Debug)]
pub(super) struct PropDef {
    pub(super) name: String,
    pub(super) kind: PropKind,
}

/// One `element` line and its properties; `line` is where it was defined.
#[derive(Debug)]
pub(super) struct ElementDef {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) props: Vec<PropDef>,
    pub(super) line: u64,
}

/// What a PLY header says.
pub(super) struct Header {
    pub(super) encoding: PlyEncoding,
    pub(super) elements: Vec<ElementDef>,
    pub(super) comments: Vec<String>,
    /// Byte offset of the body.
    pub(super) body: usize,
    /// Line number of the first body line (ASCII).
    pub(super) body_line: u64,
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

/// Parses the header: the `ply` line, then format, comment, element and property lines up to
/// `end_header`.
pub(super) fn parse_header(bytes: &[u8]) -> Result<Header, IoError> {
    let mut lines = HeaderLines {
        bytes,
        pos: 0,
        line_no: 0,
    };
    check_magic(&mut lines)?;
    let mut encoding = None;
    let mut elements: Vec<ElementDef> = Vec::new();
    let mut comments = Vec::new();
    loop {
        let line = lines.next_line()?;
        let line_no = lines.line_no;
        let mut toks = text::tokens(line);
        match toks.next().unwrap_or(b"") {
            b"format" => set_format(&mut encoding, toks.next(), line_no)?,
            kw @ (b"comment" | b"obj_info") => comments.push(comment_text(line, kw)),
            b"element" => push_element(&mut elements, toks, line_no)?,
            b"property" => push_property(&mut elements, toks, line_no)?,
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
    let encoding =
        encoding.ok_or_else(|| err_line(lines.line_no, "the header has no format line"))?;
    Ok(Header {
        encoding,
        elements,
        comments,
        body: lines.pos,
        body_line: lines.line_no + 1,
    })
}

/// The header's lines, numbered from 1.
struct HeaderLines<'a> {
    bytes: &'a [u8],
    /// Byte offset of the next line.
    pos: usize,
    /// Number of the line returned last.
    line_no: u64,
}

impl<'a> HeaderLines<'a> {
    /// The next line without its line break; a header must end with a line break.
    fn next_line(&mut self) -> Result<&'a [u8], IoError> {
        self.line_no += 1;
        let Some(nl) = self.bytes[self.pos..].iter().position(|&b| b == b'\n') else {
            return Err(err_line(
                self.line_no,
                if self.line_no == 1 {
                    "not a PLY file (no header line)"
                } else {
                    "the header has no end_header line"
                },
            ));
        };
        let line = text::strip_cr(&self.bytes[self.pos..self.pos + nl]);
        self.pos += nl + 1;
        Ok(line)
    }
}

/// The first line must be `ply`.
fn check_magic(lines: &mut HeaderLines) -> Result<(), IoError> {
    let line = lines.next_line()?;
    let kw = text::tokens(line).next().unwrap_or(b"");
    if line != b"ply" && kw != b"ply" {
        return Err(err_line(1, "not a PLY file (first line is not `ply`)"));
    }
    Ok(())
}

/// `format <encoding> <version>`: the body encoding, given once.
fn set_format(
    encoding: &mut Option<PlyEncoding>,
    name: Option<&[u8]>,
    line_no: u64,
) -> Result<(), IoError> {
    if encoding.is_some() {
        return Err(err_line(line_no, "second format line"));
    }
    *encoding = Some(match name {
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
    Ok(())
}

/// The text of a `comment` line, or an `obj_info` line kept as the comment `obj_info …`.
fn comment_text(line: &[u8], kw: &[u8]) -> String {
    let rest = keyword_rest(line, kw).unwrap_or(b"");
    let rest = String::from_utf8_lossy(rest);
    if kw == b"comment" {
        rest.into_owned()
    } else {
        format!("obj_info {rest}")
    }
}

/// `element <name> <count>`: a new element, which the property lines after it describe.
fn push_element<'a>(
    elements: &mut Vec<ElementDef>,
    mut toks: impl Iterator<Item = &'a [u8]>,
    line_no: u64,
) -> Result<(), IoError> {
    let (Some(name), Some(count), None) = (toks.next(), toks.next(), toks.next()) else {
        return Err(err_line(line_no, "expected `element <name> <count>`"));
    };
    let count: u64 = std::str::from_utf8(count)
        .ok()
        .and_then(|c| c.parse().ok())
        .ok_or_else(|| err_line(line_no, format!("bad element count {}", text::show(count))))?;
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
    Ok(())
}

/// `property <type> <name>` or `property list <count type> <item type> <name>`: a property
/// of the element defined last.
fn push_property<'a>(
    elements: &mut [ElementDef],
    mut toks: impl Iterator<Item = &'a [u8]>,
    line_no: u64,
) -> Result<(), IoError> {
    let Some(el) = elements.last_mut() else {
        return Err(err_line(line_no, "property before any element"));
    };
    let kind = property_kind(&mut toks, line_no)?;
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
    Ok(())
}

/// The type part of a property line: a scalar type, or `list` and its count and item types.
fn property_kind<'a>(
    toks: &mut impl Iterator<Item = &'a [u8]>,
    line_no: u64,
) -> Result<PropKind, IoError> {
    let t = toks.next().unwrap_or(b"");
    if t != b"list" {
        return Ok(PropKind::Scalar(scalar_type(t, line_no)?));
    }
    let ct = toks.next().unwrap_or(b"");
    let it = toks.next().unwrap_or(b"");
    let count = scalar_type(ct, line_no)?;
    let item = scalar_type(it, line_no)?;
    if !is_int(count) {
        return Err(err_line(line_no, "list count type must be an integer type"));
    }
    Ok(PropKind::List { count, item })
}

/// A scalar type name (`uchar`, `float32`, …).
fn scalar_type(name: &[u8], line_no: u64) -> Result<ScalarType, IoError> {
    parse_type(name).ok_or_else(|| err_line(line_no, format!("unknown type {}", text::show(name))))
}
