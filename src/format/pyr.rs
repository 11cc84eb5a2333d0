//! Reading and writing `.pyr` files: the progressive mesh (base mesh + vertex splits in
//! checksummed blocks), the exact original positions, and trailing sections that restore the
//! user's file exactly (vertex order, polygons, attributes). Specified in `formats/pyr.md`.
//!
//! The details of the detail pyramid are stored, quantised, in the optional `DETL` section
//! (format 2.1, module `details`), so that a loader needs only the relaxation weights and fans
//! for synthesis and nothing for the spectrum. Files without it (2.0, or written without
//! details) are analysed again: the analysis is a deterministic function of the hierarchy,
//! the original positions and the relaxation operator, so a loader recomputes the details bit
//! for bit ([`PyrData::into_pyramid`]).
//!
//! This module holds the types a file decodes to (the relaxation is `relax::RelaxationSpec`),
//! and [`encode`] and [`decode`], which assemble a file from its sections; each concern has a child module: the
//! header and `META` (`meta`), the hierarchy (`hierarchy`, with `positions` and the `SPLT`
//! blocks in `split_block`, decoded on another core by `decode_ahead`), and the user's mesh
//! (`input_side`, `attributes`). `edit` prepares an edited scan for saving; `fuzz` holds the
//! fuzz target's body.

use super::FormatError;
use super::container::{
    Container, REQUIRED, Release, Section, container_len, write_container, write_container_to,
};
use super::varint::ByteReader;
use crate::mesh::{PolygonMesh, ScalarType, SourceMap};
use crate::pm::{PmOptions, PmParts, ProgressiveMesh};
use crate::relax::RelaxationSpec;
use glam::DVec3;
use serde::{Deserialize, Serialize};

mod attributes;
mod copied_faces;
mod corners;
mod decode_ahead;
mod details;
mod edit;
mod fuzz;
mod hierarchy;
mod input_side;
mod loaded;
mod meta;
mod options;
mod pins;
mod positions;
mod rice;
mod split_block;

pub use details::StoredDetails;
pub(crate) use edit::with_positions;
pub(crate) use fuzz::{fix_checksums, fuzz_read_pyr};
pub use hierarchy::{read_level, read_level_within};
pub use loaded::FileDetails;
use loaded::file_details;

use attributes::encode_attributes;
use corners::{encode_corners, has_corner_data};
use details::{decode_details, encode_details};
use hierarchy::{
    Progressive, encode_base, encode_isolated, encode_splits, read_isolated, read_progressive,
};
use input_side::{
    InputSide, decode_input_side, encode_polygons, encode_vertex_order, finest_faces,
    restore_input_positions,
};
pub(crate) use meta::head_counts;
use meta::{build_info, describe, encode_meta};
use options::{decode_options, encode_options};
use pins::{decode_pins, encode_pins};
use positions::exactly_f32;

/// Major version written. 2.0 codes the split errors as varint deltas of their bit patterns
/// (1.x stored them as raw f32); readers take majors 1 and 2 and refuse others.
pub const MAJOR: u16 = 2;
/// The oldest major this reader still decodes.
pub const OLDEST_MAJOR: u16 = 1;
/// Minor version written; readers accept any minor of their major (unknown optional sections
/// are skipped). 2.1 adds the optional `DETL` section; 2.2 the required `CRNR` section of a
/// textured input; 2.3 the optional `OPTS` section (the uv weight, and whether the hierarchy
/// kept the seams), written with `CRNR`; 2.4 the required `PINS` section of a partitioned
/// hierarchy. A file is written with the lowest minor that has its sections: 2.4 with `PINS`,
/// else 2.3 with `CRNR` ([`MINOR_WITH_CORNERS`]), else 2.1 ([`MINOR_WITHOUT_CORNERS`]), byte
/// for byte what a 2.1 writer wrote, so untextured one-process files still open in 2.1
/// readers.
pub const MINOR: u16 = 4;
/// The minor version of a file with a `CRNR` section and without `PINS`.
pub const MINOR_WITH_CORNERS: u16 = 3;
/// The minor version of a file without a `CRNR` or `PINS` section.
pub const MINOR_WITHOUT_CORNERS: u16 = 1;
/// Vertex splits per block of the `SPLT` section.
pub(crate) const SPLITS_PER_BLOCK: u32 = 4096;

const META: [u8; 4] = *b"META";
const BASE: [u8; 4] = *b"BASE";
const SPLT: [u8; 4] = *b"SPLT";
const ISOL: [u8; 4] = *b"ISOL";
const ORDR: [u8; 4] = *b"ORDR";
const POLY: [u8; 4] = *b"POLY";
const ATTR: [u8; 4] = *b"ATTR";
const DETL: [u8; 4] = *b"DETL";
const CRNR: [u8; 4] = *b"CRNR";
const OPTS: [u8; 4] = *b"OPTS";
const PINS: [u8; 4] = *b"PINS";
const KNOWN: [[u8; 4]; 11] = [
    META, BASE, SPLT, ISOL, ORDR, POLY, ATTR, DETL, CRNR, OPTS, PINS,
];

/// The `META` section (bincode 2 standard configuration). Fixed-size fields only: nothing in
/// it allocates while decoding, so a damaged length cannot make bincode allocate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Meta {
    n_input_vertices: u64,
    n_input_faces: u64,
    n_vertices: u64,
    n_base: u64,
    n_splits: u64,
    splits_per_block: u32,
    position_bits: u8,
    bbox_min: [f64; 3],
    bbox_max: [f64; 3],
    relaxation: RelaxationSpec,
    target_vertices: u64,
    target_faces: u64,
    max_error: Option<f64>,
    max_normal_angle_degrees: f64,
    min_quality: f64,
    max_valence: u64,
    boundary_weight: f64,
}

/// How a pyramid is built (`crate::pyramid::Pyramid::build_with`): what a `.pyr` file records
/// in its header, so that loading it rebuilds the very same pyramid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PyramidOptions {
    /// How the progressive mesh is built (defaults: collapse as far as legal).
    pub pm: PmOptions,
    /// The relaxation operator that predicts each level from the coarser one (default: Guskov's
    /// second differences).
    pub relaxation: RelaxationSpec,
}

/// A fully decoded `.pyr` file.
#[derive(Clone, Debug)]
pub struct PyrData {
    /// The user's mesh exactly as it was read when the file was built.
    pub input: PolygonMesh,
    /// Where each vertex and face of the repaired mesh of `input` came from, when loading
    /// needed the builder (an input it repairs); `None` for a clean triangle mesh, whose
    /// repaired mesh is `input` itself.
    source: Option<SourceMap>,
    /// The hierarchy.
    pub pm: ProgressiveMesh,
    /// Build options.
    pub info: PyramidOptions,
    /// The details the file stores, if any, and whether they fit it.
    pub details: FileDetails,
}

/// One level of the hierarchy read from a (possibly truncated) file.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelMesh {
    /// Number of vertices of this level.
    pub level: usize,
    /// Finest level the file describes.
    pub finest: usize,
    /// Coarsest level.
    pub base: usize,
    /// True when the file is truncated (this may be less than the level asked for).
    pub truncated: bool,
    /// Positions of PM vertices `0..level`.
    pub positions: Vec<DVec3>,
    /// Triangles in PM indices.
    pub triangles: Vec<[u32; 3]>,
    /// True when the file stores positions as f32.
    pub f32_positions: bool,
}

impl LevelMesh {
    /// As a polygon mesh (positions typed f32 when the file stored f32).
    pub fn to_polygon_mesh(&self) -> PolygonMesh {
        let mut m = PolygonMesh::from_triangles(self.positions.clone(), &self.triangles);
        m.position_type = Some(if self.f32_positions {
            ScalarType::F32
        } else {
            ScalarType::F64
        });
        m
    }
}

/// Byte counts of the parts of an encoded file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SizeReport {
    /// Whole file.
    pub total: usize,
    /// Connectivity of the hierarchy: base faces + split records (survivor, wings).
    pub pm_connectivity: usize,
    /// Quadric errors of the splits (f32 each).
    pub split_errors: usize,
    /// Positions (base + split blocks + vertices without faces).
    pub positions: usize,
    /// Input vertex order, polygons and attributes.
    pub trailing: usize,
    /// The stored details (section `DETL`; 0 without).
    pub details: usize,
}

fn corrupt(offset: u64, reason: impl Into<String>) -> FormatError {
    FormatError::Corrupt {
        offset,
        reason: reason.into(),
    }
}

fn internal(reason: &str) -> FormatError {
    corrupt(0, format!("cannot encode: {reason}"))
}

/// The section `tag` of a file being read, which must be there.
fn required<'a>(c: &Container<'a>, tag: [u8; 4]) -> Result<ByteReader<'a>, FormatError> {
    c.section(tag)?.ok_or_else(|| {
        corrupt(
            0,
            format!("section {} is missing", super::container::tag_name(tag)),
        )
    })
}

/// Encodes `input` with its hierarchy `pm` (built from `Mesh::from_polygons(input)`), without
/// details ([`encode_with_details`] stores them).
pub fn encode(
    input: &PolygonMesh,
    pm: &ProgressiveMesh,
    info: &PyramidOptions,
) -> Result<(Vec<u8>, SizeReport), FormatError> {
    encode_with_details(input, pm, info, None)
}

/// [`encode`], with `details` (the pyramid of `pm`'s original positions, analysed with
/// `info.relaxation`) in a `DETL` section (see `formats/pyr.md`). Details whose step the
/// format cannot code leave the section out.
pub fn encode_with_details(
    input: &PolygonMesh,
    pm: &ProgressiveMesh,
    info: &PyramidOptions,
    details: Option<&StoredDetails>,
) -> Result<(Vec<u8>, SizeReport), FormatError> {
    let encoded = encode_sections(input, pm, info, details)?;
    let sizes = encoded.sizes;
    Ok((encoded.into_bytes(), sizes))
}

/// [`encode_with_details`], section by section, for writing to a file without gathering it.
pub fn encode_sections(
    input: &PolygonMesh,
    pm: &ProgressiveMesh,
    info: &PyramidOptions,
    details: Option<&StoredDetails>,
) -> Result<EncodedPyr, FormatError> {
    check_pm_belongs(input, pm)?;
    let f32 = pm.original_positions().iter().all(|&p| exactly_f32(p));
    let meta = encode_meta(&describe(input, pm, info, f32))?;
    let base_tris = pm.base_triangles();
    let (base, mut sizes) = encode_base(pm, &base_tris, f32);
    // The split replay is sequential and most of a save; the sections after it do not depend
    // on it, so they are encoded on another core meanwhile.
    let (splits, (isol, ordr, poly, attr)) = rayon::join(
        || encode_splits(pm, &base_tris, f32),
        || {
            (
                encode_isolated(pm, f32),
                encode_vertex_order(pm),
                encode_polygons(input),
                encode_attributes(input),
            )
        },
    );
    let (splt, split_sizes) = splits?;
    sizes.pm_connectivity += split_sizes.pm_connectivity;
    sizes.positions += split_sizes.positions + isol.len();
    sizes.split_errors += split_sizes.split_errors;
    sizes.trailing = ordr.len() + poly.len() + attr.len();
    let detl = match details {
        Some(d) => encode_details(d, [crc32fast::hash(&base), crc32fast::hash(&splt)])?,
        None => None,
    };
    let mut sections: Vec<Section> = [
        (META, meta),
        (BASE, base),
        (SPLT, splt),
        (ISOL, isol),
        (ORDR, ordr),
        (POLY, poly),
        (ATTR, attr),
    ]
    .into_iter()
    .map(|(tag, bytes)| Section {
        tag,
        flags: REQUIRED,
        bytes,
    })
    .collect();
    let textured = has_corner_data(input);
    if textured {
        let bytes = encode_corners(input);
        sizes.trailing += bytes.len();
        sections.push(Section {
            tag: CRNR,
            flags: REQUIRED,
            bytes,
        });
    }
    let mut minor = if textured || pm.keeps_seams() {
        // Optional: a 2.2 reader reads the hierarchy without knowing how it was built.
        sections.push(Section {
            tag: OPTS,
            flags: 0,
            bytes: encode_options(&info.pm, pm.keeps_seams()),
        });
        MINOR_WITH_CORNERS
    } else {
        MINOR_WITHOUT_CORNERS
    };
    if let Some(pins) = pm.pins() {
        let bytes = encode_pins(pins);
        sizes.trailing += bytes.len();
        // Required: the pins change the detail pyramid, which an older reader would analyse
        // without them.
        sections.push(Section {
            tag: PINS,
            flags: REQUIRED,
            bytes,
        });
        minor = MINOR;
    }
    if let Some(bytes) = detl {
        sizes.details = bytes.len();
        // Optional: a 2.0 reader skips it and analyses the hierarchy as before.
        sections.push(Section {
            tag: DETL,
            flags: 0,
            bytes,
        });
    }
    sizes.total = container_len(&sections);
    Ok(EncodedPyr {
        minor,
        sections,
        sizes,
    })
}

/// A `.pyr` file encoded section by section: written to a file as it is
/// ([`Self::write_to`]), it is never gathered into one buffer beside its sections.
#[derive(Clone, Debug)]
pub struct EncodedPyr {
    /// The minor version: files without corner data keep the older one, byte for byte.
    minor: u16,
    sections: Vec<Section>,
    /// The byte counts of its parts.
    pub sizes: SizeReport,
}

impl EncodedPyr {
    /// Writes the file to `w`.
    pub fn write_to(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        write_container_to(w, MAJOR, self.minor, &self.sections)
    }

    /// The file's bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        write_container(MAJOR, self.minor, &self.sections)
    }
}

/// The input positions are restored from the PM positions through the vertex order, so check
/// now that this is exact.
fn check_pm_belongs(input: &PolygonMesh, pm: &ProgressiveMesh) -> Result<(), FormatError> {
    let positions = pm.original_positions();
    let foreign = || internal("the progressive mesh does not belong to this input");
    if pm.pm_to_mesh().len() != positions.len() || input.positions.len() > positions.len() {
        return Err(foreign());
    }
    for (i, &s) in pm.pm_to_mesh().iter().enumerate() {
        if let Some(p) = input.positions.get(s as usize)
            && p.to_array().map(f64::to_bits) != positions[i].to_array().map(f64::to_bits)
        {
            return Err(foreign());
        }
    }
    Ok(())
}

/// Decodes a complete file: the hierarchy (validated), the user's mesh, and the build options.
/// Truncated or damaged files are errors (use [`read_level`] for the progressive prefix).
pub fn decode(bytes: &[u8]) -> Result<PyrData, FormatError> {
    decode_releasing(bytes, Release::default())
}

/// [`decode`], calling `release` with the parts of `bytes` it is done with (see
/// [`super::PyrFile`]).
pub(super) fn decode_releasing(bytes: &[u8], release: Release<'_>) -> Result<PyrData, FormatError> {
    // The replay of the splits is sequential and about half of a load; the input's side
    // (vertex order, polygons, attributes, its faces in canonical order) does not depend on it,
    // so it is decoded on another core meanwhile (after that core has decoded split blocks
    // ahead of the replay). Errors come in the order a sequential reader meets them: the
    // progressive part, ISOL, then the input's side.
    let (c, p, (input_side, detl)) = read_progressive(bytes, None, release, |c, meta| {
        let detl = c.section(DETL).and_then(|r| {
            r.map(|r| decode_details(r, meta.n_base as usize, meta.n_splits as usize))
                .transpose()
        });
        c.done_with(DETL);
        let input_side = decode_input_side(c, meta);
        for tag in [ORDR, POLY, ATTR] {
            c.done_with(tag);
        }
        (input_side, detl)
    })?;
    check_complete(&p, bytes.len())?;
    let Progressive {
        meta,
        mut positions,
        splits,
        errors,
        replay,
        ..
    } = p;
    read_isolated(&c, &meta, &mut positions)?;
    let InputSide {
        pm_to_mesh,
        mesh_to_pm,
        permutation,
        mut input,
        clean_faces,
    } = input_side?;
    restore_input_positions(&mut input, &pm_to_mesh, &positions);
    let n_base_faces = replay.n_base_faces();
    let order = (&pm_to_mesh[..], &mesh_to_pm[..], permutation);
    let (faces, source) = finest_faces(&input, clean_faces, replay, order, &positions)?;
    let options = c.section(OPTS)?.map(decode_options).transpose()?;
    let mut pm = ProgressiveMesh::from_checked_parts(
        PmParts {
            n_base: meta.n_base as usize,
            positions,
            pm_to_mesh,
            splits,
            faces,
            errors,
            // Read from their own section below, so that its errors name its place.
            pins: None,
        },
        n_base_faces,
        permutation.then_some(mesh_to_pm),
    )
    .map_err(|e| corrupt(0, e.to_string()))?;
    if let Some(r) = c.section(PINS)? {
        let at = r.offset();
        let pins = decode_pins(r, pm.splits().len(), pm.n_vertices())?;
        pm.set_pins(Some(pins))
            .map_err(|e| corrupt(at, e.to_string()))?;
    }
    let details = file_details(&c, detl?);
    let mut info = build_info(&meta);
    if let Some(o) = options {
        info.pm.uv_weight = o.uv_weight;
        pm.set_keeps_seams(o.keeps_seams);
    }
    Ok(PyrData {
        input,
        source,
        pm,
        info,
        details,
    })
}

/// A truncated file holds a valid hierarchy up to some level, but not the whole file.
fn check_complete(p: &Progressive, file_len: usize) -> Result<(), FormatError> {
    if p.truncated {
        return Err(FormatError::Truncated {
            offset: file_len as u64,
            what: format!(
                "the file (it holds levels up to {} of {})",
                p.meta.n_base as usize + p.splits.len(),
                p.meta.n_base + p.meta.n_splits
            ),
        });
    }
    Ok(())
}

/// True when the file in `bytes` stores a textured input (a `CRNR` or `OPTS` section), whose
/// levels carry per-corner data, materials and groups ([`PyrData::level_mesh`]); false for
/// other files and for bytes that are not a `.pyr` file's head.
pub fn is_textured(bytes: &[u8]) -> bool {
    Container::parse(bytes).is_ok_and(|c| c.entry(CRNR).is_some() || c.entry(OPTS).is_some())
}

/// True when `bytes` start with the `.pyr` signature.
pub fn is_pyr(bytes: &[u8]) -> bool {
    bytes.starts_with(&super::container::MAGIC)
}
