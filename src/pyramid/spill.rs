//! The pyramid's signal-independent streams (stencil weights, local tables, codes, split
//! offsets), kept in memory or, for large pyramids, in an unnamed temporary file mapped into
//! memory.
//!
//! Those streams are about 600 bytes per vertex, most of a large pyramid, and every pass reads
//! them front to back (`waves` stores them in the order passes visit the splits). In a file,
//! only the pages a pass is working on need to be resident: [`Stream::release`] hands the
//! pages behind it back to the kernel, which keeps them in its page cache while memory allows
//! and reads them again from disk when it does not. So a scan whose layout would not fit beside
//! the rest in memory still goes through, at the price of disk space in the temporary
//! directory (`TMPDIR`).
//!
//! Where streams go is decided once per pyramid ([`Placement::for_layout`]), from the memory
//! available when the pyramid is made (`MemAvailable`, capped by the cgroup's limit and by the
//! job's allowance, the command line's `--memory`: see [`crate::machine::available_memory`]):
//! a layout expected to take at most an eighth of it
//! ([`MEMORY_SHARE`]) stays in memory, a larger one goes to a file. In memory the layout is
//! about 60 % of the pyramid's peak, so a job whose layout passes the rule peaks near a
//! quarter of what was available, leaving the rest to other programs and to the page cache;
//! there the passes run without the file's page faults, which cost a mid-size scan a
//! noticeable share of its time (docs/performance.md). A larger layout goes to the file, where
//! the job's peak stays near 400 bytes per vertex; so the same scan may peak higher per vertex
//! on a machine with more memory free, never above a quarter or so of what was free.
//! Layouts below [`DEFAULT_THRESHOLD_MIB`]
//! always stay in memory, and where the available memory is unknown (not Linux) that is the
//! threshold. `MESHPYR_SPILL_MIB` overrides the rule: a threshold in MiB, `0` puts every
//! layout in a file, `off` none. The bytes, and so every result, are the same either way.

use bytemuck::Pod;
use std::fs::File;
use std::io::{self, Write};
use std::ops::{Deref, Range};
use std::sync::Arc;

/// Layouts expected below this many MiB stay in memory (unless `MESHPYR_SPILL_MIB` says
/// otherwise): the file would save little, and small pyramids (tests, the bunny) stay free of
/// disk traffic. Where the available memory is unknown, larger layouts go to a file.
pub(crate) const DEFAULT_THRESHOLD_MIB: usize = 64;

/// A layout stays in memory while it is expected to take at most `1 / MEMORY_SHARE` of the
/// memory available (see the module docs).
pub(crate) const MEMORY_SHARE: u64 = 8;

/// Where a pyramid's layout streams live.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Placement {
    /// In ordinary heap memory.
    Memory,
    /// In unnamed temporary files, mapped into memory.
    TempFile,
}

impl Placement {
    /// The placement of a layout of about `estimated_bytes`: by `MESHPYR_SPILL_MIB` if set,
    /// else by the memory available now (see the module docs).
    pub(crate) fn for_layout(estimated_bytes: usize) -> Placement {
        let setting = std::env::var("MESHPYR_SPILL_MIB").ok();
        let available = || crate::machine::available_memory();
        Placement::by_rule(estimated_bytes, setting.as_deref(), available)
    }

    /// The rule of [`Self::for_layout`] with the setting of `MESHPYR_SPILL_MIB` and the
    /// available memory in bytes (`None`: unknown) given.
    fn by_rule(
        estimated_bytes: usize,
        setting: Option<&str>,
        available: impl FnOnce() -> Option<u64>,
    ) -> Placement {
        let floor = (DEFAULT_THRESHOLD_MIB as u64) << 20;
        let threshold = match setting.map(str::trim) {
            Some("off") => return Placement::Memory,
            Some(s) => match s.parse::<u64>() {
                Ok(mib) => mib.saturating_mul(1 << 20),
                Err(_) => floor,
            },
            None => available().map_or(floor, |a| (a / MEMORY_SHARE).max(floor)),
        };
        if estimated_bytes as u64 >= threshold {
            Placement::TempFile
        } else {
            Placement::Memory
        }
    }
}

/// Elements a file-backed writer buffers before writing them out (each recording thread has a
/// few writers, so this stays small against a large scan's other arrays).
const WRITE_BUFFER: usize = 1 << 18;

/// An append-only stream being recorded: a vector, or a temporary file behind a buffer.
pub(crate) struct Writer<T: Pod> {
    buffer: Vec<T>,
    /// The file and how many elements it holds already; `None` in memory.
    file: Option<(File, usize)>,
}

impl<T: Pod> Writer<T> {
    /// An empty stream at `placement`; `capacity` elements are reserved in memory (address
    /// space only until written).
    pub(crate) fn new(placement: Placement, capacity: usize) -> io::Result<Writer<T>> {
        Ok(match placement {
            Placement::Memory => Writer {
                buffer: Vec::with_capacity(capacity),
                file: None,
            },
            Placement::TempFile => Writer {
                buffer: Vec::with_capacity(WRITE_BUFFER),
                file: Some((tempfile::tempfile()?, 0)),
            },
        })
    }

    /// Number of elements written.
    pub(crate) fn len(&self) -> usize {
        self.file.as_ref().map_or(0, |f| f.1) + self.buffer.len()
    }

    /// Appends `x`.
    #[inline]
    pub(crate) fn push(&mut self, x: T) -> io::Result<()> {
        self.buffer.push(x);
        self.flush_if_full()
    }

    /// Appends `xs`.
    pub(crate) fn extend_from_slice(&mut self, xs: &[T]) -> io::Result<()> {
        match &mut self.file {
            // A long slice goes to the file directly instead of through the buffer.
            Some((file, written)) if xs.len() >= WRITE_BUFFER => {
                file.write_all(bytemuck::cast_slice(&self.buffer))?;
                file.write_all(bytemuck::cast_slice(xs))?;
                *written += self.buffer.len() + xs.len();
                self.buffer.clear();
                Ok(())
            }
            _ => {
                self.buffer.extend_from_slice(xs);
                self.flush_if_full()
            }
        }
    }

    #[inline]
    fn flush_if_full(&mut self) -> io::Result<()> {
        if self.buffer.len() >= WRITE_BUFFER
            && let Some((file, written)) = &mut self.file
        {
            file.write_all(bytemuck::cast_slice(&self.buffer))?;
            *written += self.buffer.len();
            self.buffer.clear();
        }
        Ok(())
    }

    /// The finished stream: the vector itself, or the file mapped read-only.
    pub(crate) fn finish(mut self) -> io::Result<Stream<T>> {
        let Some((mut file, written)) = self.file.take() else {
            return Ok(Stream::from(self.buffer));
        };
        file.write_all(bytemuck::cast_slice(&self.buffer))?;
        let len = written + self.buffer.len();
        drop(self.buffer);
        if len == 0 {
            return Ok(Stream::from(Vec::new()));
        }
        file.flush()?;
        // SAFETY: the file is unnamed (no other process can open it) and this process never
        // writes to it again, so the mapping's contents never change while it is borrowed.
        let map = unsafe { memmap2::Mmap::map(&file)? };
        Ok(Stream {
            repr: Repr::Mapped {
                map: Arc::new(map),
                len,
            },
        })
    }
}

/// A finished stream, read as a slice: in memory, or a temporary file mapped read-only.
/// Clones of a mapped stream share the mapping.
#[derive(Clone, Debug)]
pub(crate) struct Stream<T> {
    repr: Repr<T>,
}

#[derive(Clone, Debug)]
enum Repr<T> {
    Heap(Vec<T>),
    Mapped { map: Arc<memmap2::Mmap>, len: usize },
}

impl<T> From<Vec<T>> for Stream<T> {
    fn from(v: Vec<T>) -> Stream<T> {
        Stream {
            repr: Repr::Heap(v),
        }
    }
}

impl<T> Default for Stream<T> {
    fn default() -> Stream<T> {
        Stream::from(Vec::new())
    }
}

impl<T: Pod> Deref for Stream<T> {
    type Target = [T];

    #[inline]
    fn deref(&self) -> &[T] {
        match &self.repr {
            Repr::Heap(v) => v,
            // The mapping starts on a page boundary and holds `len` whole elements.
            Repr::Mapped { map, len } => {
                bytemuck::cast_slice(&map[..len * std::mem::size_of::<T>()])
            }
        }
    }
}

impl<T: Pod> Stream<T> {
    /// Whether the stream lives in a temporary file.
    pub(crate) fn is_mapped(&self) -> bool {
        matches!(self.repr, Repr::Mapped { .. })
    }

    /// Hands the resident pages wholly inside elements `range` of a mapped stream back to the
    /// kernel (a no-op in memory, and where the platform has no such advice). Reading them
    /// again is correct, only slower: the file never changes, so the kernel refills a page with
    /// the same bytes, from its page cache or from disk.
    pub(crate) fn release(&self, range: Range<usize>) {
        #[cfg(unix)]
        if let Repr::Mapped { map, len } = &self.repr {
            const PAGE: usize = 4096;
            let size = std::mem::size_of::<T>();
            let start = (range.start.min(*len) * size).next_multiple_of(PAGE);
            let end = range.end.min(*len) * size / PAGE * PAGE;
            if end > start {
                // SAFETY: the mapping is a shared read-only mapping of a file this process
                // never writes (see `Writer::finish`): after MADV_DONTNEED the next access
                // reads the same bytes back from the file, so no borrow observes a change.
                // Failure only leaves the pages resident.
                let _ = unsafe {
                    map.unchecked_advise_range(
                        memmap2::UncheckedAdvice::DontNeed,
                        start,
                        end - start,
                    )
                };
            }
        }
        #[cfg(not(unix))]
        let _ = range;
    }

    /// [`Self::release`] on the whole stream.
    pub(crate) fn release_all(&self) {
        self.release(0..self.len());
    }

    /// Bytes of the stream's elements.
    pub(crate) fn bytes(&self) -> usize {
        std::mem::size_of_val(&**self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn written(placement: Placement, values: &[u32]) -> Stream<u32> {
        let mut w = Writer::new(placement, 0).unwrap();
        let (head, tail) = values.split_at(values.len() / 3);
        for &x in head {
            w.push(x).unwrap();
        }
        w.extend_from_slice(tail).unwrap();
        assert_eq!(w.len(), values.len());
        w.finish().unwrap()
    }

    #[test]
    fn a_stream_reads_back_what_was_written_in_memory_and_in_a_file() {
        // More than one write buffer, so the file gets several writes.
        let values: Vec<u32> = (0..(2 * WRITE_BUFFER as u32 + 12345))
            .map(|i| i.wrapping_mul(2654435761))
            .collect();
        let memory = written(Placement::Memory, &values);
        let file = written(Placement::TempFile, &values);
        assert!(!memory.is_mapped());
        assert!(file.is_mapped());
        assert_eq!(&*memory, &values[..]);
        assert_eq!(&*file, &values[..]);
        // Released pages read back the same bytes.
        file.release(1000..values.len() - 1000);
        file.release_all();
        assert_eq!(&*file, &values[..]);
        assert_eq!(file.clone().bytes(), 4 * values.len());
    }

    #[test]
    fn a_layout_stays_in_memory_up_to_an_eighth_of_the_memory_available() {
        const MIB: usize = 1 << 20;
        let gib16 = || Some(16u64 << 30);
        // 2 GiB is an eighth of 16 GiB: a 250 MB layout stays, a 4 GB one goes to a file.
        assert_eq!(
            Placement::by_rule(250 * MIB, None, gib16),
            Placement::Memory
        );
        assert_eq!(
            Placement::by_rule(2048 * MIB - 1, None, gib16),
            Placement::Memory
        );
        assert_eq!(
            Placement::by_rule(2048 * MIB, None, gib16),
            Placement::TempFile
        );
        assert_eq!(
            Placement::by_rule(4000 * MIB, None, gib16),
            Placement::TempFile
        );
        // Little memory available: the 64 MiB floor still holds small layouts in memory.
        let little = || Some(128u64 << 20);
        assert_eq!(
            Placement::by_rule(60 * MIB, None, little),
            Placement::Memory
        );
        assert_eq!(
            Placement::by_rule(65 * MIB, None, little),
            Placement::TempFile
        );
        // Unknown: the floor is the threshold.
        assert_eq!(
            Placement::by_rule(63 * MIB, None, || None),
            Placement::Memory
        );
        assert_eq!(
            Placement::by_rule(64 * MIB, None, || None),
            Placement::TempFile
        );
    }

    #[test]
    fn a_jobs_memory_allowance_sends_a_layout_to_a_file_sooner() {
        const MIB: usize = 1 << 20;
        let machine = crate::machine::available_memory();
        let by_available =
            |bytes| Placement::by_rule(bytes, None, crate::machine::available_memory);
        // An eighth of a 1 GiB allowance: a 100 MiB layout stays in memory where the machine
        // has that much free; with 512 MiB allowed, whatever the machine has, it goes to a file.
        crate::machine::set_memory_allowance(Some(1 << 30));
        let roomy = by_available(100 * MIB);
        crate::machine::set_memory_allowance(Some(512 << 20));
        let tight = by_available(100 * MIB);
        crate::machine::set_memory_allowance(None);
        if machine.is_some_and(|m| m >= 1 << 30) {
            assert_eq!(roomy, Placement::Memory);
        }
        assert_eq!(tight, Placement::TempFile);
        assert_eq!(
            crate::machine::available_memory().is_some(),
            machine.is_some()
        );
    }

    #[test]
    fn the_spill_setting_overrides_the_memory_rule() {
        const MIB: usize = 1 << 20;
        let plenty = || Some(1u64 << 40);
        assert_eq!(
            Placement::by_rule(0, Some("0"), plenty),
            Placement::TempFile
        );
        assert_eq!(
            Placement::by_rule(100 * MIB, Some(" 100 "), plenty),
            Placement::TempFile
        );
        assert_eq!(
            Placement::by_rule(99 * MIB, Some("100"), plenty),
            Placement::Memory
        );
        assert_eq!(
            Placement::by_rule(usize::MAX, Some("off"), || None),
            Placement::Memory
        );
        // An unreadable setting falls back to the floor, not to the memory rule.
        assert_eq!(
            Placement::by_rule(65 * MIB, Some("lots"), plenty),
            Placement::TempFile
        );
    }

    #[test]
    fn an_empty_stream_in_a_file_is_an_empty_slice() {
        let empty = written(Placement::TempFile, &[]);
        assert!(empty.is_empty());
        empty.release(0..10);
    }
}
