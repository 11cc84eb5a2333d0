//! Gzip-compressed meshes (`scan.obj.gz`), inflated as a stream so that memory follows the mesh
//! rather than the decompressed text.
//!
//! The readers parse a byte slice, so the decompressed data is collected first. Comments are the
//! one part of a text mesh that can be arbitrarily large without being mesh data (one triangle
//! and then a gigabyte of `#` text inflates from a few megabytes): for OBJ and OFF the comments
//! the reader would discard anyway are dropped while inflating, keeping the `#`, a `\` that
//! continues an OBJ line and every line end, so the reader sees the same statements on the same
//! line numbers. Comments before the data are kept whole, since they become
//! [`PolygonMesh::comments`](crate::PolygonMesh::comments). Binary formats have no comments to
//! drop; their decompressed size is their data.

use std::io::Read;
use std::path::Path;

use super::{IoError, Location, MeshFormat, err_file};

/// Bytes inflated per step.
const CHUNK: usize = 1 << 16;

/// Reads a gzip-compressed mesh file of `format` into the bytes its reader needs (see the
/// module docs); errors name the file.
pub(crate) fn read_gz_file(path: &Path, format: MeshFormat) -> Result<Vec<u8>, IoError> {
    let io_err = |error| IoError::Io {
        path: path.to_path_buf(),
        error,
    };
    let mut file = std::io::BufReader::new(std::fs::File::open(path).map_err(io_err)?);
    let mut magic = [0u8; 2];
    let n = file.read(&mut magic).map_err(io_err)?;
    let head = std::io::Cursor::new(magic[..n].to_vec());
    let stream = head.chain(file);
    let squeezer = CommentSqueezer::for_format(format);
    inflate(&magic[..n], stream, squeezer).map_err(|e| e.with_path(path))
}

/// The first `at_most` decompressed bytes of the gzip data that `compressed` starts with (a
/// header to read counts from); `None` when it is not gzip data or nothing inflates.
pub(crate) fn head_of_gz(compressed: &[u8], at_most: usize) -> Option<Vec<u8>> {
    if !compressed.starts_with(&[0x1f, 0x8b]) {
        return None;
    }
    let mut out = Vec::new();
    let decoder = flate2::read::MultiGzDecoder::new(compressed);
    // A truncated stream is fine here: the head is what counts.
    let _ = decoder.take(at_most as u64).read_to_end(&mut out);
    (!out.is_empty()).then_some(out)
}

/// Decompresses gzip data (several concatenated members too, as `cat a.gz b.gz` makes).
///
/// A corrupt or truncated stream is a parse error (with the number of decompressed bytes
/// reached); running out of memory for the output is an error that says the data exceeds it.
pub fn gunzip(bytes: &[u8]) -> Result<Vec<u8>, IoError> {
    inflate(bytes, bytes, None)
}

/// Compresses with gzip (level 6; no file name or time stamp in the header, so the same mesh
/// always gives the same bytes).
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(
        Vec::with_capacity(bytes.len() / 3),
        flate2::Compression::default(),
    );
    enc.write_all(bytes)
        .expect("writing into a Vec cannot fail");
    enc.finish().expect("writing into a Vec cannot fail")
}

/// Inflates `stream` (which starts with `head`, checked for the gzip signature), passing the
/// output through `squeezer` when there is one.
fn inflate(
    head: &[u8],
    stream: impl Read,
    mut squeezer: Option<CommentSqueezer>,
) -> Result<Vec<u8>, IoError> {
    if !head.starts_with(&[0x1f, 0x8b]) {
        return Err(IoError::Parse {
            path: None,
            location: Location::Byte(0),
            reason: "not a gzip file (the name ends in .gz)".into(),
        });
    }
    let mut decoder = flate2::read::MultiGzDecoder::new(stream);
    let mut chunk = vec![0u8; CHUNK];
    let mut out = Vec::new();
    let mut inflated: u64 = 0;
    loop {
        let n = match decoder.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) if e.kind() == std::io::ErrorKind::OutOfMemory => {
                return Err(exceeds_memory(inflated, out.len()));
            }
            Err(e) => {
                return Err(err_file(format!(
                    "gzip data is corrupt or truncated after {inflated} decompressed bytes: {e}"
                )));
            }
        };
        inflated += n as u64;
        // A squeezed chunk is never longer than the chunk itself.
        out.try_reserve(n)
            .map_err(|_| exceeds_memory(inflated, out.len()))?;
        match &mut squeezer {
            Some(s) => s.feed(&chunk[..n], &mut out),
            None => out.extend_from_slice(&chunk[..n]),
        }
    }
    Ok(out)
}

fn exceeds_memory(inflated: u64, kept: usize) -> IoError {
    err_file(format!(
        "the decompressed data exceeds the memory available ({kept} bytes kept of {inflated} \
         decompressed)"
    ))
}

/// Which comments a format's reader discards, and so which the squeezer may drop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CommentStyle {
    /// OBJ: `#` to the end of the logical line (`\` joins lines); the reader keeps the
    /// comments before the first statement.
    Obj,
    /// OFF: `#` to the end of the line; the reader keeps the comments up to the counts line,
    /// which is at most the second line with data.
    Off,
}

/// Drops the comment text that a reader would discard, line by line across chunk boundaries.
/// Keeps: every byte before a line's first `#`, the `#` itself, a final `\` (an OBJ
/// continuation) and the line end; everything up to the end of the preamble verbatim.
#[derive(Debug)]
pub(crate) struct CommentSqueezer {
    style: CommentStyle,
    /// Still in the preamble: lines are copied verbatim.
    verbatim: bool,
    /// OFF: lines with data seen so far in the preamble.
    data_lines: u32,
    /// The previous line ends with `\` (an OBJ continuation).
    previous_continues: bool,
    /// The current line: a `#` has been seen (and, out of the preamble, the rest is dropped).
    in_comment: bool,
    /// Non-blank bytes before the current line's first `#` (a final `\` among them).
    data_bytes: usize,
    /// The current line's last byte other than `\r` (what ends it once `\r`s are stripped).
    last: Option<u8>,
}

impl CommentSqueezer {
    /// The squeezer for a format's comments, if it has any to drop.
    fn for_format(format: MeshFormat) -> Option<CommentSqueezer> {
        let style = match format {
            MeshFormat::Obj => CommentStyle::Obj,
            MeshFormat::Off => CommentStyle::Off,
            MeshFormat::Ply | MeshFormat::Stl => return None,
        };
        Some(CommentSqueezer {
            style,
            verbatim: true,
            data_lines: 0,
            previous_continues: false,
            in_comment: false,
            data_bytes: 0,
            last: None,
        })
    }

    /// Appends `chunk`, squeezed, to `out` (never more bytes than `chunk` has).
    pub(crate) fn feed(&mut self, mut chunk: &[u8], out: &mut Vec<u8>) {
        while !chunk.is_empty() {
            match chunk.iter().position(|&b| b == b'\n') {
                Some(i) => {
                    self.take_segment(&chunk[..i], out);
                    self.end_line(out);
                    chunk = &chunk[i + 1..];
                }
                None => {
                    self.take_segment(chunk, out);
                    chunk = &[];
                }
            }
        }
    }

    /// A piece of the current line without its line end.
    fn take_segment(&mut self, segment: &[u8], out: &mut Vec<u8>) {
        if let Some(&b) = segment.iter().rev().find(|&&b| b != b'\r') {
            self.last = Some(b);
        }
        if self.in_comment {
            if self.verbatim {
                out.extend_from_slice(segment);
            }
            return;
        }
        let data_end = segment.iter().position(|&b| b == b'#');
        let data = &segment[..data_end.unwrap_or(segment.len())];
        self.data_bytes += data.iter().filter(|b| !b.is_ascii_whitespace()).count();
        match data_end {
            Some(hash) => {
                self.in_comment = true;
                let keep = if self.verbatim {
                    segment.len()
                } else {
                    hash + 1
                };
                out.extend_from_slice(&segment[..keep]);
            }
            None => out.extend_from_slice(segment),
        }
    }

    /// The end of the current line: restores a dropped continuation, writes the line end and
    /// decides whether the preamble is over.
    fn end_line(&mut self, out: &mut Vec<u8>) {
        let continues = self.last == Some(b'\\');
        if self.in_comment && !self.verbatim && continues {
            out.push(b'\\');
        }
        out.push(b'\n');
        // Without a comment, a final `\` is the line's last data byte, and no data: the reader
        // removes it when it joins the lines.
        let joins_data = !self.in_comment && continues;
        let has_data = self.data_bytes > usize::from(joins_data);
        if self.verbatim && has_data {
            self.verbatim = match self.style {
                // This line starts a statement, so the reader's preamble is over.
                CommentStyle::Obj => self.previous_continues,
                CommentStyle::Off => {
                    self.data_lines += 1;
                    self.data_lines < 2
                }
            };
        }
        self.previous_continues = continues;
        self.in_comment = false;
        self.data_bytes = 0;
        self.last = None;
    }
}

/// `bytes` as the squeezer passes them on, in chunks of `chunk` bytes (for tests and the fuzz
/// harness: a reader must parse the result exactly as it parses `bytes`). `None` for formats
/// without comments to drop.
pub(crate) fn squeeze(bytes: &[u8], format: MeshFormat, chunk: usize) -> Option<Vec<u8>> {
    let mut squeezer = CommentSqueezer::for_format(format)?;
    let mut out = Vec::with_capacity(bytes.len());
    for piece in bytes.chunks(chunk.max(1)) {
        squeezer.feed(piece, &mut out);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::read_mesh_bytes;

    fn squeezed(text: &str, format: MeshFormat) -> String {
        String::from_utf8(squeeze(text.as_bytes(), format, 3).unwrap()).unwrap()
    }

    #[test]
    fn obj_comments_after_the_first_statement_line_lose_their_text_but_keep_their_lines() {
        let text = "# kept\n#  kept too \r\nv 0 0 0 # gone\n# gone\nv 1 0 0\n";
        assert_eq!(
            squeezed(text, MeshFormat::Obj),
            "# kept\n#  kept too \r\nv 0 0 0 # gone\n#\nv 1 0 0\n"
        );
    }

    #[test]
    fn an_obj_comment_that_continues_keeps_its_backslash() {
        let text = "v 0 0 0\n# joined \\\r\nv 1 1 1\nv 2 2 2 # \\\nf 1 2 3\n";
        let out = squeezed(text, MeshFormat::Obj);
        assert_eq!(out, "v 0 0 0\n#\\\nv 1 1 1\nv 2 2 2 #\\\nf 1 2 3\n");
        let (a, b) = (
            read_mesh_bytes(text.as_bytes(), MeshFormat::Obj).unwrap(),
            read_mesh_bytes(out.as_bytes(), MeshFormat::Obj).unwrap(),
        );
        assert_eq!(a, b);
        assert_eq!(a.n_vertices(), 2);
    }

    #[test]
    fn a_continued_preamble_line_stays_in_the_preamble() {
        let text = "# a \\\nv 0 0 0\n# b\nv 1 0 0\n";
        assert_eq!(squeezed(text, MeshFormat::Obj), text);
    }

    /// A line holding only the continuation `\` joins nothing to the data: the preamble goes on
    /// (a fuzz find).
    #[test]
    fn a_lone_continuation_does_not_end_the_preamble() {
        let text = "\\\n\r#kept\nv 0 0 0\n# gone\n";
        assert_eq!(squeezed(text, MeshFormat::Obj), "\\\n\r#kept\nv 0 0 0\n#\n");
        let bytes = text.as_bytes();
        let mesh = read_mesh_bytes(bytes, MeshFormat::Obj).unwrap();
        assert_eq!(mesh.comments, ["kept"]);
    }

    #[test]
    fn off_comments_up_to_the_counts_line_are_kept() {
        let text = "OFF # a\n# b\n3 1 0 # c\n0 0 0 # d\n# e\n1 0 0\n0 1 0\n3 0 1 2 # f";
        assert_eq!(
            squeezed(text, MeshFormat::Off),
            "OFF # a\n# b\n3 1 0 # c\n0 0 0 #\n#\n1 0 0\n0 1 0\n3 0 1 2 #"
        );
    }

    #[test]
    fn binary_formats_are_not_squeezed() {
        assert!(squeeze(b"ply\n", MeshFormat::Ply, 8).is_none());
        assert!(squeeze(b"solid\n", MeshFormat::Stl, 8).is_none());
    }

    /// Every OBJ and OFF file of the test data and the fuzz corpus reads the same squeezed,
    /// whatever the chunk size.
    #[test]
    fn readers_see_the_same_mesh_through_the_squeezer() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut seen = 0;
        for (dir, format) in [
            ("tests/data", MeshFormat::Obj),
            ("tests/data", MeshFormat::Off),
            ("fuzz/corpus/read_obj", MeshFormat::Obj),
            ("fuzz/corpus/read_off", MeshFormat::Off),
            ("fuzz/regressions/read_obj", MeshFormat::Obj),
            ("fuzz/regressions/read_off", MeshFormat::Off),
        ] {
            let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
                continue;
            };
            for entry in entries.flatten() {
                let path = entry.path();
                let wanted = dir.starts_with("fuzz")
                    || path.extension().is_some_and(|e| e == format.extension());
                if !wanted || !path.is_file() {
                    continue;
                }
                let bytes = std::fs::read(&path).unwrap();
                for chunk in [1, 7, CHUNK] {
                    assert_same_reading(&bytes, format, chunk, &path.display().to_string());
                }
                seen += 1;
            }
        }
        assert!(seen > 20, "only {seen} files found");
    }

    fn assert_same_reading(bytes: &[u8], format: MeshFormat, chunk: usize, name: &str) {
        let out = squeeze(bytes, format, chunk).unwrap();
        assert!(
            out.len() <= bytes.len(),
            "{name}: the squeezer grew the data"
        );
        match (
            read_mesh_bytes(bytes, format),
            read_mesh_bytes(&out, format),
        ) {
            (Ok(a), Ok(b)) => assert!(same_mesh(&a, &b), "{name} (chunk {chunk})"),
            (Err(_), Err(_)) => {}
            (a, b) => panic!("{name} (chunk {chunk}): {:?} vs {:?}", a.err(), b.err()),
        }
    }

    /// Equal, NaN attributes included (compared through the writer, which keeps their bits).
    fn same_mesh(a: &crate::PolygonMesh, b: &crate::PolygonMesh) -> bool {
        let opts = crate::io::WriteOptions::default();
        let ply = |m| crate::io::write_mesh_bytes(m, MeshFormat::Ply, &opts).ok();
        a.comments == b.comments && ply(a) == ply(b)
    }
}
