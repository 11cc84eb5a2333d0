//! The `SPLT` blocks located up front and decoded on another core ahead of the sequential
//! replay, which then finds most blocks ready (see [`SplitBlocks`]).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

use crate::format::FormatError;
use crate::format::container::{Container, Release};

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
    /// The block the replay took last (plus one), so that decoding ahead stays near it.
    replayed: AtomicUsize,
    /// Set once the replay has stopped, finished or failed: nobody takes blocks any more.
    stopped: AtomicBool,
    release: Release<'a>,
}

/// Blocks decoded ahead of the replay at most: decoded blocks hold about 60 bytes per split,
/// so running ahead through a whole file would hold them all at once.
const LOOKAHEAD: usize = 16;

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
            replayed: AtomicUsize::new(0),
            stopped: AtomicBool::new(false),
            release: c.release(),
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
        self.replayed.store(k + 1, Ordering::Release);
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

    /// A guard for the replay: once dropped (the replay finished, failed or panicked),
    /// [`Self::decode_ahead`] stops waiting for it.
    pub(super) fn replaying(&self) -> Replaying<'_, 'a> {
        Replaying(self)
    }

    /// Decodes, in order, the blocks the replay has not claimed yet, at most [`LOOKAHEAD`]
    /// ahead of it. When `wait` is false, returns once it is that far ahead (the caller has
    /// other work); otherwise waits for the replay to move on, until every block is claimed
    /// or the replay stops.
    pub(super) fn decode_ahead(&self, wait: bool) {
        for k in 0..self.blocks.len() {
            while k >= self.replayed.load(Ordering::Acquire) + LOOKAHEAD {
                if !wait || self.stopped.load(Ordering::Acquire) {
                    return;
                }
                std::thread::sleep(std::time::Duration::from_micros(100));
            }
            if self.claimed[k].swap(true, Ordering::AcqRel) {
                continue;
            }
            let mut publish = Publish(&self.ready[k], None);
            publish.1 = Some(self.decode(k));
        }
    }

    fn decode(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        let decoded = decode_block(&self.blocks[k], &self.layout);
        self.release.done_with(self.blocks[k].payload);
        decoded
    }
}

/// See [`SplitBlocks::replaying`].
pub(super) struct Replaying<'b, 'a>(&'b SplitBlocks<'a>);

impl Drop for Replaying<'_, '_> {
    fn drop(&mut self) {
        self.0.stopped.store(true, Ordering::Release);
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
        // An intact file: check the section checksum too. Its blocks are read again one by
        // one, so their pages can go back until then.
        let checked = c.section(SPLT)?;
        c.done_with(SPLT);
        checked
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
