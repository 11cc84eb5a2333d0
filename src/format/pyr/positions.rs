//! How positions are stored: as f32 when every coordinate of the hierarchy is exactly an f32
//! (a mesh read from an f32 file), else as f64, so that decoding gives back the exact values.
//! Shared by the base mesh, the split blocks and the vertices without faces.

use crate::format::FormatError;
use crate::format::varint::ByteReader;
use glam::DVec3;

use super::corrupt;

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
