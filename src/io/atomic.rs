//! Atomic file replacement: temp file in the same directory, fsync, rename.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::IoError;

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `bytes` to `path` atomically: the data goes to a uniquely named temporary file in the
/// same directory, is flushed and synced, and is then renamed over `path`. Readers see either
/// the old file or the complete new one. On any error the temporary file is removed and an
/// existing `path` is left untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
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
            match OpenOptions::new().write(true).create_new(true).open(&tmp) {
                Ok(f) => break (tmp, f),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempt < 100 => {
                    attempt += 1;
                }
                // Name the file the user asked for, not our temporary one.
                Err(e) => return Err(io_err(path)(e)),
            }
        }
    };
    let result = write_sync(file, bytes)
        .map_err(io_err(path))
        .and_then(|()| fs::rename(&tmp, path).map_err(io_err(path)));
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    // Make the rename itself durable (best effort; not supported on every platform).
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

fn write_sync(mut file: File, bytes: &[u8]) -> std::io::Result<()> {
    file.write_all(bytes)?;
    file.flush()?;
    file.sync_all()
}
