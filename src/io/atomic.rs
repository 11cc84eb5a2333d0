//! Atomic file replacement: temp file in the same directory, fsync, rename.
//!
//! The temporary files of the writes under way are registered, so that a process stopped by a
//! signal can remove them on its way out ([`exit_removing_temporary_files`]) instead of leaving
//! hidden files beside the outputs.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use super::IoError;

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary files of the atomic writes under way. Created and renamed only while holding
/// the lock, so once [`exit_removing_temporary_files`] holds it no new one can appear.
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// How long every atomic write waits before its rename, in milliseconds (0: not at all); set by
/// [`hold_writes_for_tests`].
static HOLD_WRITES_MS: AtomicU64 = AtomicU64::new(0);

/// Test hook, not an interface: from now on every atomic write announces its temporary file on
/// standard error and waits `ms` milliseconds before renaming it, so that a test can interrupt
/// a write reliably (the command line turns it on from an environment variable).
#[doc(hidden)]
pub fn hold_writes_for_tests(ms: u64) {
    HOLD_WRITES_MS.store(ms, Ordering::Relaxed);
}

fn in_flight() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    IN_FLIGHT
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The folders of temporary files of the jobs under way (a partitioned build's task files),
/// which their jobs remove when they end, and a signal's exit removes with them.
static SCRATCH_FOLDERS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn scratch_folders() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    SCRATCH_FOLDERS
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Registers `folder`, a new folder of a job's temporary files, to be removed by
/// [`exit_removing_temporary_files`] should the process be stopped before the job removes it
/// ([`forget_scratch_folder`]).
pub(crate) fn register_scratch_folder(folder: &Path) {
    scratch_folders().push(folder.to_path_buf());
}

/// Unregisters `folder`, which its job has removed or is about to remove.
pub(crate) fn forget_scratch_folder(folder: &Path) {
    scratch_folders().retain(|f| f != folder);
}

/// Removes the temporary files of the atomic writes under way (and the registered folders of
/// temporary files) and ends the process with `code`, without letting another write start or
/// finish in between: for a handler of Ctrl-C or SIGTERM (run on an ordinary thread, as the
/// `cli` feature's handler does). Outputs that were complete stay; the ones being written are
/// not created.
pub fn exit_removing_temporary_files(code: i32) -> ! {
    let files = in_flight();
    for tmp in files.iter() {
        let _ = fs::remove_file(tmp);
    }
    for folder in scratch_folders().iter() {
        // The job's other threads may still be writing into the folder: a file made between
        // the listing and the folder's own removal fails it, and once the folder is gone they
        // can make none.
        for _ in 0..16 {
            if fs::remove_dir_all(folder).is_ok() || !folder.exists() {
                break;
            }
        }
    }
    std::process::exit(code)
}

/// Writes `bytes` to `path` atomically: the data goes to a uniquely named temporary file in the
/// same directory, is flushed and synced, and is then renamed over `path`. Readers see either
/// the old file or the complete new one. On any error the temporary file is removed and an
/// existing `path` is left untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// [`write_atomic`] of what `write` writes, through a buffer: the bytes need not be in memory
/// all at once.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let io_err = |p: &Path| {
        let p = p.to_path_buf();
        move |error| IoError::Io { path: p, error }
    };
    let file_name = path.file_name().ok_or_else(|| IoError::Io {
        path: path.to_path_buf(),
        error: std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"),
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // Unique name: pid + per-process counter + time, created with create_new (no clobbering).
    let (tmp, file) = {
        let mut attempt = 0;
        loop {
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.subsec_nanos())
                .unwrap_or(0);
            let mut name = std::ffi::OsString::from(".");
            name.push(file_name);
            name.push(format!(
                ".{}.{}.{nanos:x}.tmp",
                std::process::id(),
                COUNTER.fetch_add(1, Ordering::Relaxed)
            ));
            let tmp = dir.join(name);
            let mut registry = in_flight();
            match OpenOptions::new().write(true).create_new(true).open(&tmp) {
                Ok(f) => {
                    registry.push(tmp.clone());
                    break (tmp, f);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempt < 100 => {
                    attempt += 1;
                }
                // Name the file the user asked for, not our temporary one.
                Err(e) => return Err(io_err(path)(e)),
            }
        }
    };
    let written = write_sync(file, write).map_err(io_err(path));
    hold_for_tests(&tmp);
    let result = {
        let mut registry = in_flight();
        let result = written.and_then(|()| fs::rename(&tmp, path).map_err(io_err(path)));
        if result.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        registry.retain(|p| *p != tmp);
        result
    };
    result?;
    // Make the rename itself durable (best effort; not supported on every platform).
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// The [`hold_writes_for_tests`] hook.
fn hold_for_tests(tmp: &Path) {
    let ms = HOLD_WRITES_MS.load(Ordering::Relaxed);
    if ms == 0 {
        return;
    }
    eprintln!("holding {}", tmp.display());
    std::thread::sleep(std::time::Duration::from_millis(ms));
}

fn write_sync(
    file: File,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut buffered = std::io::BufWriter::with_capacity(1 << 20, file);
    write(&mut buffered)?;
    let file = buffered.into_inner().map_err(|e| e.into_error())?;
    file.sync_all()
}
