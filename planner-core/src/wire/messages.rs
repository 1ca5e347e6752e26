//! The message types shared by the device and the host.
//!
//! Every frame carries a [`Header`] (protocol version, request id) and one body. Large data (the
//! scenario going up, the plan coming back) travels in chunks the host asks for, so on a noisy
//! line only the damaged chunk is sent again, and every frame stays small.

use super::max_size::{max, MaxSize};
use super::motion::{MotionRequest, MotionStatus};
use crate::execute::schedule::Steps;
use crate::model::form::Form;
use crate::steer::{Pose, SteerConfig, SteerReply, SteerStats, StopReason, TipMeasurement};
use serde::{Deserialize, Serialize};

/// Version of this message set. A device answers any other version with
/// [`Fault::UnsupportedVersion`] and nothing else.
pub const PROTOCOL_VERSION: u8 = 12;

/// Largest data chunk in one [`RequestBody::Upload`] or [`ReplyBody::Part`].
pub const MAX_CHUNK: usize = 192;

/// Data of one chunk.
pub type Chunk = heapless::Vec<u8, MAX_CHUNK>;

/// Starts every message: who speaks which version, and which request this belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Header {
    /// [`PROTOCOL_VERSION`] of the sender.
    pub version: u8,
    /// Chosen by the host; replies echo it (0 for faults about frames that could not be read).
    pub id: u16,
}

impl Header {
    /// A header of this protocol version.
    pub const fn new(id: u16) -> Header {
        Header {
            version: PROTOCOL_VERSION,
            id,
        }
    }
}

/// Host to device.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Request {
    /// Version and id.
    pub header: Header,
    /// What is asked.
    pub body: RequestBody,
}

/// What the host asks.
// A chunk makes `Upload` the large variant: one message lives at a time, boxing needs a heap.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum RequestBody {
    /// Identify yourself: answered by [`ReplyBody::Hello`].
    Hello,
    /// Answered by [`ReplyBody::Pong`] with the same nonce.
    Ping {
        /// Echoed back.
        nonce: u32,
    },
    /// Part of an encoded [`PlanRequest`](super::PlanRequest) starting at `offset`; the plan starts once all `total`
    /// bytes are in and their CRC-32 is `crc`. Answered by [`ReplyBody::Uploaded`] (the host
    /// continues from `received`). A repeat of a finished upload (same id, length and CRC: the
    /// same scenario) is acknowledged without planning again.
    Upload {
        /// Position of `data` in the encoded request.
        offset: u16,
        /// Length of the whole encoded request.
        total: u16,
        /// CRC-32 of the whole encoded request.
        crc: u32,
        /// The bytes.
        data: Chunk,
    },
    /// Where is request `id`? Answered by `Uploaded`, `Progress` or `Finished`.
    Status,
    /// Send part of the finished plan's encoded [`PlanResult`](super::PlanResult): answered by [`ReplyBody::Part`].
    Fetch {
        /// First byte wanted.
        offset: u16,
        /// Most bytes wanted (the device caps it at [`MAX_CHUNK`]).
        max_len: u16,
    },
    /// Stop request `id` (uploading or planning). Always answered by [`ReplyBody::Cancelled`].
    Cancel,
    /// Start steering the finished plan `id` (its best form's schedule) with these settings:
    /// answered by [`ReplyBody::SteerStarted`]. A repeat restarts steering from the entry.
    /// An answer longer than `max_len` bytes comes as [`ReplyBody::SteerPending`].
    SteerStart {
        /// The controller's settings.
        config: SteerConfig,
        /// Longest encoded answer wanted in one frame (bytes): a noisy line damages long frames.
        max_len: u16,
    },
    /// A tracker reading with the robot's progress: answered by [`ReplyBody::Steer`], or by
    /// [`ReplyBody::SteerPending`] when that is longer than `max_len` bytes. A reading whose
    /// sequence number was the last one's is answered again and not applied twice.
    SteerReading {
        /// The reading.
        reading: TipMeasurement,
        /// Longest encoded answer wanted in one frame (bytes).
        max_len: u16,
    },
    /// Send part of the steering answer last announced by [`ReplyBody::SteerPending`]:
    /// answered by [`ReplyBody::Part`].
    SteerFetch {
        /// First byte wanted.
        offset: u16,
        /// Most bytes wanted (the device caps it at [`MAX_CHUNK`]).
        max_len: u16,
    },
    /// The controller's counters and stop: answered by [`ReplyBody::SteerStatus`].
    SteerStatus,
    /// A motion or safety request: answered by [`ReplyBody::Motion`], or refused with
    /// [`Fault::Motion`] (or [`Fault::NoMotion`] on a device without axes).
    Motion(MotionRequest),
    /// The board moves the insertion steered under plan `id` itself, on its axes (armed, homed,
    /// at the entry), one piece at a time: the first piece now, each next one after the reading
    /// taken once the last has ended (a reading while a piece moves is refused with
    /// [`Fault::PieceMoving`]). Answered by [`ReplyBody::Motion`] with the first piece queued.
    SteerDrive {
        /// Longest piece of insertion between two readings (mm, above 0 and at most 1).
        piece_mm: f32,
    },
}

/// Device to host.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reply {
    /// Version and the id of the request answered.
    pub header: Header,
    /// The answer.
    pub body: ReplyBody,
}

/// What the device says.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ReplyBody {
    /// Who the device is and what it can hold.
    Hello(DeviceInfo),
    /// Answer to a ping.
    Pong {
        /// The ping's nonce.
        nonce: u32,
    },
    /// Bytes of the plan request received so far (contiguous from 0).
    Uploaded {
        /// Received.
        received: u16,
        /// Expected in all.
        total: u16,
    },
    /// Sent once per form finished (and in answer to `Status` while planning).
    Progress {
        /// The round of a plan under a collision bound (each round plans every form with the
        /// obstacles grown further), counted from 1; always 1 without a bound.
        round: u8,
        /// Forms done (in this round).
        done: u8,
        /// Forms to plan.
        total: u8,
        /// The form just finished (absent before the first).
        form: Option<Form>,
        /// Whether that form gave a feasible path.
        feasible: bool,
    },
    /// The plan is done: fetch `len` bytes of encoded [`PlanResult`](super::PlanResult) whose CRC-32 is `crc`.
    Finished {
        /// Length of the encoded result.
        len: u16,
        /// CRC-32 of the whole encoded result (checks the reassembly).
        crc: u32,
    },
    /// Part of the encoded result.
    Part {
        /// Position of `data`.
        offset: u16,
        /// Length of the whole encoded result.
        total: u16,
        /// The bytes.
        data: Chunk,
    },
    /// Answer to `Cancel`.
    Cancelled {
        /// Whether an upload or a plan was stopped.
        was_active: bool,
    },
    /// Steering has started: the steps to execute first (the plan's schedule).
    SteerStarted {
        /// The motor steps.
        steps: Steps,
    },
    /// The controller's answer to a reading.
    Steer(SteerReply),
    /// The answer to `SteerStart` or `SteerReading` (an encoded [`ReplyBody::SteerStarted`] or
    /// [`ReplyBody::Steer`]) is `len` bytes, more than the request allowed: fetch it with
    /// `SteerFetch`; `crc` is the CRC-32 of the whole.
    SteerPending {
        /// What it answers: the reading of this sequence number, or (`None`) the start. A late
        /// copy of an earlier announcement is told apart by it.
        reading: Option<u32>,
        /// Length of the encoded answer.
        len: u16,
        /// CRC-32 of the encoded answer.
        crc: u32,
    },
    /// The controller's counters, why it stopped once it has, and where it estimates the tip.
    SteerStatus {
        /// Counters over the insertion.
        stats: SteerStats,
        /// The stop, if any.
        stopped: Option<StopReason>,
        /// The estimated tip after the last reading (the plan's entry before the first), in the
        /// scenario's frame, its bevel direction included: what a viewer draws.
        estimate: Pose,
    },
    /// A protocol fault.
    Fault(Fault),
    /// The motion core's status, after a motion request.
    Motion(MotionStatus),
}

/// Protocol faults, reported in place of an answer.
// Non-exhaustive: a later protocol version may report faults this one does not know.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Fault {
    /// A frame failed its CRC-32 (it was corrupted on the line).
    BadCrc,
    /// A frame was longer than the largest message; it was dropped up to the next delimiter.
    FrameTooLong,
    /// A frame was too short to hold a checksum, or its byte stuffing was cut.
    Truncated,
    /// A frame passed its CRC but is not a message of this protocol.
    Undecodable,
    /// The request speaks another protocol version.
    UnsupportedVersion {
        /// The device's version.
        supported: u8,
        /// The request's version.
        got: u8,
    },
    /// Another request is being planned; cancel it or wait.
    Busy {
        /// Its id.
        active: u16,
    },
    /// No upload, plan or result with this id.
    UnknownRequest,
    /// The plan request is larger than the device's upload buffer.
    TooLarge {
        /// Bytes announced.
        len: u16,
        /// Bytes the device holds.
        capacity: u16,
    },
    /// A fetch past the end of the result.
    BadOffset {
        /// Offset asked for.
        offset: u16,
        /// Length of the result.
        len: u16,
    },
    /// Bytes arrived faster than they were processed and some were lost.
    Overrun,
    /// The complete plan request did not decode as a scenario.
    BadScenario,
    /// The complete plan request does not match the CRC-32 its chunks announced.
    BadUploadCrc,
    /// Steering was asked for, but request `id` has no finished plan with a schedule.
    NoPlan,
    /// A reading arrived, but steering has not been started.
    NotSteering,
    /// The steering settings are not finite and positive.
    BadSteerConfig,
    /// The device hit an internal error (a firmware bug) and restarts; every request in progress
    /// is lost. Sent with id 0 by the firmware's panic handler.
    Internal,
    /// The motion core refused the request, and why.
    Motion(needle_motion::MotionError),
    /// A motion request reached a device that drives no axes.
    NoMotion,
    /// A driven insertion's reading arrived while its piece was still moving.
    PieceMoving,
    /// `SteerDrive` after the steered insertion had taken readings: the board starts at the entry.
    NotAtEntry,
    /// `SteerDrive`'s piece length is not above 0 and at most 1 mm.
    BadPieceLength,
}

impl core::fmt::Display for Fault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Fault::BadCrc => f.write_str("a frame failed its CRC-32"),
            Fault::FrameTooLong => f.write_str("a frame was longer than the largest message"),
            Fault::Truncated => f.write_str("a frame was cut short"),
            Fault::Undecodable => f.write_str("a frame is not a message of this protocol"),
            Fault::UnsupportedVersion { supported, got } => write!(
                f,
                "the request speaks protocol version {got}, the device {supported}"
            ),
            Fault::Busy { active } => write!(f, "the device is busy planning request {active}"),
            Fault::UnknownRequest => f.write_str("no upload, plan or result with this id"),
            Fault::TooLarge { len, capacity } => write!(
                f,
                "the plan request ({len} bytes) is larger than the device's buffer ({capacity} bytes)"
            ),
            Fault::BadOffset { offset, len } => {
                write!(f, "fetch at offset {offset} past the result's {len} bytes")
            }
            Fault::Overrun => f.write_str("bytes arrived faster than they were processed"),
            Fault::BadScenario => f.write_str("the plan request is not a scenario"),
            Fault::BadUploadCrc => {
                f.write_str("the plan request does not match its announced CRC-32")
            }
            Fault::NoPlan => f.write_str("no finished plan with a schedule to steer"),
            Fault::NotSteering => f.write_str("a reading arrived, but steering has not started"),
            Fault::BadSteerConfig => f.write_str("the steering settings are not finite and positive"),
            Fault::Internal => f.write_str("the device hit an internal error and restarts"),
            Fault::Motion(e) => write!(f, "the motion core refused: {e}"),
            Fault::NoMotion => f.write_str("the device drives no axes"),
            Fault::PieceMoving => f.write_str("a reading arrived while the board's piece moved"),
            Fault::NotAtEntry => f.write_str("the steered insertion has left the entry"),
            Fault::BadPieceLength => f.write_str("the piece length is not in (0, 1] mm"),
        }
    }
}

impl core::error::Error for Fault {}

/// What a device reports about itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceInfo {
    /// [`PROTOCOL_VERSION`] of the device.
    pub protocol: u8,
    /// Board or simulator name.
    pub name: heapless::String<16>,
    /// Firmware version.
    pub firmware: heapless::String<16>,
    /// Build details (commit, target, profile).
    pub build: heapless::String<32>,
    /// Obstacles the planner holds.
    pub max_obstacles: u16,
    /// Largest control degree.
    pub max_control_degree: u8,
    /// Forms in the catalogue.
    pub form_count: u8,
    /// Largest chunk per frame.
    pub max_chunk: u16,
    /// Largest encoded plan request.
    pub upload_capacity: u16,
}

impl MaxSize for Header {
    const MAX_SIZE: usize = u8::MAX_SIZE + u16::MAX_SIZE;
}

impl MaxSize for RequestBody {
    const MAX_SIZE: usize = 1 + max(
        u32::MAX_SIZE,
        max(
            2 * u16::MAX_SIZE + u32::MAX_SIZE + Chunk::MAX_SIZE,
            max(
                2 * u16::MAX_SIZE,
                max(
                    max(SteerConfig::MAX_SIZE, TipMeasurement::MAX_SIZE) + u16::MAX_SIZE,
                    MotionRequest::MAX_SIZE,
                ),
            ),
        ),
    );
}

impl MaxSize for Request {
    const MAX_SIZE: usize = Header::MAX_SIZE + RequestBody::MAX_SIZE;
}

impl MaxSize for Fault {
    const MAX_SIZE: usize = 1 + max(2 * u16::MAX_SIZE, needle_motion::MotionError::MAX_SIZE);
}

impl MaxSize for DeviceInfo {
    const MAX_SIZE: usize = u8::MAX_SIZE
        + 2 * heapless::String::<16>::MAX_SIZE
        + heapless::String::<32>::MAX_SIZE
        + u16::MAX_SIZE
        + u8::MAX_SIZE
        + u8::MAX_SIZE
        + 2 * u16::MAX_SIZE;
}

impl MaxSize for ReplyBody {
    const MAX_SIZE: usize = 1 + max(
        DeviceInfo::MAX_SIZE,
        max(
            2 * u16::MAX_SIZE + Chunk::MAX_SIZE,
            max(
                u16::MAX_SIZE + u32::MAX_SIZE,
                max(
                    max(3 + Option::<Form>::MAX_SIZE + 1, Fault::MAX_SIZE),
                    max(
                        max(Steps::MAX_SIZE, SteerReply::MAX_SIZE),
                        max(
                            SteerStats::MAX_SIZE + Option::<StopReason>::MAX_SIZE + Pose::MAX_SIZE,
                            MotionStatus::MAX_SIZE,
                        ),
                    ),
                ),
            ),
        ),
    );
}

impl MaxSize for Reply {
    const MAX_SIZE: usize = Header::MAX_SIZE + ReplyBody::MAX_SIZE;
}
