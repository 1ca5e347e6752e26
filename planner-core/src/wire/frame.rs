//! Framing: `0x00, COBS(postcard(message) ++ CRC-32 little-endian), 0x00`.
//!
//! The leading delimiter closes whatever garbage preceded the frame, so noise on an idle line
//! costs at most one rejected pseudo-frame and never the next real one.
//!
//! The CRC also covers a direction byte that is not sent (1 for requests, 2 for replies): a line
//! that echoes or loops back the host's own frames (a misconfigured port, a loopback adapter)
//! shows up as damaged frames, never as replies.

use super::cobs;
use super::crc::Crc32;
use super::max_size::{max, MaxSize};
use super::messages::{Reply, Request};
use serde::Serialize;

/// Bytes of the checksum after the payload.
pub const CRC_LEN: usize = 4;

/// Largest payload (postcard message) of any frame.
pub const MAX_PAYLOAD: usize = max(Request::MAX_SIZE, Reply::MAX_SIZE);

/// Largest frame between delimiters (COBS of payload and CRC).
pub const MAX_FRAME: usize = cobs::max_encoded_len(MAX_PAYLOAD + CRC_LEN);

/// Largest frame on the wire, both delimiters included.
pub const MAX_WIRE_FRAME: usize = MAX_FRAME + 2;

/// Why a frame could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The message does not fit the scratch buffer (a bound in `max_size` is wrong).
    TooLarge,
}

/// Which way a message travels; part of its frame's CRC.
pub trait Directed {
    /// 1 for host to device, 2 for device to host.
    const DIRECTION: u8;
}

impl Directed for Request {
    const DIRECTION: u8 = 1;
}

impl Directed for Reply {
    const DIRECTION: u8 = 2;
}

/// The frame checksum of `payload` travelling in `direction`.
pub fn frame_crc(direction: u8, payload: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(&[direction]);
    c.update(payload);
    c.value()
}

/// Serialises `msg` into `scratch` and hands the complete frame to `out` piece by piece.
/// Returns the number of bytes handed out.
pub fn encode_frame<T: Serialize + Directed>(
    msg: &T,
    scratch: &mut [u8],
    out: &mut dyn FnMut(&[u8]),
) -> Result<usize, EncodeError> {
    let payload_cap = scratch.len().saturating_sub(CRC_LEN);
    let n = postcard::to_slice(msg, &mut scratch[..payload_cap])
        .map_err(|_| EncodeError::TooLarge)?
        .len();
    let crc = frame_crc(T::DIRECTION, &scratch[..n]);
    scratch[n..n + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
    let mut written = 2;
    out(&[0]);
    cobs::encode(&scratch[..n + CRC_LEN], &mut |b: &[u8]| {
        written += b.len();
        out(b);
    });
    out(&[0]);
    Ok(written)
}

/// A frame that was received but must not be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// More than [`MAX_FRAME`] bytes before a delimiter; the rest was skipped.
    TooLong,
    /// The stuffing was cut or too few bytes for a checksum.
    Truncated,
    /// The CRC-32 does not match.
    BadCrc,
}

/// Accumulates line bytes and yields checked payloads. Fixed buffer of `N` bytes.
pub struct FrameDecoder<const N: usize> {
    direction: u8,
    buf: [u8; N],
    len: usize,
    skip: Skip,
}

/// Why bytes are being skipped up to the next delimiter.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Skip {
    No,
    TooLong,
    Resync,
}

impl<const N: usize> FrameDecoder<N> {
    /// An empty decoder of requests (the device's side). There is no `new`: a decoder that
    /// expects the wrong direction rejects every frame as damaged, so the side is always named.
    pub const fn for_requests() -> Self {
        Self::expecting(<Request as Directed>::DIRECTION)
    }

    /// An empty decoder of replies (the host's side).
    pub const fn for_replies() -> Self {
        Self::expecting(<Reply as Directed>::DIRECTION)
    }

    const fn expecting(direction: u8) -> Self {
        FrameDecoder {
            direction,
            buf: [0; N],
            len: 0,
            skip: Skip::No,
        }
    }

    /// Forgets the frame in progress and skips bytes up to the next delimiter (after lost bytes).
    pub fn resync(&mut self) {
        self.len = 0;
        self.skip = Skip::Resync;
    }

    /// Takes one byte; at a delimiter that ends a non-empty frame, returns its payload or fault.
    pub fn push(&mut self, byte: u8) -> Option<Result<&[u8], FrameError>> {
        if byte != 0 {
            if self.skip != Skip::No {
                return None;
            }
            if self.len == N {
                self.skip = Skip::TooLong;
                self.len = 0;
                return None;
            }
            self.buf[self.len] = byte;
            self.len += 1;
            return None;
        }
        let len = core::mem::take(&mut self.len);
        match core::mem::replace(&mut self.skip, Skip::No) {
            Skip::TooLong => return Some(Err(FrameError::TooLong)),
            // The frame cut by lost bytes was reported when they were lost.
            Skip::Resync => return None,
            Skip::No => {}
        }
        if len == 0 {
            return None;
        }
        let n = match cobs::decode_in_place(&mut self.buf, len) {
            Ok(n) if n > CRC_LEN => n,
            _ => return Some(Err(FrameError::Truncated)),
        };
        let body = n - CRC_LEN;
        let mut crc_bytes = [0u8; CRC_LEN];
        crc_bytes.copy_from_slice(&self.buf[body..n]);
        if frame_crc(self.direction, &self.buf[..body]) != u32::from_le_bytes(crc_bytes) {
            return Some(Err(FrameError::BadCrc));
        }
        Some(Ok(&self.buf[..body]))
    }
}
