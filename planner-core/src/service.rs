//! The device-side request handler: bytes in, reply frames out, no knowledge of the transport.
//!
//! The firmware and `hil-sim` drive it the same way: hand every received byte to
//! [`DeviceService::receive`], then call [`DeviceService::poll`] until it returns `false`;
//! `poll` does one bounded unit of work (handle one frame, or plan one form) and passes outgoing
//! bytes to `tx`. Received frames are handled before the next form is planned, so pings, status
//! queries and cancels are answered between forms. All buffers are fixed and sized from the
//! message types (see [`crate::wire::max_size`]).

use crate::form::Form;
use crate::planner::PlanSession;
use crate::wire::frame::CRC_LEN;
use crate::wire::{
    encode_frame, Chunk, DeviceInfo, Fault, FrameDecoder, FrameError, Header, PlanRequest,
    PlanResult, Reply, ReplyBody, Request, RequestBody, MAX_CHUNK, MAX_FRAME, MAX_PAYLOAD,
    MAX_PLAN_REQUEST, MAX_PLAN_RESULT, MAX_WIRE_FRAME, PROTOCOL_VERSION,
};
use crate::{FORM_COUNT, MAX_CONTROL_DEGREE, MAX_OBSTACLES};

/// Received bytes the service buffers between polls: two full frames.
pub const RX_QUEUE: usize = 2 * MAX_WIRE_FRAME;

/// How a device names itself in [`ReplyBody::Hello`].
#[derive(Clone, Copy, Debug)]
pub struct DeviceIdentity {
    /// Board or simulator (up to 16 bytes are sent).
    pub name: &'static str,
    /// Firmware version (up to 16 bytes are sent).
    pub firmware: &'static str,
    /// Build details (up to 32 bytes are sent).
    pub build: &'static str,
}

impl DeviceIdentity {
    /// The core library itself, for tests.
    pub const CORE: DeviceIdentity = DeviceIdentity {
        name: "planner-core",
        firmware: env!("CARGO_PKG_VERSION"),
        build: "",
    };
}

/// Counters of what the service has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceStats {
    /// Frames that passed the CRC and decoded.
    pub frames: u32,
    /// Frames rejected by their CRC.
    pub bad_crc: u32,
    /// Frames over the maximum size.
    pub too_long: u32,
    /// Frames cut short.
    pub truncated: u32,
    /// Frames that passed the CRC but did not decode (or spoke another version).
    pub undecodable: u32,
    /// Times the receive queue overflowed.
    pub overruns: u32,
    /// Plans run to the end.
    pub plans: u32,
}

/// The request in progress or last finished.
// The session is large, but the service lives in a static with no heap to box it in.
#[allow(clippy::large_enum_variant)]
enum Job {
    Idle,
    Uploading {
        id: u16,
        total: u16,
        crc: u32,
        received: u16,
    },
    Planning {
        id: u16,
        total_bytes: u16,
        request_crc: u32,
        session: PlanSession,
        done: u8,
        forms: u8,
        last: Option<(Form, bool)>,
    },
    Finished {
        id: u16,
        total_bytes: u16,
        request_crc: u32,
        len: u16,
        crc: u32,
    },
}

/// What identifies an upload: its length and CRC (with the request id).
#[derive(Clone, Copy)]
struct Upload {
    offset: u16,
    total: u16,
    crc: u32,
}

/// Fixed-size receive queue (a ring); `const`-constructible so the service can live in a static.
struct RxQueue {
    buf: [u8; RX_QUEUE],
    head: usize,
    len: usize,
}

impl RxQueue {
    const fn new() -> Self {
        RxQueue {
            buf: [0; RX_QUEUE],
            head: 0,
            len: 0,
        }
    }

    /// Appends what fits; returns false if bytes were lost.
    fn extend(&mut self, bytes: &[u8]) -> bool {
        for &b in bytes {
            if self.len == RX_QUEUE {
                return false;
            }
            self.buf[(self.head + self.len) % RX_QUEUE] = b;
            self.len += 1;
        }
        true
    }

    fn pop(&mut self) -> Option<u8> {
        if self.len == 0 {
            return None;
        }
        let b = self.buf[self.head];
        self.head = (self.head + 1) % RX_QUEUE;
        self.len -= 1;
        Some(b)
    }
}

/// Everything but the frame decoder, so a decoded payload (borrowed from the decoder) can be
/// handled while the rest of the state changes.
struct Core {
    identity: DeviceIdentity,
    job: Job,
    upload: [u8; MAX_PLAN_REQUEST],
    result: [u8; MAX_PLAN_RESULT],
    scratch: [u8; MAX_PAYLOAD + CRC_LEN],
    stats: DeviceStats,
}

/// The device's request handler.
pub struct DeviceService {
    rx: RxQueue,
    overrun: bool,
    decoder: FrameDecoder<MAX_FRAME>,
    core: Core,
}

impl Default for DeviceService {
    fn default() -> Self {
        Self::new()
    }
}

impl DeviceService {
    /// A service with empty buffers and no request in progress.
    pub const fn new() -> Self {
        Self::with_identity(DeviceIdentity::CORE)
    }

    /// A service that introduces itself as `identity`.
    pub const fn with_identity(identity: DeviceIdentity) -> Self {
        DeviceService {
            rx: RxQueue::new(),
            overrun: false,
            decoder: FrameDecoder::for_requests(),
            core: Core {
                identity,
                job: Job::Idle,
                upload: [0; MAX_PLAN_REQUEST],
                result: [0; MAX_PLAN_RESULT],
                scratch: [0; MAX_PAYLOAD + CRC_LEN],
                stats: DeviceStats {
                    frames: 0,
                    bad_crc: 0,
                    too_long: 0,
                    truncated: 0,
                    undecodable: 0,
                    overruns: 0,
                    plans: 0,
                },
            },
        }
    }

    /// Counters of frames seen and plans run.
    pub fn stats(&self) -> DeviceStats {
        self.core.stats
    }

    /// Whether a plan is being computed.
    pub fn is_planning(&self) -> bool {
        matches!(self.core.job, Job::Planning { .. })
    }

    /// Takes received bytes; never blocks and never fails (overflow is reported on the wire).
    pub fn receive(&mut self, bytes: &[u8]) {
        if !self.rx.extend(bytes) {
            self.overrun = true;
        }
    }

    /// Takes as many of `bytes` as the receive queue has room for and returns how many; the
    /// caller polls and offers the rest again (flow control for transports that can wait).
    pub fn receive_partial(&mut self, bytes: &[u8]) -> usize {
        let n = bytes.len().min(RX_QUEUE - self.rx.len);
        self.rx.extend(&bytes[..n]);
        n
    }

    /// Does one bounded unit of work, writing reply bytes to `tx`; `true` while work is pending.
    pub fn poll(&mut self, tx: &mut dyn FnMut(&[u8])) -> bool {
        if core::mem::take(&mut self.overrun) {
            self.core.stats.overruns += 1;
            self.decoder.resync();
            self.core.send(0, ReplyBody::Fault(Fault::Overrun), tx);
            return true;
        }
        while let Some(b) = self.rx.pop() {
            if let Some(event) = self.decoder.push(b) {
                self.core.handle_frame(event, tx);
                return true;
            }
        }
        if self.core.step(tx) {
            return true;
        }
        self.rx.len > 0
    }
}

impl Core {
    fn send(&mut self, id: u16, body: ReplyBody, tx: &mut dyn FnMut(&[u8])) {
        let reply = Reply {
            header: Header::new(id),
            body,
        };
        // Cannot fail: the scratch buffer is sized from `Reply::MAX_SIZE`, checked by tests.
        let _ = encode_frame(&reply, &mut self.scratch, tx);
    }

    fn fault(&mut self, id: u16, fault: Fault, tx: &mut dyn FnMut(&[u8])) {
        self.send(id, ReplyBody::Fault(fault), tx);
    }

    fn handle_frame(&mut self, event: Result<&[u8], FrameError>, tx: &mut dyn FnMut(&[u8])) {
        let payload = match event {
            Ok(p) => p,
            Err(e) => {
                let fault = match e {
                    FrameError::BadCrc => {
                        self.stats.bad_crc += 1;
                        Fault::BadCrc
                    }
                    FrameError::TooLong => {
                        self.stats.too_long += 1;
                        Fault::FrameTooLong
                    }
                    FrameError::Truncated => {
                        self.stats.truncated += 1;
                        Fault::Truncated
                    }
                };
                return self.fault(0, fault, tx);
            }
        };
        let (header, rest) = match postcard::take_from_bytes::<Header>(payload) {
            Ok(h) => h,
            Err(_) => {
                self.stats.undecodable += 1;
                return self.fault(0, Fault::Undecodable, tx);
            }
        };
        if header.version != PROTOCOL_VERSION {
            self.stats.undecodable += 1;
            let fault = Fault::UnsupportedVersion {
                supported: PROTOCOL_VERSION,
                got: header.version,
            };
            return self.fault(header.id, fault, tx);
        }
        let body = match postcard::take_from_bytes::<RequestBody>(rest) {
            Ok((body, [])) => body,
            _ => {
                self.stats.undecodable += 1;
                return self.fault(header.id, Fault::Undecodable, tx);
            }
        };
        self.stats.frames += 1;
        self.handle(Request { header, body }, tx);
    }

    fn handle(&mut self, req: Request, tx: &mut dyn FnMut(&[u8])) {
        let id = req.header.id;
        match req.body {
            RequestBody::Hello => {
                let info = self.info();
                self.send(id, ReplyBody::Hello(info), tx);
            }
            RequestBody::Ping { nonce } => self.send(id, ReplyBody::Pong { nonce }, tx),
            RequestBody::Upload {
                offset,
                total,
                crc,
                data,
            } => self.upload(id, Upload { offset, total, crc }, &data, tx),
            RequestBody::Status => self.status(id, tx),
            RequestBody::Fetch { offset, max_len } => self.fetch(id, offset, max_len, tx),
            RequestBody::Cancel => {
                let was_active = match self.job {
                    Job::Uploading { id: a, .. } | Job::Planning { id: a, .. } => a == id,
                    _ => false,
                };
                if was_active {
                    self.job = Job::Idle;
                }
                self.send(id, ReplyBody::Cancelled { was_active }, tx);
            }
        }
    }

    fn info(&self) -> DeviceInfo {
        DeviceInfo {
            protocol: PROTOCOL_VERSION,
            name: truncated(self.identity.name),
            firmware: truncated(self.identity.firmware),
            build: truncated(self.identity.build),
            max_obstacles: MAX_OBSTACLES as u16,
            max_control_degree: MAX_CONTROL_DEGREE as u8,
            form_count: FORM_COUNT as u8,
            max_chunk: MAX_CHUNK as u16,
            upload_capacity: MAX_PLAN_REQUEST as u16,
        }
    }

    fn upload(&mut self, id: u16, up: Upload, data: &[u8], tx: &mut dyn FnMut(&[u8])) {
        let Upload { offset, total, crc } = up;
        let ack = |received, total| ReplyBody::Uploaded { received, total };
        match self.job {
            // A repeated chunk of an upload already complete: the ack was lost.
            Job::Planning {
                id: a,
                total_bytes,
                request_crc,
                ..
            }
            | Job::Finished {
                id: a,
                total_bytes,
                request_crc,
                ..
            } if a == id && total_bytes == total && request_crc == crc => {
                return self.send(id, ack(total, total), tx);
            }
            Job::Planning { id: active, .. } => {
                return self.fault(id, Fault::Busy { active }, tx);
            }
            Job::Uploading {
                id: a,
                total: t,
                crc: c,
                received,
            } if a == id && t == total && c == crc => {
                if offset != received {
                    // A repeat or a gap: tell the host where to continue.
                    return self.send(id, ack(received, total), tx);
                }
            }
            _ => {
                if offset != 0 {
                    return self.send(id, ack(0, total), tx);
                }
                if usize::from(total) > MAX_PLAN_REQUEST {
                    let capacity = MAX_PLAN_REQUEST as u16;
                    return self.fault(
                        id,
                        Fault::TooLarge {
                            len: total,
                            capacity,
                        },
                        tx,
                    );
                }
            }
        }
        let start = usize::from(offset);
        let end = start + data.len();
        if end > usize::from(total) {
            let fault = Fault::BadOffset { offset, len: total };
            return self.fault(id, fault, tx);
        }
        self.upload[start..end].copy_from_slice(data);
        let received = end as u16;
        self.job = Job::Uploading {
            id,
            total,
            crc,
            received,
        };
        if received < total {
            return self.send(id, ack(received, total), tx);
        }
        let whole = &self.upload[..usize::from(total)];
        if crate::wire::crc::crc32(whole) != crc {
            self.job = Job::Idle;
            return self.fault(id, Fault::BadUploadCrc, tx);
        }
        self.send(id, ack(received, total), tx);
        self.start_plan(id, up, tx);
    }

    fn start_plan(&mut self, id: u16, up: Upload, tx: &mut dyn FnMut(&[u8])) {
        let total = up.total;
        let request =
            match postcard::take_from_bytes::<PlanRequest>(&self.upload[..usize::from(total)]) {
                Ok((r, [])) => r,
                _ => {
                    self.job = Job::Idle;
                    self.stats.undecodable += 1;
                    return self.fault(id, Fault::BadScenario, tx);
                }
            };
        match request.into_scenario().and_then(PlanSession::new) {
            Ok(session) => {
                let forms = session.form_count() as u8;
                self.job = Job::Planning {
                    id,
                    total_bytes: total,
                    request_crc: up.crc,
                    session,
                    done: 0,
                    forms,
                    last: None,
                };
                self.status(id, tx);
            }
            Err(e) => self.store_result(id, up, &Err(e), tx),
        }
    }

    /// Plans one form of the active plan; false if there is none.
    fn step(&mut self, tx: &mut dyn FnMut(&[u8])) -> bool {
        let Job::Planning {
            id,
            total_bytes,
            request_crc,
            session,
            done,
            last,
            ..
        } = &mut self.job
        else {
            return false;
        };
        let id = *id;
        let up = Upload {
            offset: 0,
            total: *total_bytes,
            crc: *request_crc,
        };
        match session.step() {
            Some(o) => {
                *last = Some((o.form, o.feasible));
                *done = done.saturating_add(1);
                self.status(id, tx);
            }
            None => {
                if let Job::Planning { session, .. } = core::mem::replace(&mut self.job, Job::Idle)
                {
                    let result = session.finish();
                    self.stats.plans += 1;
                    self.store_result(id, up, &result, tx);
                }
            }
        }
        true
    }

    fn store_result(
        &mut self,
        id: u16,
        up: Upload,
        result: &PlanResult,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        match postcard::to_slice(result, &mut self.result) {
            Ok(bytes) => {
                let len = bytes.len() as u16;
                let crc = crate::wire::crc::crc32(bytes);
                self.job = Job::Finished {
                    id,
                    total_bytes: up.total,
                    request_crc: up.crc,
                    len,
                    crc,
                };
                self.send(id, ReplyBody::Finished { len, crc }, tx);
            }
            // Cannot happen: the buffer is sized from `PlanResult::MAX_SIZE`, checked by tests.
            Err(_) => {
                self.job = Job::Idle;
                self.fault(id, Fault::Undecodable, tx);
            }
        }
    }

    fn status(&mut self, id: u16, tx: &mut dyn FnMut(&[u8])) {
        let body = match &self.job {
            Job::Uploading {
                id: a,
                total,
                received,
                ..
            } if *a == id => ReplyBody::Uploaded {
                received: *received,
                total: *total,
            },
            Job::Planning {
                id: a,
                done,
                forms,
                last,
                ..
            } if *a == id => ReplyBody::Progress {
                done: *done,
                total: *forms,
                form: last.map(|(f, _)| f),
                feasible: last.is_some_and(|(_, ok)| ok),
            },
            Job::Finished {
                id: a, len, crc, ..
            } if *a == id => ReplyBody::Finished {
                len: *len,
                crc: *crc,
            },
            _ => ReplyBody::Fault(Fault::UnknownRequest),
        };
        self.send(id, body, tx);
    }

    fn fetch(&mut self, id: u16, offset: u16, max_len: u16, tx: &mut dyn FnMut(&[u8])) {
        let len = match self.job {
            Job::Finished { id: a, len, .. } if a == id => len,
            _ => return self.status(id, tx),
        };
        if offset > len {
            return self.fault(id, Fault::BadOffset { offset, len }, tx);
        }
        let start = usize::from(offset);
        let n = usize::from(max_len)
            .min(MAX_CHUNK)
            .min(usize::from(len) - start);
        let mut data = Chunk::new();
        // Cannot fail: n <= MAX_CHUNK.
        let _ = data.extend_from_slice(&self.result[start..start + n]);
        self.send(
            id,
            ReplyBody::Part {
                offset,
                total: len,
                data,
            },
            tx,
        );
    }
}

/// The longest prefix of `s` that fits `N` bytes, cut at a character boundary.
fn truncated<const N: usize>(s: &str) -> heapless::String<N> {
    let mut out = heapless::String::new();
    for c in s.chars() {
        if out.push(c).is_err() {
            break;
        }
    }
    out
}
