//! A protocol session with one device: its state, and the frame layer under every request.
//!
//! Every exchange sends one request and waits up to `timeout` for its answer; on silence, or on
//! a damaged frame (caught by the CRC here, or reported by the device), it sends the request
//! again, at most `retries` times, then gives up with [`LinkError::NoAnswer`]. Every request is
//! idempotent, so a repeat never does harm. Chunk sizes shrink when frames get damaged and grow
//! back as they get through, so a noisy line still carries a plan.

use crate::error::{too_large, LinkError};
use crate::transport::Transport;
use planner_core::wire::{
    encode_frame, FrameDecoder, Header, Reply, Request, RequestBody, ENCODE_SCRATCH, MAX_CHUNK,
    MAX_FRAME,
};
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// Smallest chunk the client shrinks to on a noisy line.
pub(crate) const MIN_CHUNK: usize = 16;

/// Timeouts and retries.
#[derive(Clone, Copy, Debug)]
pub struct ClientConfig {
    /// Longest wait for an answer (and longest silence while planning).
    pub timeout: Duration,
    /// Repeats of a request before giving up.
    pub retries: u32,
}

impl Default for ClientConfig {
    fn default() -> Self {
        ClientConfig {
            timeout: Duration::from_secs(5),
            retries: 5,
        }
    }
}

/// What happened on the link.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Frames sent.
    pub sent: u64,
    /// Frames sent again (after silence or a damaged frame).
    pub retried: u64,
    /// Damaged frames detected: by the CRC here, or reported by the device.
    pub detected: u64,
    /// Waits that ended in silence.
    pub timeouts: u64,
    /// Bytes sent and received.
    pub bytes_out: u64,
    /// Bytes received.
    pub bytes_in: u64,
}

/// A frame from the device.
pub(crate) enum Event {
    /// An intact reply.
    Reply(Box<Reply>),
    /// A frame that failed its CRC, stuffing or decoding.
    Damaged,
}

/// A protocol session with one device.
pub struct Client<T: Transport> {
    pub(crate) link: T,
    pub(crate) config: ClientConfig,
    decoder: FrameDecoder<MAX_FRAME>,
    events: VecDeque<Event>,
    pub(crate) stats: LinkStats,
    next_id: u16,
    /// Chunk size of the next upload or fetch frame.
    pub(crate) chunk: usize,
    /// The device's largest chunk (from its hello).
    pub(crate) max_chunk: usize,
    /// A `Finished` seen for (request id, result length, result CRC).
    pub(crate) finished: Option<(u16, u16, u32)>,
    /// A plan request this client gave up on, which the device may still be running.
    pub(crate) abandoned: Option<u16>,
    /// While the device plans: wait this long in silence, asking nothing (see
    /// [`Client::with_quiet_planning`]); `None`: ask for the status after `timeout`.
    pub(crate) quiet_planning: Option<Duration>,
}

impl<T: Transport> Client<T> {
    /// A client on `link`. Request ids start at a per-process value so that two sessions in a
    /// row do not reuse each other's.
    pub fn new(link: T, config: ClientConfig) -> Self {
        let seed = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0)
            ^ std::process::id();
        Client {
            link,
            config,
            decoder: FrameDecoder::for_replies(),
            events: VecDeque::new(),
            stats: LinkStats::default(),
            next_id: (seed as u16).max(1),
            chunk: MAX_CHUNK,
            max_chunk: MAX_CHUNK,
            finished: None,
            abandoned: None,
            quiet_planning: None,
        }
    }

    /// Numbers requests from `first` on instead of a per-process value. Measurements want this:
    /// an id's length on the wire (a postcard varint) changes the device's work for every frame,
    /// so the same small ids make instruction counts repeat from run to run.
    pub fn with_first_id(mut self, first: u16) -> Self {
        self.next_id = first.wrapping_sub(1);
        self
    }

    /// Sends nothing while the device plans, however long it stays silent, up to `limit` of
    /// silence ([`LinkError::NoResult`] after that). Without it the client asks for the status
    /// after every `timeout` of silence, which a measurement of the device's work would count.
    pub fn with_quiet_planning(mut self, limit: Duration) -> Self {
        self.quiet_planning = Some(limit);
        self
    }

    /// Counters so far.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// The transport (for tests that inspect the simulated device).
    pub fn link(&self) -> &T {
        &self.link
    }

    pub(crate) fn new_id(&mut self) -> u16 {
        self.next_id = self.next_id.wrapping_add(1).max(1);
        self.next_id
    }

    /// Sends request `body` with id `id`, once.
    pub(crate) fn send(&mut self, id: u16, body: &RequestBody) -> Result<(), LinkError> {
        let req = Request {
            header: Header::new(id),
            body: body.clone(),
        };
        let mut scratch = [0u8; ENCODE_SCRATCH];
        let mut out = Vec::with_capacity(MAX_FRAME + 2);
        encode_frame(&req, &mut scratch, &mut |b: &[u8]| out.extend_from_slice(b))
            .map_err(|_| too_large("request too large to encode"))?;
        self.stats.sent += 1;
        self.stats.bytes_out += out.len() as u64;
        self.link.send(&out)?;
        Ok(())
    }

    /// Sends raw bytes (for tests of malformed input).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.stats.bytes_out += bytes.len() as u64;
        Ok(self.link.send(bytes)?)
    }

    /// The next frame that arrives before `deadline`, if any.
    pub(crate) fn next_event(&mut self, deadline: Instant) -> Result<Option<Event>, LinkError> {
        let mut buf = [0u8; 512];
        loop {
            if let Some(e) = self.events.pop_front() {
                return Ok(Some(e));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            let n = self.link.recv(&mut buf, deadline - now)?;
            if n == 0 {
                return Ok(None);
            }
            self.stats.bytes_in += n as u64;
            for &b in &buf[..n] {
                if let Some(ev) = self.decoder.push(b) {
                    let ev = match ev.map(postcard::from_bytes::<Reply>) {
                        Ok(Ok(reply)) => Event::Reply(Box::new(reply)),
                        _ => Event::Damaged,
                    };
                    self.events.push_back(ev);
                }
            }
        }
    }
}
