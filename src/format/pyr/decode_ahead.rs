//! The `SPLT` blocks located up front and decoded on another core ahead of the sequential
//! replay, which then finds most blocks ready (see [`SplitBlocks`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError};

use crate::format::FormatError;
use crate::format::container::Container;

use super::split_block::{BlockLayout, BlockRef, DecodedBlock, decode_block};
use super::{Meta, SPLT, corrupt, internal};

/// A block's decoding, once a thread has done it.
type Slot = Mutex<Option<Result<DecodedBlock, FormatError>>>;

/// The `SPLT` blocks of a file, located by a scan of their headers (12 bytes per 4096
/// splits), each decoded by whichever thread claims it first. The replay is sequential and
/// most of a load; decoding a block (checksum, positions, varint records, errors) does not
/// depend on it, so another core decodes blocks ahead of the replay while the replaying thread
/// only decodes a block nobody has claimed yet. Decoding is a pure function of the bytes, so
/// who does it changes nothing, and the replay never waits on a block that is not being
/// decoded: no deadlock on a one-thread pool.
pub(super) struct SplitBlocks<'a> {
    blocks: Vec<BlockRef<'a>>,
    /// What the scan met after the last block it found: nothing, or the error a sequential
    /// reader reports once it has replayed the blocks before it.
    end: Result<(), FormatError>,
    layout: BlockLayout,
    claimed: Vec<AtomicBool>,
    ready: Vec<Slot>,
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
        let end = locate_blocks(c, meta, want, &mut blocks);
        let n = blocks.len();
        SplitBlocks {
            blocks,
            end,
            layout: BlockLayout {
                n_base,
                f32: meta.position_bits == 32,
                coded_errors: c.major >= 2,
            },
            claimed: (0..n).map(|_| Default::default()).collect(),
            ready: (0..n).map(|_| Default::default()).collect(),
        }
    }

    /// Number of blocks found.
    pub(super) fn len(&self) -> usize {
        self.blocks.len()
    }

    /// Number of splits the reader wants from the blocks found.
    pub(super) fn wanted(&self) -> usize {
        self.blocks.iter().map(|b| b.used).sum()
    }

    /// What the scan met after the last block it found (see [`Self::scan`]).
    pub(super) fn end(&self) -> Result<(), FormatError> {
        self.end.clone()
    }

    /// Block `k`, for the replay: decoded here unless another thread claimed it first, in
    /// which case that thread is decoding it right now and the wait is short.
    pub(super) fn take(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        if !self.claimed[k].swap(true, Ordering::AcqRel) {
            return self.decode(k);
        }
        loop {
            let slot = self.ready[k]
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take();
            if let Some(d) = slot {
                return d;
            }
            std::thread::yield_now();
        }
    }

    /// Decodes, in order, every block the replay has not claimed yet.
    pub(super) fn decode_ahead(&self) {
        for k in 0..self.blocks.len() {
            if self.claimed[k].swap(true, Ordering::AcqRel) {
                continue;
            }
            let mut publish = Publish(&self.ready[k], None);
            publish.1 = Some(self.decode(k));
        }
    }

    fn decode(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        decode_block(&self.blocks[k], &self.layout)
    }
}

/// Puts a block's decoding in its slot when dropped: should decoding panic (a bug), the replay
/// must not wait forever for the block.
struct Publish<'b>(&'b Slot, Option<Result<DecodedBlock, FormatError>>);

impl Drop for Publish<'_> {
    fn drop(&mut self) {
        let d = self
            .1
            .take()
            .unwrap_or_else(|| Err(internal("split block decoder panicked")));
        *self.0.lock().unwrap_or_else(PoisonError::into_inner) = Some(d);
    }
}

/// Pushes the blocks of `c`'s `SPLT` section onto `blocks` until they hold `want` splits, and
/// returns what it met after the last one (see [`SplitBlocks::scan`]).
fn locate_blocks<'a>(
    c: &Container<'a>,
    meta: &Meta,
    want: usize,
    blocks: &mut Vec<BlockRef<'a>>,
) -> Result<(), FormatError> {
    let n_splits = meta.n_splits as usize;
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
}
