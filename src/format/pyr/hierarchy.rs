//! The hierarchy codec: the base mesh (`BASE`), the split blocks (`SPLT`) and the vertices
//! without faces (`ISOL`), written from a progressive mesh; and the progressive reader that
//! replays the base mesh through the split blocks, shared by the full decoder and the level
//! reader.

use crate::format::FormatError;
use crate::format::container::{Container, Release};
use crate::format::varint::{ByteReader, put_ivarint, put_uvarint};
use crate::pm::{FlatReplay, ProgressiveMesh, VertexSplit};
use glam::DVec3;

use super::decode_ahead::SplitBlocks;
use super::meta::{check_version, read_meta};
use super::positions::{put_position, read_positions};
use super::split_block::{put_block, put_split_errors, put_split_records, wing_indices};
use super::{
    BASE, ISOL, LevelMesh, Meta, SPLITS_PER_BLOCK, SizeReport, corrupt, internal, required,
};

// ---------------------------------------------------------------------------------------------
// Writing

/// `BASE`: the base positions, then the base triangles as zig-zag deltas; with its sizes.
pub(super) fn encode_base(
    pm: &ProgressiveMesh,
    base_tris: &[[u32; 3]],
    f32: bool,
) -> (Vec<u8>, SizeReport) {
    let mut base = Vec::new();
    for &p in &pm.original_positions()[..pm.n_base_vertices()] {
        put_position(&mut base, p, f32);
    }
    let before = base.len();
    put_uvarint(&mut base, base_tris.len() as u64);
    let mut prev = 0i64;
    for t in base_tris {
        put_ivarint(&mut base, i64::from(t[0]) - prev);
        put_ivarint(&mut base, i64::from(t[1]) - i64::from(t[0]));
        put_ivarint(&mut base, i64::from(t[2]) - i64::from(t[0]));
        prev = i64::from(t[0]);
    }
    let sizes = SizeReport {
        pm_connectivity: base.len() - before,
        positions: before,
        ..SizeReport::default()
    };
    (base, sizes)
}

/// `SPLT`: blocks of split records, replayed on the base mesh to code wings as ring indices;
/// with its sizes.
pub(super) fn encode_splits(
    pm: &ProgressiveMesh,
    base_tris: &[[u32; 3]],
    f32: bool,
) -> Result<(Vec<u8>, SizeReport), FormatError> {
    let positions = pm.original_positions();
    let n_base = pm.n_base_vertices();
    let width = if f32 { 4 } else { 8 };
    let mut sizes = SizeReport::default();
    let mut replay = FlatReplay::new(&positions[..n_base], base_tris, pm.splits().len())
        .map_err(|e| internal(&e.to_string()))?;
    let mut splt = Vec::with_capacity(pm.splits().len() * (4 + 4 + 3 * width) + 64);
    let mut payload = Vec::new();
    for (b, chunk) in pm.splits().chunks(SPLITS_PER_BLOCK as usize).enumerate() {
        let first = n_base + b * SPLITS_PER_BLOCK as usize;
        payload.clear();
        payload.reserve(chunk.len() * (4 + 4 + 3 * width));
        put_split_records(&mut payload, &mut replay, chunk)?;
        sizes.pm_connectivity += payload.len() + 12;
        let before = payload.len();
        put_split_errors(
            &mut payload,
            &pm.split_errors()[first - n_base..first - n_base + chunk.len()],
        );
        sizes.split_errors += payload.len() - before;
        for &p in &positions[first..first + chunk.len()] {
            put_position(&mut payload, p, f32);
        }
        sizes.positions += chunk.len() * 3 * width;
        put_block(&mut splt, chunk.len(), &payload);
    }
    Ok((splt, sizes))
}

/// `ISOL`: the positions of the vertices after the finest level (no face uses them).
pub(super) fn encode_isolated(pm: &ProgressiveMesh, f32: bool) -> Vec<u8> {
    let mut isol = Vec::new();
    for &p in &pm.original_positions()[pm.n_vertices()..] {
        put_position(&mut isol, p, f32);
    }
    isol
}

// ---------------------------------------------------------------------------------------------
// Reading

/// The parsed header and the progressive part, shared by the full and the level readers.
pub(super) struct Progressive {
    pub(super) meta: Meta,
    pub(super) truncated: bool,
    /// The base mesh with `splits` applied.
    pub(super) replay: FlatReplay,
    pub(super) splits: Vec<VertexSplit>,
    pub(super) positions: Vec<DVec3>,
    pub(super) errors: Vec<f32>,
}

/// The progressive part of `bytes` up to `max_level` (default: all), handing the parts it is
/// done with to `release`, with `also` run on
/// another core meanwhile (after it has helped decode the split blocks). Errors come in the
/// order a sequential reader meets them: header, `BASE`, then block by block.
pub(super) fn read_progressive<'a, R: Send>(
    bytes: &'a [u8],
    max_level: Option<usize>,
    release: Release<'a>,
    also: impl FnOnce(&Container<'a>, &Meta) -> R + Send,
) -> Result<(Container<'a>, Progressive, R), FormatError> {
    let c = Container::parse(bytes)?.releasing(release);
    check_version(&c)?;
    let meta = read_meta(&c)?;
    let blocks = SplitBlocks::scan(&c, &meta, max_level);
    let (p, r) = rayon::join(
        || {
            let _replaying = blocks.replaying();
            replay_progressive(&c, &meta, &blocks, bytes.len())
        },
        || {
            blocks.decode_ahead(false);
            let r = also(&c, &meta);
            blocks.decode_ahead(true);
            r
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
    let n_base = meta.n_base as usize;
    // Every split takes at least 3 record bytes and a position, so the file size caps the
    // room reserved for the replay.
    let hint = (meta.n_splits as usize).min(file_len / 15);
    let (mut positions, mut replay) = decode_base(c, meta, hint)?;
    let want = blocks.wanted();
    let mut splits: Vec<VertexSplit> = Vec::with_capacity(want.min(hint));
    let mut errors: Vec<f32> = Vec::with_capacity(want.min(hint));
    positions.reserve(want.min(hint));
    for k in 0..blocks.len() {
        let block = blocks.take(k)?;
        positions.extend_from_slice(&block.positions);
        replay_block(&mut replay, &block.records, n_base, &mut splits)?;
        errors.extend_from_slice(&block.errors);
        if let Some(e) = block.trailing {
            return Err(e);
        }
    }
    blocks.end()?;
    Ok(Progressive {
        meta: meta.clone(),
        truncated: c.is_truncated(),
        replay,
        splits,
        positions,
        errors,
    })
}

/// `BASE`: the base positions, and the replay started on the base triangles with room for
/// `hint` splits.
fn decode_base(
    c: &Container<'_>,
    meta: &Meta,
    hint: usize,
) -> Result<(Vec<DVec3>, FlatReplay), FormatError> {
    let n_base = meta.n_base as usize;
    let mut r = required(c, BASE)?;
    let mut positions = Vec::new();
    read_positions(&mut r, n_base, meta.position_bits == 32, &mut positions)?;
    let base_faces = read_base_faces(&mut r, n_base)?;
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in BASE"));
    }
    let replay = FlatReplay::new(&positions, &base_faces, hint)
        .map_err(|e| corrupt(r.offset(), e.to_string()))?;
    Ok((positions, replay))
}

/// The base triangles, coded as [`encode_base`] writes them.
fn read_base_faces(r: &mut ByteReader<'_>, n_base: usize) -> Result<Vec<[u32; 3]>, FormatError> {
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
    Ok(base_faces)
}

/// Applies a block's decoded records to `replay`, appending the splits they make.
fn replay_block(
    replay: &mut FlatReplay,
    records: &[(u32, u64, u64, u64)],
    n_base: usize,
    splits: &mut Vec<VertexSplit>,
) -> Result<(), FormatError> {
    for (k, &(survivor, lc, rc, at)) in records.iter().enumerate() {
        replay.prefetch_upcoming(k, |j| records.get(j).map(|r| r.0));
        let vertex = (n_base + splits.len()) as u32;
        let deg = replay
            .valence(survivor)
            .map_err(|e| corrupt(at, e.to_string()))? as u64;
        let (il, ir) = wing_indices(lc, rc, deg)
            .ok_or_else(|| corrupt(at, "wing index past the survivor's ring"))?;
        let s = replay
            .apply_indexed(vertex, survivor, il, ir)
            .map_err(|e| corrupt(at, e.to_string()))?;
        splits.push(s);
    }
    Ok(())
}

/// `ISOL`: appends the positions of the vertices without faces to `positions` (which holds
/// those of the finest level), making up the file's `n_vertices`.
pub(super) fn read_isolated(
    c: &Container<'_>,
    meta: &Meta,
    positions: &mut Vec<DVec3>,
) -> Result<(), FormatError> {
    let n_missing = meta.n_vertices as usize - positions.len();
    let mut r = required(c, ISOL)?;
    read_positions(&mut r, n_missing, meta.position_bits == 32, positions)?;
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "trailing bytes in ISOL"));
    }
    Ok(())
}

/// The finest level with at most `max_triangles` triangles (the base level if even that has
/// more), read from the progressive part's prefix only: the level
/// [`ProgressiveMesh::level_for_faces`](crate::pm::ProgressiveMesh::level_for_faces) picks,
/// for a viewer's first picture of a large file. A truncated file yields at most its last
/// complete level (`truncated` set).
pub fn read_level_within(bytes: &[u8], max_triangles: usize) -> Result<LevelMesh, FormatError> {
    let c = Container::parse(bytes)?;
    check_version(&c)?;
    let meta = read_meta(&c)?;
    let n_base = meta.n_base as usize;
    // A split adds one or two triangles, so the level sought is at most `max_triangles`
    // splits past the base; one past it tells whether the prefix's last level still fits.
    let upto = n_base.saturating_add(max_triangles).saturating_add(1);
    let (_, p, ()) = read_progressive(bytes, Some(upto), Release::default(), |_, _| ())?;
    let replayed = p.replay.triangles();
    let added: usize = p.splits.iter().map(VertexSplit::n_new_faces).sum();
    let mut faces = replayed.len() - added;
    let mut kept = 0;
    for s in &p.splits {
        faces += s.n_new_faces();
        if faces > max_triangles {
            break;
        }
        kept += 1;
    }
    let level = n_base + kept;
    // Splits past `level` are undone by mapping their vertices to their survivors, which
    // drops exactly the triangles they made.
    let mut ancestor: Vec<u32> = (0..(n_base + p.splits.len()) as u32).collect();
    for (k, s) in p.splits.iter().enumerate().skip(kept) {
        ancestor[n_base + k] = ancestor[s.survivor as usize];
    }
    let triangles = replayed
        .into_iter()
        .map(|t| t.map(|x| ancestor[x as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    let mut positions = p.positions;
    positions.truncate(level);
    Ok(LevelMesh {
        level,
        finest: n_base + meta.n_splits as usize,
        base: n_base,
        truncated: p.truncated,
        positions,
        triangles,
        f32_positions: meta.position_bits == 32,
    })
}

/// Reads level `level` (default: the finest in the file) from the progressive part only. A
/// truncated file yields its last complete level (`truncated` set); the caller warns.
pub fn read_level(bytes: &[u8], level: Option<usize>) -> Result<LevelMesh, FormatError> {
    let (_, p, ()) = read_progressive(bytes, level, Release::default(), |_, _| ())?;
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
