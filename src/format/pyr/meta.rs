//! The checks on a file's header (version, required sections) and the `META` section, the
//! bincode-coded summary (counts, position width, build options) every reader starts from.

use crate::format::FormatError;
use crate::format::container::Container;

use super::{KNOWN, MAJOR, META, MINOR, Meta, OLDEST_MAJOR, corrupt, required};

/// Largest `META` section a reader decodes.
const MAX_META: usize = 4096;

pub(super) fn check_version(c: &Container<'_>) -> Result<(), FormatError> {
    if !(OLDEST_MAJOR..=MAJOR).contains(&c.major) {
        return Err(FormatError::Version {
            major: c.major,
            minor: c.minor,
            supported: format!("{OLDEST_MAJOR}.x to {MAJOR}.x"),
        });
    }
    let unknown = c.unknown_required(&KNOWN);
    if !unknown.is_empty() {
        return Err(FormatError::Version {
            major: c.major,
            minor: c.minor,
            supported: format!(
                "{MAJOR}.{MINOR}; required sections {} are unknown",
                unknown.join(", ")
            ),
        });
    }
    Ok(())
}

pub(super) fn read_meta(c: &Container<'_>) -> Result<Meta, FormatError> {
    let mut r = required(c, META)?;
    let at = r.offset();
    if r.remaining() > MAX_META {
        return Err(corrupt(at, "META section is too large"));
    }
    let bytes = r.take(r.remaining(), "META")?;
    let cfg = bincode::config::standard().with_limit::<MAX_META>();
    let (meta, used): (Meta, usize) = bincode::serde::decode_from_slice(bytes, cfg)
        .map_err(|e| corrupt(at, format!("META: {e}")))?;
    if used != bytes.len() {
        return Err(corrupt(at, "META has trailing bytes"));
    }
    if meta.position_bits != 32 && meta.position_bits != 64 {
        return Err(corrupt(at, "position width must be 32 or 64 bits"));
    }
    if let Some(why) = meta.relaxation.invalid() {
        return Err(corrupt(at, why));
    }
    if meta.splits_per_block == 0
        || meta
            .n_base
            .checked_add(meta.n_splits)
            .is_none_or(|n| n > meta.n_vertices)
        || meta.n_input_vertices > meta.n_vertices
        || meta.n_vertices >= u64::from(u32::MAX)
    {
        return Err(corrupt(at, "inconsistent counts in META"));
    }
    Ok(meta)
}
