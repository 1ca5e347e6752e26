//! The serial protocol: message types shared by device and host, their size bounds, and framing.
//!
//! A frame on the line is `0x00, COBS(postcard(message) ++ CRC-32), 0x00`. Every message starts
//! with a [`Header`] (protocol version and request id). The host uploads a scenario in chunks,
//! the device pushes one [`ReplyBody::Progress`] per form planned and a [`ReplyBody::Finished`],
//! and the host fetches the encoded [`PlanResult`] in chunks, each checked by its frame's CRC and
//! the whole by the CRC in `Finished`. See `docs/protocol.md`.

pub mod crc;
pub mod frame;
pub mod max_size;
pub mod messages;
pub mod motion;
pub mod obstacles;
pub mod plan;
pub mod steer;

pub use frame::{
    encode_frame, encode_payload, frame_crc, Directed, EncodeError, FrameDecoder, FrameError,
    ENCODE_SCRATCH, FAULT_SCRATCH, MAX_FRAME, MAX_PAYLOAD, MAX_WIRE_FRAME,
};
pub use max_size::MaxSize;
pub use messages::{
    Chunk, DeviceInfo, Fault, Header, Reply, ReplyBody, Request, RequestBody, MAX_CHUNK,
    PROTOCOL_VERSION,
};
pub use motion::{motion_move, motion_rates, MotionFault, MotionRequest, MotionStatus};
pub use obstacles::{WireObstacles, WIRE_MAX_OBSTACLES};
pub use plan::{ChanceRequest, DevicePlan, PlanRequest, PlanResult, RequestError};

/// Largest encoded [`PlanRequest`]: the device's upload buffer.
pub const MAX_PLAN_REQUEST: usize = <PlanRequest as MaxSize>::MAX_SIZE;

/// Largest encoded [`PlanResult`]: the device's result buffer.
pub const MAX_PLAN_RESULT: usize = <PlanResult as MaxSize>::MAX_SIZE;

/// Largest encoded steering answer ([`ReplyBody::SteerStarted`] or [`ReplyBody::Steer`]): the
/// device's buffer for an answer fetched in parts.
pub const MAX_STEER_ANSWER: usize = 1 + max_size::max(
    <crate::execute::schedule::Steps as MaxSize>::MAX_SIZE,
    <crate::steer::SteerReply as MaxSize>::MAX_SIZE,
);

// Every frame fits one COBS block (one byte of stuffing overhead); offsets and lengths are u16;
// a hello fits any reply frame.
const _: () = assert!(MAX_PAYLOAD + frame::CRC_LEN < 254);
const _: () = assert!(MAX_PLAN_RESULT < u16::MAX as usize);
const _: () = assert!(MAX_PLAN_REQUEST < u16::MAX as usize);
const _: () = assert!(MAX_STEER_ANSWER < u16::MAX as usize);
const _: () = assert!(DeviceInfo::MAX_SIZE <= <ReplyBody as MaxSize>::MAX_SIZE);

#[cfg(test)]
mod tests;
