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
    /// f32 for f32 (and integer) typed positions, f64 for f64 or unknown (text input).
    pub(crate) fn for_positions(t: Option<crate::mesh::ScalarType>) -> Self {
        match t {
            None | Some(crate::mesh::ScalarType::F64) => TextPrecision::F64,
            Some(_) => TextPrecision::F32,
        }
    }

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
    fn lines_strip_cr() {
        let v: Vec<_> = Lines::new(b"a\r\nb\n\nc", 1).collect();
        assert_eq!(v, vec![(1, &b"a"[..]), (2, b"b"), (3, b""), (4, b"c")]);
    }
}
