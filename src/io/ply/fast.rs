//! Fast paths for binary bodies: fixed-stride scalar blocks decoded column by column, and
//! the common face layout decoded in one tight loop.

use glam::DVec3;

use super::header::{ElementDef, PropKind};
use super::plan::{Out, Plan};
use super::rows::Ctx;
use super::types::empty_col;
use crate::io::{IoError, err_byte};
use crate::mesh::{AttributeData, ScalarType};

/// Decodes one fixed-offset scalar column of a fixed-stride binary block.
fn column(block: &[u8], stride: usize, off: usize, t: ScalarType, big: bool) -> AttributeData {
    macro_rules! col {
        ($ty:ty, $var:ident) => {{
            const N: usize = std::mem::size_of::<$ty>();
            AttributeData::$var(
                block
                    .chunks_exact(stride)
                    .map(|r| {
                        let mut a = [0u8; N];
                        a.copy_from_slice(&r[off..off + N]);
                        if big {
                            <$ty>::from_be_bytes(a)
                        } else {
                            <$ty>::from_le_bytes(a)
                        }
                    })
                    .collect(),
            )
        }};
    }
    match t {
        ScalarType::I8 => col!(i8, I8),
        ScalarType::U8 => col!(u8, U8),
        ScalarType::I16 => col!(i16, I16),
        ScalarType::U16 => col!(u16, U16),
        ScalarType::I32 => col!(i32, I32),
        ScalarType::U32 => col!(u32, U32),
        ScalarType::F32 => col!(f32, F32),
        ScalarType::F64 => col!(f64, F64),
    }
}

/// Fast path: binary little-endian face element whose only property is
/// `list <uchar|ushort|uint|…> <int|uint> vertex_indices`; `rows` rows from the element's row
/// `first` (messages name the element's row).
pub(super) fn read_faces_fast(
    data: &[u8],
    mut pos: usize,
    (first, rows): (usize, usize),
    count: ScalarType,
    item: ScalarType,
    ctx: &mut Ctx,
) -> Result<usize, IoError> {
    let csize = count.size();
    let nv = ctx.nv;
    let signed = item == ScalarType::I32;
    let left = data.len() - pos;
    ctx.face_starts.reserve(rows + 1);
    ctx.face_indices
        .reserve((rows.saturating_mul(3)).min(left / 4));
    // Indices below `limit` are valid (for `int` items this also rules out negatives).
    let limit = if signed { nv.min(1 << 31) } else { nv };
    for f in first..first + rows {
        // Shortcut: `uchar 3` followed by three valid indices.
        if count == ScalarType::U8
            && let Some(r) = data.get(pos..pos + 13)
            && r[0] == 3
        {
            let idx = |k: usize| u32::from_le_bytes([r[k], r[k + 1], r[k + 2], r[k + 3]]);
            let t = [idx(1), idx(5), idx(9)];
            if t.iter().all(|&v| (v as u64) < limit) {
                ctx.face_indices.extend_from_slice(&t);
                pos += 13;
                let len = u32::try_from(ctx.face_indices.len())
                    .map_err(|_| err_byte(pos as u64, "more than 2^32 - 1 face indices"))?;
                ctx.face_starts.push(len);
                continue;
            }
        }
        let Some(cb) = data.get(pos..pos + csize) else {
            return Err(err_byte(
                pos as u64,
                "the file ends in the middle of the faces",
            ));
        };
        let n: i64 = match count {
            ScalarType::U8 => cb[0] as i64,
            ScalarType::I8 => cb[0] as i8 as i64,
            ScalarType::U16 => u16::from_le_bytes([cb[0], cb[1]]) as i64,
            ScalarType::I16 => i16::from_le_bytes([cb[0], cb[1]]) as i64,
            ScalarType::U32 => u32::from_le_bytes([cb[0], cb[1], cb[2], cb[3]]) as i64,
            _ => i32::from_le_bytes([cb[0], cb[1], cb[2], cb[3]]) as i64,
        };
        if n < 0 {
            return Err(err_byte(
                pos as u64,
                format!("face {f} has a negative length {n}"),
            ));
        }
        pos += csize;
        let end = (n as u64)
            .checked_mul(4)
            .and_then(|b| b.checked_add(pos as u64))
            .filter(|&e| e <= data.len() as u64)
            .ok_or_else(|| {
                err_byte(
                    pos as u64,
                    format!("face {f} has {n} indices, more than the rest of the file holds"),
                )
            })? as usize;
        for (k, c) in data[pos..end].chunks_exact(4).enumerate() {
            let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if v as u64 >= nv || (signed && v > i32::MAX as u32) {
                let at = (pos + 4 * k) as u64;
                return Err(if signed && v > i32::MAX as u32 {
                    err_byte(at, format!("face {f} has negative index {}", v as i32))
                } else {
                    err_byte(
                        at,
                        format!("face {f} has index {v} but the file has {nv} vertices"),
                    )
                });
            }
            ctx.face_indices.push(v);
        }
        pos = end;
        let len = u32::try_from(ctx.face_indices.len())
            .map_err(|_| err_byte(pos as u64, "more than 2^32 - 1 face indices"))?;
        ctx.face_starts.push(len);
    }
    Ok(pos)
}

/// Positions straight from a fixed-stride binary vertex block when `x`, `y`, `z` are all
/// `float`; `Ok(None)` for other layouts. Checks finiteness. The block's first row is the
/// element's row `first` (for messages).
pub(super) fn float_positions(
    el: &ElementDef,
    block: &[u8],
    stride: usize,
    (start, first): (usize, usize),
    big: bool,
) -> Result<Option<Vec<DVec3>>, IoError> {
    let mut offs = [usize::MAX; 3];
    let mut off = 0;
    for p in &el.props {
        let PropKind::Scalar(t) = p.kind else {
            return Ok(None);
        };
        if let Some(k) = ["x", "y", "z"].iter().position(|c| *c == p.name) {
            if t != ScalarType::F32 {
                return Ok(None);
            }
            offs[k] = off;
        }
        off += t.size();
    }
    let [ox, oy, oz] = offs;
    let rd = |r: &[u8], o: usize| {
        let a = [r[o], r[o + 1], r[o + 2], r[o + 3]];
        if big {
            f32::from_be_bytes(a)
        } else {
            f32::from_le_bytes(a)
        }
    };
    let mut out = Vec::with_capacity(block.len() / stride.max(1));
    let mut all_finite = true;
    for r in block.chunks_exact(stride) {
        let (x, y, z) = (rd(r, ox), rd(r, oy), rd(r, oz));
        all_finite &= x.is_finite() & y.is_finite() & z.is_finite();
        out.push(DVec3::new(x as f64, y as f64, z as f64));
    }
    if !all_finite {
        let i = out.iter().position(|p| !p.is_finite()).unwrap_or(0);
        let k = (0..3).find(|&k| !out[i][k].is_finite()).unwrap_or(0);
        return Err(err_byte(
            (start + i * stride + offs[k]) as u64,
            format!("vertex {} has a non-finite coordinate", first + i),
        ));
    }
    Ok(Some(out))
}

/// Bytes per row of an element of scalars only.
pub(super) fn row_stride(plans: &[Plan]) -> usize {
    plans
        .iter()
        .map(|p| match p {
            Plan::Scalar { t, .. } => t.size(),
            _ => 0,
        })
        .sum()
}

/// The columns of a fixed-stride block starting at byte `start` (the element's row `first`),
/// position columns checked for non-finite values. With `positions_decoded` (x, y, z already
/// read by [`float_positions`]) the position columns are left empty.
pub(super) fn scalar_columns(
    plans: &[Plan],
    block: &[u8],
    stride: usize,
    (start, first): (usize, usize),
    big: bool,
    positions_decoded: bool,
) -> Result<Vec<Out>, IoError> {
    let mut off = 0;
    let mut outs = Vec::with_capacity(plans.len());
    for plan in plans {
        let Plan::Scalar { t, finite } = *plan else {
            unreachable!()
        };
        if finite && positions_decoded {
            outs.push(Out::Col(empty_col(t, 0)));
            off += t.size();
            continue;
        }
        let col = column(block, stride, off, t, big);
        if let Some(i) = first_non_finite(&col, finite) {
            return Err(err_byte(
                (start + i * stride + off) as u64,
                format!("vertex {} has a non-finite coordinate", first + i),
            ));
        }
        outs.push(Out::Col(col));
        off += t.size();
    }
    Ok(outs)
}

/// The first non-finite value of a position column (`finite`: the column holds positions);
/// integers are always finite.
fn first_non_finite(col: &AttributeData, finite: bool) -> Option<usize> {
    match (col, finite) {
        (AttributeData::F32(v), true) => v.iter().position(|x| !x.is_finite()),
        (AttributeData::F64(v), true) => v.iter().position(|x| !x.is_finite()),
        _ => None,
    }
}
