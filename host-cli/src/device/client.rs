//! The host side of the protocol: requests with explicit timeouts and retries.
//!
//! Every exchange sends one request and waits up to `timeout` for its answer; on silence, or on
//! a damaged frame (caught by the CRC here, or reported by the device), it sends the request
//! again, at most `retries` times, then gives up with [`LinkError::NoAnswer`]. Every request is
//! idempotent, so a repeat never does harm. Chunk sizes shrink when frames get damaged and grow
//! back as they get through, so a noisy line still carries a plan.

use planner_core::model::form::Form;
use planner_core::wire::crc::crc32;
use planner_core::wire::{
    encode_frame, Chunk, DeviceInfo, Fault, FrameDecoder, Header, PlanRequest, PlanResult, Reply,
    ReplyBody, Request, RequestBody, ENCODE_SCRATCH, MAX_CHUNK, MAX_FRAME, MAX_PLAN_REQUEST,
    PROTOCOL_VERSION,
};
use planner_core::Scenario;
use std::collections::VecDeque;
use std::fmt;
use std::io;
use std::time::{Duration, Instant};

use super::transport::Transport;

/// Smallest chunk the client shrinks to on a noisy line.
const MIN_CHUNK: usize = 16;

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

/// One progress report of the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Forms done.
    pub done: u8,
    /// Forms in all.
    pub total: u8,
    /// The form just finished.
    pub form: Option<Form>,
    /// Whether it gave a feasible path.
    pub feasible: bool,
}

/// Why talking to the device failed.
#[derive(Debug)]
pub enum LinkError {
    /// The port or socket failed.
    Io(io::Error),
    /// No usable answer after every retry.
    NoAnswer {
        /// What was asked.
        what: &'static str,
        /// Times it was sent.
        attempts: u32,
        /// Wait after each.
        timeout: Duration,
    },
    /// The device refused the request.
    Device(Fault),
    /// The device speaks another protocol version.
    Version {
        /// The device's.
        device: u8,
    },
    /// The plan came back damaged every time, or did not decode.
    CorruptResult,
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "link failed: {e}"),
            LinkError::NoAnswer {
                what,
                attempts,
                timeout,
            } => write!(
                f,
                "the device did not answer ({what}: {attempts} attempts, {:.1} s each)",
                timeout.as_secs_f64()
            ),
            LinkError::Device(Fault::Internal) => f.write_str(
                "the device hit an internal error and is restarting; the request was lost \
                 (a firmware bug: please report it with the device's log)",
            ),
            LinkError::Device(fault) => write!(f, "the device refused the request: {fault:?}"),
            LinkError::Version { device } => write!(
                f,
                "the device speaks protocol version {device}, this needle speaks {PROTOCOL_VERSION}"
            ),
            LinkError::CorruptResult => {
                f.write_str("the plan arrived damaged on every attempt (CRC mismatch)")
            }
        }
    }
}

impl std::error::Error for LinkError {}

impl From<io::Error> for LinkError {
    fn from(e: io::Error) -> Self {
        LinkError::Io(e)
    }
}

enum Event {
    Reply(Box<Reply>),
    /// A frame that failed its CRC, stuffing or decoding.
    Damaged,
}

/// Faults the device reports about frames it could not read: the request is worth resending.
fn is_line_fault(f: Fault) -> bool {
    matches!(
        f,
        Fault::BadCrc
            | Fault::Truncated
            | Fault::FrameTooLong
            | Fault::Overrun
            | Fault::Undecodable
    )
}

/// A protocol session with one device.
pub struct Client<T: Transport> {
    link: T,
    config: ClientConfig,
    decoder: FrameDecoder<MAX_FRAME>,
    events: VecDeque<Event>,
    stats: LinkStats,
    next_id: u16,
    chunk: usize,
    max_chunk: usize,
    finished: Option<(u16, u16, u32)>,
    abandoned: Option<u16>,
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
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// The transport (for tests that inspect the simulated device).
    pub fn link(&self) -> &T {
        &self.link
    }

    fn new_id(&mut self) -> u16 {
        self.next_id = self.next_id.wrapping_add(1).max(1);
        self.next_id
    }

    fn send(&mut self, id: u16, body: &RequestBody) -> Result<(), LinkError> {
        let req = Request {
            header: Header::new(id),
            body: body.clone(),
        };
        let mut scratch = [0u8; ENCODE_SCRATCH];
        let mut out = Vec::with_capacity(MAX_FRAME + 2);
        encode_frame(&req, &mut scratch, &mut |b: &[u8]| out.extend_from_slice(b))
            .map_err(|_| LinkError::Io(io::Error::other("request too large to encode")))?;
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
    fn next_event(&mut self, deadline: Instant) -> Result<Option<Event>, LinkError> {
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

    /// The next reply (damaged frames counted and skipped), for tests of malformed input.
    pub fn next_reply(&mut self) -> Result<Option<Reply>, LinkError> {
        let deadline = Instant::now() + self.config.timeout;
        loop {
            match self.next_event(deadline)? {
                None => return Ok(None),
                Some(Event::Damaged) => self.stats.detected += 1,
                Some(Event::Reply(r)) => return Ok(Some(*r)),
            }
        }
    }

    /// Sends `body` until `accept` takes an answer to request `id`.
    fn exchange<R>(
        &mut self,
        what: &'static str,
        id: u16,
        body: &RequestBody,
        mut accept: impl FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<R, LinkError> {
        self.exchange_with(what, id, |_| body.clone(), &mut accept)
    }

    /// Like `exchange`, but the body is rebuilt for each attempt from the current chunk size,
    /// which halves after every failed attempt and grows back after every answered one.
    fn exchange_with<R>(
        &mut self,
        what: &'static str,
        id: u16,
        mut make: impl FnMut(usize) -> RequestBody,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<R, LinkError> {
        for attempt in 0..=self.config.retries {
            if attempt > 0 {
                self.stats.retried += 1;
                self.chunk = (self.chunk / 2).max(MIN_CHUNK);
            }
            let body = make(self.chunk);
            if let Some(r) = self.attempt(id, &body, accept)? {
                self.chunk = (self.chunk + MIN_CHUNK).min(self.max_chunk);
                return Ok(r);
            }
        }
        Err(LinkError::NoAnswer {
            what,
            attempts: self.config.retries + 1,
            timeout: self.config.timeout,
        })
    }

    /// Sends `body` once and waits for an answer; `None` after silence or a damaged frame.
    fn attempt<R>(
        &mut self,
        id: u16,
        body: &RequestBody,
        accept: &mut dyn FnMut(&ReplyBody) -> Option<R>,
    ) -> Result<Option<R>, LinkError> {
        self.send(id, body)?;
        let deadline = Instant::now() + self.config.timeout;
        loop {
            let reply = match self.next_event(deadline)? {
                None => {
                    self.stats.timeouts += 1;
                    return Ok(None);
                }
                Some(Event::Damaged) => {
                    self.stats.detected += 1;
                    return Ok(None);
                }
                Some(Event::Reply(r)) => *r,
            };
            if let ReplyBody::Fault(Fault::UnsupportedVersion { supported, .. }) = reply.body {
                return Err(LinkError::Version { device: supported });
            }
            if reply.header.version != PROTOCOL_VERSION {
                return Err(LinkError::Version {
                    device: reply.header.version,
                });
            }
            if reply.body == ReplyBody::Fault(Fault::Internal) {
                return Err(LinkError::Device(Fault::Internal));
            }
            if let ReplyBody::Fault(f) = reply.body {
                if is_line_fault(f) && (reply.header.id == 0 || f == Fault::Undecodable) {
                    // The device saw a damaged frame, most likely this request.
                    self.stats.detected += 1;
                    return Ok(None);
                }
            }
            if reply.header.id != id {
                continue;
            }
            if let Some(r) = accept(&reply.body) {
                return Ok(Some(r));
            }
            match reply.body {
                ReplyBody::Fault(f) => return Err(LinkError::Device(f)),
                ReplyBody::Finished { len, crc } => self.finished = Some((id, len, crc)),
                _ => {}
            }
        }
    }

    /// Asks the device who it is; fails on a protocol version mismatch.
    pub fn hello(&mut self) -> Result<DeviceInfo, LinkError> {
        let id = self.new_id();
        let info = self.exchange("hello", id, &RequestBody::Hello, |b| match b {
            ReplyBody::Hello(info) => Some(info.clone()),
            _ => None,
        })?;
        if info.protocol != PROTOCOL_VERSION {
            return Err(LinkError::Version {
                device: info.protocol,
            });
        }
        self.max_chunk = usize::from(info.max_chunk).clamp(MIN_CHUNK, MAX_CHUNK);
        self.chunk = self.chunk.min(self.max_chunk);
        Ok(info)
    }

    /// Round-trip time of one ping.
    pub fn ping(&mut self) -> Result<Duration, LinkError> {
        let id = self.new_id();
        let nonce = u32::from(id) << 16 | 0x5A5A;
        let start = Instant::now();
        self.exchange("ping", id, &RequestBody::Ping { nonce }, |b| {
            matches!(b, ReplyBody::Pong { nonce: n } if *n == nonce).then_some(())
        })?;
        Ok(start.elapsed())
    }

    /// Plans `scenario` on the device: upload, wait (reporting progress), fetch.
    pub fn plan(
        &mut self,
        scenario: &Scenario,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<PlanResult, LinkError> {
        let mut buf = vec![0u8; MAX_PLAN_REQUEST];
        let request = postcard::to_slice(&PlanRequest::new(scenario), &mut buf)
            .map_err(|_| LinkError::Io(io::Error::other("scenario too large to encode")))?
            .to_vec();
        self.plan_encoded(&request, progress)
    }

    /// Plans an already encoded [`PlanRequest`] (tests use it to send what a scenario cannot hold).
    pub fn plan_encoded(
        &mut self,
        request: &[u8],
        progress: &mut dyn FnMut(Progress),
    ) -> Result<PlanResult, LinkError> {
        let id = self.new_id();
        self.finished = None;
        let result = self.upload(id, request).and_then(|()| {
            let (len, crc) = self.await_plan(id, progress)?;
            self.fetch(id, len, crc)
        });
        match result {
            Ok(bytes) => {
                postcard::from_bytes::<PlanResult>(&bytes).map_err(|_| LinkError::CorruptResult)
            }
            Err(e) => {
                // Leave the device free for the next request: one cancel, without waiting (the
                // line may be dead), and remember the id in case it never arrived.
                self.abandoned = Some(id);
                let _ = self.send(id, &RequestBody::Cancel);
                Err(e)
            }
        }
    }

    /// Stops request `id` on the device; true if something was running.
    pub fn cancel(&mut self, id: u16) -> Result<bool, LinkError> {
        self.exchange("cancel", id, &RequestBody::Cancel, |b| match b {
            ReplyBody::Cancelled { was_active } => Some(*was_active),
            _ => None,
        })
    }

    fn upload(&mut self, id: u16, bytes: &[u8]) -> Result<(), LinkError> {
        let total = u16::try_from(bytes.len())
            .map_err(|_| LinkError::Io(io::Error::other("scenario too large")))?;
        let crc = crc32(bytes);
        let mut offset = 0u16;
        let mut stalls = 0;
        while offset < total {
            let make = |chunk: usize| {
                let start = usize::from(offset);
                let n = chunk.min(usize::from(total - offset));
                RequestBody::Upload {
                    offset,
                    total,
                    crc,
                    data: Chunk::from_slice(&bytes[start..start + n]).unwrap_or_default(),
                }
            };
            let answer = self.exchange_with("upload", id, make, &mut |b| match b {
                ReplyBody::Uploaded { received, total: t } if *t == total => Some(*received),
                _ => None,
            });
            let received = match answer {
                // Still planning a request this client gave up on: stop it and go on.
                Err(LinkError::Device(Fault::Busy { active }))
                    if Some(active) == self.abandoned =>
                {
                    self.cancel(active)?;
                    self.abandoned = None;
                    continue;
                }
                other => other?,
            };
            if received <= offset {
                stalls += 1;
                if stalls > self.config.retries {
                    return Err(LinkError::NoAnswer {
                        what: "upload",
                        attempts: stalls,
                        timeout: self.config.timeout,
                    });
                }
            } else {
                stalls = 0;
            }
            offset = received.min(total);
        }
        Ok(())
    }

    fn await_plan(
        &mut self,
        id: u16,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(u16, u32), LinkError> {
        loop {
            if let Some((fid, len, crc)) = self.finished.take() {
                if fid == id {
                    return Ok((len, crc));
                }
            }
            let deadline = Instant::now() + self.config.timeout;
            let ask = match self.next_event(deadline)? {
                None => {
                    self.stats.timeouts += 1;
                    true
                }
                Some(Event::Damaged) => {
                    // Perhaps the report that the plan is done: ask rather than wait.
                    self.stats.detected += 1;
                    true
                }
                Some(Event::Reply(r)) if r.header.id == id => {
                    self.on_plan_news(id, &r.body, progress)?;
                    false
                }
                Some(Event::Reply(_)) => false,
            };
            if ask {
                let news = self.exchange("plan status", id, &RequestBody::Status, |b| {
                    matches!(b, ReplyBody::Progress { .. } | ReplyBody::Finished { .. })
                        .then(|| b.clone())
                })?;
                self.on_plan_news(id, &news, progress)?;
            }
        }
    }

    fn on_plan_news(
        &mut self,
        id: u16,
        body: &ReplyBody,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), LinkError> {
        match *body {
            ReplyBody::Progress {
                done,
                total,
                form,
                feasible,
            } => progress(Progress {
                done,
                total,
                form,
                feasible,
            }),
            ReplyBody::Finished { len, crc } => {
                self.finished = Some((id, len, crc));
            }
            ReplyBody::Fault(f) if !is_line_fault(f) => return Err(LinkError::Device(f)),
            _ => {}
        }
        Ok(())
    }

    fn fetch(&mut self, id: u16, len: u16, crc: u32) -> Result<Vec<u8>, LinkError> {
        for _ in 0..=self.config.retries {
            let mut out = Vec::with_capacity(usize::from(len));
            while out.len() < usize::from(len) {
                let offset = out.len() as u16;
                let make = |chunk: usize| RequestBody::Fetch {
                    offset,
                    max_len: chunk as u16,
                };
                let data = self.exchange_with("fetch", id, make, &mut |b| match b {
                    ReplyBody::Part {
                        offset: o,
                        total,
                        data,
                    } if *o == offset && *total == len && !data.is_empty() => Some(data.clone()),
                    _ => None,
                })?;
                out.extend_from_slice(&data);
            }
            out.truncate(usize::from(len));
            if crc32(&out) == crc {
                return Ok(out);
            }
            self.stats.detected += 1;
        }
        Err(LinkError::CorruptResult)
    }
}
