//! The `META` section, the bincode-coded summary (counts, position width, bounding box, build
//! options) every reader starts from, and the checks on a file's header (version, required
//! sections) that come before it.

use super::PyramidOptions;
use crate::format::FormatError;
use crate::format::container::Container;
use crate::mesh::PolygonMesh;
use crate::pm::{PmOptions, ProgressiveMesh};
use glam::DVec3;

use super::{
    KNOWN, MAJOR, META, MINOR, Meta, OLDEST_MAJOR, SPLITS_PER_BLOCK, corrupt, internal, required,
};

/// Largest `META` section a reader decodes.
const MAX_META: usize = 4096;

// ---------------------------------------------------------------------------------------------
// Writing

/// The `META` of `input` with its hierarchy `pm`, positions stored as f32 when `f32`.
pub(super) fn describe(
    input: &PolygonMesh,
    pm: &ProgressiveMesh,
    info: &PyramidOptions,
    f32: bool,
) -> Meta {
    let (lo, hi) = bounding_box(pm.original_positions());
    let o = &info.pm;
    Meta {
        n_input_vertices: input.positions.len() as u64,
        n_input_faces: input.n_faces() as u64,
        n_vertices: pm.original_positions().len() as u64,
        n_base: pm.n_base_vertices() as u64,
        n_splits: pm.splits().len() as u64,
        splits_per_block: SPLITS_PER_BLOCK,
        position_bits: if f32 { 32 } else { 64 },
        bbox_min: lo.to_array(),
        bbox_max: hi.to_array(),
        relaxation: info.relaxation,
        target_vertices: o.target_vertices as u64,
        target_faces: o.target_faces as u64,
        max_error: o.max_error,
        max_normal_angle_degrees: o.max_normal_angle_degrees,
        min_quality: o.min_quality,
        max_valence: o.max_valence as u64,
        boundary_weight: o.boundary_weight,
    }
}

/// The corners of the box around `positions` (zero for none).
fn bounding_box(positions: &[DVec3]) -> (DVec3, DVec3) {
    if positions.is_empty() {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// The `META` section's bytes.
pub(super) fn encode_meta(meta: &Meta) -> Result<Vec<u8>, FormatError> {
    bincode::serde::encode_to_vec(meta, bincode::config::standard())
        .map_err(|e| internal(&e.to_string()))
}

// ---------------------------------------------------------------------------------------------
// Reading

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

/// The build options `meta` records.
pub(super) fn build_info(meta: &Meta) -> PyramidOptions {
    PyramidOptions {
        pm: PmOptions {
            target_vertices: meta.target_vertices as usize,
            target_faces: meta.target_faces as usize,
            max_error: meta.max_error,
            max_normal_angle_degrees: meta.max_normal_angle_degrees,
            min_quality: meta.min_quality,
            max_valence: meta.max_valence as usize,
            block_vertices: None,
            boundary_weight: meta.boundary_weight,
            ..PmOptions::default()
        },
        relaxation: meta.relaxation,
    }
}

/// The input's vertex and face counts from the head of a `.pyr` file (its header, section
/// table and `META`, checked), for an estimate before the file is read; `None` when the head
/// does not hold them or they are not valid.
pub(crate) fn head_counts(head: &[u8]) -> Option<(u64, u64)> {
    let c = Container::parse(head).ok()?;
    check_version(&c).ok()?;
    let meta = read_meta(&c).ok()?;
    Some((meta.n_input_vertices, meta.n_input_faces))
}
