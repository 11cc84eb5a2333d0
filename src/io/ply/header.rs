//! The PLY header: format line, comments, elements and their properties.

use super::types::{is_int, parse_type};
use crate::io::text;
use crate::io::{IoError, PlyEncoding, err_line};
use crate::mesh::ScalarType;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum PropKind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

#[derive(Debug)]
pub(super) struct PropDef {
    pub(super) name: String,
    pub(super) kind: PropKind,
}

#[derive(Debug)]
pub(super) struct ElementDef {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) props: Vec<PropDef>,
    pub(super) line: u64,
}

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

pub(super) fn parse_header(bytes: &[u8]) -> Result<Header, IoError> {
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
