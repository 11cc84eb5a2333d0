//! The `PINS` section (2.4): per pass of a partitioned build, its run of splits and the
//! vertices pinned in it (`crate::pm::Pins`). The detail pyramid of such a hierarchy leaves a
//! split's ring vertices pinned in its pass untouched, so the pins define the pyramid as much
//! as the splits do: a reader that analysed the hierarchy without them would compute other
//! details (and a `DETL` stored with them would not fit its splits).
//!
//! Written only for a hierarchy that carries pins, so every other file keeps its bytes and
//! version. REQUIRED: a 2.3 reader refuses such a file (naming the section) instead of
//! filtering it with another pyramid.
//!
//! Layout: `uvarint` the number of passes, then per pass (split order) `uvarint` its number of
//! splits (> 0), `uvarint` its number of pinned vertices, and the vertices ascending, the
//! first as `uvarint v`, each next as `uvarint (v − previous − 1)`.

use crate::format::FormatError;
use crate::format::varint::{ByteReader, put_uvarint};
use crate::pm::Pins;

use super::corrupt;

/// `PINS` of `pins`.
pub(super) fn encode_pins(pins: &Pins) -> Vec<u8> {
    let mut out = Vec::new();
    put_uvarint(&mut out, pins.n_passes() as u64);
    for (run, pinned) in pins.passes() {
        put_uvarint(&mut out, run.len() as u64);
        put_uvarint(&mut out, pinned.len() as u64);
        let mut next = 0u64;
        for &v in pinned {
            put_uvarint(&mut out, u64::from(v) - next);
            next = u64::from(v) + 1;
        }
    }
    out
}

/// Reads `PINS` for a hierarchy of `n_splits` splits and `n_vertices` vertices (every count
/// is checked before anything is allocated from it, also against the bytes left: a pass takes
/// at least two, a vertex one; the record's fit to the splits is checked by
/// [`crate::pm::ProgressiveMesh::set_pins`]).
pub(super) fn decode_pins(
    mut r: ByteReader<'_>,
    n_splits: usize,
    n_vertices: usize,
) -> Result<Pins, FormatError> {
    let most_passes = n_splits.min(r.remaining() / 2) as u64;
    let n_passes = r.count(most_passes, "PINS pass count")?;
    let mut passes = Vec::with_capacity(n_passes);
    for p in 0..n_passes {
        let at = r.offset();
        let run = r.count(n_splits as u64, "PINS pass length")?;
        if run == 0 {
            return Err(corrupt(at, format!("PINS: pass {p} has no split")));
        }
        let k = r.count(n_vertices.min(r.remaining()) as u64, "PINS pinned count")?;
        let mut pinned = Vec::with_capacity(k);
        let mut next = 0u64;
        for _ in 0..k {
            let at = r.offset();
            let v = next.saturating_add(r.uvarint("PINS vertex")?);
            if v >= n_vertices as u64 {
                return Err(corrupt(
                    at,
                    format!("PINS: pass {p}: vertex {v} out of range ({n_vertices} vertices)"),
                ));
            }
            pinned.push(v as u32);
            next = v + 1;
        }
        passes.push((run, pinned));
    }
    if !r.is_empty() {
        return Err(corrupt(r.offset(), "PINS: bytes after the passes"));
    }
    Ok(Pins::from_passes(passes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_round_trip_and_damaged_ones_are_errors_not_panics() {
        let pins = Pins::from_passes([(3, vec![]), (2, vec![0, 1, 7, 300])]);
        let bytes = encode_pins(&pins);
        let read = |b: &[u8]| decode_pins(ByteReader::new(b, 0), 5, 400);
        assert_eq!(read(&bytes).unwrap(), pins);
        // Every truncation, and a vertex beyond the hierarchy, is an error.
        for n in 0..bytes.len() {
            assert!(read(&bytes[..n]).is_err(), "{n} bytes");
        }
        assert!(decode_pins(ByteReader::new(&bytes, 0), 5, 300).is_err());
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(read(&longer).is_err());
        // A pass without splits.
        assert!(read(&[1, 0, 0]).is_err());
    }
}
