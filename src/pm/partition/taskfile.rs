//! The container of the files a partitioned build's tasks exchange (`formats/blocks.md`): a
//! fixed header, a table of checksummed sections, the sections.
//!
//! ```text
//! offset size
//!      0    8  magic  89 'M' 'P' 'B' 0D 0A 1A 0A
//!      8    2  version (u16 LE)              readers refuse any other
//!     10    2  kind (u16 LE)                 what the file holds ([`Kind`])
//!     12    4  section count n (u32 LE)      the table must fit in the file
//!     16    4  CRC-32 of bytes 0..16 and of the section table
//!     20    4  reserved, 0
//!     24 32·n  section table, per entry: tag [u8; 4], cell u32, offset u64, length u64,
//!                CRC-32 of the section u32, reserved u32
//!      …       sections, in table order, contiguous
//! ```
//!
//! Why so: a task reads only the sections it needs (a cell's share of another task's output is
//! one section of it), each behind its own checksum; a file is written whole under a
//! temporary name and renamed into place, so a reader sees a complete file or none, and a task
//! retried after a crash writes the same bytes. Errors name the file and the byte offset.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// File signature.
pub(crate) const MAGIC: [u8; 8] = [0x89, b'M', b'P', b'B', 0x0d, 0x0a, 0x1a, 0x0a];
/// The version this code reads and writes.
pub(crate) const VERSION: u16 = 1;
const HEADER_LEN: usize = 24;
const ENTRY_LEN: usize = 32;

/// What a task file holds (`formats/blocks.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A part of the whole mesh between passes: faces and vertex records.
    Piece = 1,
    /// A piece's faces and vertices sorted by the cells of a pass, one set of sections per cell.
    Routed = 2,
    /// One block's input for a pass.
    Input = 3,
    /// One block's candidate costs, ascending.
    Costs = 4,
    /// One block's result: collapses, faces afterwards, records of its free survivors.
    Result = 5,
    /// A pass's parameters and its cell labels.
    Pass = 6,
    /// A pass's collapses, interleaved by cost.
    Sequence = 7,
    /// What the streaming split of a scan wrote: counts, bounding boxes, the cut tree and the
    /// cells' files' sizes and checksums.
    Manifest = 8,
    /// What a round of the cell tasks hands on: a cell's patches or extra fans, the driver's
    /// flips or copies, a cell's refusal.
    CellRound = 9,
}

impl Kind {
    /// Every kind of task file.
    pub(crate) const ALL: [Kind; 9] = [
        Kind::Piece,
        Kind::Routed,
        Kind::Input,
        Kind::Costs,
        Kind::Result,
        Kind::Pass,
        Kind::Sequence,
        Kind::Manifest,
        Kind::CellRound,
    ];

    fn from_code(code: u16) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| *k as u16 == code)
    }
}

/// A task file that cannot be read or written: the file, the byte offset, what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}: byte {offset}: {what}", path.display())]
pub struct BlockFileError {
    /// The file.
    pub path: PathBuf,
    /// Where in it (0 for the file as a whole).
    pub offset: u64,
    /// What is wrong.
    pub what: String,
}

impl BlockFileError {
    pub(crate) fn new(path: &Path, offset: u64, what: impl Into<String>) -> BlockFileError {
        BlockFileError {
            path: path.to_path_buf(),
            offset,
            what: what.into(),
        }
    }
}

/// A section to write: its tag, the cell it belongs to (0 when the file has no cells), its
/// bytes.
pub(crate) struct Section {
    pub tag: [u8; 4],
    pub cell: u32,
    pub bytes: Vec<u8>,
}

/// The bytes of a task file of `kind` with `sections`.
pub(crate) fn encode(kind: Kind, sections: &[Section]) -> Vec<u8> {
    let table_len = ENTRY_LEN * sections.len();
    let total = HEADER_LEN + table_len + sections.iter().map(|s| s.bytes.len()).sum::<usize>();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(kind as u16).to_le_bytes());
    out.extend_from_slice(&(sections.len() as u32).to_le_bytes());
    out.extend_from_slice(&[0; 8]);
    let mut offset = (HEADER_LEN + table_len) as u64;
    for s in sections {
        out.extend_from_slice(&s.tag);
        out.extend_from_slice(&s.cell.to_le_bytes());
        out.extend_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&(s.bytes.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&s.bytes).to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        offset += s.bytes.len() as u64;
    }
    let crc = head_crc(&out[..HEADER_LEN + table_len]);
    out[16..20].copy_from_slice(&crc.to_le_bytes());
    for s in sections {
        out.extend_from_slice(&s.bytes);
    }
    out
}

fn head_crc(head_and_table: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&head_and_table[..16]);
    h.update(&head_and_table[HEADER_LEN..]);
    h.finalize()
}

/// Distinguishes the temporary names of files written at the same time by one process.
static TEMPORARY: AtomicU64 = AtomicU64::new(0);

/// Writes a task file of `kind` to `path`: under a temporary name next to it, then renamed.
pub(crate) fn write(path: &Path, kind: Kind, sections: &[Section]) -> Result<(), BlockFileError> {
    let bytes = encode(kind, sections);
    let n = TEMPORARY.fetch_add(1, Ordering::Relaxed);
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".tmp.{}.{n}", std::process::id()));
    let temporary = path.with_file_name(name);
    let failed = |e: std::io::Error| BlockFileError::new(path, 0, format!("cannot write: {e}"));
    let written = File::create(&temporary)
        .and_then(|mut f| f.write_all(&bytes))
        .and_then(|()| std::fs::rename(&temporary, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temporary);
        return Err(failed(e));
    }
    Ok(())
}

/// A section table entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Entry {
    pub tag: [u8; 4],
    pub cell: u32,
    pub offset: u64,
    pub length: u64,
    crc: u32,
}

enum Source {
    File(File),
    Bytes(Vec<u8>),
}

/// An open task file: its header and section table checked, its sections read on demand.
pub(crate) struct TaskFile {
    path: PathBuf,
    source: Source,
    len: u64,
    /// What the file holds.
    pub kind: Kind,
    /// The section table.
    pub entries: Vec<Entry>,
}

impl TaskFile {
    /// Opens `path`, which must hold a task file of one of `kinds`.
    pub(crate) fn open(path: &Path, kinds: &[Kind]) -> Result<TaskFile, BlockFileError> {
        let file = File::open(path)
            .map_err(|e| BlockFileError::new(path, 0, format!("cannot open: {e}")))?;
        let len = file
            .metadata()
            .map_err(|e| BlockFileError::new(path, 0, format!("cannot read: {e}")))?
            .len();
        TaskFile::parse(path, Source::File(file), len, kinds)
    }

    /// Reads `bytes` as a task file named `name` of one of `kinds`.
    pub(crate) fn from_bytes(
        name: &Path,
        bytes: Vec<u8>,
        kinds: &[Kind],
    ) -> Result<TaskFile, BlockFileError> {
        let len = bytes.len() as u64;
        TaskFile::parse(name, Source::Bytes(bytes), len, kinds)
    }

    fn parse(
        path: &Path,
        source: Source,
        len: u64,
        kinds: &[Kind],
    ) -> Result<TaskFile, BlockFileError> {
        let mut file = TaskFile {
            path: path.to_path_buf(),
            source,
            len,
            kind: Kind::Piece,
            entries: Vec::new(),
        };
        let head = file.read_at(0, HEADER_LEN as u64)?;
        if head[..8] != MAGIC {
            return Err(file.error(0, "not a meshpyr block task file (bad magic)"));
        }
        let version = u16::from_le_bytes([head[8], head[9]]);
        if version != VERSION {
            return Err(file.error(8, format!("version {version}, this reader knows {VERSION}")));
        }
        let code = u16::from_le_bytes([head[10], head[11]]);
        file.kind =
            Kind::from_code(code).ok_or_else(|| file.error(10, format!("unknown kind {code}")))?;
        if !kinds.contains(&file.kind) {
            return Err(file.error(
                10,
                format!("a {:?} file where a {kinds:?} file was expected", file.kind),
            ));
        }
        if head[20..24] != [0; 4] {
            return Err(file.error(20, "reserved bytes are not zero"));
        }
        let n = u32::from_le_bytes(head[12..16].try_into().expect("4 bytes")) as u64;
        if n.saturating_mul(ENTRY_LEN as u64) > len - HEADER_LEN as u64 {
            return Err(file.error(12, format!("{n} sections do not fit in {len} bytes")));
        }
        let table = file.read_at(HEADER_LEN as u64, n * ENTRY_LEN as u64)?;
        let mut head_and_table = head.clone();
        head_and_table.extend_from_slice(&table);
        let crc = u32::from_le_bytes(head[16..20].try_into().expect("4 bytes"));
        if head_crc(&head_and_table) != crc {
            return Err(file.error(16, "header checksum mismatch"));
        }
        let mut next = HEADER_LEN as u64 + table.len() as u64;
        for (i, e) in table.chunks_exact(ENTRY_LEN).enumerate() {
            let at = HEADER_LEN as u64 + (i * ENTRY_LEN) as u64;
            let word = |k: usize| u32::from_le_bytes(e[k..k + 4].try_into().expect("4 bytes"));
            let long = |k: usize| u64::from_le_bytes(e[k..k + 8].try_into().expect("8 bytes"));
            let entry = Entry {
                tag: e[..4].try_into().expect("4 bytes"),
                cell: word(4),
                offset: long(8),
                length: long(16),
                crc: word(24),
            };
            if entry.offset != next || entry.length > len.saturating_sub(next) {
                return Err(file.error(at, "section outside the file or out of order"));
            }
            next += entry.length;
            file.entries.push(entry);
        }
        Ok(file)
    }

    /// An error at `offset` of this file.
    pub(crate) fn error(&self, offset: u64, what: impl Into<String>) -> BlockFileError {
        BlockFileError::new(&self.path, offset, what)
    }

    fn read_at(&mut self, offset: u64, length: u64) -> Result<Vec<u8>, BlockFileError> {
        if offset.saturating_add(length) > self.len {
            return Err(self.error(self.len, "file is truncated"));
        }
        match &mut self.source {
            Source::Bytes(b) => Ok(b[offset as usize..(offset + length) as usize].to_vec()),
            Source::File(f) => {
                let mut buf = vec![0u8; length as usize];
                f.seek(SeekFrom::Start(offset))
                    .and_then(|_| f.read_exact(&mut buf))
                    .map_err(|e| {
                        BlockFileError::new(&self.path, offset, format!("cannot read: {e}"))
                    })?;
                Ok(buf)
            }
        }
    }

    /// The table entry of the section `tag` of `cell`.
    fn entry(&self, tag: [u8; 4], cell: u32) -> Option<Entry> {
        self.entries
            .iter()
            .find(|e| e.tag == tag && e.cell == cell)
            .copied()
    }

    /// The section `tag` of `cell`, checked against its checksum; `None` when the file has none.
    pub(crate) fn section(
        &mut self,
        tag: [u8; 4],
        cell: u32,
    ) -> Result<Option<(Vec<u8>, u64)>, BlockFileError> {
        let Some(e) = self.entry(tag, cell) else {
            return Ok(None);
        };
        let bytes = self.read_at(e.offset, e.length)?;
        if crc32fast::hash(&bytes) != e.crc {
            return Err(self.error(
                e.offset,
                format!("section {} checksum mismatch", tag_name(tag)),
            ));
        }
        Ok(Some((bytes, e.offset)))
    }

    /// [`Self::section`] without reading it into memory: the file is mapped and the section's
    /// bytes checked in place, for a section a task looks into here and there (a pass's labels:
    /// 4 B per input vertex, read by every split task). The file must not change while mapped;
    /// task files are written once under a temporary name and renamed.
    pub(crate) fn mapped_section(
        &mut self,
        tag: [u8; 4],
        cell: u32,
    ) -> Result<Option<(SectionBytes, u64)>, BlockFileError> {
        let Source::File(f) = &self.source else {
            return Ok(self
                .section(tag, cell)?
                .map(|(b, at)| (SectionBytes::Read(b), at)));
        };
        let Some(e) = self.entry(tag, cell) else {
            return Ok(None);
        };
        if e.offset.saturating_add(e.length) > self.len {
            return Err(self.error(self.len, "file is truncated"));
        }
        // SAFETY: the map is only read; task files are not written after their rename.
        let map = unsafe { memmap2::Mmap::map(f) }
            .map_err(|err| BlockFileError::new(&self.path, 0, format!("cannot map: {err}")))?;
        let range = e.offset as usize..(e.offset + e.length) as usize;
        if map.len() < range.end {
            return Err(self.error(map.len() as u64, "file is truncated"));
        }
        if crc32fast::hash(&map[range.clone()]) != e.crc {
            return Err(self.error(
                e.offset,
                format!("section {} checksum mismatch", tag_name(tag)),
            ));
        }
        Ok(Some((SectionBytes::Mapped(map, range), e.offset)))
    }
}

/// A section's bytes, mapped from its file or read into memory.
pub(crate) enum SectionBytes {
    /// The section as a range of the mapped file.
    Mapped(memmap2::Mmap, std::ops::Range<usize>),
    /// The section read into memory.
    Read(Vec<u8>),
}

impl std::ops::Deref for SectionBytes {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        match self {
            SectionBytes::Mapped(map, range) => &map[range.clone()],
            SectionBytes::Read(bytes) => bytes,
        }
    }
}

/// `bytes` with every checksum recomputed where the header and table can be followed, so that
/// mutated inputs of the fuzz target reach the readers behind the checksums.
pub(crate) fn fix_checksums(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if out.len() < HEADER_LEN || out[..8] != MAGIC {
        return out;
    }
    let n = u32::from_le_bytes(out[12..16].try_into().expect("4 bytes")) as usize;
    let table_end = HEADER_LEN.saturating_add(n.saturating_mul(ENTRY_LEN));
    if table_end > out.len() {
        return out;
    }
    for i in 0..n {
        let e = HEADER_LEN + i * ENTRY_LEN;
        let long = |k: usize| u64::from_le_bytes(out[e + k..e + k + 8].try_into().expect("8"));
        let (offset, length) = (long(8), long(16));
        let end = offset.saturating_add(length);
        if end <= out.len() as u64 {
            let crc = crc32fast::hash(&out[offset as usize..end as usize]);
            out[e + 24..e + 28].copy_from_slice(&crc.to_le_bytes());
        }
    }
    let crc = head_crc(&out[..table_end]);
    out[16..20].copy_from_slice(&crc.to_le_bytes());
    out
}

/// A tag as text for messages.
pub(crate) fn tag_name(tag: [u8; 4]) -> String {
    tag.iter()
        .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        encode(
            Kind::Piece,
            &[
                Section {
                    tag: *b"FACE",
                    cell: 0,
                    bytes: vec![1, 2, 3, 4],
                },
                Section {
                    tag: *b"PINS",
                    cell: 7,
                    bytes: vec![9; 8],
                },
            ],
        )
    }

    #[test]
    fn sections_read_back_by_tag_and_cell() {
        let mut f = TaskFile::from_bytes(Path::new("t"), sample(), &[Kind::Piece]).unwrap();
        assert_eq!(f.section(*b"PINS", 7).unwrap().unwrap().0, vec![9; 8]);
        assert_eq!(f.section(*b"FACE", 0).unwrap().unwrap().0, vec![1, 2, 3, 4]);
        assert!(f.section(*b"PINS", 0).unwrap().is_none());
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error_naming_a_place() {
        let good = sample();
        for n in 0..good.len() {
            let r = TaskFile::from_bytes(Path::new("t"), good[..n].to_vec(), &[Kind::Piece]);
            let e = r.err().unwrap_or_else(|| panic!("truncated at {n} reads"));
            assert!(e.to_string().starts_with("t: byte "), "{e}");
        }
        for i in 0..good.len() {
            let mut bad = good.clone();
            bad[i] ^= 0x10;
            let read =
                TaskFile::from_bytes(Path::new("t"), bad, &[Kind::Piece]).and_then(|mut f| {
                    f.section(*b"FACE", 0)?;
                    f.section(*b"PINS", 7)
                });
            assert!(read.is_err(), "flipped byte {i} reads");
        }
    }

    #[test]
    fn a_file_of_another_kind_is_refused() {
        let e = TaskFile::from_bytes(Path::new("x.bin"), sample(), &[Kind::Input])
            .err()
            .unwrap();
        assert_eq!(e.offset, 10);
    }
}
