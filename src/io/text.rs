//! Small helpers shared by the text formats: line splitting, number parsing and shortest
//! round-trip float formatting.

use std::fmt::Write;

/// Iterates over `(line_number, line)` with `\n` line ends; a trailing `\r` is removed.
/// Line numbers are 1-based.
pub(crate) struct Lines<'a> {
    rest: &'a [u8],
    line: u64,
    done: bool,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(bytes: &'a [u8], first_line: u64) -> Self {
        Lines {
            rest: bytes,
            line: first_line.saturating_sub(1),
            done: false,
        }
    }
}

impl Lines<'_> {
    /// Bytes not yet returned.
    pub(crate) fn rest_len(&self) -> usize {
        if self.done { 0 } else { self.rest.len() }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (u64, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        self.line += 1;
        let (line, rest) = match self.rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&self.rest[..i], &self.rest[i + 1..]),
            None => {
                self.done = true;
                if self.rest.is_empty() {
                    return None;
                }
                (self.rest, &self.rest[self.rest.len()..])
            }
        };
        self.rest = rest;
        Some((self.line, strip_cr(line)))
    }
}

/// Removes trailing `\r` characters.
pub(crate) fn strip_cr(mut line: &[u8]) -> &[u8] {
    while let [head @ .., b'\r'] = line {
        line = head;
    }
    line
}

/// ASCII-whitespace separated tokens of a line.
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// A token for an error message: quoted, escaped, shortened.
pub(crate) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(&tok[..tok.len().min(40)]);
    let mut out = format!("{s:?}");
    if tok.len() > 40 {
        out.push('…');
    }
    out
}

/// Parses a decimal float (accepts what Rust's `f64::from_str` accepts).
pub(crate) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a decimal float directly as `f32` (correctly rounded, no double rounding).
pub(crate) fn parse_f32(tok: &[u8]) -> Option<f32> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a decimal integer.
pub(crate) fn parse_i64(tok: &[u8]) -> Option<i64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Appends the shortest decimal text that parses back to exactly `x`.
pub(crate) fn push_f32(out: &mut String, x: f32) {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        let _ = write!(out, "{x:e}");
    } else {
        let _ = write!(out, "{x}");
    }
}

/// Appends the shortest decimal text that parses back to exactly `x`.
pub(crate) fn push_f64(out: &mut String, x: f64) {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        let _ = write!(out, "{x:e}");
    } else {
        let _ = write!(out, "{x}");
    }
}

/// How a text writer formats positions: as `f32` (bit-exact for f32 data) or `f64`.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum TextPrecision {
    F32,
    F64,
}

impl TextPrecision {
    /// Appends `x` in this precision; `None` if an f32 rendering would overflow to infinity.
    pub(crate) fn push(self, out: &mut String, x: f64) -> Option<()> {
        match self {
            TextPrecision::F64 => push_f64(out, x),
            TextPrecision::F32 => {
                let y = x as f32;
                if !y.is_finite() {
                    return None;
                }
                push_f32(out, y)
            }
        }
        Some(())
    }
}

// ---------------------------------------------------------------------------------------------
// Position precision of OBJ / OFF text
// ---------------------------------------------------------------------------------------------
//
// Text does not say whether it holds float or double data, yet f32 positions written as text
// must re-read bit-identically. The rule, applied to a whole file:
// - if every coordinate has at most 9 significant digits (what shortest f32 formatting and
//   the usual `%f`/`%g` output produce) and parses to a finite f32 that is zero only when the
//   number is, the file holds float data: positions are the f32 parses and `position_type`
//   is `Some(F32)`;
// - otherwise positions are the exact f64 parses and `position_type` is `None`.
// The writers mirror it: f32-typed positions, and untyped/f64 positions that are all exactly
// f32 values, are written with shortest f32 formatting; other positions with shortest f64
// formatting, and if that text would still look like float data, one coordinate that is not
// an f32 value is written with 17 significant digits so the file re-reads as double.

/// Significant digits of a decimal token's mantissa (leading zeros excluded).
pub(crate) fn sig_digits(tok: &[u8]) -> usize {
    let mut n = 0;
    let mut started = false;
    for &b in tok {
        match b {
            b'e' | b'E' => break,
            b'0' if !started => {}
            b'0'..=b'9' => {
                started = true;
                n += 1;
            }
            _ => {}
        }
    }
    n
}

/// The f32 reading of a coordinate token when it looks like float data (see above).
pub(crate) fn as_float_data(tok: &[u8], x: f64) -> Option<f32> {
    if sig_digits(tok) > 9 {
        return None;
    }
    let y = parse_f32(tok)?;
    (y.is_finite() && ((y == 0.0) == (x == 0.0))).then_some(y)
}

/// Collects text positions in both precisions and picks one for the whole file.
pub(crate) struct TextPositions {
    p64: Vec<glam::DVec3>,
    p32: Option<Vec<[f32; 3]>>,
}

impl TextPositions {
    pub(crate) fn new() -> Self {
        TextPositions {
            p64: Vec::new(),
            p32: Some(Vec::new()),
        }
    }

    pub(crate) fn reserve(&mut self, n: usize) {
        self.p64.reserve(n);
        if let Some(p) = &mut self.p32 {
            p.reserve(n);
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.p64.len()
    }

    /// Adds a vertex from its tokens and their (finite) f64 values.
    pub(crate) fn push(&mut self, toks: [&[u8]; 3], x: [f64; 3]) {
        self.p64.push(glam::DVec3::from_array(x));
        if let Some(p) = &mut self.p32 {
            let f = [0, 1, 2].map(|k| as_float_data(toks[k], x[k]));
            match f {
                [Some(a), Some(b), Some(c)] => p.push([a, b, c]),
                _ => self.p32 = None,
            }
        }
    }

    /// Positions and their type.
    pub(crate) fn finish(self) -> (Vec<glam::DVec3>, Option<crate::mesh::ScalarType>) {
        match self.p32 {
            Some(p) if !p.is_empty() => (
                p.into_iter()
                    .map(|c| glam::DVec3::from_array(c.map(f64::from)))
                    .collect(),
                Some(crate::mesh::ScalarType::F32),
            ),
            _ => (self.p64, None),
        }
    }
}

/// How a text writer renders positions (see the rule above).
pub(crate) struct PositionFormat {
    precision: TextPrecision,
    /// Flat index (3 · vertex + axis) of the coordinate written with 17 digits.
    force: Option<usize>,
}

impl PositionFormat {
    /// Chooses the rendering; `Err(vertex)` if f32-typed positions overflow f32.
    pub(crate) fn new(mesh: &crate::mesh::PolygonMesh) -> Result<Self, usize> {
        let f32_exact = |x: f64| (x as f32) as f64 == x;
        let typed_f32 = matches!(mesh.position_type, Some(t) if t != crate::mesh::ScalarType::F64);
        if typed_f32 {
            if let Some(i) = mesh.positions.iter().position(|p| !p.as_vec3().is_finite()) {
                return Err(i);
            }
            return Ok(PositionFormat {
                precision: TextPrecision::F32,
                force: None,
            });
        }
        let flat = || mesh.positions.iter().flat_map(|p| p.to_array());
        let Some(first_wide) = flat().position(|x| !f32_exact(x)) else {
            return Ok(PositionFormat {
                precision: TextPrecision::F32,
                force: None,
            });
        };
        // Would shortest f64 text be taken for float data?
        let mut s = String::new();
        let looks_float = flat().all(|x| {
            s.clear();
            push_f64(&mut s, x);
            as_float_data(s.as_bytes(), x).is_some()
        });
        Ok(PositionFormat {
            precision: TextPrecision::F64,
            force: looks_float.then_some(first_wide),
        })
    }

    /// Appends coordinate `axis` of vertex `v`.
    pub(crate) fn push(&self, out: &mut String, v: usize, axis: usize, x: f64) {
        if self.force == Some(3 * v + axis) {
            let _ = write!(out, "{x:.16e}");
        } else {
            let _ = self.precision.push(out, x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_round_trip() {
        for &x in &[
            0.1f32, -0.0, 1e-30, 3.4e38, 1.17e-38, 1e-45, 123456.79, 1e16, 9.99e15,
        ] {
            let mut s = String::new();
            push_f32(&mut s, x);
            assert_eq!(
                parse_f32(s.as_bytes()).unwrap().to_bits(),
                x.to_bits(),
                "{s}"
            );
        }
        for &x in &[0.1f64, -0.0, 1e-300, 1.7e308, 5e-324, 1e16, 0.3] {
            let mut s = String::new();
            push_f64(&mut s, x);
            assert_eq!(
                parse_f64(s.as_bytes()).unwrap().to_bits(),
                x.to_bits(),
                "{s}"
            );
        }
    }

    #[test]
    fn float_data_detection() {
        assert_eq!(sig_digits(b"-0.000123e5"), 3);
        assert_eq!(sig_digits(b"1.000000"), 7);
        assert_eq!(sig_digits(b"-0"), 0);
        assert!(as_float_data(b"0.471660", 0.47166).is_some());
        assert!(as_float_data(b"0.1000000001", 0.1000000001).is_none());
        assert!(as_float_data(b"1e-50", 1e-50).is_none());
        assert!(as_float_data(b"1e39", 1e39).is_none());
        let mut s = String::new();
        let x = 0.1f64;
        let _ = write!(s, "{x:.16e}");
        assert_eq!(parse_f64(s.as_bytes()), Some(0.1));
        assert!(as_float_data(s.as_bytes(), x).is_none());
    }

    #[test]
    fn lines_strip_cr() {
        let v: Vec<_> = Lines::new(b"a\r\nb\n\nc", 1).collect();
        assert_eq!(v, vec![(1, &b"a"[..]), (2, b"b"), (3, b""), (4, b"c")]);
    }
}
