//! Framing: `0x00, COBS(postcard(message) ++ CRC-32 little-endian), 0x00`.
//!
//! The leading delimiter closes whatever garbage preceded the frame, so noise on an idle line
//! costs at most one rejected pseudo-frame and never the next real one.
//!
//! The CRC also covers a direction byte that is not sent (1 for requests, 2 for replies): a line
//! that echoes or loops back the host's own frames (a misconfigured port, a loopback adapter)
//! shows up as damaged frames, never as replies.

use super::crc::CRC32;
use super::max_size::{max, MaxSize};
use super::messages::{Fault, Header, Reply, Request};
use serde::Serialize;

/// Bytes of the checksum after the payload.
pub const CRC_LEN: usize = 4;

/// Largest payload (postcard message) of any frame.
pub const MAX_PAYLOAD: usize = max(Request::MAX_SIZE, Reply::MAX_SIZE);

/// Largest frame between delimiters (COBS of payload and CRC).
pub const MAX_FRAME: usize = cobs::max_encoding_length(MAX_PAYLOAD + CRC_LEN);

/// Largest frame on the wire, both delimiters included.
pub const MAX_WIRE_FRAME: usize = MAX_FRAME + 2;

/// Scratch [`encode_frame`] needs for any message: the payload with its CRC, and the frame.
pub const ENCODE_SCRATCH: usize = scratch_for(MAX_PAYLOAD);

/// Scratch [`encode_frame`] needs for a [`ReplyBody::Fault`](super::ReplyBody::Fault) reply: what
/// a panic handler can afford on whatever stack is left.
pub const FAULT_SCRATCH: usize = scratch_for(Header::MAX_SIZE + 1 + Fault::MAX_SIZE);

const fn scratch_for(payload: usize) -> usize {
    payload + CRC_LEN + cobs::max_encoding_length(payload + CRC_LEN) + 2
}

/// Why a frame could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError {
    /// The message does not fit the scratch buffer (a bound in `max_size` is wrong).
    TooLarge,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::TooLarge => f.write_str("the message does not fit the frame buffer"),
        }
    }
}

impl core::error::Error for EncodeError {}

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
    let mut c = CRC32.digest();
    c.update(&[direction]);
    c.update(payload);
    c.finalize()
}

/// Serialises `msg` into `scratch` (at least [`ENCODE_SCRATCH`] bytes for any message) and
/// hands the complete frame, delimiters included, to `out`. Returns its length.
///
/// ```
/// use planner_core::wire::{encode_frame, Header, Request, RequestBody, ENCODE_SCRATCH};
///
/// let ping = Request { header: Header::new(7), body: RequestBody::Ping { nonce: 1 } };
/// let mut scratch = [0u8; ENCODE_SCRATCH];
/// let mut line = Vec::new();
/// let n = encode_frame(&ping, &mut scratch, &mut |b: &[u8]| line.extend_from_slice(b)).unwrap();
/// assert_eq!((line.len(), line[0], line[n - 1]), (n, 0, 0));
/// ```
pub fn encode_frame<T: Serialize + Directed>(
    msg: &T,
    scratch: &mut [u8],
    out: &mut dyn FnMut(&[u8]),
) -> Result<usize, EncodeError> {
    let payload_cap = scratch.len().saturating_sub(CRC_LEN).min(MAX_PAYLOAD);
    let n = postcard::to_slice(msg, &mut scratch[..payload_cap])
        .map_err(|_| EncodeError::TooLarge)?
        .len();
    frame_in_place(T::DIRECTION, n, scratch, out)
}

/// Frames bytes that are not necessarily a message (tests of the receiving side use it to build
/// frames with a valid CRC around garbage), like [`encode_frame`].
pub fn encode_payload(
    direction: u8,
    payload: &[u8],
    scratch: &mut [u8],
    out: &mut dyn FnMut(&[u8]),
) -> Result<usize, EncodeError> {
    scratch
        .get_mut(..payload.len())
        .ok_or(EncodeError::TooLarge)?
        .copy_from_slice(payload);
    frame_in_place(direction, payload.len(), scratch, out)
}

/// Appends the CRC to the `n` payload bytes at the start of `scratch`, stuffs them into the rest
/// of `scratch` and hands out the delimited frame.
fn frame_in_place(
    direction: u8,
    n: usize,
    scratch: &mut [u8],
    out: &mut dyn FnMut(&[u8]),
) -> Result<usize, EncodeError> {
    let crc = frame_crc(direction, &scratch[..n]);
    scratch
        .get_mut(n..n + CRC_LEN)
        .ok_or(EncodeError::TooLarge)?
        .copy_from_slice(&crc.to_le_bytes());
    let (raw, frame) = scratch.split_at_mut(n + CRC_LEN);
    let body = frame.get_mut(1..).ok_or(EncodeError::TooLarge)?;
    let len = cobs::try_encode(raw, body).map_err(|_| EncodeError::TooLarge)?;
    let wire = frame.get_mut(..len + 2).ok_or(EncodeError::TooLarge)?;
    wire[0] = 0;
    wire[len + 1] = 0;
    out(wire);
    Ok(wire.len())
}

/// A frame that was received but must not be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// More than [`MAX_FRAME`] bytes before a delimiter; the rest was skipped.
    TooLong,
    /// The stuffing was cut or too few bytes for a checksum.
    Truncated,
    /// The CRC-32 does not match.
    BadCrc,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FrameError::TooLong => "frame longer than the decoder's buffer",
            FrameError::Truncated => "frame cut short",
            FrameError::BadCrc => "frame failed its CRC-32",
        })
    }
}

impl core::error::Error for FrameError {}

/// Accumulates line bytes and yields checked payloads. Fixed buffer of `N` bytes.
pub struct FrameDecoder<const N: usize> {
    // A flag rather than the direction byte, so a request decoder is all zero bytes and a
    // `static` holding one lives in `.bss` (no initial image in flash).
    expects_replies: bool,
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
        Self::expecting(false)
    }

    /// An empty decoder of replies (the host's side).
    pub const fn for_replies() -> Self {
        Self::expecting(true)
    }

    const fn expecting(expects_replies: bool) -> Self {
        FrameDecoder {
            expects_replies,
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
    ///
    /// ```
    /// use planner_core::wire::{
    ///     encode_frame, FrameDecoder, FrameError, Header, Request, RequestBody, ENCODE_SCRATCH,
    ///     MAX_FRAME,
    /// };
    ///
    /// let ping = Request { header: Header::new(7), body: RequestBody::Ping { nonce: 1 } };
    /// let mut scratch = [0u8; ENCODE_SCRATCH];
    /// let mut line = Vec::new();
    /// encode_frame(&ping, &mut scratch, &mut |b: &[u8]| line.extend_from_slice(b)).unwrap();
    ///
    /// // The device's side: bytes in, one payload out at the closing delimiter.
    /// let mut decoder = FrameDecoder::<MAX_FRAME>::for_requests();
    /// let mut received = Vec::new();
    /// for &b in &line {
    ///     if let Some(frame) = decoder.push(b) {
    ///         received.push(frame.map(<[u8]>::to_vec));
    ///     }
    /// }
    /// assert_eq!(received.len(), 1);
    /// let got: Request = postcard::from_bytes(received[0].as_ref().unwrap()).unwrap();
    /// assert_eq!(got, ping);
    ///
    /// // One bit flipped on the line: the frame is reported damaged, never handed on.
    /// line[2] ^= 0x10;
    /// let mut faults = Vec::new();
    /// for &b in &line {
    ///     if let Some(frame) = decoder.push(b) {
    ///         faults.push(frame.map(<[u8]>::to_vec));
    ///     }
    /// }
    /// assert_eq!(faults, [Err(FrameError::BadCrc)]);
    /// ```
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
        // The buffer holds no zero (zeros delimit), so the crate decodes exactly `len` bytes.
        let n = match cobs::decode_in_place(&mut self.buf[..len]) {
            Ok(n) if n > CRC_LEN => n,
            _ => return Some(Err(FrameError::Truncated)),
        };
        let body = n - CRC_LEN;
        let mut crc_bytes = [0u8; CRC_LEN];
        crc_bytes.copy_from_slice(&self.buf[body..n]);
        let direction = if self.expects_replies {
            <Reply as Directed>::DIRECTION
        } else {
            <Request as Directed>::DIRECTION
        };
        if frame_crc(direction, &self.buf[..body]) != u32::from_le_bytes(crc_bytes) {
            return Some(Err(FrameError::BadCrc));
        }
        Some(Ok(&self.buf[..body]))
    }
}
