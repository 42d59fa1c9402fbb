//! Value readers of the body: binary (either byte order) and ASCII, behind one trait.

use std::path::Path;

use super::header::Scalar;
use crate::load::error::LoadError;

/// Reads values from the body, in either encoding.
pub(super) trait Reader {
    /// Reads one value of type `t`.
    fn value(&mut self, t: Scalar, what: &str) -> Result<f64, LoadError>;
    /// Whether `n` more items of type `t` can possibly be in the rest of the body.
    fn can_hold(&self, n: u64, t: Scalar) -> bool;
    /// Skips `n` instances of `size` bytes each when the encoding allows it (binary).
    fn skip_fixed(&mut self, n: usize, size: usize, what: &str) -> Result<bool, LoadError>;
    /// An error at the current position.
    fn error(&self, message: String) -> LoadError;
}

pub(super) struct BinaryReader<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    pub(super) base: u64,
    pub(super) big_endian: bool,
    pub(super) path: &'a Path,
}

impl BinaryReader<'_> {
    fn take<const N: usize>(&mut self, what: &str) -> Result<[u8; N], LoadError> {
        let end = self.pos.checked_add(N);
        match end.and_then(|e| self.data.get(self.pos..e)) {
            Some(s) => {
                let mut a = [0u8; N];
                a.copy_from_slice(s);
                self.pos += N;
                Ok(a)
            }
            None => Err(self.error(format!("unexpected end of file while reading {what}"))),
        }
    }
}

impl Reader for BinaryReader<'_> {
    fn value(&mut self, t: Scalar, what: &str) -> Result<f64, LoadError> {
        let be = self.big_endian;
        Ok(match t {
            Scalar::I8 => self.take::<1>(what)?[0] as i8 as f64,
            Scalar::U8 => self.take::<1>(what)?[0] as f64,
            Scalar::I16 => {
                let b = self.take::<2>(what)?;
                (if be {
                    i16::from_be_bytes(b)
                } else {
                    i16::from_le_bytes(b)
                }) as f64
            }
            Scalar::U16 => {
                let b = self.take::<2>(what)?;
                (if be {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                }) as f64
            }
            Scalar::I32 => {
                let b = self.take::<4>(what)?;
                (if be {
                    i32::from_be_bytes(b)
                } else {
                    i32::from_le_bytes(b)
                }) as f64
            }
            Scalar::U32 => {
                let b = self.take::<4>(what)?;
                (if be {
                    u32::from_be_bytes(b)
                } else {
                    u32::from_le_bytes(b)
                }) as f64
            }
            Scalar::F32 => {
                let b = self.take::<4>(what)?;
                (if be {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                }) as f64
            }
            Scalar::F64 => {
                let b = self.take::<8>(what)?;
                if be {
                    f64::from_be_bytes(b)
                } else {
                    f64::from_le_bytes(b)
                }
            }
        })
    }

    fn can_hold(&self, n: u64, t: Scalar) -> bool {
        let remaining = (self.data.len() - self.pos.min(self.data.len())) as u64;
        n.checked_mul(t.size() as u64)
            .is_some_and(|bytes| bytes <= remaining)
    }

    fn skip_fixed(&mut self, n: usize, size: usize, what: &str) -> Result<bool, LoadError> {
        match n.checked_mul(size).and_then(|b| self.pos.checked_add(b)) {
            Some(end) if end <= self.data.len() => {
                self.pos = end;
                Ok(true)
            }
            _ => Err(self.error(format!("unexpected end of file while skipping {what}"))),
        }
    }

    fn error(&self, message: String) -> LoadError {
        LoadError::at_offset(self.path, self.base + self.pos as u64, message)
    }
}

pub(super) struct AsciiReader<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    pub(super) line: usize,
    pub(super) path: &'a Path,
}

impl<'a> AsciiReader<'a> {
    fn token(&mut self, what: &str) -> Result<&'a [u8], LoadError> {
        while let Some(&b) = self.data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self
            .data
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.error(format!("unexpected end of file while reading {what}")));
        }
        Ok(&self.data[start..self.pos])
    }
}

impl Reader for AsciiReader<'_> {
    fn value(&mut self, t: Scalar, what: &str) -> Result<f64, LoadError> {
        let tok = self.token(what)?;
        let text = std::str::from_utf8(tok).unwrap_or("");
        let v = if t.is_int() {
            text.parse::<i64>().ok().map(|i| i as f64)
        } else {
            text.parse::<f64>().ok()
        };
        let (lo, hi) = t.range();
        match v {
            Some(v) if v >= lo && v <= hi || v.is_nan() && !t.is_int() => Ok(v),
            _ => Err(self.error(format!(
                "{what}: {:?} is not a valid {t:?} value",
                String::from_utf8_lossy(tok)
            ))),
        }
    }

    fn can_hold(&self, n: u64, _t: Scalar) -> bool {
        let remaining = (self.data.len() - self.pos.min(self.data.len())) as u64;
        n.saturating_mul(2) <= remaining.saturating_add(1)
    }

    fn skip_fixed(&mut self, _n: usize, _size: usize, _what: &str) -> Result<bool, LoadError> {
        Ok(false)
    }

    fn error(&self, message: String) -> LoadError {
        LoadError::at_line(self.path, self.line, message)
    }
}
