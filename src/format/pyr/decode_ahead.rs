//! The `SPLT` blocks located up front and decoded on another core ahead of the sequential
//! replay, which then finds most blocks ready (see [`SplitBlocks`]).

use crate::format::FormatError;
use crate::format::container::Container;
use crate::format::varint::ByteReader;
use glam::DVec3;

use super::hierarchy::read_positions;
use super::{Meta, SPLT, corrupt, internal};

/// Largest ring index a wing code may hold (far above any real valence).
const MAX_RING: u64 = 1 << 20;

/// One `SPLT` block as the header scan found it.
pub(super) struct BlockRef<'a> {
    /// Offset of its header (for errors).
    at: u64,
    count: usize,
    /// How many of its splits the reader wants (all but in the last block read).
    pub(super) used: usize,
    /// Index of its first split.
    first: usize,
    crc: u32,
    payload: &'a [u8],
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

/// The `SPLT` blocks of a file, located by a scan of their headers (12 bytes per 4096
/// splits), each decoded by whichever thread claims it first. The replay is sequential and
/// most of a load; decoding a block (checksum, positions, varint records, errors) does not
/// depend on it, so another core decodes blocks ahead of the replay while the replaying thread
/// only decodes a block nobody has claimed yet. Decoding is a pure function of the bytes, so
/// who does it changes nothing, and the replay never waits on a block that is not being
/// decoded: no deadlock on a one-thread pool.
pub(super) struct SplitBlocks<'a> {
    pub(super) blocks: Vec<BlockRef<'a>>,
    /// What the scan met after the last block it found: nothing, or the error a sequential
    /// reader reports once it has replayed the blocks before it.
    pub(super) end: Result<(), FormatError>,
    n_base: usize,
    f32: bool,
    /// Format 2.x: errors as varint deltas between the records and the positions (1.x: raw
    /// f32 after the positions).
    coded_errors: bool,
    claimed: Vec<std::sync::atomic::AtomicBool>,
    ready: Vec<std::sync::Mutex<Option<Result<DecodedBlock, FormatError>>>>,
}

impl<'a> SplitBlocks<'a> {
    /// Scans the block headers of `c`'s `SPLT` section up to `max_level` (default: all).
    /// A truncated file stops at its last complete block.
    pub(super) fn scan(
        c: &Container<'a>,
        meta: &Meta,
        max_level: Option<usize>,
    ) -> SplitBlocks<'a> {
        let n_base = meta.n_base as usize;
        let n_splits = meta.n_splits as usize;
        let want = max_level.map_or(n_splits, |l| l.saturating_sub(n_base).min(n_splits));
        let mut blocks = Vec::new();
        let end = (|| {
            let truncated = c.is_truncated();
            let whole = if truncated {
                c.section_prefix(SPLT)
            } else {
                // An intact file: check the section checksum too.
                c.section(SPLT)?
            };
            let mut r = whole.ok_or_else(|| corrupt(0, "section SPLT is missing"))?;
            let mut done = 0;
            while done < want {
                if r.remaining() < 12 && truncated {
                    break;
                }
                let at = r.offset();
                let count = r.u32("split block")? as usize;
                let len = r.u32("split block")? as usize;
                let crc = r.u32("split block")?;
                let expected = (n_splits - done).min(meta.splits_per_block as usize);
                if count != expected {
                    return Err(corrupt(
                        at,
                        format!("split block holds {count} splits, expected {expected}"),
                    ));
                }
                if len > r.remaining() {
                    if truncated {
                        break;
                    }
                    return Err(FormatError::Truncated {
                        offset: r.offset(),
                        what: "split block".into(),
                    });
                }
                let payload = r.take(len, "split block")?;
                let used = count.min(want - done);
                blocks.push(BlockRef {
                    at,
                    count,
                    used,
                    first: done,
                    crc,
                    payload,
                });
                done += used;
            }
            Ok(())
        })();
        let n = blocks.len();
        SplitBlocks {
            blocks,
            end,
            n_base,
            f32: meta.position_bits == 32,
            coded_errors: c.major >= 2,
            claimed: (0..n).map(|_| Default::default()).collect(),
            ready: (0..n).map(|_| Default::default()).collect(),
        }
    }

    /// Decodes block `k`: checksum, positions, records, errors (only the splits wanted).
    fn decode(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        let b = &self.blocks[k];
        if crc32fast::hash(b.payload) != b.crc {
            return Err(FormatError::Checksum {
                what: "split block".into(),
                offset: b.at,
            });
        }
        // Payload, 2.x: the records and the error deltas (variable length), then `count`
        // positions (fixed length), so the positions start at a known offset from the end.
        // 1.x: the records, then `count` positions and `count` raw f32 errors.
        let width = 3 * if self.f32 { 4 } else { 8 };
        let tail = b.count * (width + if self.coded_errors { 0 } else { 4 });
        if tail > b.payload.len() {
            return Err(corrupt(b.at, "split block is shorter than its positions"));
        }
        let (records, fixed) = b.payload.split_at(b.payload.len() - tail);
        let mut p = ByteReader::new(records, b.at + 12);
        let mut q = ByteReader::new(fixed, b.at + 12 + records.len() as u64);
        let mut positions = Vec::new();
        read_positions(&mut q, b.used, self.f32, &mut positions)?;
        let mut decoded = Vec::with_capacity(b.used);
        for k in 0..b.used {
            let vertex = (self.n_base + b.first + k) as u32;
            let at = p.offset();
            if vertex == 0 {
                return Err(corrupt(at, "split without a survivor"));
            }
            let back = p.count(u64::from(vertex - 1), "survivor")? as u32;
            let lc = p.count(MAX_RING, "left wing")?;
            let rc = p.count(MAX_RING, "right wing")?;
            decoded.push((vertex - 1 - back, lc as u64, rc as u64, at));
        }
        let mut errors = Vec::with_capacity(b.used);
        if self.coded_errors {
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
        } else {
            q.take((b.count - b.used) * width, "positions")?;
            for _ in 0..b.used {
                errors.push(f32::from_le_bytes(q.array("split error")?));
            }
        }
        let trailing = (b.used == b.count && !p.is_empty())
            .then(|| corrupt(p.offset(), "trailing bytes in split block"));
        Ok(DecodedBlock {
            records: decoded,
            positions,
            errors,
            trailing,
        })
    }

    /// Block `k`, for the replay: decoded here unless another thread claimed it first, in
    /// which case that thread is decoding it right now and the wait is short.
    pub(super) fn take(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        use std::sync::atomic::Ordering;
        if !self.claimed[k].swap(true, Ordering::AcqRel) {
            return self.decode(k);
        }
        loop {
            let slot = self.ready[k]
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take();
            if let Some(d) = slot {
                return d;
            }
            std::thread::yield_now();
        }
    }

    /// Decodes, in order, every block the replay has not claimed yet.
    pub(super) fn decode_ahead(&self) {
        use std::sync::atomic::Ordering;
        for k in 0..self.blocks.len() {
            if self.claimed[k].swap(true, Ordering::AcqRel) {
                continue;
            }
            // Should decoding panic (a bug), the replay must not wait forever for the block.
            struct Publish<'b>(
                &'b std::sync::Mutex<Option<Result<DecodedBlock, FormatError>>>,
                Option<Result<DecodedBlock, FormatError>>,
            );
            impl Drop for Publish<'_> {
                fn drop(&mut self) {
                    let d = self
                        .1
                        .take()
                        .unwrap_or_else(|| Err(internal("split block decoder panicked")));
                    *self
                        .0
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(d);
                }
            }
            let mut publish = Publish(&self.ready[k], None);
            publish.1 = Some(self.decode(k));
        }
    }
}
