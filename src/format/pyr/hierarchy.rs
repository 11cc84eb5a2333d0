//! The hierarchy codec: positions (f32 when exact, else f64), the split records' wing coding,
//! and the progressive reader that replays the base mesh (`BASE`) through the split blocks
//! (`SPLT`), shared by the full decoder and the level reader.

use crate::format::FormatError;
use crate::format::container::Container;
use crate::format::varint::ByteReader;
use crate::pm::{FlatReplay, VertexSplit};
use glam::DVec3;

use super::decode_ahead::SplitBlocks;
use super::meta::{check_version, read_meta};
use super::{BASE, LevelMesh, Meta, corrupt, required};

pub(super) fn put_position(out: &mut Vec<u8>, p: DVec3, f32: bool) {
    for c in p.to_array() {
        if f32 {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        } else {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}

pub(super) fn exactly_f32(p: DVec3) -> bool {
    p.to_array()
        .iter()
        .all(|&c| ((c as f32) as f64).to_bits() == c.to_bits())
}

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

pub(super) fn read_positions(
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
pub(super) struct Progressive {
    pub(super) meta: Meta,
    pub(super) truncated: bool,
    /// The base mesh with `splits` applied.
    pub(super) replay: FlatReplay,
    pub(super) splits: Vec<VertexSplit>,
    pub(super) positions: Vec<DVec3>,
    pub(super) errors: Vec<f32>,
}

/// `x mod n` for `x < 2n`: the right wing's code is `(r − l) mod valence` and decodes as
/// `(l + code) mod valence`, both with `l, r < valence`, so a compare and subtract does
/// instead of a division per split.
#[inline]
pub(super) fn wrap_once(x: u64, n: u64) -> u64 {
    if x >= n { x - n } else { x }
}

/// The progressive part of `bytes` up to `max_level` (default: all), with `also` run on
/// another core meanwhile (after it has helped decode the split blocks). Errors come in the
/// order a sequential reader meets them: header, `BASE`, then block by block.
pub(super) fn read_progressive<'a, R: Send>(
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
