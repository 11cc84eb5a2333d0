//! The `.pyr` container: a fixed header, a table of checksummed sections, then the sections.
//!
//! ```text
//! offset size
//!      0    8  magic  89 'P' 'Y' 'R' 0D 0A 1A 0A   (catches text-mode and 7-bit mangling)
//!      8    2  major version (u16 LE)     readers refuse a major they do not know
//!     10    2  minor version (u16 LE)     additions that old readers may ignore
//!     12    4  flags (u32 LE)             reserved, 0
//!     16    4  section count n (u32 LE)   at most MAX_SECTIONS
//!     20    4  CRC-32 of bytes 0..20 and of the section table
//!     24 32·n  section table, per entry:
//!                tag [u8; 4], flags u32 (bit 0: required), offset u64, length u64,
//!                CRC-32 of the section bytes u32, reserved u32
//!      …       sections, in table order, contiguous
//! ```
//! All integers are little endian. A reader skips sections whose tag it does not know unless
//! they are marked required, so minor versions can add sections without breaking old readers.

use super::FormatError;
use super::varint::ByteReader;

/// File signature.
pub(crate) const MAGIC: [u8; 8] = [0x89, b'P', b'Y', b'R', 0x0d, 0x0a, 0x1a, 0x0a];
/// Upper bound on the number of sections a reader accepts (bounds the table allocation).
pub const MAX_SECTIONS: u32 = 64;
const HEADER_LEN: usize = 24;
const ENTRY_LEN: usize = 32;
/// Section flag: a reader that does not know this tag must refuse the file.
pub const REQUIRED: u32 = 1;

/// A section to write.
#[derive(Clone, Debug)]
pub struct Section {
    /// Four-byte tag, e.g. `*b"BASE"`.
    pub tag: [u8; 4],
    /// Section flags ([`REQUIRED`]).
    pub flags: u32,
    /// Payload.
    pub bytes: Vec<u8>,
}

/// A section table entry as read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SectionEntry {
    /// Tag.
    pub tag: [u8; 4],
    /// Flags.
    pub flags: u32,
    /// Absolute file offset of the payload.
    pub offset: u64,
    /// Payload length in bytes.
    pub length: u64,
    /// CRC-32 of the payload.
    pub crc: u32,
}

/// Serialises a container with the given version and sections.
pub fn write_container(major: u16, minor: u16, sections: &[Section]) -> Vec<u8> {
    let mut out = Vec::with_capacity(container_len(sections));
    write_container_to(&mut out, major, minor, sections).expect("writing to memory");
    out
}

/// The size of the container of `sections`.
pub fn container_len(sections: &[Section]) -> usize {
    HEADER_LEN + ENTRY_LEN * sections.len() + sections.iter().map(|s| s.bytes.len()).sum::<usize>()
}

/// Writes the container [`write_container`] makes to `w`, without gathering it in memory.
pub fn write_container_to(
    w: &mut dyn std::io::Write,
    major: u16,
    minor: u16,
    sections: &[Section],
) -> std::io::Result<()> {
    let table_len = ENTRY_LEN * sections.len();
    let mut head = Vec::with_capacity(HEADER_LEN + table_len);
    head.extend_from_slice(&MAGIC);
    head.extend_from_slice(&major.to_le_bytes());
    head.extend_from_slice(&minor.to_le_bytes());
    head.extend_from_slice(&0u32.to_le_bytes());
    head.extend_from_slice(&(sections.len() as u32).to_le_bytes());
    head.extend_from_slice(&[0; 4]); // header CRC, filled below
    let mut offset = (HEADER_LEN + table_len) as u64;
    for s in sections {
        head.extend_from_slice(&s.tag);
        head.extend_from_slice(&s.flags.to_le_bytes());
        head.extend_from_slice(&offset.to_le_bytes());
        head.extend_from_slice(&(s.bytes.len() as u64).to_le_bytes());
        head.extend_from_slice(&crc32fast::hash(&s.bytes).to_le_bytes());
        head.extend_from_slice(&0u32.to_le_bytes());
        offset += s.bytes.len() as u64;
    }
    let crc = header_crc(&head);
    head[20..24].copy_from_slice(&crc.to_le_bytes());
    w.write_all(&head)?;
    for s in sections {
        w.write_all(&s.bytes)?;
    }
    Ok(())
}

fn header_crc(header_and_table: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&header_and_table[..20]);
    h.update(&header_and_table[HEADER_LEN..]);
    h.finalize()
}

/// A parsed container over the file's bytes (which may be truncated).
#[derive(Clone, Debug)]
pub struct Container<'a> {
    /// Major version.
    pub major: u16,
    /// Minor version.
    pub minor: u16,
    /// Section table.
    pub sections: Vec<SectionEntry>,
    bytes: &'a [u8],
    release: Release<'a>,
}

/// What a reader calls with the parts of the bytes it is done with: a mapped file hands their
/// pages back to the kernel (see [`crate::format::PyrFile`]), bytes in memory do nothing.
#[derive(Clone, Copy, Default)]
pub(crate) struct Release<'a>(Option<&'a ReleaseFn<'a>>);

/// See [`Release`].
type ReleaseFn<'a> = dyn Fn(&[u8]) + Sync + 'a;

impl<'a> Release<'a> {
    /// Calls `f` with every part a reader is done with.
    pub(crate) fn to(f: &'a ReleaseFn<'a>) -> Release<'a> {
        Release(Some(f))
    }

    /// The reader is done with `part` (a slice of the bytes it reads).
    pub(crate) fn done_with(&self, part: &[u8]) {
        if let Some(f) = self.0 {
            f(part);
        }
    }
}

impl std::fmt::Debug for Release<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() { "Release" } else { "Keep" })
    }
}

impl<'a> Container<'a> {
    /// Parses and checks the header and section table. Sections themselves are checked when
    /// asked for, so a truncated file still yields the sections it holds completely.
    pub fn parse(bytes: &'a [u8]) -> Result<Container<'a>, FormatError> {
        Self::parse_inner(bytes, true)
    }

    /// Like [`parse`](Self::parse) but without checking the header checksum (for tools that
    /// repair checksums, such as the fuzz harness).
    pub(crate) fn parse_unchecked(bytes: &'a [u8]) -> Result<Container<'a>, FormatError> {
        Self::parse_inner(bytes, false)
    }

    fn parse_inner(bytes: &'a [u8], check: bool) -> Result<Container<'a>, FormatError> {
        let mut r = ByteReader::new(bytes, 0);
        let magic: [u8; 8] = r.array("magic")?;
        if magic != MAGIC {
            return Err(FormatError::NotPyr);
        }
        let major = u16::from_le_bytes(r.array("version")?);
        let minor = u16::from_le_bytes(r.array("version")?);
        let _flags = r.u32("flags")?;
        let n = r.u32("section count")?;
        if n > MAX_SECTIONS {
            return Err(FormatError::Corrupt {
                offset: 16,
                reason: format!("{n} sections (at most {MAX_SECTIONS})"),
            });
        }
        let stored_crc = r.u32("header checksum")?;
        let table = r.take(ENTRY_LEN * n as usize, "section table")?;
        let crc = header_crc(&bytes[..HEADER_LEN + table.len()]);
        if check && crc != stored_crc {
            return Err(FormatError::Checksum {
                what: "header".into(),
                offset: 0,
            });
        }
        let mut sections = Vec::with_capacity(n as usize);
        let mut t = ByteReader::new(table, HEADER_LEN as u64);
        for _ in 0..n {
            let tag: [u8; 4] = t.array("section tag")?;
            let flags = t.u32("section flags")?;
            let offset = t.u64("section offset")?;
            let length = t.u64("section length")?;
            let crc = t.u32("section checksum")?;
            let _reserved = t.u32("reserved")?;
            if offset.checked_add(length).is_none() {
                return Err(FormatError::Corrupt {
                    offset: t.offset(),
                    reason: "section extends past 2^64".into(),
                });
            }
            sections.push(SectionEntry {
                tag,
                flags,
                offset,
                length,
                crc,
            });
        }
        Ok(Container {
            major,
            minor,
            sections,
            bytes,
            release: Release::default(),
        })
    }

    /// The container, calling `release` with the parts of the bytes its reader is done with.
    pub(crate) fn releasing(self, release: Release<'a>) -> Container<'a> {
        Container { release, ..self }
    }

    /// What to call with the parts of the bytes a reader is done with.
    pub(crate) fn release(&self) -> Release<'a> {
        self.release
    }

    /// The reader is done with section `tag` (if the file holds it).
    pub(crate) fn done_with(&self, tag: [u8; 4]) {
        if let Some(e) = self.entry(tag) {
            let start = e.offset.min(self.bytes.len() as u64) as usize;
            let end = (e.offset + e.length).min(self.bytes.len() as u64) as usize;
            self.release.done_with(&self.bytes[start..end]);
        }
    }

    /// Total size of the file the table describes (larger than the bytes held if truncated).
    pub(crate) fn described_len(&self) -> u64 {
        self.sections
            .iter()
            .map(|s| s.offset + s.length)
            .max()
            .unwrap_or((HEADER_LEN + ENTRY_LEN * self.sections.len()) as u64)
    }

    /// True when the bytes end before the last section does.
    pub fn is_truncated(&self) -> bool {
        (self.bytes.len() as u64) < self.described_len()
    }

    /// The table entry for `tag`, if present.
    pub fn entry(&self, tag: [u8; 4]) -> Option<SectionEntry> {
        self.sections.iter().copied().find(|s| s.tag == tag)
    }

    /// The complete, checksum-verified payload of section `tag`; `Ok(None)` if the file has no
    /// such section; an error if it is truncated or corrupt.
    pub fn section(&self, tag: [u8; 4]) -> Result<Option<ByteReader<'a>>, FormatError> {
        let Some(e) = self.entry(tag) else {
            return Ok(None);
        };
        let end = e.offset + e.length;
        if end > self.bytes.len() as u64 {
            return Err(FormatError::Truncated {
                offset: self.bytes.len() as u64,
                what: format!("section {}", tag_name(tag)),
            });
        }
        let payload = &self.bytes[e.offset as usize..end as usize];
        if crc32fast::hash(payload) != e.crc {
            return Err(FormatError::Checksum {
                what: format!("section {}", tag_name(tag)),
                offset: e.offset,
            });
        }
        Ok(Some(ByteReader::new(payload, e.offset)))
    }

    /// The bytes of section `tag` that the file actually holds, unverified (for progressive
    /// sections whose blocks carry their own checksums).
    pub fn section_prefix(&self, tag: [u8; 4]) -> Option<ByteReader<'a>> {
        let e = self.entry(tag)?;
        let start = (e.offset).min(self.bytes.len() as u64) as usize;
        let end = (e.offset + e.length).min(self.bytes.len() as u64) as usize;
        Some(ByteReader::new(&self.bytes[start..end], start as u64))
    }

    /// Tags of required sections not in `known` (a reader must refuse such files).
    pub fn unknown_required(&self, known: &[[u8; 4]]) -> Vec<String> {
        self.sections
            .iter()
            .filter(|s| s.flags & REQUIRED != 0 && !known.contains(&s.tag))
            .map(|s| tag_name(s.tag))
            .collect()
    }
}

/// A tag as printable text.
pub(crate) fn tag_name(tag: [u8; 4]) -> String {
    tag.iter()
        .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
        .collect()
}
