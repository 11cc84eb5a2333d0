//! The user's side of the file: the vertex order (`ORDR`) and polygons (`POLY`) that, with the
//! attributes (`ATTR`, in [`super::attributes`]), restore the mesh as it was read; and, on
//! reading, the finest faces of the hierarchy recovered from that mesh.

use crate::format::FormatError;
use crate::format::container::Container;
use crate::format::varint::{ByteReader, put_ivarint, put_uvarint};
use crate::mesh::{CornerTable, PolygonMesh, SourceMap};
use crate::pm::{FaceBuckets, FlatReplay, ProgressiveMesh, canonical_sorted, triangles_of};
use glam::DVec3;

use super::attributes::decode_attributes;
use super::copied_faces::copied_faces;
use super::corners::decode_corners;
use super::{ATTR, CRNR, Meta, ORDR, POLY, corrupt, required};

/// `ORDR`: the input vertex of each PM vertex.
pub(super) fn encode_vertex_order(pm: &ProgressiveMesh) -> Vec<u8> {
    let mut ordr = Vec::with_capacity(pm.original_positions().len() * 3);
    for &s in pm.pm_to_mesh() {
        put_uvarint(&mut ordr, u64::from(s));
    }
    ordr
}

/// `POLY`: the polygons, per face its degree, then its indices, each as a zig-zag delta from
/// the previous index in the stream (neighbouring faces share vertices, so deltas are small).
pub(super) fn encode_polygons(m: &PolygonMesh) -> Vec<u8> {
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

/// What [`decode`](super::decode) reads besides the hierarchy: the input's vertex order, its polygons and
/// attributes (positions still zero: they come from the hierarchy), and, for a clean triangle
/// input, its faces in PM indices with their canonical sorted order.
pub(super) struct InputSide {
    pub(super) pm_to_mesh: Vec<u32>,
    /// The inverse of `pm_to_mesh` (`u32::MAX` where nothing maps).
    pub(super) mesh_to_pm: Vec<u32>,
    /// Whether `pm_to_mesh` is a permutation, so that `mesh_to_pm` is its exact inverse.
    pub(super) permutation: bool,
    pub(super) input: PolygonMesh,
    pub(super) clean_faces: Option<CleanFaces>,
}

/// The faces of a clean triangle input in PM indices, in the input's order and bucketed by
/// smallest index (see [`clean_triangle_faces`]).
pub(super) struct CleanFaces {
    pub(super) faces: Vec<[u32; 3]>,
    pub(super) buckets: FaceBuckets,
}

/// The input's side of the file (see [`InputSide`]), decoded and checked.
pub(super) fn decode_input_side(c: &Container<'_>, meta: &Meta) -> Result<InputSide, FormatError> {
    let n_total = meta.n_vertices as usize;
    let pm_to_mesh = read_vertex_order(c, n_total)?;
    let n_input = meta.n_input_vertices as usize;
    check_order_covers(&pm_to_mesh, n_input)?;
    let mut input = PolygonMesh::new();
    input.positions = vec![DVec3::ZERO; n_input];
    let mut r = required(c, POLY)?;
    decode_polygons(&mut r, meta.n_input_faces, n_input, &mut input)?;
    let mut r = required(c, ATTR)?;
    decode_attributes(&mut r, &mut input)?;
    if let Some(mut r) = c.section(CRNR)? {
        decode_corners(&mut r, &mut input)?;
    }
    let (mesh_to_pm, permutation) = invert_order(&pm_to_mesh, n_total);
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

/// `ORDR`: the input vertex of each of the `n_total` PM vertices.
fn read_vertex_order(c: &Container<'_>, n_total: usize) -> Result<Vec<u32>, FormatError> {
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
    Ok(pm_to_mesh)
}

/// Every input vertex must come from some PM vertex, or its position would be lost.
fn check_order_covers(pm_to_mesh: &[u32], n_input: usize) -> Result<(), FormatError> {
    let mut seen = vec![false; n_input];
    for &s in pm_to_mesh {
        if let Some(x) = seen.get_mut(s as usize) {
            *x = true;
        }
    }
    if seen.iter().any(|&x| !x) {
        return Err(corrupt(0, "vertex order does not cover the input vertices"));
    }
    Ok(())
}

/// The inverse of `pm_to_mesh` over `n_total` mesh vertices, and whether it is exact (see
/// [`InputSide::mesh_to_pm`]).
fn invert_order(pm_to_mesh: &[u32], n_total: usize) -> (Vec<u32>, bool) {
    let mut mesh_to_pm = vec![u32::MAX; n_total];
    let mut permutation = true;
    for (i, &s) in pm_to_mesh.iter().enumerate() {
        if let Some(m) = mesh_to_pm.get_mut(s as usize) {
            permutation &= *m == u32::MAX;
            *m = i as u32;
        }
    }
    (mesh_to_pm, permutation)
}

/// Gives the input's vertices their positions from the hierarchy's `positions`.
pub(super) fn restore_input_positions(
    input: &mut PolygonMesh,
    pm_to_mesh: &[u32],
    positions: &[DVec3],
) {
    // Vertex copies the builder made (order entries past the input's vertices) have no row.
    for (i, &s) in pm_to_mesh.iter().enumerate() {
        if let Some(p) = input.positions.get_mut(s as usize) {
            *p = positions[i];
        }
    }
}

/// The finest faces in PM indices, checked to be exactly what the splits rebuild in `replay`:
/// read off a clean triangle input, or off an input whose repair only copied vertices
/// (`copied_faces`), else from the builder's repaired triangles (with their map back onto the
/// input, returned too). `order` is the file's vertex order and `mesh_to_pm` its inverse
/// (`permutation`: exactly).
pub(super) fn finest_faces(
    input: &PolygonMesh,
    clean_faces: Option<CleanFaces>,
    replay: FlatReplay,
    (order, mesh_to_pm, permutation): (&[u32], &[u32], bool),
    positions: &[DVec3],
) -> Result<(Vec<[u32; 3]>, Option<SourceMap>), FormatError> {
    // A clean input whose faces are not the replay's had triangles flipped by the builder:
    // only the builder tells which.
    let not_clean = clean_faces.is_none();
    if let Some(clean) = clean_faces.filter(|c| replay.has_faces(&c.buckets)) {
        return Ok((clean.faces, None));
    }
    let n_input = input.positions.len();
    let copied = (not_clean && permutation)
        .then(|| copied_faces(input, mesh_to_pm, positions))
        .flatten()
        .and_then(|c| c.resolve(n_input, &replay, order, positions));
    if let Some((faces, source)) = copied {
        return Ok((faces, Some(source)));
    }
    // The replay's rings (about 160 B per vertex) go before the builder's repair, whose
    // temporaries are as large: only the faces they rebuilt are compared.
    let rebuilt = replay.canonical_faces();
    drop(replay);
    let n_total = positions.len();
    let (faces, source) = repaired_faces(input, mesh_to_pm, positions)?;
    if canonical_sorted(&faces, n_total) != rebuilt {
        return Err(corrupt(0, "the splits do not rebuild the finest faces"));
    }
    Ok((faces, Some(source)))
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

/// The finest faces in PM indices from the builder's corner table of `input` (any polygons,
/// any repairs), checking that the builder's vertices are the stored ones. The half-edge mesh
/// would have the same faces (`CornerTable` docs: face slot `t` is triangle `t`, starting at
/// its first corner) at several times the memory, held for the whole load.
fn repaired_faces(
    input: &PolygonMesh,
    mesh_to_pm: &[u32],
    positions: &[DVec3],
) -> Result<(Vec<[u32; 3]>, SourceMap), FormatError> {
    let repaired = CornerTable::from_polygons(input).map_err(|e| corrupt(0, e.to_string()))?;
    let source = repaired.source;
    let foreign = || corrupt(0, "the polygons do not build the stored hierarchy");
    if source.vertex_source.len() != positions.len() {
        return Err(foreign());
    }
    // The builder's vertices (including its vertex copies) must sit where the stored ones do.
    for (v, &s) in source.vertex_source.iter().enumerate() {
        let i = mesh_to_pm.get(v).copied().unwrap_or(u32::MAX) as usize;
        let same = positions.get(i).is_some_and(|p| {
            p.to_array().map(f64::to_bits)
                == input.positions[s as usize].to_array().map(f64::to_bits)
        });
        if !same {
            return Err(foreign());
        }
    }
    let CornerTable {
        mut corner_vertex,
        mate,
    } = repaired.corners;
    drop(mate);
    for v in &mut corner_vertex {
        *v = mesh_to_pm.get(*v as usize).copied().unwrap_or(u32::MAX);
    }
    Ok((triangles_of(corner_vertex), source))
}
