//! LEB128 variable-length integers and zig-zag signed coding, with bounded decoding.
//!
//! Bulk index streams in the `.pyr` file are mostly small deltas, which this codes in one or
//! two bytes instead of four.

use super::FormatError;

/// Appends `v` as unsigned LEB128 (7 bits per byte, low groups first).
#[inline]
pub fn put_uvarint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// Maps signed to unsigned so that small magnitudes get small codes: 0, −1, 1, −2, … → 0, 1, 2, 3, …
#[inline]
pub(crate) fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

/// Inverse of [`zigzag`].
#[inline]
pub(crate) fn unzigzag(v: u64) -> i64 {
    ((v >> 1) as i64) ^ -((v & 1) as i64)
}

/// Appends `v` zig-zag coded.
#[inline]
pub fn put_ivarint(out: &mut Vec<u8>, v: i64) {
    put_uvarint(out, zigzag(v));
}

/// A cursor over a byte slice whose every read is bounds-checked; errors report the absolute
/// file offset (`base + position`).
#[derive(Clone, Debug)]
pub struct ByteReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    base: u64,
}

impl<'a> ByteReader<'a> {
    /// A reader over `bytes`, which start at file offset `base`.
    pub fn new(bytes: &'a [u8], base: u64) -> Self {
        ByteReader {
            bytes,
            pos: 0,
            base,
        }
    }

    /// Current absolute file offset.
    pub fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }

    /// Bytes left.
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// True when every byte was consumed.
    pub fn is_empty(&self) -> bool {
        self.remaining() == 0
    }

    fn truncated(&self, what: &str) -> FormatError {
        FormatError::Truncated {
            offset: self.offset(),
            what: what.to_string(),
        }
    }

    /// The next `n` bytes.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], FormatError> {
        if n > self.remaining() {
            return Err(self.truncated(what));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// A fixed-size array.
    pub(crate) fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], FormatError> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    /// Little-endian u32.
    pub fn u32(&mut self, what: &str) -> Result<u32, FormatError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    /// Little-endian u64.
    pub fn u64(&mut self, what: &str) -> Result<u64, FormatError> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }

    /// Little-endian f64 (bit pattern preserved).
    pub fn f64(&mut self, what: &str) -> Result<f64, FormatError> {
        Ok(f64::from_bits(self.u64(what)?))
    }

    /// Unsigned LEB128; at most 10 bytes, overlong or overflowing codes are errors.
    #[inline]
    pub fn uvarint(&mut self, what: &str) -> Result<u64, FormatError> {
        // Most codes of a `.pyr` file (split records, vertex order, polygon deltas) take one
        // to three bytes: decode those without the general loop.
        if let Some(&b0) = self.bytes.get(self.pos) {
            if b0 < 0x80 {
                self.pos += 1;
                return Ok(u64::from(b0));
            }
            if let Some(&b1) = self.bytes.get(self.pos + 1) {
                let v = u64::from(b0 & 0x7f) | u64::from(b1 & 0x7f) << 7;
                if b1 < 0x80 {
                    self.pos += 2;
                    return Ok(v);
                }
                if let Some(&b2) = self.bytes.get(self.pos + 2)
                    && b2 < 0x80
                {
                    self.pos += 3;
                    return Ok(v | u64::from(b2) << 14);
                }
            }
        }
        self.uvarint_long(what)
    }

    /// [`Self::uvarint`] for codes of four or more bytes, and the errors.
    #[cold]
    #[inline(never)]
    fn uvarint_long(&mut self, what: &str) -> Result<u64, FormatError> {
        let mut v = 0u64;
        for i in 0..10 {
            let Some(&b) = self.bytes.get(self.pos) else {
                return Err(self.truncated(what));
            };
            self.pos += 1;
            if i == 9 && b > 1 {
                return Err(FormatError::Corrupt {
                    offset: self.offset() - 1,
                    reason: format!("{what}: varint overflows 64 bits"),
                });
            }
            v |= u64::from(b & 0x7f) << (7 * i);
            if b < 0x80 {
                return Ok(v);
            }
        }
        Err(FormatError::Corrupt {
            offset: self.offset(),
            reason: format!("{what}: varint longer than 10 bytes"),
        })
    }

    /// Zig-zag signed LEB128.
    pub fn ivarint(&mut self, what: &str) -> Result<i64, FormatError> {
        Ok(unzigzag(self.uvarint(what)?))
    }

    /// An unsigned varint that must be `<= max` (used for every count read from a file before
    /// anything is allocated from it).
    #[inline]
    pub fn count(&mut self, max: u64, what: &str) -> Result<usize, FormatError> {
        let at = self.offset();
        let v = self.uvarint(what)?;
        if v > max {
            return Err(too_large(at, what, v, max));
        }
        Ok(v as usize)
    }
}

/// The error of [`ByteReader::count`], out of line so that the check inlines.
#[cold]
#[inline(never)]
fn too_large(offset: u64, what: &str, v: u64, max: u64) -> FormatError {
    FormatError::Corrupt {
        offset,
        reason: format!("{what} is {v}, more than the {max} the file can hold"),
    }
}
