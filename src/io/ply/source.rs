//! Streams of property values: binary (either byte order) and ASCII bodies.

use super::types::type_name;
use crate::io::text::{self, Lines};
use crate::io::{IoError, err_byte, err_line};
use crate::mesh::{AttributeData, ScalarType};

/// A stream of property values (binary or ASCII).
pub(super) trait Source {
    fn err(&self, reason: String) -> IoError;
    /// Starts a row (ASCII: moves to the next non-blank line).
    fn begin_row(&mut self, what: &dyn Fn() -> String) -> Result<(), IoError>;
    /// Ends a row (ASCII: no values may be left on the line).
    fn end_row(&mut self) -> Result<(), IoError>;
    /// Reads a scalar of the column's type and appends it.
    fn push_scalar(&mut self, col: &mut AttributeData) -> Result<(), IoError>;
    /// Reads an integer of type `t` (exact).
    fn int(&mut self, t: ScalarType) -> Result<i64, IoError>;
    /// Reads a value of type `t` widened to f64 (exact).
    fn num(&mut self, t: ScalarType) -> Result<f64, IoError>;
    /// Fails unless `n` items of type `t` can still follow (bounds list allocations).
    fn check_items(&self, n: u64, t: ScalarType) -> Result<(), IoError>;
}

pub(super) struct Bin<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    /// Start of the value read last (errors about a value point at it).
    pub(super) last: usize,
    pub(super) big: bool,
}

impl Bin<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], IoError> {
        self.last = self.pos;
        match self.data.get(self.pos..self.pos + N) {
            Some(s) => {
                self.pos += N;
                let mut a = [0u8; N];
                a.copy_from_slice(s);
                Ok(a)
            }
            None => Err(err_byte(
                self.pos as u64,
                "the file ends in the middle of the data",
            )),
        }
    }
}

macro_rules! rd {
    ($self:ident, $t:ty) => {{
        let b = $self.take::<{ std::mem::size_of::<$t>() }>()?;
        if $self.big {
            <$t>::from_be_bytes(b)
        } else {
            <$t>::from_le_bytes(b)
        }
    }};
}

impl Source for Bin<'_> {
    fn err(&self, reason: String) -> IoError {
        err_byte(self.last as u64, reason)
    }
    fn begin_row(&mut self, _what: &dyn Fn() -> String) -> Result<(), IoError> {
        Ok(())
    }
    fn end_row(&mut self) -> Result<(), IoError> {
        Ok(())
    }
    fn push_scalar(&mut self, col: &mut AttributeData) -> Result<(), IoError> {
        match col {
            AttributeData::I8(v) => v.push(rd!(self, i8)),
            AttributeData::U8(v) => v.push(rd!(self, u8)),
            AttributeData::I16(v) => v.push(rd!(self, i16)),
            AttributeData::U16(v) => v.push(rd!(self, u16)),
            AttributeData::I32(v) => v.push(rd!(self, i32)),
            AttributeData::U32(v) => v.push(rd!(self, u32)),
            AttributeData::F32(v) => v.push(rd!(self, f32)),
            AttributeData::F64(v) => v.push(rd!(self, f64)),
        }
        Ok(())
    }
    fn int(&mut self, t: ScalarType) -> Result<i64, IoError> {
        Ok(match t {
            ScalarType::I8 => rd!(self, i8) as i64,
            ScalarType::U8 => rd!(self, u8) as i64,
            ScalarType::I16 => rd!(self, i16) as i64,
            ScalarType::U16 => rd!(self, u16) as i64,
            ScalarType::I32 => rd!(self, i32) as i64,
            ScalarType::U32 => rd!(self, u32) as i64,
            _ => return Err(self.err("expected an integer type".into())),
        })
    }
    fn num(&mut self, t: ScalarType) -> Result<f64, IoError> {
        Ok(match t {
            ScalarType::F32 => rd!(self, f32) as f64,
            ScalarType::F64 => rd!(self, f64),
            _ => self.int(t)? as f64,
        })
    }
    fn check_items(&self, n: u64, t: ScalarType) -> Result<(), IoError> {
        let need = n.saturating_mul(t.size() as u64);
        let left = (self.data.len() - self.pos) as u64;
        if need > left {
            return Err(self.err(format!(
                "a list of {n} items needs {need} bytes but only {left} remain"
            )));
        }
        Ok(())
    }
}

pub(super) struct Ascii<'a> {
    pub(super) lines: Lines<'a>,
    pub(super) line_no: u64,
    pub(super) toks: Vec<&'a [u8]>,
    pub(super) next: usize,
}

impl<'a> Ascii<'a> {
    fn tok(&mut self) -> Result<&'a [u8], IoError> {
        match self.toks.get(self.next) {
            Some(t) => {
                self.next += 1;
                Ok(t)
            }
            None => Err(self.err("the line has too few values for its element".into())),
        }
    }
}

impl Source for Ascii<'_> {
    fn err(&self, reason: String) -> IoError {
        err_line(self.line_no, reason)
    }
    fn begin_row(&mut self, what: &dyn Fn() -> String) -> Result<(), IoError> {
        loop {
            match self.lines.next() {
                Some((n, l)) => {
                    self.line_no = n;
                    self.toks.clear();
                    self.toks.extend(text::tokens(l));
                    self.next = 0;
                    if !self.toks.is_empty() {
                        return Ok(());
                    }
                }
                None => {
                    return Err(err_line(
                        self.line_no + 1,
                        format!("the file ends before {}", what()),
                    ));
                }
            }
        }
    }
    fn end_row(&mut self) -> Result<(), IoError> {
        if self.next < self.toks.len() {
            return Err(self.err(format!(
                "the line has {} values, more than its element defines",
                self.toks.len()
            )));
        }
        Ok(())
    }
    fn push_scalar(&mut self, col: &mut AttributeData) -> Result<(), IoError> {
        let tok = self.tok()?;
        let bad = |s: &Self, t: ScalarType| {
            s.err(format!(
                "{} is not a valid {}",
                text::show(tok),
                type_name(t)
            ))
        };
        let t = col.scalar_type();
        match col {
            AttributeData::F32(v) => v.push(text::parse_f32(tok).ok_or_else(|| bad(self, t))?),
            AttributeData::F64(v) => v.push(text::parse_f64(tok).ok_or_else(|| bad(self, t))?),
            _ => {
                let x = text::parse_i64(tok).ok_or_else(|| bad(self, t))?;
                let ok = match col {
                    AttributeData::I8(v) => i8::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::U8(v) => u8::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::I16(v) => i16::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::U16(v) => u16::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::I32(v) => i32::try_from(x).map(|x| v.push(x)).is_ok(),
                    AttributeData::U32(v) => u32::try_from(x).map(|x| v.push(x)).is_ok(),
                    _ => false,
                };
                if !ok {
                    return Err(bad(self, t));
                }
            }
        }
        Ok(())
    }
    fn int(&mut self, t: ScalarType) -> Result<i64, IoError> {
        let tok = self.tok()?;
        let x = text::parse_i64(tok);
        let ok = match (t, x) {
            (ScalarType::I8, Some(x)) => i8::try_from(x).is_ok(),
            (ScalarType::U8, Some(x)) => u8::try_from(x).is_ok(),
            (ScalarType::I16, Some(x)) => i16::try_from(x).is_ok(),
            (ScalarType::U16, Some(x)) => u16::try_from(x).is_ok(),
            (ScalarType::I32, Some(x)) => i32::try_from(x).is_ok(),
            (ScalarType::U32, Some(x)) => u32::try_from(x).is_ok(),
            _ => false,
        };
        match x {
            Some(x) if ok => Ok(x),
            _ => Err(self.err(format!(
                "{} is not a valid {}",
                text::show(tok),
                type_name(t)
            ))),
        }
    }
    fn num(&mut self, t: ScalarType) -> Result<f64, IoError> {
        match t {
            ScalarType::F32 | ScalarType::F64 => {
                let tok = self.tok()?;
                let x = if t == ScalarType::F32 {
                    text::parse_f32(tok).map(|x| x as f64)
                } else {
                    text::parse_f64(tok)
                };
                x.ok_or_else(|| {
                    self.err(format!(
                        "{} is not a valid {}",
                        text::show(tok),
                        type_name(t)
                    ))
                })
            }
            _ => Ok(self.int(t)? as f64),
        }
    }
    fn check_items(&self, n: u64, _t: ScalarType) -> Result<(), IoError> {
        let left = (self.toks.len() - self.next) as u64;
        if n > left {
            return Err(self.err(format!(
                "a list of {n} items but only {left} values remain on the line"
            )));
        }
        Ok(())
    }
}
