//! The `OPTS` section (2.3): the build options `META` has no field for, and what the build made
//! of the input's texture seams. `META` is frozen (bincode, fixed fields: a new field would be a
//! major version), so options that change the hierarchy and came later are stored here:
//! `uv_weight` (how texture-coordinate error weighs against geometric error) and whether every
//! collapse kept the seams (`docs/seams.md`), which tells a reader that each level's corners
//! follow from the finest ones (`crate::pm::level_corners`).
//!
//! Written only for a textured input (one with a `CRNR` section, or a hierarchy that kept
//! seams), so untextured files keep their 2.1 bytes. Optional: a 2.2 reader skips it and reads
//! the hierarchy as before. Readers ignore bytes after the fields they know, so that later
//! options can be appended without a version bump of their own.

use crate::format::FormatError;
use crate::format::varint::ByteReader;
use crate::pm::PmOptions;

use super::corrupt;

/// What `OPTS` records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BuildOptions {
    /// [`PmOptions::uv_weight`].
    pub uv_weight: f64,
    /// Whether every collapse kept the seams
    /// ([`ProgressiveMesh::keeps_seams`](crate::pm::ProgressiveMesh::keeps_seams)).
    pub keeps_seams: bool,
}

/// `OPTS`: `f64 uv_weight` (LE), `u8 keeps_seams` (0 or 1).
pub(super) fn encode_options(o: &PmOptions, keeps_seams: bool) -> Vec<u8> {
    let mut out = o.uv_weight.to_le_bytes().to_vec();
    out.push(u8::from(keeps_seams));
    out
}

/// Reads `OPTS` (bytes after its known fields are ignored).
pub(super) fn decode_options(mut r: ByteReader<'_>) -> Result<BuildOptions, FormatError> {
    let at = r.offset();
    let uv_weight = r.f64("OPTS uv weight")?;
    if !(uv_weight >= 0.0 && uv_weight.is_finite()) {
        return Err(corrupt(at, "OPTS: uv weight must be finite and >= 0"));
    }
    let at = r.offset();
    let keeps_seams = match r.array::<1>("OPTS seam flag")? {
        [0] => false,
        [1] => true,
        _ => return Err(corrupt(at, "OPTS: seam flag must be 0 or 1")),
    };
    Ok(BuildOptions {
        uv_weight,
        keeps_seams,
    })
}
