//! Adaptive Golomb–Rice coding of signed integers, for the quantised details of `DETL`.
//!
//! Each value is zig-zag mapped, then coded as `v >> k` in unary (ones ended by a zero) and the
//! low `k` bits; `k` follows the running mean magnitude of its context (as in LOCO-I), so a
//! context whose values shrink from coarse to fine levels keeps its codes near the entropy of
//! a Laplacian of that mean. A quotient of [`ESCAPE`] or more is written as [`ESCAPE`] ones,
//! seven bits of bit length and the value's bits, so no code is longer than 95 bits.

use crate::format::FormatError;
use crate::format::varint::{unzigzag, zigzag};

/// Unary quotients at and above this are escaped.
const ESCAPE: u64 = 24;
/// The running sums are halved when a context has seen this many values.
const RESET: u32 = 64;

/// The adaptive state of one context.
#[derive(Clone, Copy, Debug)]
pub(super) struct Context {
    sum: u64,
    n: u32,
}

impl Default for Context {
    fn default() -> Self {
        Context { sum: 4, n: 1 }
    }
}

impl Context {
    /// The Rice parameter: the smallest `k` with `n · 2^k ≥ sum`, at most 60.
    #[inline]
    fn k(&self) -> u32 {
        let mut k = 0;
        while (u128::from(self.n) << k) < u128::from(self.sum) && k < 60 {
            k += 1;
        }
        k
    }

    #[inline]
    fn update(&mut self, v: u64) {
        self.sum = self.sum.saturating_add(v);
        self.n += 1;
        if self.n >= RESET {
            self.sum = self.sum.div_ceil(2);
            self.n /= 2;
        }
    }
}

/// Writes bits, least significant first, into bytes.
#[derive(Default)]
pub(super) struct BitWriter {
    out: Vec<u8>,
    acc: u64,
    n: u32,
}

impl BitWriter {
    /// Appends the low `n ≤ 57` bits of `v`.
    #[inline]
    fn put(&mut self, v: u64, n: u32) {
        debug_assert!(n <= 57);
        self.acc |= (v & ((1u64 << n) - 1)) << self.n;
        self.n += n;
        while self.n >= 8 {
            self.out.push(self.acc as u8);
            self.acc >>= 8;
            self.n -= 8;
        }
    }

    /// Appends `n` one bits.
    fn ones(&mut self, mut n: u64) {
        while n > 0 {
            let m = n.min(32);
            self.put((1u64 << m) - 1, m as u32);
            n -= m;
        }
    }

    /// Appends `v` coded in context `c`.
    pub(super) fn code(&mut self, c: &mut Context, v: i64) {
        let u = zigzag(v);
        let k = c.k();
        let q = u >> k;
        if q < ESCAPE {
            self.ones(q);
            self.put(0, 1);
            self.put(u, k.min(32));
            if k > 32 {
                self.put(u >> 32, k - 32);
            }
        } else {
            self.ones(ESCAPE);
            let len = 64 - u.leading_zeros();
            self.put(u64::from(len), 7);
            self.put(u, len.min(32));
            if len > 32 {
                self.put(u >> 32, len - 32);
            }
        }
        c.update(u);
    }

    /// The bytes, the last one padded with zeros.
    pub(super) fn finish(mut self) -> Vec<u8> {
        if self.n > 0 {
            self.out.push(self.acc as u8);
        }
        self.out
    }
}

/// Reads what [`BitWriter`] wrote; reading past the end is an error.
pub(super) struct BitReader<'a> {
    bytes: &'a [u8],
    /// Offset of `bytes` in the file (for errors).
    base: u64,
    pos: usize,
    acc: u64,
    n: u32,
}

impl<'a> BitReader<'a> {
    pub(super) fn new(bytes: &'a [u8], base: u64) -> Self {
        BitReader {
            bytes,
            base,
            pos: 0,
            acc: 0,
            n: 0,
        }
    }

    /// Tops the accumulator up to at least 57 bits, or to the end of the bytes.
    #[inline]
    fn refill(&mut self) {
        while self.n <= 56 && self.pos < self.bytes.len() {
            self.acc |= u64::from(self.bytes[self.pos]) << self.n;
            self.pos += 1;
            self.n += 8;
        }
    }

    /// The next `n ≤ 32` bits.
    #[inline]
    fn take(&mut self, n: u32) -> Result<u64, FormatError> {
        if n == 0 {
            return Ok(0);
        }
        if self.n < n {
            self.refill();
            if self.n < n {
                return Err(self.past_end());
            }
        }
        let v = self.acc & ((1u64 << n) - 1);
        self.acc >>= n;
        self.n -= n;
        Ok(v)
    }

    #[cold]
    fn past_end(&self) -> FormatError {
        FormatError::Corrupt {
            offset: self.base + self.bytes.len() as u64,
            reason: "detail block ends inside a code".into(),
        }
    }

    /// The number of one bits before the next zero (at most [`ESCAPE`]; the zero is consumed
    /// unless the run reached [`ESCAPE`]).
    #[inline]
    fn unary(&mut self) -> Result<u64, FormatError> {
        if self.n < ESCAPE as u32 + 1 {
            self.refill();
        }
        let ones = u64::from((!self.acc).trailing_zeros()).min(ESCAPE);
        if ones < ESCAPE {
            if ones as u32 >= self.n {
                return Err(self.past_end());
            }
            self.acc >>= ones + 1;
            self.n -= ones as u32 + 1;
        } else {
            if self.n < ESCAPE as u32 {
                return Err(self.past_end());
            }
            self.acc >>= ESCAPE;
            self.n -= ESCAPE as u32;
        }
        Ok(ones)
    }

    /// The next value of context `c`.
    #[inline]
    pub(super) fn decode(&mut self, c: &mut Context) -> Result<i64, FormatError> {
        let k = c.k();
        let q = self.unary()?;
        let u = if q < ESCAPE {
            let low = self.wide(k)?;
            (q << k) | low
        } else {
            let len = self.take(7)? as u32;
            if len > 64 {
                return Err(FormatError::Corrupt {
                    offset: self.base + self.pos as u64,
                    reason: format!("escaped detail of {len} bits"),
                });
            }
            self.wide(len)?
        };
        c.update(u);
        Ok(unzigzag(u))
    }

    /// The next `n ≤ 64` bits.
    #[inline]
    fn wide(&mut self, n: u32) -> Result<u64, FormatError> {
        let low = self.take(n.min(32))?;
        if n <= 32 {
            return Ok(low);
        }
        Ok(low | self.take(n - 32)? << 32)
    }

    /// True when only zero padding of the last byte is left.
    pub(super) fn at_end(&mut self) -> bool {
        self.refill();
        self.pos == self.bytes.len() && self.n < 8 && self.acc == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_values_round_trip_in_any_context_history() {
        let values: Vec<i64> = [0, 1, -1, 5, -300, 1 << 40, i64::MIN, i64::MAX, 7, 0, 0, -2]
            .into_iter()
            .chain((0..500).map(|i| (i * i * 7919) % 2001 - 1000))
            .collect();
        let mut w = BitWriter::default();
        let mut c = Context::default();
        for &v in &values {
            w.code(&mut c, v);
        }
        let bytes = w.finish();
        let mut r = BitReader::new(&bytes, 0);
        let mut c = Context::default();
        for &v in &values {
            assert_eq!(r.decode(&mut c).unwrap(), v);
        }
        assert!(r.at_end());
        // Every prefix cut short is an error, not a panic or a wrong value read as complete.
        for cut in 0..bytes.len() {
            let mut r = BitReader::new(&bytes[..cut], 0);
            let mut c = Context::default();
            assert!(values.iter().any(|_| r.decode(&mut c).is_err()));
        }
    }
}
