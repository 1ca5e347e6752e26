//! A protocol session with one device: its state, and the frame layer under every request.
//!
//! Every exchange sends one request until an answer to it arrives (the policy is in `exchange`):
//! at once again after a damaged frame, again after a resend interval adapted to the measured
//! round trip when the line is silent, until the device has been silent for `timeout`, the
//! request has been repeated `retries` times, or the operation's `deadline` passes. Every
//! request is idempotent, so a repeat never does harm, and replies are matched to the request
//! by id and offset, so the answers to earlier attempts are dropped. Chunk sizes shrink when
//! frames get damaged and grow back as they get through, so a noisy line still carries a plan.

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

/// Smallest resend interval after silence.
pub(crate) const MIN_RESEND: Duration = Duration::from_millis(10);

/// Resend interval before any round trip has been measured.
pub(crate) const FIRST_RESEND: Duration = Duration::from_millis(50);

/// Time and count bounds of the retry policy.
#[derive(Clone, Copy, Debug)]
pub struct ClientConfig {
    /// Silence allowed per exchange: it fails once the device has sent no frame at all (intact
    /// or damaged) for this long. Also the longest silence while the device plans.
    pub timeout: Duration,
    /// Most repeats of one request (after damaged frames or silence).
    pub retries: u32,
    /// Longest time one operation (a hello, a ping, a whole plan) may take; `None`: no bound
    /// but the others.
    pub deadline: Option<Duration>,
}

impl ClientConfig {
    /// The defaults of `needle send`: 5 s of silence, 40 repeats, 120 s for a whole plan.
    pub const DEFAULT: ClientConfig = ClientConfig {
        timeout: Duration::from_secs(5),
        retries: 40,
        deadline: Some(Duration::from_secs(120)),
    };
}

impl Default for ClientConfig {
    fn default() -> Self {
        Self::DEFAULT
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
    /// Waits that ended in silence (a resend interval passed without a frame).
    pub timeouts: u64,
    /// Intact replies dropped because they answer an earlier request or attempt.
    pub stale: u64,
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
    /// The request id of the last plan fetched whole (steering runs under it).
    pub(crate) last_plan: Option<u16>,
    /// A plan request this client gave up on, which the device may still be running.
    pub(crate) abandoned: Option<u16>,
    /// While the device plans: wait this long in silence, asking nothing (see
    /// [`Client::with_quiet_planning`]); `None`: ask for the status after `timeout`.
    pub(crate) quiet_planning: Option<Duration>,
    /// Smoothed round trip and its mean deviation (answers to first sends only).
    pub(crate) rtt: Option<(Duration, Duration)>,
    /// End of the current operation (from `config.deadline`) and of everything (`set_deadline`).
    pub(crate) op_end: Option<(Instant, Duration)>,
    /// Start of the current operation.
    pub(crate) op_start: Instant,
    pub(crate) until: Option<(Instant, Duration)>,
    /// When the frame now arriving last received a byte, if one is open.
    open_since: Option<Instant>,
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
            last_plan: None,
            abandoned: None,
            quiet_planning: None,
            rtt: None,
            op_end: None,
            op_start: Instant::now(),
            until: None,
            open_since: None,
        }
    }

    /// Ends everything this client does from now on within `limit` (a whole `needle send`, the
    /// hello included), on top of the per-operation `deadline`.
    /// A limit too far to represent (`Duration::MAX`) means none.
    pub fn set_deadline(&mut self, limit: Duration) {
        self.until = Instant::now().checked_add(limit).map(|end| (end, limit));
    }

    /// Starts the clock of one operation.
    pub(crate) fn begin(&mut self) {
        self.op_start = Instant::now();
        self.op_end = self
            .config
            .deadline
            .and_then(|d| Some((Instant::now().checked_add(d)?, d)));
    }

    /// The earliest deadline in force, with its length.
    pub(crate) fn deadline(&self) -> Option<(Instant, Duration)> {
        match (self.op_end, self.until) {
            (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
            (a, b) => a.or(b),
        }
    }

    /// How long to wait in silence before sending a request again: the measured round trip
    /// with four deviations (Jacobson's estimator), at least [`MIN_RESEND`], at most half the
    /// silence allowed; doubled for each silent attempt of the same request.
    pub(crate) fn resend_interval(&self, silent_attempts: u32) -> Duration {
        let base = match self.rtt {
            Some((srtt, dev)) => srtt + 4 * dev,
            None => FIRST_RESEND,
        };
        let cap = (self.config.timeout / 2).max(MIN_RESEND);
        (base * 2u32.saturating_pow(silent_attempts.min(16)))
            .max(MIN_RESEND)
            .min(cap)
    }

    /// Takes one round-trip sample.
    pub(crate) fn sample_rtt(&mut self, rtt: Duration) {
        self.rtt = Some(match self.rtt {
            None => (rtt, rtt / 2),
            Some((srtt, dev)) => {
                let err = srtt.abs_diff(rtt);
                ((srtt * 7 + rtt) / 8, (dev * 3 + err) / 4)
            }
        });
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

    /// The transport, to act on it between requests (an in-process device's simulated time).
    pub fn link_mut(&mut self) -> &mut T {
        &mut self.link
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
            // A frame left open (its closing delimiter lost) ends only with the next frame: after
            // the transport's frame gap without a byte it is damaged, and the request is resent.
            let settle = self.open_since.map(|t| t + self.link.frame_gap());
            let until = settle.map_or(deadline, |s| s.min(deadline));
            let n = self
                .link
                .recv(&mut buf, until.saturating_duration_since(now))?;
            if n == 0 {
                if self.open_since.is_some() && Instant::now() < deadline {
                    self.open_since = None;
                    self.decoder.resync();
                    return Ok(Some(Event::Damaged));
                }
                return Ok(None);
            }
            self.stats.bytes_in += n as u64;
            self.open_since = (buf[n - 1] != 0).then(Instant::now);
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
