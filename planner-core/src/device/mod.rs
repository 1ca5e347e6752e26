//! The device-side request handler: bytes in, reply frames out, no knowledge of the transport.
//!
//! The firmware and `hil-sim` drive it the same way: hand every received byte to
//! [`DeviceService::receive`], then call [`DeviceService::poll`] until it returns `false`;
//! `poll` does one bounded unit of work (handle one frame, or plan one form) and passes outgoing
//! bytes to `tx`. Received frames are handled before the next form is planned, so pings, status
//! queries and cancels are answered between forms. All buffers are fixed and sized from the
//! message types (see [`crate::wire::max_size`]).
//!
//! The service is split by concern: [`receive`] (the queue of received bytes), `dispatch`
//! (frame checks and routing), `upload` (the request arriving in chunks) and `job` (planning
//! form by form and serving the result).

mod dispatch;
mod drive;
mod job;
mod motion;
pub mod receive;
mod steer;
mod upload;

use crate::wire::{
    encode_frame, Chunk, Fault, FrameDecoder, Header, Reply, ReplyBody, ENCODE_SCRATCH, MAX_CHUNK,
    MAX_FRAME, MAX_PLAN_REQUEST, MAX_PLAN_RESULT, MAX_STEER_ANSWER,
};
pub use job::plan_as_device;
use job::Job;
pub use motion::MotionPort;
use receive::Inbox;
pub use receive::RX_QUEUE;

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
    /// Steering readings answered.
    pub steer_readings: u32,
    /// `Move` requests the motion core took (a board measures each one's work).
    pub motion_moves: u32,
}

/// Everything but the frame decoder, so a decoded payload (borrowed from the decoder) can be
/// handled while the rest of the state changes.
struct Core {
    /// `None` introduces the service as [`DeviceIdentity::CORE`]; an option so that
    /// [`DeviceService::new`] has no pointer in it (see there).
    identity: Option<DeviceIdentity>,
    job: Job,
    /// The plan of the request in progress or last finished: its scenario, decoded in place,
    /// and the search over it. Apart from the job, so that it is built in place, never moved.
    plan: job::Planner,
    upload: [u8; MAX_PLAN_REQUEST],
    result: [u8; MAX_PLAN_RESULT],
    scratch: [u8; ENCODE_SCRATCH],
    stats: DeviceStats,
    /// The insertion being steered, under the id of the plan it executes.
    steering: steer::Steered,
    /// The last steering answer, encoded, for `SteerFetch`, and its length.
    steer_answer: [u8; MAX_STEER_ANSWER],
    steer_answer_len: u16,
    /// The board's axes, if it drives any.
    motion: motion::Motion,
    /// The steered insertion the board moves itself, if any.
    driven: drive::Driven,
}

/// The device's request handler.
pub struct DeviceService {
    inbox: Inbox,
    decoder: FrameDecoder<MAX_FRAME>,
    core: Core,
}

impl Default for DeviceService {
    fn default() -> Self {
        Self::new()
    }
}

impl DeviceService {
    /// A service with empty buffers and no request in progress, introducing itself as
    /// [`DeviceIdentity::CORE`] until [`DeviceService::set_identity`] is called.
    ///
    /// Its value is zero bytes only, so a `static` initialised with it lives in `.bss`: a
    /// `static` of [`DeviceService::with_identity`] holds string pointers and is copied at boot
    /// from an image of the whole service (30 KiB at 256 obstacles) in flash.
    ///
    /// ```
    /// use planner_core::device::{DeviceIdentity, DeviceService};
    ///
    /// static IDENTITY: DeviceIdentity = DeviceIdentity { name: "bench", firmware: "1", build: "" };
    /// let mut service = DeviceService::new();
    /// service.set_identity(IDENTITY);
    /// assert!(!service.is_planning());
    /// ```
    pub const fn new() -> Self {
        Self::introduced_as(None)
    }

    /// A service that introduces itself as `identity`.
    pub const fn with_identity(identity: DeviceIdentity) -> Self {
        Self::introduced_as(Some(identity))
    }

    /// From now on, introduce the service as `identity`.
    pub fn set_identity(&mut self, identity: DeviceIdentity) {
        self.core.identity = Some(identity);
    }

    const fn introduced_as(identity: Option<DeviceIdentity>) -> Self {
        DeviceService {
            inbox: Inbox::new(),
            decoder: FrameDecoder::for_requests(),
            core: Core {
                identity,
                job: Job::Idle,
                plan: job::Planner::idle(),
                upload: [0; MAX_PLAN_REQUEST],
                result: [0; MAX_PLAN_RESULT],
                scratch: [0; ENCODE_SCRATCH],
                stats: DeviceStats {
                    frames: 0,
                    bad_crc: 0,
                    too_long: 0,
                    truncated: 0,
                    undecodable: 0,
                    overruns: 0,
                    plans: 0,
                    steer_readings: 0,
                    motion_moves: 0,
                },
                steering: steer::Steered::Off,
                steer_answer: [0; MAX_STEER_ANSWER],
                steer_answer_len: 0,
                motion: motion::Motion::Off,
                driven: drive::Driven::Off,
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
        self.inbox.receive(bytes);
    }

    /// Takes as many of `bytes` as the receive queue has room for and returns how many; the
    /// caller polls and offers the rest again (flow control for transports that can wait).
    pub fn receive_partial(&mut self, bytes: &[u8]) -> usize {
        self.inbox.receive_partial(bytes)
    }

    /// Does one bounded unit of work, writing reply bytes to `tx`; `true` while work is pending.
    pub fn poll(&mut self, tx: &mut dyn FnMut(&[u8])) -> bool {
        if self.inbox.take_overrun() {
            self.core.stats.overruns += 1;
            self.decoder.resync();
            self.core.send(0, ReplyBody::Fault(Fault::Overrun), tx);
            return true;
        }
        while let Some(b) = self.inbox.pop() {
            if let Some(event) = self.decoder.push(b) {
                self.core.handle_frame(event, tx);
                return true;
            }
        }
        if self.core.step(tx) {
            return true;
        }
        self.inbox.pending()
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
}

/// The part of `bytes` (the whole encoded answer) from `offset`, at most `max_len` and
/// [`MAX_CHUNK`] bytes, or why not.
fn part_of(bytes: &[u8], offset: u16, max_len: u16) -> ReplyBody {
    let len = bytes.len() as u16;
    if offset > len {
        return ReplyBody::Fault(Fault::BadOffset { offset, len });
    }
    let start = usize::from(offset);
    let n = usize::from(max_len).min(MAX_CHUNK).min(bytes.len() - start);
    let mut data = Chunk::new();
    // Cannot fail: n <= MAX_CHUNK.
    let _ = data.extend_from_slice(&bytes[start..start + n]);
    ReplyBody::Part {
        offset,
        total: len,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/protocol.md quotes this size (`cargo test -p planner-core device -- --nocapture`).
    #[test]
    fn the_service_fits_its_ram_budget() {
        let size = core::mem::size_of::<DeviceService>();
        let motion = core::mem::size_of::<motion::Motion>();
        std::println!("DeviceService: {size} bytes, of which the motion core {motion}");
        // 12.7 KiB at 32 obstacles. Each obstacle of the capacity adds its place in the upload
        // buffer (two on the wire per one held), in the two scenarios held (the plan's and the
        // steering controller's), in the bound's true radii and margins and in the result:
        // under 90 bytes (30.1 KiB at the device's 256, 43.4 KiB at the host's 512).
        let per_obstacle = 90 * (crate::MAX_OBSTACLES - 32);
        assert!(size <= 13 * 1024 + per_obstacle, "{size} bytes");
    }
}
