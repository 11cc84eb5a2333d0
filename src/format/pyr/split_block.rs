//! One block of the `SPLT` section: a header (split count, payload length, payload CRC-32) and
//! a payload holding each split's record (survivor and wings), its quadric error and the
//! position of its new vertex. Blocks decode independently of each other and of the replay,
//! which is what lets [`super::decode_ahead`] decode them on another core.

use crate::format::FormatError;
use crate::format::varint::{ByteReader, put_ivarint, put_uvarint};
use crate::pm::{FlatReplay, VertexSplit};
use glam::DVec3;

use super::positions::read_positions;
use super::{corrupt, internal};

/// Largest ring index a wing code may hold (far above any real valence).
const MAX_RING: u64 = 1 << 20;

/// One `SPLT` block as the header scan found it.
pub(super) struct BlockRef<'a> {
    /// Offset of its header (for errors).
    pub(super) at: u64,
    pub(super) count: usize,
    /// How many of its splits the reader wants (all but in the last block read).
    pub(super) used: usize,
    /// Index of its first split.
    pub(super) first: usize,
    pub(super) crc: u32,
    pub(super) payload: &'a [u8],
}

/// What decoding a block needs besides its bytes.
pub(super) struct BlockLayout {
    pub(super) n_base: usize,
    pub(super) f32: bool,
    /// Format 2.x: errors as varint deltas between the records and the positions (1.x: raw
    /// f32 after the positions).
    pub(super) coded_errors: bool,
}

impl BlockLayout {
    /// Bytes per stored position.
    fn position_width(&self) -> usize {
        3 * if self.f32 { 4 } else { 8 }
    }
}

/// One block's contents, decoded but not yet replayed.
pub(super) struct DecodedBlock {
    /// Survivor, left and right wing codes, and the record's offset, per split.
    pub(super) records: Vec<(u32, u64, u64, u64)>,
    pub(super) positions: Vec<DVec3>,
    pub(super) errors: Vec<f32>,
    /// Trailing bytes after the records: an error a sequential reader meets only after
    /// replaying the block.
    pub(super) trailing: Option<FormatError>,
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Appends the records of `splits`, applying each to `replay`, which holds the rings the next
/// split's wings are coded in.
pub(super) fn put_split_records(
    payload: &mut Vec<u8>,
    replay: &mut FlatReplay,
    splits: &[VertexSplit],
) -> Result<(), FormatError> {
    for (k, s) in splits.iter().enumerate() {
        replay.prefetch_upcoming(k, |j| splits.get(j).map(|t| t.survivor));
        put_uvarint(payload, u64::from(s.vertex - 1 - s.survivor));
        let (il, ir) = replay
            .wing_indices(s)
            .map_err(|e| internal(&e.to_string()))?;
        let (left_code, right_code) = wing_codes(il, ir, replay.listed_valence());
        put_uvarint(payload, left_code);
        put_uvarint(payload, right_code);
        replay
            .apply_indexed(s.vertex, s.survivor, il, ir)
            .map_err(|e| internal(&e.to_string()))?;
    }
    Ok(())
}

/// The codes of the wings at ring indices `left` and `right` in a ring of `valence`: 0 for no
/// wing, else the left one's index + 1, and the right one's offset from the left one (its
/// index without a left wing) + 1.
fn wing_codes(left: Option<usize>, right: Option<usize>, valence: usize) -> (u64, u64) {
    let left_code = left.map_or(0, |i| i as u64 + 1);
    let right_code = match (left, right) {
        (_, None) => 0,
        (Some(l), Some(r)) => wrap_once((r + valence - l) as u64, valence as u64) + 1,
        (None, Some(r)) => r as u64 + 1,
    };
    (left_code, right_code)
}

/// Appends the quadric errors of a block's splits as deltas of their bit patterns: successive
/// splits have similar errors, and positive floats order like their bits, so the deltas are
/// short (about 2 bytes on scans, against 4 raw) and the coding is exact for any value.
pub(super) fn put_split_errors(payload: &mut Vec<u8>, errors: &[f32]) {
    let mut prev = 0u32;
    for e in errors {
        let bits = e.to_bits();
        put_ivarint(payload, i64::from(bits) - i64::from(prev));
        prev = bits;
    }
}

/// Appends a block of `count` splits: its header, then `payload`.
pub(super) fn put_block(splt: &mut Vec<u8>, count: usize, payload: &[u8]) {
    splt.extend_from_slice(&(count as u32).to_le_bytes());
    splt.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    splt.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    splt.extend_from_slice(payload);
}

// ---------------------------------------------------------------------------------------------
// Reading

/// Decodes block `b`: checksum, positions, records, errors (only the splits wanted).
pub(super) fn decode_block(
    b: &BlockRef<'_>,
    layout: &BlockLayout,
) -> Result<DecodedBlock, FormatError> {
    check_checksum(b)?;
    let (mut records, mut fixed) = split_payload(b, layout)?;
    let mut positions = Vec::new();
    read_positions(&mut fixed, b.used, layout.f32, &mut positions)?;
    let decoded = read_split_records(&mut records, b, layout.n_base)?;
    let errors = if layout.coded_errors {
        read_coded_errors(&mut records, b)?
    } else {
        read_raw_errors(&mut fixed, b, layout.position_width())?
    };
    let trailing = (b.used == b.count && !records.is_empty())
        .then(|| corrupt(records.offset(), "trailing bytes in split block"));
    Ok(DecodedBlock {
        records: decoded,
        positions,
        errors,
        trailing,
    })
}

fn check_checksum(b: &BlockRef<'_>) -> Result<(), FormatError> {
    if crc32fast::hash(b.payload) != b.crc {
        return Err(FormatError::Checksum {
            what: "split block".into(),
            offset: b.at,
        });
    }
    Ok(())
}

/// The payload's variable-length part and its fixed-length tail. 2.x: the records and the
/// error deltas (variable length), then `count` positions (fixed length), so the positions
/// start at a known offset from the end. 1.x: the records, then `count` positions and `count`
/// raw f32 errors.
fn split_payload<'a>(
    b: &BlockRef<'a>,
    layout: &BlockLayout,
) -> Result<(ByteReader<'a>, ByteReader<'a>), FormatError> {
    let tail = b.count * (layout.position_width() + if layout.coded_errors { 0 } else { 4 });
    if tail > b.payload.len() {
        return Err(corrupt(b.at, "split block is shorter than its positions"));
    }
    let (records, fixed) = b.payload.split_at(b.payload.len() - tail);
    Ok((
        ByteReader::new(records, b.at + 12),
        ByteReader::new(fixed, b.at + 12 + records.len() as u64),
    ))
}

/// The wanted splits' records: survivor, wing codes (not yet checked against the rings, which
/// only the replay knows) and offset.
fn read_split_records(
    p: &mut ByteReader<'_>,
    b: &BlockRef<'_>,
    n_base: usize,
) -> Result<Vec<(u32, u64, u64, u64)>, FormatError> {
    let mut decoded = Vec::with_capacity(b.used);
    for k in 0..b.used {
        let vertex = (n_base + b.first + k) as u32;
        let at = p.offset();
        if vertex == 0 {
            return Err(corrupt(at, "split without a survivor"));
        }
        let back = p.count(u64::from(vertex - 1), "survivor")? as u32;
        let lc = p.count(MAX_RING, "left wing")?;
        let rc = p.count(MAX_RING, "right wing")?;
        decoded.push((vertex - 1 - back, lc as u64, rc as u64, at));
    }
    Ok(decoded)
}

/// 2.x: the wanted splits' errors, coded as in [`put_split_errors`].
fn read_coded_errors(p: &mut ByteReader<'_>, b: &BlockRef<'_>) -> Result<Vec<f32>, FormatError> {
    let mut errors = Vec::with_capacity(b.used);
    // The errors follow every record of the block, wanted or not.
    for _ in 0..3 * (b.count - b.used) {
        p.uvarint("split record")?;
    }
    let mut prev = 0u32;
    for _ in 0..b.used {
        let at = p.offset();
        let bits = i64::from(prev)
            .checked_add(p.ivarint("split error")?)
            .and_then(|x| u32::try_from(x).ok())
            .ok_or_else(|| corrupt(at, "split error out of range"))?;
        errors.push(f32::from_bits(bits));
        prev = bits;
    }
    Ok(errors)
}

/// 1.x: the wanted splits' errors, raw f32 after all the block's positions (`q` is past the
/// wanted ones).
fn read_raw_errors(
    q: &mut ByteReader<'_>,
    b: &BlockRef<'_>,
    position_width: usize,
) -> Result<Vec<f32>, FormatError> {
    let mut errors = Vec::with_capacity(b.used);
    q.take((b.count - b.used) * position_width, "positions")?;
    for _ in 0..b.used {
        errors.push(f32::from_le_bytes(q.array("split error")?));
    }
    Ok(errors)
}

/// The ring indices of a split's wings from their codes (see [`wing_codes`]), `None` when a
/// code points past the survivor's ring of `valence`.
#[inline]
pub(super) fn wing_indices(
    left_code: u64,
    right_code: u64,
    valence: u64,
) -> Option<(Option<usize>, Option<usize>)> {
    if left_code > valence || right_code > valence {
        return None;
    }
    let il = left_code.checked_sub(1);
    // l, r < valence (checked above).
    let ir = right_code
        .checked_sub(1)
        .map(|r| il.map_or(r, |l| wrap_once(l + r, valence)));
    Some((il.map(|i| i as usize), ir.map(|i| i as usize)))
}

/// `x mod n` for `x < 2n`: the right wing's code is `(r − l) mod valence` and decodes as
/// `(l + code) mod valence`, both with `l, r < valence`, so a compare and subtract does
/// instead of a division per split.
#[inline]
fn wrap_once(x: u64, n: u64) -> u64 {
    if x >= n { x - n } else { x }
}
