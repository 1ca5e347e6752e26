//! Frames out of a byte stream (a TCP connection) as its bytes arrive, in bounded memory.
//!
//! Only the body of a message this codec reads, and that fits the decoder's `N` bytes, is
//! buffered; any other body is skipped by the header's body size as it streams past, which is
//! how the spec lets old receivers pass over newer types.
//!
//! OpenIGTLink has no sync marker. After a header that is not one (unsupported version, type
//! name not NUL-padded ASCII) the decoder reports it once and then slides one byte at a time
//! until 58 bytes read as a header again.

use crate::frame::{decode_body, Frame};
use crate::header::{body_size_of, Header, HEADER_SIZE};
use crate::messages::Message;
use crate::Error;

/// What a [`FrameDecoder`] passed over without returning it as a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stats {
    /// Messages of a type this codec does not read, skipped by body size.
    pub skipped_unknown: u32,
    /// Messages of a known type whose body is larger than the decoder's buffer, skipped.
    pub skipped_too_large: u32,
    /// Bytes dropped while looking for a header after one that was not.
    pub discarded_bytes: u64,
}

enum State {
    /// Collecting the 58 header bytes.
    Header,
    /// Collecting a body to decode.
    Body { header: Header, filled: usize },
    /// Passing over a body.
    Skip { remaining: u64 },
}

/// A streaming decoder holding at most one body of up to `N` bytes.
///
/// ```
/// use needle_igtl::{encode_frame, FrameDecoder, FrameInfo, Message, Position};
///
/// let pose = Position::new([1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])?;
/// let mut wire = [0u8; 2 * 86];
/// let n = encode_frame(&FrameInfo::new("Probe")?, &Message::Position(pose), &mut wire)?;
/// wire.copy_within(..n, n); // two frames back to back
///
/// let mut decoder = FrameDecoder::<256>::new();
/// let mut frames = 0;
/// for chunk in wire.chunks(5) {
///     // TCP delivers arbitrary pieces: feed each until it is used up.
///     let mut input = chunk;
///     while let Some(result) = decoder.feed(&mut input) {
///         assert_eq!(result?.message, Message::Position(pose));
///         frames += 1;
///     }
/// }
/// assert_eq!(frames, 2);
/// # Ok::<(), needle_igtl::Error>(())
/// ```
pub struct FrameDecoder<const N: usize> {
    head: [u8; HEADER_SIZE],
    head_len: usize,
    body: [u8; N],
    state: State,
    hunting: bool,
    stats: Stats,
}

impl<const N: usize> Default for FrameDecoder<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FrameDecoder<N> {
    /// A decoder at the start of a stream.
    pub const fn new() -> Self {
        FrameDecoder {
            head: [0; HEADER_SIZE],
            head_len: 0,
            body: [0; N],
            state: State::Header,
            hunting: false,
            stats: Stats {
                skipped_unknown: 0,
                skipped_too_large: 0,
                discarded_bytes: 0,
            },
        }
    }

    /// What was passed over so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Forgets any partial frame (a new connection); keeps the stats.
    pub fn reset(&mut self) {
        self.head_len = 0;
        self.state = State::Header;
        self.hunting = false;
    }

    /// Consumes bytes from the front of `input` until a frame completes (`Some(Ok)`), a frame
    /// or header is rejected (`Some(Err)`: the stream goes on after it), or `input` is used up
    /// (`None`). Call again with the rest of `input` until `None`.
    pub fn feed(&mut self, input: &mut &[u8]) -> Option<Result<Frame, Error>> {
        loop {
            match &mut self.state {
                State::Header => {
                    let want = HEADER_SIZE - self.head_len;
                    let (now, rest) = input.split_at(want.min(input.len()));
                    self.head[self.head_len..self.head_len + now.len()].copy_from_slice(now);
                    self.head_len += now.len();
                    *input = rest;
                    if self.head_len < HEADER_SIZE {
                        return None;
                    }
                    if let Some(err) = self.on_header() {
                        return Some(Err(err));
                    }
                }
                State::Skip { remaining } => {
                    let n = usize::try_from(*remaining).map_or(input.len(), |r| r.min(input.len()));
                    *input = &input[n..];
                    *remaining -= n as u64;
                    if *remaining > 0 {
                        return None;
                    }
                    self.state = State::Header;
                }
                State::Body { header, filled } => {
                    // Body state is only entered with body_size <= N.
                    let len = header.body_size as usize;
                    let (now, rest) = input.split_at((len - *filled).min(input.len()));
                    self.body[*filled..*filled + now.len()].copy_from_slice(now);
                    *filled += now.len();
                    *input = rest;
                    if *filled < len {
                        return None;
                    }
                    if let State::Body { header, .. } =
                        core::mem::replace(&mut self.state, State::Header)
                    {
                        return Some(decode_body(&header, &self.body[..len]));
                    }
                }
            }
        }
    }

    /// Routes a complete header to its body; returns an error to report, if any.
    fn on_header(&mut self) -> Option<Error> {
        self.head_len = 0;
        match Header::decode(&self.head) {
            Ok(header) => {
                self.hunting = false;
                self.state = if !Message::is_known(&header.type_name) {
                    self.stats.skipped_unknown = self.stats.skipped_unknown.saturating_add(1);
                    State::Skip {
                        remaining: header.body_size,
                    }
                } else if header.body_size > N as u64 {
                    self.stats.skipped_too_large = self.stats.skipped_too_large.saturating_add(1);
                    State::Skip {
                        remaining: header.body_size,
                    }
                } else {
                    State::Body { header, filled: 0 }
                };
                None
            }
            Err(Error::NotUtf8) => {
                // A real header with a bad device name: its body size still holds.
                self.hunting = false;
                self.state = State::Skip {
                    remaining: body_size_of(&self.head),
                };
                Some(Error::NotUtf8)
            }
            Err(err) => {
                self.head.copy_within(1.., 0);
                self.head_len = HEADER_SIZE - 1;
                self.stats.discarded_bytes = self.stats.discarded_bytes.saturating_add(1);
                let first = !self.hunting;
                self.hunting = true;
                first.then_some(err)
            }
        }
    }
}
