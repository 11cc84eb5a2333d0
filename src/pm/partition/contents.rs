//! What the task files of a partitioned build hold, section by section (`formats/blocks.md`):
//! the records, their byte layout, and the checks a reader makes before a task uses them.
//!
//! Every record has a fixed size, all integers and floats little endian, floats as their
//! IEEE-754 bits (a value read back is the value written, so a pass run through files makes
//! the decisions the in-memory pass makes). Lists keyed by vertex are sorted by vertex; a
//! reader refuses anything a task could not use (a face with a vertex that has no record, a
//! repeated half-edge, an unsorted list) with the file and the byte offset of the record.

use super::block::VertexQuadric;
use super::taskfile::{BlockFileError, Kind, Section, SectionBytes, TaskFile, write};
use crate::pm::Stop;
use crate::pm::decimate::{Collapse, DecimateParams};
use crate::pm::legality::{Legality, Refusal};
use crate::pm::quadric::Quadric;
use glam::DVec3;
use std::path::Path;

const FACE: [u8; 4] = *b"FACE";
const VREC: [u8; 4] = *b"VREC";
const RIMS: [u8; 4] = *b"RIMS";
const PINS: [u8; 4] = *b"PINS";
const COLL: [u8; 4] = *b"COLL";
const COST: [u8; 4] = *b"COST";
const LABL: [u8; 4] = *b"LABL";
const PASS: [u8; 4] = *b"PASS";
const STOP: [u8; 4] = *b"STOP";

const NONE: u32 = u32::MAX;

/// A vertex as the tasks pass it on: input index, position, quadric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Record {
    pub vertex: u32,
    pub position: DVec3,
    pub quadric: VertexQuadric,
}

/// A cell's share of a piece, or a block's input: faces, vertex records, pinned vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Bucket {
    pub faces: Vec<[u32; 3]>,
    pub records: Vec<Record>,
    pub pins: Vec<u32>,
}

/// What every task of a pass reads besides its own input (`PASS` section).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PassInfo {
    /// The pass's number, from 0; informative.
    pub pass: u32,
    /// The number of cells (a power of two).
    pub n_cells: u32,
    /// Whether this is the last block (the whole mesh, nothing pinned, decimated to the end).
    pub last: bool,
    /// The input's vertex count: the length of the labels.
    pub n_vertices: u64,
    /// The faces of the input (the rules' coarseness is measured against them).
    pub input_faces: u64,
    /// The faces of the whole mesh when the pass starts.
    pub whole_faces: u64,
    /// The decimator's targets, bound and rules.
    pub params: DecimateParams,
}

const PASS_LEN: usize = 96;

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, x: u32) -> &mut Self {
        self.0.extend_from_slice(&x.to_le_bytes());
        self
    }
    fn u64(&mut self, x: u64) -> &mut Self {
        self.0.extend_from_slice(&x.to_le_bytes());
        self
    }
    fn f64(&mut self, x: f64) -> &mut Self {
        self.0.extend_from_slice(&x.to_bits().to_le_bytes());
        self
    }
    fn quadric(&mut self, q: &Quadric) -> &mut Self {
        for x in q.a.iter().chain(&q.b).chain([&q.c, &q.weight]) {
            self.f64(*x);
        }
        self
    }
}

/// Reads fixed-size fields from one record.
struct Fields<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Fields<'_> {
    fn u32(&mut self) -> u32 {
        let x = u32::from_le_bytes(self.bytes[self.at..self.at + 4].try_into().expect("4"));
        self.at += 4;
        x
    }
    fn u64(&mut self) -> u64 {
        let x = u64::from_le_bytes(self.bytes[self.at..self.at + 8].try_into().expect("8"));
        self.at += 8;
        x
    }
    fn f64(&mut self) -> f64 {
        f64::from_bits(self.u64())
    }
    fn quadric(&mut self) -> Quadric {
        let mut q = Quadric::default();
        for x in q.a.iter_mut().chain(q.b.iter_mut()) {
            *x = self.f64();
        }
        q.c = self.f64();
        q.weight = self.f64();
        q
    }
}

/// A section's bytes split into records of `size` bytes, each with its file offset.
fn records<'a>(
    file: &TaskFile,
    tag: [u8; 4],
    bytes: &'a [u8],
    at: u64,
    size: usize,
) -> Result<impl Iterator<Item = (Fields<'a>, u64)>, BlockFileError> {
    if !bytes.len().is_multiple_of(size) {
        let end = at + (bytes.len() - bytes.len() % size) as u64;
        return Err(file.error(end, format!("section {} ends inside a record", name(tag))));
    }
    Ok(bytes
        .chunks_exact(size)
        .enumerate()
        .map(move |(i, r)| (Fields { bytes: r, at: 0 }, at + (i * size) as u64)))
}

fn name(tag: [u8; 4]) -> String {
    super::taskfile::tag_name(tag)
}

/// The section `tag` of `cell` with its offset, empty when the file has none.
fn section(file: &mut TaskFile, tag: [u8; 4], cell: u32) -> Result<(Vec<u8>, u64), BlockFileError> {
    Ok(file.section(tag, cell)?.unwrap_or_default())
}

fn faces_bytes(faces: &[[u32; 3]]) -> Vec<u8> {
    let mut w = Writer(Vec::with_capacity(12 * faces.len()));
    for f in faces {
        w.u32(f[0]).u32(f[1]).u32(f[2]);
    }
    w.0
}

fn read_faces(file: &mut TaskFile, cell: u32) -> Result<Vec<[u32; 3]>, BlockFileError> {
    let (bytes, at) = section(file, FACE, cell)?;
    let mut out = Vec::with_capacity(bytes.len() / 12);
    for (mut r, off) in records(file, FACE, &bytes, at, 12)? {
        let f = [r.u32(), r.u32(), r.u32()];
        if f[0] == f[1] || f[1] == f[2] || f[2] == f[0] || f.contains(&NONE) {
            return Err(file.error(off, format!("face {f:?} is not a triangle")));
        }
        out.push(f);
    }
    Ok(out)
}

const VREC_LEN: usize = 8 + 24 + 88;
const RIMS_LEN: usize = 8 + 88;

fn records_sections(records: &[Record], cell: u32) -> [Section; 2] {
    let mut v = Writer(Vec::with_capacity(VREC_LEN * records.len()));
    let mut r = Writer(Vec::new());
    for x in records {
        let p = x.position;
        v.u32(x.vertex).u32(0).f64(p.x).f64(p.y).f64(p.z);
        v.quadric(&x.quadric.planes);
        if let Some(q) = &x.quadric.rim {
            r.u32(x.vertex).u32(0).quadric(q);
        }
    }
    [
        Section {
            tag: VREC,
            cell,
            bytes: v.0,
        },
        Section {
            tag: RIMS,
            cell,
            bytes: r.0,
        },
    ]
}

/// The vertex records of `cell`, ascending by vertex, their rims attached.
fn read_records(file: &mut TaskFile, cell: u32) -> Result<Vec<Record>, BlockFileError> {
    let (bytes, at) = section(file, VREC, cell)?;
    let mut out: Vec<Record> = Vec::with_capacity(bytes.len() / VREC_LEN);
    for (mut r, off) in records(file, VREC, &bytes, at, VREC_LEN)? {
        let vertex = r.u32();
        let _reserved = r.u32();
        if vertex == NONE || out.last().is_some_and(|l| l.vertex >= vertex) {
            return Err(file.error(off, format!("vertex {vertex} out of order")));
        }
        let position = DVec3::new(r.f64(), r.f64(), r.f64());
        let planes = r.quadric();
        out.push(Record {
            vertex,
            position,
            quadric: VertexQuadric { planes, rim: None },
        });
    }
    let (bytes, at) = section(file, RIMS, cell)?;
    let mut next = 0;
    for (mut r, off) in records(file, RIMS, &bytes, at, RIMS_LEN)? {
        let vertex = r.u32();
        let _reserved = r.u32();
        let i = out[next..]
            .iter()
            .position(|x| x.vertex == vertex)
            .map(|i| i + next)
            .filter(|&i| out[i].quadric.rim.is_none())
            .ok_or_else(|| {
                file.error(off, format!("rim of vertex {vertex}, which has no record"))
            })?;
        out[i].quadric.rim = Some(r.quadric());
        next = i + 1;
    }
    Ok(out)
}

fn ids_bytes(ids: &[u32]) -> Vec<u8> {
    let mut w = Writer(Vec::with_capacity(4 * ids.len()));
    for &v in ids {
        w.u32(v);
    }
    w.0
}

/// Strictly ascending vertex ids.
fn read_ids(file: &mut TaskFile, tag: [u8; 4], cell: u32) -> Result<Vec<u32>, BlockFileError> {
    let (bytes, at) = section(file, tag, cell)?;
    let mut out: Vec<u32> = Vec::with_capacity(bytes.len() / 4);
    for (mut r, off) in records(file, tag, &bytes, at, 4)? {
        let v = r.u32();
        if v == NONE || out.last().is_some_and(|&l| l >= v) {
            return Err(file.error(off, format!("vertex {v} out of order")));
        }
        out.push(v);
    }
    Ok(out)
}

fn bucket_sections(b: &Bucket, cell: u32) -> Vec<Section> {
    let mut out = vec![Section {
        tag: FACE,
        cell,
        bytes: faces_bytes(&b.faces),
    }];
    out.extend(records_sections(&b.records, cell));
    out.push(Section {
        tag: PINS,
        cell,
        bytes: ids_bytes(&b.pins),
    });
    out.retain(|s| !s.bytes.is_empty());
    out
}

fn read_bucket(file: &mut TaskFile, cell: u32) -> Result<Bucket, BlockFileError> {
    Ok(Bucket {
        faces: read_faces(file, cell)?,
        records: read_records(file, cell)?,
        pins: read_ids(file, PINS, cell)?,
    })
}

/// Writes a piece of the whole mesh: `faces` in order, `records` ascending.
pub(crate) fn write_piece(
    path: &Path,
    faces: &[[u32; 3]],
    records: &[Record],
) -> Result<(), BlockFileError> {
    // The sections of a bucket without pins, made from the slices rather than a copy of them.
    let mut sections = vec![Section {
        tag: FACE,
        cell: 0,
        bytes: faces_bytes(faces),
    }];
    sections.extend(records_sections(records, 0));
    sections.retain(|s| !s.bytes.is_empty());
    write(path, Kind::Piece, &sections)
}

/// Reads a piece (or a result, which is one): its faces and vertex records.
pub(crate) fn read_piece(path: &Path) -> Result<(Vec<[u32; 3]>, Vec<Record>), BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Piece, Kind::Result])?;
    Ok((read_faces(&mut f, 0)?, read_records(&mut f, 0)?))
}

/// The counts of a piece's faces and vertices, from its section table.
pub(crate) fn piece_counts(path: &Path) -> Result<(u64, u64), BlockFileError> {
    let f = TaskFile::open(path, &[Kind::Piece, Kind::Result])?;
    let len = |tag| {
        f.entries
            .iter()
            .filter(|e| e.tag == tag && e.cell == 0)
            .map(|e| e.length)
            .sum::<u64>()
    };
    Ok((len(FACE) / 12, len(VREC) / VREC_LEN as u64))
}

/// The vertices and positions of a piece, without their quadrics.
pub(crate) fn read_positions(path: &Path) -> Result<Vec<(u32, DVec3)>, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Piece, Kind::Result])?;
    let (bytes, at) = section(&mut f, VREC, 0)?;
    let mut out = Vec::with_capacity(bytes.len() / VREC_LEN);
    for (mut r, _) in records(&f, VREC, &bytes, at, VREC_LEN)? {
        let v = r.u32();
        let _reserved = r.u32();
        out.push((v, DVec3::new(r.f64(), r.f64(), r.f64())));
    }
    Ok(out)
}

/// Writes a piece sorted into cells: bucket `k` is cell `k`'s share.
pub(crate) fn write_routed(path: &Path, buckets: &[Bucket]) -> Result<(), BlockFileError> {
    let sections: Vec<Section> = (buckets.iter().enumerate())
        .flat_map(|(k, b)| bucket_sections(b, k as u32))
        .collect();
    write(path, Kind::Routed, &sections)
}

/// Reads cell `cell`'s share of a routed piece.
pub(crate) fn read_routed(path: &Path, cell: u32) -> Result<Bucket, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Routed])?;
    read_bucket(&mut f, cell)
}

/// The bytes of cell `cell`'s sections in the routed piece `path`, from its section table.
pub(crate) fn share_len(path: &Path, cell: u32) -> Result<u64, BlockFileError> {
    let f = TaskFile::open(path, &[Kind::Routed])?;
    Ok((f.entries.iter())
        .filter(|e| e.cell == cell)
        .map(|e| e.length)
        .sum())
}

/// Writes a block's input.
pub(crate) fn write_input(path: &Path, block: &Bucket) -> Result<(), BlockFileError> {
    write(path, Kind::Input, &bucket_sections(block, 0))
}

/// Reads a block's input and checks that a task can decimate it: every face's vertices have
/// records, every record has a face, no half-edge appears twice, pins have records.
pub(crate) fn read_input(path: &Path) -> Result<Bucket, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Input])?;
    let b = read_bucket(&mut f, 0)?;
    let at = |f: &mut TaskFile, tag| {
        f.entries
            .iter()
            .find(|e| e.tag == tag)
            .map_or(0, |e| e.offset)
    };
    let has = |v: u32| b.records.binary_search_by_key(&v, |r| r.vertex).is_ok();
    let mut used = vec![false; b.records.len()];
    let mut half_edges = Vec::with_capacity(3 * b.faces.len());
    for (i, face) in b.faces.iter().enumerate() {
        for k in 0..3 {
            let Ok(j) = b.records.binary_search_by_key(&face[k], |r| r.vertex) else {
                let off = at(&mut f, FACE) + 12 * i as u64;
                return Err(f.error(
                    off,
                    format!("face uses vertex {}, which has no record", face[k]),
                ));
            };
            used[j] = true;
            half_edges.push((face[k], face[(k + 1) % 3]));
        }
    }
    if let Some(j) = used.iter().position(|u| !u) {
        let off = at(&mut f, VREC) + (VREC_LEN * j) as u64;
        return Err(f.error(off, format!("vertex {} has no face", b.records[j].vertex)));
    }
    half_edges.sort_unstable();
    if let Some(w) = half_edges.windows(2).find(|w| w[0] == w[1]) {
        let off = at(&mut f, FACE);
        return Err(f.error(off, format!("half-edge {:?} appears twice", w[0])));
    }
    if let Some(p) = b.pins.iter().position(|&v| !has(v)) {
        let off = at(&mut f, PINS) + 4 * p as u64;
        return Err(f.error(off, format!("pinned vertex {} has no record", b.pins[p])));
    }
    Ok(b)
}

/// Costs as integers in the order of `f64::total_cmp`, so that selections over them are exact.
pub(crate) fn cost_key(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

/// The cost whose [`cost_key`] is `k`.
pub(crate) fn key_cost(k: u64) -> f64 {
    if k >> 63 == 1 {
        f64::from_bits(k & !(1 << 63))
    } else {
        f64::from_bits(!k)
    }
}

/// Writes a block's candidate costs, ascending in the total order.
pub(crate) fn write_costs(path: &Path, keys: &[u64]) -> Result<(), BlockFileError> {
    let mut w = Writer(Vec::with_capacity(8 * keys.len()));
    for &k in keys {
        w.u64(k);
    }
    let s = Section {
        tag: COST,
        cell: 0,
        bytes: w.0,
    };
    write(path, Kind::Costs, &[s])
}

/// Reads a block's candidate costs as [`cost_key`]s, ascending.
pub(crate) fn read_costs(path: &Path) -> Result<Vec<u64>, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Costs])?;
    let (bytes, at) = section(&mut f, COST, 0)?;
    let mut out: Vec<u64> = Vec::with_capacity(bytes.len() / 8);
    for (mut r, off) in records(&f, COST, &bytes, at, 8)? {
        let k = r.u64();
        if out.last().is_some_and(|&l| l > k) {
            return Err(f.error(off, "costs out of order"));
        }
        out.push(k);
    }
    Ok(out)
}

fn collapses_bytes(collapses: &[Collapse]) -> Vec<u8> {
    let mut w = Writer(Vec::with_capacity(24 * collapses.len()));
    for c in collapses {
        w.u32(c.from)
            .u32(c.to)
            .u32(c.left)
            .u32(c.right)
            .f64(c.error_sq);
    }
    w.0
}

/// Reads the collapses of a result or a sequence, checking that their vertices lie below
/// `n_vertices`.
pub(crate) fn read_collapses(
    path: &Path,
    n_vertices: u64,
) -> Result<Vec<Collapse>, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Result, Kind::Sequence])?;
    let (bytes, at) = section(&mut f, COLL, 0)?;
    let mut out = Vec::with_capacity(bytes.len() / 24);
    let ok = |v: u32, may_be_none: bool| (v as u64) < n_vertices || (may_be_none && v == NONE);
    for (mut r, off) in records(&f, COLL, &bytes, at, 24)? {
        let c = Collapse {
            from: r.u32(),
            to: r.u32(),
            left: r.u32(),
            right: r.u32(),
            error_sq: r.f64(),
        };
        if !ok(c.from, false)
            || !ok(c.to, false)
            || !ok(c.left, true)
            || !ok(c.right, true)
            || c.from == c.to
        {
            return Err(f.error(off, "collapse with a vertex out of range"));
        }
        out.push(c);
    }
    Ok(out)
}

/// Writes a pass's collapses in order.
pub(crate) fn write_sequence(path: &Path, collapses: &[Collapse]) -> Result<(), BlockFileError> {
    let s = Section {
        tag: COLL,
        cell: 0,
        bytes: collapses_bytes(collapses),
    };
    write(path, Kind::Sequence, &[s])
}

/// A block's result.
pub(crate) struct BlockOutput<'a> {
    pub collapses: &'a [Collapse],
    pub faces: &'a [[u32; 3]],
    pub records: &'a [Record],
    /// Why the last block stopped (`None` for a block of a pass).
    pub stop: Option<&'a Stop>,
}

/// Writes a block's result.
pub(crate) fn write_result(path: &Path, out: &BlockOutput) -> Result<(), BlockFileError> {
    let mut sections = vec![Section {
        tag: COLL,
        cell: 0,
        bytes: collapses_bytes(out.collapses),
    }];
    sections.extend(bucket_sections(
        &Bucket {
            faces: out.faces.to_vec(),
            records: out.records.to_vec(),
            pins: Vec::new(),
        },
        0,
    ));
    if let Some(stop) = out.stop {
        sections.push(Section {
            tag: STOP,
            cell: 0,
            bytes: stop_bytes(stop),
        });
    }
    sections.retain(|s| !s.bytes.is_empty() || s.tag == STOP);
    write(path, Kind::Result, &sections)
}

/// The refusals in the order of their codes in a `STOP` section.
const REFUSALS: [Refusal; 9] = [
    Refusal::Boundary,
    Refusal::DanglingFace,
    Refusal::Pillow,
    Refusal::Link,
    Refusal::Valence,
    Refusal::Normal,
    Refusal::Degenerate,
    Refusal::Seam,
    Refusal::Costly,
];

fn stop_bytes(stop: &Stop) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    match stop {
        Stop::Target => w.u32(0).u32(0),
        Stop::ErrorBound => w.u32(1).u32(0),
        Stop::NoLegalCollapse(refusals) => {
            w.u32(2).u32(refusals.len() as u32);
            for (r, n) in refusals {
                let code = REFUSALS
                    .iter()
                    .position(|x| x == r)
                    .expect("every refusal has a code");
                w.u32(code as u32).u32(0).u64(*n as u64);
            }
            &mut w
        }
    };
    w.0
}

/// Why the last block stopped, from its result.
pub(crate) fn read_stop(path: &Path) -> Result<Stop, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Result])?;
    let Some((bytes, at)) = f.section(STOP, 0)? else {
        return Err(f.error(0, "no STOP section (not the last block's result)"));
    };
    if bytes.len() < 8 {
        return Err(f.error(at, "STOP section is too short"));
    }
    let mut head = Fields {
        bytes: &bytes,
        at: 0,
    };
    let (kind, count) = (head.u32(), head.u32());
    let refusals = &bytes[8..];
    match (kind, count) {
        (0, 0) if refusals.is_empty() => Ok(Stop::Target),
        (1, 0) if refusals.is_empty() => Ok(Stop::ErrorBound),
        (2, n) if refusals.len() as u64 == 16 * n as u64 => {
            let mut out = Vec::with_capacity(n as usize);
            for (mut r, off) in records(&f, STOP, refusals, at + 8, 16)? {
                let code = r.u32() as usize;
                let _reserved = r.u32();
                let n = r.u64();
                let rule = REFUSALS
                    .get(code)
                    .ok_or_else(|| f.error(off, format!("unknown refusal {code}")))?;
                out.push((*rule, n as usize));
            }
            Ok(Stop::NoLegalCollapse(out))
        }
        _ => Err(f.error(at, format!("unknown stop {kind} with {count} refusals"))),
    }
}

/// Writes a pass's parameters and each input vertex's cell (`u32::MAX`: not in the mesh).
pub(crate) fn write_pass(
    path: &Path,
    info: &PassInfo,
    labels: &[u32],
) -> Result<(), BlockFileError> {
    let p = &info.params;
    let mut w = Writer(Vec::with_capacity(PASS_LEN));
    w.u32(info.pass)
        .u32(info.n_cells)
        .u32(info.last as u32)
        .u32(0);
    w.u64(info.n_vertices)
        .u64(info.input_faces)
        .u64(info.whole_faces);
    w.u64(p.target_vertices as u64)
        .u64(p.target_faces as u64)
        .f64(p.max_error_sq);
    w.u64(p.legality.max_valence as u64)
        .f64(p.legality.min_normal_cos);
    w.f64(p.legality.min_quality).f64(p.boundary_weight);
    let sections = [
        Section {
            tag: PASS,
            cell: 0,
            bytes: w.0,
        },
        Section {
            tag: LABL,
            cell: 0,
            bytes: ids_bytes(labels),
        },
    ];
    write(path, Kind::Pass, &sections)
}

/// Reads a pass's parameters.
pub(crate) fn read_pass_info(path: &Path) -> Result<PassInfo, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Pass])?;
    let Some((bytes, at)) = f.section(PASS, 0)? else {
        return Err(f.error(0, "no PASS section"));
    };
    if bytes.len() != PASS_LEN {
        return Err(f.error(
            at,
            format!("PASS section of {} bytes, not {PASS_LEN}", bytes.len()),
        ));
    }
    let mut r = Fields {
        bytes: &bytes,
        at: 0,
    };
    let (pass, n_cells, last, _reserved) = (r.u32(), r.u32(), r.u32(), r.u32());
    let (n_vertices, input_faces, whole_faces) = (r.u64(), r.u64(), r.u64());
    let (target_vertices, target_faces, max_error_sq) = (r.u64(), r.u64(), r.f64());
    let (max_valence, min_normal_cos, min_quality, boundary_weight) =
        (r.u64(), r.f64(), r.f64(), r.f64());
    if !n_cells.is_power_of_two() || last > 1 || (last == 1 && n_cells != 1) {
        return Err(f.error(at + 4, format!("{n_cells} cells, last {last}")));
    }
    if n_vertices >= NONE as u64 || max_valence < 3 || max_valence > u32::MAX as u64 {
        return Err(f.error(at + 16, "vertex count or valence cap out of range"));
    }
    let params = DecimateParams {
        target_vertices: target_vertices.min(usize::MAX as u64) as usize,
        target_faces: target_faces.min(usize::MAX as u64) as usize,
        max_error_sq,
        legality: Legality {
            max_valence: max_valence as usize,
            min_normal_cos,
            min_quality,
        },
        boundary_weight,
    };
    Ok(PassInfo {
        pass,
        n_cells,
        last: last == 1,
        n_vertices,
        input_faces,
        whole_faces,
        params,
    })
}

/// A pass's cell labels, one per input vertex (a cell, or `u32::MAX` for a vertex not in the
/// pass's mesh), mapped and checked against the section's checksum when read, and decoded when
/// looked up:
/// a split task sorts a piece of a few blocks' vertices, and decoding the whole scan's labels
/// for it made the split tasks the largest share of a partitioned build's work.
pub(crate) struct Labels {
    bytes: SectionBytes,
    at: u64,
    n_cells: u32,
    path: std::path::PathBuf,
}

impl Labels {
    /// How many input vertices have a label.
    pub(crate) fn len(&self) -> usize {
        self.bytes.len() / 4
    }

    /// The cell of input vertex `v`: `None` when `v` is not in the pass's mesh (no label, or
    /// `u32::MAX`), an error naming the label's byte when it names no cell of the pass.
    pub(crate) fn cell(&self, v: u32) -> Result<Option<u32>, BlockFileError> {
        let i = 4 * v as usize;
        let Some(b) = self.bytes.get(i..i + 4) else {
            return Ok(None);
        };
        let c = u32::from_le_bytes(b.try_into().expect("4 bytes"));
        if c == NONE {
            Ok(None)
        } else if c >= self.n_cells {
            let at = self.at + i as u64;
            let what = format!("cell {c} of {}", self.n_cells);
            Err(BlockFileError::new(&self.path, at, what))
        } else {
            Ok(Some(c))
        }
    }
}

/// Reads a pass's cell labels ([`Labels`]).
pub(crate) fn read_labels(path: &Path, info: &PassInfo) -> Result<Labels, BlockFileError> {
    let mut f = TaskFile::open(path, &[Kind::Pass])?;
    let (bytes, at) = f
        .mapped_section(LABL, 0)?
        .unwrap_or((SectionBytes::Read(Vec::new()), 0));
    if bytes.len() as u64 != 4 * info.n_vertices {
        return Err(f.error(
            at,
            format!(
                "{} bytes of labels for {} vertices",
                bytes.len(),
                info.n_vertices
            ),
        ));
    }
    Ok(Labels {
        bytes,
        at,
        n_cells: info.n_cells,
        path: path.to_path_buf(),
    })
}

/// Reads `bytes`, as given and with their checksums fixed, as every kind of task file with
/// every reader, for the fuzz target: returns without panicking whatever the bytes.
pub(crate) fn read_any(bytes: &[u8]) {
    let dir = std::env::temp_dir().join(format!("meshpyr-fuzz-blocks-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let thread = format!("{:?}", std::thread::current().id());
    let path = dir.join(thread.replace(|c: char| !c.is_ascii_alphanumeric(), ""));
    for bytes in [bytes.to_vec(), super::taskfile::fix_checksums(bytes)] {
        if let Ok(mut f) = TaskFile::from_bytes(&path, bytes.clone(), &Kind::ALL) {
            for e in f.entries.clone().iter().take(64) {
                let _ = f.section(e.tag, e.cell);
            }
        }
        if std::fs::write(&path, &bytes).is_err() {
            return;
        }
        let _ = read_piece(&path);
        let _ = piece_counts(&path);
        let _ = read_positions(&path);
        let _ = read_input(&path);
        let _ = read_costs(&path);
        let _ = read_collapses(&path, u32::MAX as u64);
        let _ = read_stop(&path);
        let _ = super::stream::Manifest::read(&path);
        super::stream::read_any_round(&path);
        if let Ok(info) = read_pass_info(&path)
            && let Ok(labels) = read_labels(&path, &info)
        {
            for v in 0..labels.len() {
                let _ = labels.cell(v as u32);
            }
        }
        if let Ok(f) = TaskFile::open(&path, &[Kind::Routed]) {
            for e in f.entries.iter().take(64) {
                let _ = read_routed(&path, e.cell);
            }
        }
    }
    let _ = std::fs::remove_file(&path);
}
