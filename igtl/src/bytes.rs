//! Big-endian cursors over byte slices: reading past the end or writing past the buffer is an
//! error, never a panic, so the decoders can be written straight from the spec's tables.

use crate::Error;

/// Reads big-endian fields from the front of a slice.
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes }
    }

    /// Bytes not read yet.
    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len()
    }

    /// The next `n` bytes (`Malformed` if fewer are left: the caller's sizes were inconsistent).
    pub(crate) fn take(&mut self, n: usize) -> Result<&'a [u8], Error> {
        if n > self.bytes.len() {
            return Err(Error::Malformed);
        }
        let (head, tail) = self.bytes.split_at(n);
        self.bytes = tail;
        Ok(head)
    }

    pub(crate) fn array<const K: usize>(&mut self) -> Result<[u8; K], Error> {
        let mut out = [0u8; K];
        out.copy_from_slice(self.take(K)?);
        Ok(out)
    }

    pub(crate) fn u16(&mut self) -> Result<u16, Error> {
        self.array().map(u16::from_be_bytes)
    }

    pub(crate) fn u32(&mut self) -> Result<u32, Error> {
        self.array().map(u32::from_be_bytes)
    }

    pub(crate) fn u64(&mut self) -> Result<u64, Error> {
        self.array().map(u64::from_be_bytes)
    }

    pub(crate) fn i64(&mut self) -> Result<i64, Error> {
        self.array().map(i64::from_be_bytes)
    }

    pub(crate) fn f32(&mut self) -> Result<f32, Error> {
        self.u32().map(f32::from_bits)
    }

    /// Three floats that must be finite: coordinates feed a planner, where NaN spreads silently.
    pub(crate) fn finite3(&mut self) -> Result<[f32; 3], Error> {
        let v = [self.f32()?, self.f32()?, self.f32()?];
        if v.iter().all(|x| x.is_finite()) {
            Ok(v)
        } else {
            Err(Error::NotFinite)
        }
    }
}

/// Writes big-endian fields into a caller's buffer.
pub(crate) struct Writer<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(out: &'a mut [u8]) -> Self {
        Writer { out, len: 0 }
    }

    /// Bytes written so far.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    pub(crate) fn put(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let end = self
            .len
            .checked_add(bytes.len())
            .ok_or(Error::BufferTooSmall)?;
        let slot = self
            .out
            .get_mut(self.len..end)
            .ok_or(Error::BufferTooSmall)?;
        slot.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    pub(crate) fn zeros(&mut self, n: usize) -> Result<(), Error> {
        let end = self.len.checked_add(n).ok_or(Error::BufferTooSmall)?;
        let slot = self
            .out
            .get_mut(self.len..end)
            .ok_or(Error::BufferTooSmall)?;
        slot.fill(0);
        self.len = end;
        Ok(())
    }

    pub(crate) fn u8(&mut self, v: u8) -> Result<(), Error> {
        self.put(&[v])
    }

    pub(crate) fn u16(&mut self, v: u16) -> Result<(), Error> {
        self.put(&v.to_be_bytes())
    }

    pub(crate) fn u32(&mut self, v: u32) -> Result<(), Error> {
        self.put(&v.to_be_bytes())
    }

    pub(crate) fn u64(&mut self, v: u64) -> Result<(), Error> {
        self.put(&v.to_be_bytes())
    }

    pub(crate) fn i64(&mut self, v: i64) -> Result<(), Error> {
        self.put(&v.to_be_bytes())
    }

    pub(crate) fn f32(&mut self, v: f32) -> Result<(), Error> {
        self.u32(v.to_bits())
    }

    pub(crate) fn f32s(&mut self, vs: &[f32]) -> Result<(), Error> {
        vs.iter().try_for_each(|&v| self.f32(v))
    }
}
