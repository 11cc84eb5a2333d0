//! Reading and writing `.pyr` files: the progressive mesh (base mesh + vertex splits in
//! checksummed blocks), the exact original positions, and trailing sections that restore the
//! user's file exactly (vertex order, polygons, attributes). Specified in `formats/pyr.md`.
//!
//! Details of the detail pyramid are *not* stored: the analysis is a deterministic function of
//! the hierarchy, the original positions and the relaxation operator, so a loader recomputes
//! them bit for bit ([`PyrData::into_scan`]).

use super::FormatError;
use super::container::{Container, REQUIRED, Section, write_container};
use super::varint::{ByteReader, put_ivarint, put_uvarint};
use crate::mesh::{
    Attribute, AttributeData, Built, ElementProperty, ExtraElement, ListProperty, Mesh,
    PolygonMesh, ScalarType, SlotIndex, SourceMap,
};
use crate::pm::{
    FaceBuckets, FlatReplay, PmOptions, PmParts, ProgressiveMesh, VertexSplit, canonical_sorted,
};
use crate::progress::Progress;
use crate::pyramid::{Pyramid, PyramidError, PyramidOptions, ScanPyramid};
use crate::relax::RelaxationSpec;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Major version written. 2.0 codes the split errors as varint deltas of their bit patterns
/// (1.x stored them as raw f32); readers take majors 1 and 2 and refuse others.
pub const MAJOR: u16 = 2;
/// The oldest major this reader still decodes.
pub const OLDEST_MAJOR: u16 = 1;
/// Minor version written; readers accept any minor of their major (unknown optional sections
/// are skipped).
pub const MINOR: u16 = 0;
/// Vertex splits per block of the `SPLT` section.
pub const SPLITS_PER_BLOCK: u32 = 4096;
/// Largest `META` section a reader decodes.
const MAX_META: usize = 4096;
/// Largest ring index a wing code may hold (far above any real valence).
const MAX_RING: u64 = 1 << 20;

const META: [u8; 4] = *b"META";
const BASE: [u8; 4] = *b"BASE";
const SPLT: [u8; 4] = *b"SPLT";
const ISOL: [u8; 4] = *b"ISOL";
const ORDR: [u8; 4] = *b"ORDR";
const POLY: [u8; 4] = *b"POLY";
const ATTR: [u8; 4] = *b"ATTR";
const KNOWN: [[u8; 4]; 7] = [META, BASE, SPLT, ISOL, ORDR, POLY, ATTR];

/// The build options recorded in the header.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildInfo {
    /// How the progressive mesh was built.
    pub pm_options: PmOptions,
    /// The relaxation operator of the pyramid.
    pub relaxation: RelaxationSpec,
}

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

/// A fully decoded `.pyr` file.
#[derive(Clone, Debug)]
pub struct PyrData {
    /// The user's mesh exactly as it was read when the file was built.
    pub input: PolygonMesh,
    /// The repaired half-edge mesh of `input` when loading needed it (an input the builder
    /// repairs); `None` for a clean triangle mesh, whose half-edge mesh is built only when a
    /// command needs it ([`Self::into_scan`], [`Self::built`]).
    built: Option<Built>,
    /// The hierarchy.
    pub pm: ProgressiveMesh,
    /// Build options.
    pub info: BuildInfo,
}

impl PyrData {
    /// Recomputes the detail pyramid (bit-identical to the one the file was built with) and
    /// returns the whole scan.
    pub fn into_scan(self, progress: &dyn Progress) -> Result<ScanPyramid, PyramidError> {
        let op = self.info.relaxation.operator();
        let pyramid = Pyramid::analyze(&self.pm, op.as_ref(), progress)?;
        // A file whose input needed no repair was loaded without building the half-edge mesh
        // (see `clean_triangle_faces`): its mesh is the input itself, vertex for vertex and
        // face for face.
        let source = match self.built {
            Some(b) => b.source,
            None => SourceMap {
                vertex_source: (0..self.input.positions.len() as u32).collect(),
                face_source: (0..self.input.n_faces() as u32).collect(),
                input_vertices: self.input.positions.len(),
            },
        };
        Ok(ScanPyramid {
            input: self.input,
            source,
            pm: self.pm,
            pyramid,
            options: PyramidOptions {
                pm: self.info.pm_options,
                relaxation: self.info.relaxation,
            },
        })
    }
}

impl PyrData {
    /// The repaired half-edge mesh of [`Self::input`] and its map back (the one `build` made;
    /// deterministic). Built on demand unless loading already needed it.
    pub fn built(&self) -> Result<Built, FormatError> {
        match &self.built {
            Some(b) => Ok(b.clone()),
            None => Mesh::from_polygons(&self.input).map_err(|e| corrupt(0, e.to_string())),
        }
    }
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

// ---------------------------------------------------------------------------------------------
// Writing

fn put_position(out: &mut Vec<u8>, p: DVec3, f32: bool) {
    for c in p.to_array() {
        if f32 {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        } else {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}

fn exactly_f32(p: DVec3) -> bool {
    p.to_array()
        .iter()
        .all(|&c| ((c as f32) as f64).to_bits() == c.to_bits())
}

fn put_str(out: &mut Vec<u8>, s: &str) {
    put_uvarint(out, s.len() as u64);
    out.extend_from_slice(s.as_bytes());
}

fn scalar_code(t: ScalarType) -> u8 {
    match t {
        ScalarType::I8 => 1,
        ScalarType::U8 => 2,
        ScalarType::I16 => 3,
        ScalarType::U16 => 4,
        ScalarType::I32 => 5,
        ScalarType::U32 => 6,
        ScalarType::F32 => 7,
        ScalarType::F64 => 8,
    }
}

fn scalar_of(code: u8) -> Option<ScalarType> {
    Some(match code {
        1 => ScalarType::I8,
        2 => ScalarType::U8,
        3 => ScalarType::I16,
        4 => ScalarType::U16,
        5 => ScalarType::I32,
        6 => ScalarType::U32,
        7 => ScalarType::F32,
        8 => ScalarType::F64,
        _ => return None,
    })
}

fn put_column(out: &mut Vec<u8>, d: &AttributeData) {
    out.push(scalar_code(d.scalar_type()));
    match d {
        AttributeData::I8(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::U8(v) => out.extend_from_slice(v),
        AttributeData::I16(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::U16(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::I32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::U32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::F32(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        AttributeData::F64(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
    }
}

fn put_attribute(out: &mut Vec<u8>, a: &Attribute) {
    put_str(out, &a.name);
    put_column(out, &a.data);
}

fn encode_attributes(m: &PolygonMesh) -> Vec<u8> {
    let mut out = Vec::new();
    out.push(m.position_type.map_or(0, scalar_code));
    for list in [&m.vertex_attributes, &m.face_attributes] {
        put_uvarint(&mut out, list.len() as u64);
        for a in list {
            put_attribute(&mut out, a);
        }
    }
    put_uvarint(&mut out, m.extra_elements.len() as u64);
    for e in &m.extra_elements {
        put_str(&mut out, &e.name);
        put_uvarint(&mut out, e.rows as u64);
        put_uvarint(&mut out, e.properties.len() as u64);
        for p in &e.properties {
            match p {
                ElementProperty::Scalar(a) => {
                    out.push(0);
                    put_attribute(&mut out, a);
                }
                ElementProperty::List(l) => {
                    out.push(1);
                    put_str(&mut out, &l.name);
                    out.push(scalar_code(l.count_type));
                    out.push(scalar_code(l.item_type));
                    let mut prev = 0u32;
                    for &s in &l.starts {
                        put_uvarint(&mut out, u64::from(s.wrapping_sub(prev)));
                        prev = s;
                    }
                    for x in &l.items {
                        out.extend_from_slice(&x.to_le_bytes());
                    }
                }
            }
        }
    }
    put_uvarint(&mut out, m.comments.len() as u64);
    for c in &m.comments {
        put_str(&mut out, c);
    }
    out
}

/// Encodes the polygons: per face its degree, then its indices, each as a zig-zag delta from
/// the previous index in the stream (neighbouring faces share vertices, so deltas are small).
fn encode_polygons(m: &PolygonMesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(m.face_indices.len() * 2 + m.n_faces());
    put_uvarint(&mut out, m.n_faces() as u64);
    let mut prev = 0i64;
    for f in m.faces() {
        put_uvarint(&mut out, f.len() as u64);
        for &i in f {
            put_ivarint(&mut out, i64::from(i) - prev);
            prev = i64::from(i);
        }
    }
    out
}

/// Encodes `input` with its hierarchy `pm` (built from `Mesh::from_polygons(input)`).
pub fn encode(
    input: &PolygonMesh,
    pm: &ProgressiveMesh,
    info: &BuildInfo,
) -> Result<(Vec<u8>, SizeReport), FormatError> {
    let positions = pm.original_positions();
    let n_total = positions.len();
    let n_base = pm.n_base_vertices();
    let n_fin = pm.n_vertices();
    if pm.pm_to_mesh().len() != n_total || input.positions.len() > n_total {
        return Err(internal(
            "the progressive mesh does not belong to this input",
        ));
    }
    // The input positions are restored from the PM positions through the vertex order, so
    // check now that this is exact.
    for (i, &s) in pm.pm_to_mesh().iter().enumerate() {
        if let Some(p) = input.positions.get(s as usize)
            && p.to_array().map(f64::to_bits) != positions[i].to_array().map(f64::to_bits)
        {
            return Err(internal(
                "the progressive mesh does not belong to this input",
            ));
        }
    }
    let f32 = positions.iter().all(|&p| exactly_f32(p));
    let width = if f32 { 4 } else { 8 };
    let mut sizes = SizeReport::default();

    let (lo, hi) = positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let (lo, hi) = if n_total == 0 {
        (DVec3::ZERO, DVec3::ZERO)
    } else {
        (lo, hi)
    };
    let o = &info.pm_options;
    let meta = Meta {
        n_input_vertices: input.positions.len() as u64,
        n_input_faces: input.n_faces() as u64,
        n_vertices: n_total as u64,
        n_base: n_base as u64,
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
    };
    let meta_bytes = bincode::serde::encode_to_vec(&meta, bincode::config::standard())
        .map_err(|e| internal(&e.to_string()))?;

    // BASE: positions, then triangles as zig-zag deltas.
    let base_tris = pm.base_triangles();
    let mut base = Vec::new();
    for &p in &positions[..n_base] {
        put_position(&mut base, p, f32);
    }
    let before = base.len();
    put_uvarint(&mut base, base_tris.len() as u64);
    let mut prev = 0i64;
    for t in &base_tris {
        put_ivarint(&mut base, i64::from(t[0]) - prev);
        put_ivarint(&mut base, i64::from(t[1]) - i64::from(t[0]));
        put_ivarint(&mut base, i64::from(t[2]) - i64::from(t[0]));
        prev = i64::from(t[0]);
    }
    sizes.pm_connectivity += base.len() - before;
    sizes.positions += before;

    // SPLT: blocks of split records, replayed on the base mesh to code wings as ring indices.
    // The replay is sequential and most of a save; the sections after it do not depend on it,
    // so they are encoded on another core meanwhile.
    let encode_splits = || -> Result<(Vec<u8>, SizeReport), FormatError> {
        let mut sizes = SizeReport::default();
        let mut replay = FlatReplay::new(&positions[..n_base], &base_tris, pm.splits().len())
            .map_err(|e| internal(&e.to_string()))?;
        let mut splt = Vec::with_capacity(pm.splits().len() * (4 + 4 + 3 * width) + 64);
        let mut payload = Vec::new();
        for (b, chunk) in pm.splits().chunks(SPLITS_PER_BLOCK as usize).enumerate() {
            let first = n_base + b * SPLITS_PER_BLOCK as usize;
            payload.clear();
            payload.reserve(chunk.len() * (4 + 4 + 3 * width));
            for (k, s) in chunk.iter().enumerate() {
                replay.prefetch_upcoming(k, |j| chunk.get(j).map(|t| t.survivor));
                put_uvarint(&mut payload, u64::from(s.vertex - 1 - s.survivor));
                let (il, ir) = replay
                    .wing_indices(s)
                    .map_err(|e| internal(&e.to_string()))?;
                let valence = replay.listed_valence();
                put_uvarint(&mut payload, il.map_or(0, |i| i as u64 + 1));
                let rc = match (il, ir) {
                    (_, None) => 0,
                    (Some(l), Some(r)) => wrap_once((r + valence - l) as u64, valence as u64) + 1,
                    (None, Some(r)) => r as u64 + 1,
                };
                put_uvarint(&mut payload, rc);
                replay
                    .apply_indexed(s.vertex, s.survivor, il, ir)
                    .map_err(|e| internal(&e.to_string()))?;
            }
            sizes.pm_connectivity += payload.len() + 12;
            // Errors as deltas of their bit patterns: successive splits have similar errors,
            // and positive floats order like their bits, so the deltas are short (about 2
            // bytes on scans, against 4 raw) and the coding is exact for any value.
            let before = payload.len();
            let mut prev = 0u32;
            for e in &pm.split_errors()[first - n_base..first - n_base + chunk.len()] {
                let bits = e.to_bits();
                put_ivarint(&mut payload, i64::from(bits) - i64::from(prev));
                prev = bits;
            }
            sizes.split_errors += payload.len() - before;
            for &p in &positions[first..first + chunk.len()] {
                put_position(&mut payload, p, f32);
            }
            sizes.positions += chunk.len() * 3 * width;
            splt.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
            splt.extend_from_slice(&(payload.len() as u32).to_le_bytes());
            splt.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
            splt.extend_from_slice(&payload);
        }
        Ok((splt, sizes))
    };
    let encode_rest = || {
        let mut isol = Vec::new();
        for &p in &positions[n_fin..] {
            put_position(&mut isol, p, f32);
        }
        let mut ordr = Vec::with_capacity(n_total * 3);
        for &s in pm.pm_to_mesh() {
            put_uvarint(&mut ordr, u64::from(s));
        }
        (isol, ordr, encode_polygons(input), encode_attributes(input))
    };
    let (splits, (isol, ordr, poly, attr)) = rayon::join(encode_splits, encode_rest);
    let (splt, split_sizes) = splits?;
    sizes.pm_connectivity += split_sizes.pm_connectivity;
    sizes.positions += split_sizes.positions + isol.len();
    sizes.split_errors += split_sizes.split_errors;
    sizes.trailing = ordr.len() + poly.len() + attr.len();

    let sections = [
        Section {
            tag: META,
            flags: REQUIRED,
            bytes: meta_bytes,
        },
        Section {
            tag: BASE,
            flags: REQUIRED,
            bytes: base,
        },
        Section {
            tag: SPLT,
            flags: REQUIRED,
            bytes: splt,
        },
        Section {
            tag: ISOL,
            flags: REQUIRED,
            bytes: isol,
        },
        Section {
            tag: ORDR,
            flags: REQUIRED,
            bytes: ordr,
        },
        Section {
            tag: POLY,
            flags: REQUIRED,
            bytes: poly,
        },
        Section {
            tag: ATTR,
            flags: REQUIRED,
            bytes: attr,
        },
    ];
    let bytes = write_container(MAJOR, MINOR, &sections);
    sizes.total = bytes.len();
    Ok((bytes, sizes))
}

// ---------------------------------------------------------------------------------------------
// Reading

fn read_position(r: &mut ByteReader<'_>, f32: bool) -> Result<DVec3, FormatError> {
    let mut c = [0f64; 3];
    for x in &mut c {
        *x = if f32 {
            f64::from(f32::from_le_bytes(r.array("position")?))
        } else {
            r.f64("position")?
        };
    }
    let p = DVec3::from_array(c);
    if !p.is_finite() {
        return Err(corrupt(r.offset(), "non-finite position"));
    }
    Ok(p)
}

fn read_positions(
    r: &mut ByteReader<'_>,
    n: usize,
    f32: bool,
    out: &mut Vec<DVec3>,
) -> Result<(), FormatError> {
    let width = if f32 { 12 } else { 24 };
    if n.saturating_mul(width) > r.remaining() {
        return Err(FormatError::Truncated {
            offset: r.offset(),
            what: "positions".into(),
        });
    }
    out.reserve(n);
    for _ in 0..n {
        out.push(read_position(r, f32)?);
    }
    Ok(())
}

/// The parsed header and the progressive part, shared by the full and the level readers.
struct Progressive {
    meta: Meta,
    truncated: bool,
    /// The base mesh with `splits` applied.
    replay: FlatReplay,
    splits: Vec<VertexSplit>,
    positions: Vec<DVec3>,
    errors: Vec<f32>,
}

fn check_version(c: &Container<'_>) -> Result<(), FormatError> {
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

fn required<'a>(c: &Container<'a>, tag: [u8; 4]) -> Result<ByteReader<'a>, FormatError> {
    c.section(tag)?.ok_or_else(|| {
        corrupt(
            0,
            format!("section {} is missing", super::container::tag_name(tag)),
        )
    })
}

fn read_meta(c: &Container<'_>) -> Result<Meta, FormatError> {
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

/// `x mod n` for `x < 2n`: the right wing's code is `(r − l) mod valence` and decodes as
/// `(l + code) mod valence`, both with `l, r < valence`, so a compare and subtract does
/// instead of a division per split.
#[inline]
fn wrap_once(x: u64, n: u64) -> u64 {
    if x >= n { x - n } else { x }
}

/// One `SPLT` block as the header scan found it.
struct BlockRef<'a> {
    /// Offset of its header (for errors).
    at: u64,
    count: usize,
    /// How many of its splits the reader wants (all but in the last block read).
    used: usize,
    /// Index of its first split.
    first: usize,
    crc: u32,
    payload: &'a [u8],
}

/// One block's contents, decoded but not yet replayed.
struct DecodedBlock {
    /// Survivor, left and right wing codes, and the record's offset, per split.
    records: Vec<(u32, u64, u64, u64)>,
    positions: Vec<DVec3>,
    errors: Vec<f32>,
    /// Trailing bytes after the records: an error a sequential reader meets only after
    /// replaying the block.
    trailing: Option<FormatError>,
}

/// The `SPLT` blocks of a file, located by a scan of their headers (12 bytes per 4096
/// splits), each decoded by whichever thread claims it first. The replay is sequential and
/// most of a load; decoding a block (checksum, positions, varint records, errors) does not
/// depend on it, so another core decodes blocks ahead of the replay while the replaying thread
/// only decodes a block nobody has claimed yet. Decoding is a pure function of the bytes, so
/// who does it changes nothing, and the replay never waits on a block that is not being
/// decoded: no deadlock on a one-thread pool.
struct SplitBlocks<'a> {
    blocks: Vec<BlockRef<'a>>,
    /// What the scan met after the last block it found: nothing, or the error a sequential
    /// reader reports once it has replayed the blocks before it.
    end: Result<(), FormatError>,
    n_base: usize,
    f32: bool,
    /// Format 2.x: errors as varint deltas between the records and the positions (1.x: raw
    /// f32 after the positions).
    coded_errors: bool,
    claimed: Vec<std::sync::atomic::AtomicBool>,
    ready: Vec<std::sync::Mutex<Option<Result<DecodedBlock, FormatError>>>>,
}

impl<'a> SplitBlocks<'a> {
    /// Scans the block headers of `c`'s `SPLT` section up to `max_level` (default: all).
    /// A truncated file stops at its last complete block.
    fn scan(c: &Container<'a>, meta: &Meta, max_level: Option<usize>) -> SplitBlocks<'a> {
        let n_base = meta.n_base as usize;
        let n_splits = meta.n_splits as usize;
        let want = max_level.map_or(n_splits, |l| l.saturating_sub(n_base).min(n_splits));
        let mut blocks = Vec::new();
        let end = (|| {
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
        })();
        let n = blocks.len();
        SplitBlocks {
            blocks,
            end,
            n_base,
            f32: meta.position_bits == 32,
            coded_errors: c.major >= 2,
            claimed: (0..n).map(|_| Default::default()).collect(),
            ready: (0..n).map(|_| Default::default()).collect(),
        }
    }

    /// Decodes block `k`: checksum, positions, records, errors (only the splits wanted).
    fn decode(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        let b = &self.blocks[k];
        if crc32fast::hash(b.payload) != b.crc {
            return Err(FormatError::Checksum {
                what: "split block".into(),
                offset: b.at,
            });
        }
        // Payload, 2.x: the records and the error deltas (variable length), then `count`
        // positions (fixed length), so the positions start at a known offset from the end.
        // 1.x: the records, then `count` positions and `count` raw f32 errors.
        let width = 3 * if self.f32 { 4 } else { 8 };
        let tail = b.count * (width + if self.coded_errors { 0 } else { 4 });
        if tail > b.payload.len() {
            return Err(corrupt(b.at, "split block is shorter than its positions"));
        }
        let (records, fixed) = b.payload.split_at(b.payload.len() - tail);
        let mut p = ByteReader::new(records, b.at + 12);
        let mut q = ByteReader::new(fixed, b.at + 12 + records.len() as u64);
        let mut positions = Vec::new();
        read_positions(&mut q, b.used, self.f32, &mut positions)?;
        let mut decoded = Vec::with_capacity(b.used);
        for k in 0..b.used {
            let vertex = (self.n_base + b.first + k) as u32;
            let at = p.offset();
            if vertex == 0 {
                return Err(corrupt(at, "split without a survivor"));
            }
            let back = p.count(u64::from(vertex - 1), "survivor")? as u32;
            let lc = p.count(MAX_RING, "left wing")?;
            let rc = p.count(MAX_RING, "right wing")?;
            decoded.push((vertex - 1 - back, lc as u64, rc as u64, at));
        }
        let mut errors = Vec::with_capacity(b.used);
        if self.coded_errors {
            // The errors follow every record of the block, wanted or not.
            for _ in 0..3 * (b.count - b.used) {
                p.uvarint("split record")?;
            }
            let mut prev = 0u32;
            for _ in 0..b.used {
                let at = p.offset();
                let bits = i64::from(prev)
                    .checked_add(p.ivarint("split error")?)
                    .and_then(|x| u32::try_from(x).ok())
                    .ok_or_else(|| corrupt(at, "split error out of range"))?;
                errors.push(f32::from_bits(bits));
                prev = bits;
            }
        } else {
            q.take((b.count - b.used) * width, "positions")?;
            for _ in 0..b.used {
                errors.push(f32::from_le_bytes(q.array("split error")?));
            }
        }
        let trailing = (b.used == b.count && !p.is_empty())
            .then(|| corrupt(p.offset(), "trailing bytes in split block"));
        Ok(DecodedBlock {
            records: decoded,
            positions,
            errors,
            trailing,
        })
    }

    /// Block `k`, for the replay: decoded here unless another thread claimed it first, in
    /// which case that thread is decoding it right now and the wait is short.
    fn take(&self, k: usize) -> Result<DecodedBlock, FormatError> {
        use std::sync::atomic::Ordering;
        if !self.claimed[k].swap(true, Ordering::AcqRel) {
            return self.decode(k);
        }
        loop {
            let slot = self.ready[k]
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take();
            if let Some(d) = slot {
                return d;
            }
            std::thread::yield_now();
        }
    }

    /// Decodes, in order, every block the replay has not claimed yet.
    fn decode_ahead(&self) {
        use std::sync::atomic::Ordering;
        for k in 0..self.blocks.len() {
            if self.claimed[k].swap(true, Ordering::AcqRel) {
                continue;
            }
            // Should decoding panic (a bug), the replay must not wait forever for the block.
            struct Publish<'b>(
                &'b std::sync::Mutex<Option<Result<DecodedBlock, FormatError>>>,
                Option<Result<DecodedBlock, FormatError>>,
            );
            impl Drop for Publish<'_> {
                fn drop(&mut self) {
                    let d = self
                        .1
                        .take()
                        .unwrap_or_else(|| Err(internal("split block decoder panicked")));
                    *self
                        .0
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(d);
                }
            }
            let mut publish = Publish(&self.ready[k], None);
            publish.1 = Some(self.decode(k));
        }
    }
}

/// The progressive part of `bytes` up to `max_level` (default: all), with `also` run on
/// another core meanwhile (after it has helped decode the split blocks). Errors come in the
/// order a sequential reader meets them: header, `BASE`, then block by block.
fn read_progressive<'a, R: Send>(
    bytes: &'a [u8],
    max_level: Option<usize>,
    also: impl FnOnce(&Container<'a>, &Meta) -> R + Send,
) -> Result<(Container<'a>, Progressive, R), FormatError> {
    let c = Container::parse(bytes)?;
    check_version(&c)?;
    let meta = read_meta(&c)?;
    let blocks = SplitBlocks::scan(&c, &meta, max_level);
    let (p, r) = rayon::join(
        || replay_progressive(&c, &meta, &blocks, bytes.len()),
        || {
            blocks.decode_ahead();
            also(&c, &meta)
        },
    );
    Ok((c, p?, r))
}

/// `BASE`, then the blocks of `blocks` replayed in order.
fn replay_progressive(
    c: &Container<'_>,
    meta: &Meta,
    blocks: &SplitBlocks<'_>,
    file_len: usize,
) -> Result<Progressive, FormatError> {
    let f32 = meta.position_bits == 32;
    let n_base = meta.n_base as usize;
    let n_splits = meta.n_splits as usize;

    let mut r = required(c, BASE)?;
    let mut positions = Vec::new();
    read_positions(&mut r, n_base, f32, &mut positions)?;
    let n_faces = r.count(r.remaining() as u64 / 3, "base face count")?;
    let mut base_faces = Vec::with_capacity(n_faces);
    let mut prev = 0i64;
    for _ in 0..n_faces {
        let at = r.offset();
        let a = prev + r.ivarint("base face")?;
        let b = a + r.ivarint("base face")?;
        let cc = a + r.ivarint("base face")?;
        let t = [a, b, cc].map(|x| u32::try_from(x).unwrap_or(u32::MAX));
        if t.iter().any(|&x| x as usize >= n_base) {
            return Err(corrupt(at, "base face index out of range"));
        }
        base_faces.push(t);
        prev = a;
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in BASE"));
    }
    // Every split takes at least 3 record bytes and a position, so the file size caps the
    // room reserved for the replay.
    let hint = n_splits.min(file_len / 15);
    let mut replay = FlatReplay::new(&positions, &base_faces, hint)
        .map_err(|e| corrupt(r.offset(), e.to_string()))?;

    let want: usize = blocks.blocks.iter().map(|b| b.used).sum();
    let mut splits: Vec<VertexSplit> = Vec::with_capacity(want.min(hint));
    let mut errors: Vec<f32> = Vec::with_capacity(want.min(hint));
    positions.reserve(want.min(hint));
    for k in 0..blocks.blocks.len() {
        let block = blocks.take(k)?;
        positions.extend_from_slice(&block.positions);
        let decoded = &block.records;
        for (k, &(survivor, lc, rc, at)) in decoded.iter().enumerate() {
            replay.prefetch_upcoming(k, |j| decoded.get(j).map(|r| r.0));
            let vertex = (n_base + splits.len()) as u32;
            let deg = replay
                .valence(survivor)
                .map_err(|e| corrupt(at, e.to_string()))? as u64;
            if lc > deg || rc > deg {
                return Err(corrupt(at, "wing index past the survivor's ring"));
            }
            let il = lc.checked_sub(1);
            // l, r < deg (checked above).
            let ir = rc
                .checked_sub(1)
                .map(|r| il.map_or(r, |l| wrap_once(l + r, deg)));
            let s = replay
                .apply_indexed(
                    vertex,
                    survivor,
                    il.map(|i| i as usize),
                    ir.map(|i| i as usize),
                )
                .map_err(|e| corrupt(at, e.to_string()))?;
            splits.push(s);
        }
        errors.extend_from_slice(&block.errors);
        if let Some(e) = block.trailing {
            return Err(e);
        }
    }
    blocks.end.clone()?;
    Ok(Progressive {
        meta: meta.clone(),
        truncated: c.is_truncated(),
        replay,
        splits,
        positions,
        errors,
    })
}

/// Reads level `level` (default: the finest in the file) from the progressive part only. A
/// truncated file yields its last complete level (`truncated` set); the caller warns.
pub fn read_level(bytes: &[u8], level: Option<usize>) -> Result<LevelMesh, FormatError> {
    let (_, p, ()) = read_progressive(bytes, level, |_, _| ())?;
    let n_base = p.meta.n_base as usize;
    let finest = n_base + p.meta.n_splits as usize;
    // The progressive reader stopped at the level asked for (or where the file ends).
    let splits_needed = p.splits.len();
    let n = n_base + splits_needed;
    let mut positions = p.positions;
    positions.truncate(n);
    let triangles = p.replay.triangles();
    Ok(LevelMesh {
        level: n_base + splits_needed,
        finest,
        base: n_base,
        truncated: p.truncated,
        positions,
        triangles,
        f32_positions: p.meta.position_bits == 32,
    })
}

fn read_str(r: &mut ByteReader<'_>) -> Result<String, FormatError> {
    let n = r.count(r.remaining() as u64, "string length")?;
    let at = r.offset();
    let b = r.take(n, "string")?;
    String::from_utf8(b.to_vec()).map_err(|_| corrupt(at, "string is not UTF-8"))
}

fn read_scalar_type(r: &mut ByteReader<'_>) -> Result<ScalarType, FormatError> {
    let at = r.offset();
    let [c] = r.array("scalar type")?;
    scalar_of(c).ok_or_else(|| corrupt(at, format!("unknown scalar type {c}")))
}

fn read_column(r: &mut ByteReader<'_>, rows: usize) -> Result<AttributeData, FormatError> {
    let t = read_scalar_type(r)?;
    let bytes = r.take(
        rows.checked_mul(t.size())
            .ok_or_else(|| corrupt(r.offset(), "column too large"))?,
        "attribute values",
    )?;
    macro_rules! col {
        ($v:ident, $ty:ty) => {
            AttributeData::$v(
                bytes
                    .chunks_exact(std::mem::size_of::<$ty>())
                    .map(|c| <$ty>::from_le_bytes(c.try_into().unwrap_or_default()))
                    .collect(),
            )
        };
    }
    Ok(match t {
        ScalarType::I8 => col!(I8, i8),
        ScalarType::U8 => AttributeData::U8(bytes.to_vec()),
        ScalarType::I16 => col!(I16, i16),
        ScalarType::U16 => col!(U16, u16),
        ScalarType::I32 => col!(I32, i32),
        ScalarType::U32 => col!(U32, u32),
        ScalarType::F32 => col!(F32, f32),
        ScalarType::F64 => col!(F64, f64),
    })
}

fn read_attribute(r: &mut ByteReader<'_>, rows: usize) -> Result<Attribute, FormatError> {
    let name = read_str(r)?;
    let data = read_column(r, rows)?;
    Ok(Attribute { name, data })
}

fn decode_attributes(r: &mut ByteReader<'_>, m: &mut PolygonMesh) -> Result<(), FormatError> {
    let at = r.offset();
    let [pt] = r.array("position type")?;
    m.position_type = match pt {
        0 => None,
        c => Some(scalar_of(c).ok_or_else(|| corrupt(at, "unknown position type"))?),
    };
    let rows = [m.positions.len(), m.n_faces()];
    for (k, &n) in rows.iter().enumerate() {
        let count = r.count(r.remaining() as u64 / 2, "attribute count")?;
        let mut list = Vec::with_capacity(count);
        for _ in 0..count {
            list.push(read_attribute(r, n)?);
        }
        if k == 0 {
            m.vertex_attributes = list;
        } else {
            m.face_attributes = list;
        }
    }
    let n_el = r.count(r.remaining() as u64 / 3, "element count")?;
    for _ in 0..n_el {
        let name = read_str(r)?;
        let rows = r.count(u64::from(u32::MAX), "element rows")?;
        let n_prop = r.count(r.remaining() as u64 / 2, "property count")?;
        let mut properties = Vec::with_capacity(n_prop);
        for _ in 0..n_prop {
            let at = r.offset();
            let [kind] = r.array("property kind")?;
            match kind {
                0 => properties.push(ElementProperty::Scalar(read_attribute(r, rows)?)),
                1 => {
                    let name = read_str(r)?;
                    let count_type = read_scalar_type(r)?;
                    let item_type = read_scalar_type(r)?;
                    if rows >= r.remaining() {
                        return Err(FormatError::Truncated {
                            offset: r.offset(),
                            what: "list offsets".into(),
                        });
                    }
                    let mut starts = Vec::with_capacity(rows + 1);
                    let mut s = 0u64;
                    for _ in 0..=rows {
                        s += r.count(u64::from(u32::MAX), "list offset")? as u64;
                        if s > u64::from(u32::MAX) {
                            return Err(corrupt(r.offset(), "list offsets overflow"));
                        }
                        starts.push(s as u32);
                    }
                    let n_items = s as usize;
                    let bytes = r.take(
                        n_items
                            .checked_mul(8)
                            .ok_or_else(|| corrupt(r.offset(), "list too large"))?,
                        "list items",
                    )?;
                    let items = bytes
                        .chunks_exact(8)
                        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
                        .collect();
                    properties.push(ElementProperty::List(ListProperty {
                        name,
                        count_type,
                        item_type,
                        starts,
                        items,
                    }));
                }
                k => return Err(corrupt(at, format!("unknown property kind {k}"))),
            }
        }
        m.extra_elements.push(ExtraElement {
            name,
            rows,
            properties,
        });
    }
    let n_c = r.count(r.remaining() as u64, "comment count")?;
    for _ in 0..n_c {
        m.comments.push(read_str(r)?);
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in ATTR"));
    }
    Ok(())
}

fn decode_polygons(
    r: &mut ByteReader<'_>,
    n_faces_meta: u64,
    n_vertices: usize,
    m: &mut PolygonMesh,
) -> Result<(), FormatError> {
    let at = r.offset();
    let n = r.count(r.remaining() as u64, "face count")?;
    if n as u64 != n_faces_meta {
        return Err(corrupt(at, "face count disagrees with META"));
    }
    m.face_starts = Vec::with_capacity(n + 1);
    m.face_starts.push(0);
    m.face_indices = Vec::with_capacity(n * 3);
    let mut prev = 0i64;
    for _ in 0..n {
        let d = r.count(r.remaining() as u64, "face degree")?;
        for _ in 0..d {
            let at = r.offset();
            let i = prev + r.ivarint("face index")?;
            if i < 0 || i as u64 >= n_vertices as u64 {
                return Err(corrupt(at, "face index out of range"));
            }
            m.face_indices.push(i as u32);
            prev = i;
        }
        if m.face_indices.len() > u32::MAX as usize {
            return Err(corrupt(at, "too many face indices"));
        }
        m.face_starts.push(m.face_indices.len() as u32);
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in POLY"));
    }
    Ok(())
}

/// What [`decode`] reads besides the hierarchy: the input's vertex order, its polygons and
/// attributes (positions still zero: they come from the hierarchy), and, for a clean triangle
/// input, its faces in PM indices with their canonical sorted order.
struct InputSide {
    pm_to_mesh: Vec<u32>,
    /// The inverse of `pm_to_mesh` (`u32::MAX` where nothing maps).
    mesh_to_pm: Vec<u32>,
    /// Whether `pm_to_mesh` is a permutation, so that `mesh_to_pm` is its exact inverse.
    permutation: bool,
    input: PolygonMesh,
    clean_faces: Option<CleanFaces>,
}

/// The faces of a clean triangle input in PM indices, in the input's order and bucketed by
/// smallest index (see [`clean_triangle_faces`]).
struct CleanFaces {
    faces: Vec<[u32; 3]>,
    buckets: FaceBuckets,
}

fn decode_input_side(c: &Container<'_>, meta: &Meta) -> Result<InputSide, FormatError> {
    let n_total = meta.n_vertices as usize;
    let mut r = required(c, ORDR)?;
    if n_total > r.remaining() {
        return Err(FormatError::Truncated {
            offset: r.offset(),
            what: "vertex order".into(),
        });
    }
    let mut pm_to_mesh = Vec::with_capacity(n_total);
    for _ in 0..n_total {
        pm_to_mesh.push(r.count(n_total as u64, "vertex order")? as u32);
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in ORDR"));
    }
    let n_input = meta.n_input_vertices as usize;
    let mut input = PolygonMesh::new();
    input.positions = vec![DVec3::ZERO; n_input];
    let mut seen = vec![false; n_input];
    for &s in &pm_to_mesh {
        if let Some(x) = seen.get_mut(s as usize) {
            *x = true;
        }
    }
    if seen.iter().any(|&x| !x) {
        return Err(corrupt(0, "vertex order does not cover the input vertices"));
    }
    let mut r = required(c, POLY)?;
    decode_polygons(&mut r, meta.n_input_faces, n_input, &mut input)?;
    let mut r = required(c, ATTR)?;
    decode_attributes(&mut r, &mut input)?;
    let mut mesh_to_pm = vec![u32::MAX; n_total];
    let mut permutation = true;
    for (i, &s) in pm_to_mesh.iter().enumerate() {
        if let Some(m) = mesh_to_pm.get_mut(s as usize) {
            permutation &= *m == u32::MAX;
            *m = i as u32;
        }
    }
    // The positions are placeholders (all finite, as the stored ones are: `read_position`
    // refuses others), so this checks the polygons and attributes here, off the replay's
    // critical path.
    input
        .check()
        .map_err(|e| corrupt(0, format!("restored mesh: {e}")))?;
    let clean_faces = clean_triangle_faces(&input, &mesh_to_pm, n_total);
    Ok(InputSide {
        pm_to_mesh,
        mesh_to_pm,
        permutation,
        input,
        clean_faces,
    })
}

/// Decodes a complete file: the hierarchy (validated), the user's mesh, and the build options.
/// Truncated or damaged files are errors (use [`read_level`] for the progressive prefix).
pub fn decode(bytes: &[u8]) -> Result<PyrData, FormatError> {
    // The replay of the splits is sequential and about half of a load; the input's side
    // (vertex order, polygons, attributes, its faces in canonical order) does not depend on it,
    // so it is decoded on another core meanwhile (after that core has decoded split blocks
    // ahead of the replay). Errors come in the order a sequential reader meets them: the
    // progressive part, ISOL, then the input's side.
    let (c, p, input_side) = read_progressive(bytes, None, decode_input_side)?;
    if p.truncated {
        return Err(FormatError::Truncated {
            offset: bytes.len() as u64,
            what: format!(
                "the file (it holds levels up to {} of {})",
                p.meta.n_base as usize + p.splits.len(),
                p.meta.n_base + p.meta.n_splits
            ),
        });
    }
    let Progressive {
        meta,
        mut positions,
        splits,
        errors,
        replay,
        ..
    } = p;
    let f32 = meta.position_bits == 32;
    let n_total = meta.n_vertices as usize;
    let n_fin = positions.len();
    let mut r = required(&c, ISOL)?;
    read_positions(&mut r, n_total - n_fin, f32, &mut positions)?;
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in ISOL"));
    }
    let InputSide {
        pm_to_mesh,
        mesh_to_pm,
        permutation,
        mut input,
        clean_faces,
    } = input_side?;
    // Vertex copies the builder made (order entries past the input's vertices) have no row.
    for (i, &s) in pm_to_mesh.iter().enumerate() {
        if let Some(p) = input.positions.get_mut(s as usize) {
            *p = positions[i];
        }
    }
    // The finest faces, checked to be exactly what the splits rebuild: read off a clean
    // triangle input, else from the builder's repaired mesh.
    let (faces, built) = match clean_faces.filter(|c| replay.has_faces(&c.buckets)) {
        Some(clean) => (clean.faces, None),
        None => {
            let (faces, built) = built_faces(&input, &mesh_to_pm, n_total, &positions)?;
            if canonical_sorted(&faces, n_total) != replay.canonical_faces() {
                return Err(corrupt(0, "the splits do not rebuild the finest faces"));
            }
            (faces, Some(built))
        }
    };
    let pm = ProgressiveMesh::from_checked_parts(
        PmParts {
            n_base: meta.n_base as usize,
            positions,
            pm_to_mesh,
            splits,
            faces,
            errors,
        },
        replay.n_base_faces(),
        permutation.then_some(mesh_to_pm),
    )
    .map_err(|e| corrupt(0, e.to_string()))?;
    let info = BuildInfo {
        pm_options: PmOptions {
            target_vertices: meta.target_vertices as usize,
            target_faces: meta.target_faces as usize,
            max_error: meta.max_error,
            max_normal_angle_degrees: meta.max_normal_angle_degrees,
            min_quality: meta.min_quality,
            max_valence: meta.max_valence as usize,
            boundary_weight: meta.boundary_weight,
        },
        relaxation: meta.relaxation,
    };
    Ok(PyrData {
        input,
        built,
        pm,
        info,
    })
}

/// The finest faces in PM indices read straight off the input, when the input is a clean
/// triangle mesh (every polygon a triangle of three distinct vertices, no vertex copies), with
/// the same faces bucketed by smallest index. When those are exactly the faces the splits
/// rebuilt, they form a consistently oriented manifold without multi-edges, on which
/// `Mesh::from_polygons` repairs nothing, keeps vertex slots and face order and starts each
/// face at its first corner, so the faces are what it would give, without building the
/// half-edge mesh (most of a load's time on big meshes). `None`, or a mismatch, sends the
/// caller to the builder.
fn clean_triangle_faces(
    input: &PolygonMesh,
    mesh_to_pm: &[u32],
    n_total: usize,
) -> Option<CleanFaces> {
    if n_total != input.positions.len() || input.face_indices.len() != 3 * input.n_faces() {
        return None;
    }
    let mut faces = Vec::with_capacity(input.n_faces());
    for t in input.face_indices.chunks_exact(3) {
        let f = [t[0], t[1], t[2]].map(|x| mesh_to_pm.get(x as usize).copied().unwrap_or(u32::MAX));
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || f.contains(&u32::MAX) {
            return None;
        }
        faces.push(f);
    }
    let buckets = FaceBuckets::new(&faces, n_total);
    Some(CleanFaces { faces, buckets })
}

/// The finest faces in PM indices from the repaired half-edge mesh of `input` (any polygons,
/// any repairs), checking that the builder's vertices are the stored ones.
fn built_faces(
    input: &PolygonMesh,
    mesh_to_pm: &[u32],
    n_total: usize,
    positions: &[DVec3],
) -> Result<(Vec<[u32; 3]>, Built), FormatError> {
    let built = Mesh::from_polygons(input).map_err(|e| corrupt(0, e.to_string()))?;
    if built.mesh.n_vertices() != n_total {
        return Err(corrupt(0, "the polygons do not build the stored hierarchy"));
    }
    let mut faces = Vec::with_capacity(built.mesh.n_faces());
    for f in built.mesh.faces() {
        let t = built
            .mesh
            .face_vertices(f)
            .map(|v| mesh_to_pm.get(v.slot()).copied().unwrap_or(u32::MAX));
        faces.push(t);
    }
    // The positions of the built mesh (including the builder's vertex copies) must be the
    // stored ones.
    for v in built.mesh.vertices() {
        let i = mesh_to_pm.get(v.slot()).copied().unwrap_or(u32::MAX) as usize;
        let same = positions.get(i).is_some_and(|p| {
            p.to_array().map(f64::to_bits) == built.mesh.position(v).to_array().map(f64::to_bits)
        });
        if !same {
            return Err(corrupt(0, "the polygons do not build the stored hierarchy"));
        }
    }
    Ok((faces, built))
}

/// True when `bytes` start with the `.pyr` signature.
pub fn is_pyr(bytes: &[u8]) -> bool {
    bytes.starts_with(&super::container::MAGIC)
}

/// `bytes` with every checksum (header, sections, `SPLT` blocks) recomputed, where the
/// structure can be followed. Lets the fuzzer reach the decoders behind the checksums, which
/// random mutations almost never get past.
pub(crate) fn fix_checksums(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let Ok(c) = Container::parse_unchecked(bytes) else {
        return out;
    };
    for (k, e) in c.sections.iter().enumerate() {
        let (start, len) = (e.offset as usize, e.length as usize);
        let Some(end) = start.checked_add(len).filter(|&x| x <= out.len()) else {
            continue;
        };
        if e.tag == SPLT {
            let mut at = start;
            while at + 12 <= end {
                let plen = u32::from_le_bytes([out[at + 4], out[at + 5], out[at + 6], out[at + 7]])
                    as usize;
                let Some(pend) = (at + 12).checked_add(plen).filter(|&x| x <= end) else {
                    break;
                };
                let crc = crc32fast::hash(&out[at + 12..pend]);
                out[at + 8..at + 12].copy_from_slice(&crc.to_le_bytes());
                at = pend;
            }
        }
        let crc = crc32fast::hash(&out[start..end]);
        let entry = 24 + 32 * k + 24;
        out[entry..entry + 4].copy_from_slice(&crc.to_le_bytes());
    }
    let table_end = 24 + 32 * c.sections.len();
    let mut h = crc32fast::Hasher::new();
    h.update(&out[..20]);
    h.update(&out[24..table_end]);
    let crc = h.finalize();
    out[20..24].copy_from_slice(&crc.to_le_bytes());
    out
}

/// Body of the `read_pyr` fuzz target: every reader on arbitrary bytes must return, never
/// panic; whatever decodes must re-encode to a file that decodes to the same data. The input
/// is tried as is and with its checksums fixed ([`fix_checksums`]).
pub(crate) fn fuzz_read_pyr(data: &[u8]) {
    fuzz_one(data);
    let fixed = fix_checksums(data);
    if fixed != data {
        fuzz_one(&fixed);
    }
}

fn fuzz_one(data: &[u8]) {
    let _ = read_level(data, None);
    let _ = read_level(data, Some(5));
    if let Ok(d) = decode(data)
        && let Ok((again, _)) = encode(&d.input, &d.pm, &d.info)
    {
        let Ok(d2) = decode(&again) else {
            panic!("re-encoded file does not decode");
        };
        assert_eq!(d2.input, d.input);
        assert_eq!(d2.pm.splits(), d.pm.splits());
        let Ok((third, _)) = encode(&d2.input, &d2.pm, &d2.info) else {
            panic!("cannot re-encode");
        };
        assert!(third == again, "encode is not idempotent");
    }
}

/// The same hierarchy with new original positions (for saving an edit): `positions` are the
/// new positions of the input's vertices; split copies follow their source vertex. When the
/// input stores f32 positions they are rounded to f32 first, as writing a mesh file would.
pub fn with_positions(
    input: &PolygonMesh,
    source: &SourceMap,
    pm: &ProgressiveMesh,
    positions: Vec<DVec3>,
) -> Result<(PolygonMesh, ProgressiveMesh), FormatError> {
    if positions.len() != input.positions.len() {
        return Err(internal("position count differs from the input"));
    }
    let round = input.position_type == Some(ScalarType::F32);
    let mut new_input = input.clone();
    new_input.positions = positions
        .into_iter()
        .map(|p| if round { p.as_vec3().as_dvec3() } else { p })
        .collect();
    let source = &source.vertex_source;
    let mut pm_positions = Vec::with_capacity(pm.pm_to_mesh().len());
    for &s in pm.pm_to_mesh() {
        let src = source.get(s as usize).copied().unwrap_or(s) as usize;
        let p = new_input
            .positions
            .get(src)
            .copied()
            .ok_or_else(|| internal("vertex source out of range"))?;
        pm_positions.push(p);
    }
    let new_pm = ProgressiveMesh::from_parts(PmParts {
        n_base: pm.n_base_vertices(),
        positions: pm_positions,
        pm_to_mesh: pm.pm_to_mesh().to_vec(),
        splits: pm.splits().to_vec(),
        faces: pm.finest_faces().to_vec(),
        errors: pm.split_errors().to_vec(),
    })
    .map_err(|e| internal(&e.to_string()))?;
    Ok((new_input, new_pm))
}
