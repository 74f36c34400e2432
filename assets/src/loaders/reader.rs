//! A small bounds-checked little-endian reader shared by the binary loaders.
//! Every error carries the byte offset at which it happened.

use crate::error::{FormatError, FormatErrorKind};

/// Reads little-endian values from a byte slice; never panics.
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }
    pub fn pos(&self) -> usize {
        self.pos
    }
    pub fn len(&self) -> usize {
        self.data.len()
    }
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Moves to `offset`, which must lie within the file (or at its end).
    pub fn seek(&mut self, offset: usize, what: &'static str) -> Result<(), FormatError> {
        if offset > self.data.len() {
            return Err(FormatError::at_byte(
                self.pos,
                FormatErrorKind::Truncated {
                    what,
                    needed: offset as u64,
                    available: self.data.len() as u64,
                },
            ));
        }
        self.pos = offset;
        Ok(())
    }

    /// Takes `n` bytes, or reports a truncated file at the current offset.
    pub fn bytes(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], FormatError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len());
        match end.and_then(|e| self.data.get(self.pos..e)) {
            Some(s) => {
                self.pos += n;
                Ok(s)
            }
            None => Err(FormatError::at_byte(
                self.pos,
                FormatErrorKind::Truncated {
                    what,
                    needed: n as u64,
                    available: (self.data.len() - self.pos.min(self.data.len())) as u64,
                },
            )),
        }
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], FormatError> {
        let s = self.bytes(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub fn u16(&mut self, what: &'static str) -> Result<u16, FormatError> {
        Ok(u16::from_le_bytes(self.array(what)?))
    }
    pub fn u32(&mut self, what: &'static str) -> Result<u32, FormatError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    pub fn f32(&mut self, what: &'static str) -> Result<f32, FormatError> {
        Ok(f32::from_le_bytes(self.array(what)?))
    }

    /// Checks that an array of `count` elements of `elem_size` bytes starting at `offset`
    /// fits in the file. Call this BEFORE allocating anything sized by `count`.
    pub fn check_array(
        &self,
        field_offset: usize,
        field: &'static str,
        offset: usize,
        count: u64,
        elem_size: u64,
    ) -> Result<(), FormatError> {
        let available = self.data.len() as u64;
        let needed = count
            .checked_mul(elem_size)
            .and_then(|b| b.checked_add(offset as u64));
        match needed {
            Some(n) if n <= available => Ok(()),
            _ => Err(FormatError::at_byte(
                field_offset,
                FormatErrorKind::CountExceedsFile {
                    field,
                    count,
                    needed: needed.unwrap_or(u64::MAX),
                    available,
                    unit: "bytes",
                },
            )),
        }
    }

    /// Reads `count` f32 values (already checked to fit), rejecting NaN and Inf.
    /// `group` is the number of floats per element, for the element index in the error.
    pub fn finite_f32s(
        &mut self,
        count: usize,
        group: usize,
        what: &'static str,
    ) -> Result<Vec<f32>, FormatError> {
        let start = self.pos;
        let bytes = self.bytes(count.saturating_mul(4), what)?;
        let mut out = Vec::with_capacity(count);
        for (i, c) in bytes.chunks_exact(4).enumerate() {
            let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if !v.is_finite() {
                return Err(FormatError::at_byte(
                    start + i * 4,
                    FormatErrorKind::NonFinite {
                        what,
                        index: (i / group.max(1)) as u64,
                    },
                ));
            }
            out.push(v);
        }
        Ok(out)
    }
}

/// Checks a header count against zero and an absurdity bound.
pub fn check_count(
    offset: usize,
    field: &'static str,
    value: u64,
    max: u64,
) -> Result<(), FormatError> {
    if value == 0 {
        return Err(FormatError::at_byte(
            offset,
            FormatErrorKind::ZeroCount { field },
        ));
    }
    if value > max {
        return Err(FormatError::at_byte(
            offset,
            FormatErrorKind::AbsurdCount { field, value, max },
        ));
    }
    Ok(())
}

/// Little-endian writer used by the format writers.
#[derive(Default)]
pub struct Writer {
    pub buf: Vec<u8>,
}

impl Writer {
    pub fn u16(&mut self, v: u16) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u32(&mut self, v: u32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f32(&mut self, v: f32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub fn zeros(&mut self, n: usize) {
        self.buf.resize(self.buf.len() + n, 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_and_reports_offsets() {
        let d = [1u8, 0, 0, 0, 0, 0, 0x80, 0x7f];
        let mut r = Reader::new(&d);
        assert_eq!(r.u32("a").unwrap(), 1);
        let e = r.finite_f32s(1, 1, "x").unwrap_err();
        assert_eq!(e.location, crate::error::Location::Byte(4));
        let mut r = Reader::new(&d);
        r.seek(6, "s").unwrap();
        let e = r.u32("b").unwrap_err();
        assert!(matches!(e.kind, FormatErrorKind::Truncated { .. }));
        assert!(r.check_array(0, "n", 0, u64::MAX, 4).is_err());
        assert!(r.check_array(0, "n", 4, 1, 4).is_ok());
    }
}
