//! A `.pyr` file read in place: mapped into memory rather than copied into a buffer, its pages
//! handed back to the kernel as the decoder finishes with each part, so that opening a scan's
//! file holds a window of it, not the whole file beside what it decodes to.

use super::FormatError;
use super::container::Release;
use super::pyr::{PyrData, decode_releasing};
use std::fs::File;
use std::path::Path;

/// A `.pyr` file opened for reading.
///
/// The file is mapped read-only. meshpyr replaces files atomically and never writes into a
/// `.pyr` in place; a file truncated by another program while it is open makes the process
/// fail on the next page it reads (as with any mapped file).
pub struct PyrFile {
    map: Option<memmap2::Mmap>,
}

impl PyrFile {
    /// Opens the file at `path`.
    pub fn open(path: impl AsRef<Path>) -> std::io::Result<PyrFile> {
        let file = File::open(path)?;
        if file.metadata()?.len() == 0 {
            // An empty mapping is an error on some systems; an empty file is simply not a
            // `.pyr` file, which the decoder says.
            return Ok(PyrFile { map: None });
        }
        // SAFETY: the mapping is read-only and only read through `bytes`; see the type's
        // documentation for what happens if another program truncates the file meanwhile.
        let map = unsafe { memmap2::Mmap::map(&file)? };
        Ok(PyrFile { map: Some(map) })
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        self.map.as_deref().unwrap_or_default()
    }

    /// Decodes the whole file ([`super::decode`]), handing back the pages of each part once
    /// decoded.
    pub fn decode(&self) -> Result<PyrData, FormatError> {
        let release = |part: &[u8]| self.release(part);
        decode_releasing(self.bytes(), Release::to(&release))
    }

    /// Hands the whole pages inside `part` (a slice of [`Self::bytes`]) back to the kernel.
    fn release(&self, part: &[u8]) {
        #[cfg(unix)]
        if let Some(map) = &self.map {
            const PAGE: usize = 4096;
            let base = map.as_ptr() as usize;
            let Some(offset) = (part.as_ptr() as usize).checked_sub(base) else {
                return;
            };
            let start = offset.next_multiple_of(PAGE);
            let end = (offset + part.len()).min(map.len()) / PAGE * PAGE;
            if end > start {
                // SAFETY: a read-only mapping of a file: after MADV_DONTNEED the next access
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
        let _ = part;
    }
}
