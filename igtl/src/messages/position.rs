//! POSITION (`Documents/Protocol/position.md`): 7 × f32, position (mm) then the quaternion
//! x, y, z, w.
//!
//! The reference library also reads 12-byte (no quaternion) and 24-byte (quaternion without w)
//! bodies, but the protocol document defines only the 28-byte one, so only that one is read.

use crate::bytes::{Reader, Writer};
use crate::messages::transform::RIGID_TOLERANCE;
use crate::Error;

/// Bytes of a POSITION body.
pub const POSITION_SIZE: usize = 28;

/// A position and a unit quaternion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Position {
    position: [f32; 3],
    quaternion: [f32; 4],
}

impl Position {
    /// From a position in mm and a quaternion `[x, y, z, w]`; `NotRigid` unless the quaternion's
    /// squared norm is within [`RIGID_TOLERANCE`] of 1, `NotFinite` for a NaN or infinite
    /// coordinate.
    pub fn new(position: [f32; 3], quaternion: [f32; 4]) -> Result<Self, Error> {
        if !position.iter().all(|p| p.is_finite()) {
            return Err(Error::NotFinite);
        }
        let norm2: f32 = quaternion.iter().map(|q| q * q).sum();
        // Written as a test that NaN fails.
        let unit = (norm2 - 1.0).abs() <= RIGID_TOLERANCE;
        if !unit {
            return Err(Error::NotRigid);
        }
        Ok(Position {
            position,
            quaternion,
        })
    }

    /// The position in mm.
    pub fn position(&self) -> [f32; 3] {
        self.position
    }

    /// The orientation as `[x, y, z, w]`.
    pub fn quaternion(&self) -> [f32; 4] {
        self.quaternion
    }

    /// Writes the 28-byte body; returns 28 or `BufferTooSmall`.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut w = Writer::new(out);
        w.f32s(&self.position)?;
        w.f32s(&self.quaternion)?;
        Ok(w.len())
    }

    /// Reads a 28-byte body: `BadBodySize` for another size, then as [`Position::new`].
    pub fn decode(content: &[u8]) -> Result<Self, Error> {
        if content.len() != POSITION_SIZE {
            return Err(Error::BadBodySize);
        }
        let mut r = Reader::new(content);
        let position = [r.f32()?, r.f32()?, r.f32()?];
        let quaternion = [r.f32()?, r.f32()?, r.f32()?, r.f32()?];
        Position::new(position, quaternion)
    }
}
