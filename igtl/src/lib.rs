//! OpenIGTLink codec: `no_std`, no heap, every capacity fixed in the types.
//!
//! The 58-byte [`Header`] and the messages TRANSFORM, POSITION, STATUS, STRING, POINT and
//! POLYDATA ([`messages`]). No networking.
//!
//! ```
//! use needle_igtl::Transform;
//!
//! let mut body = [0u8; 48];
//! assert_eq!(Transform::IDENTITY.encode(&mut body), Ok(48));
//! assert_eq!(Transform::decode(&body), Ok(Transform::IDENTITY));
//! ```
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Matrices on fixed arrays read best with explicit row and column indices.
#![allow(clippy::needless_range_loop)]

mod bytes;
pub mod crc;
pub mod error;
pub mod header;
pub mod messages;
mod text;

pub use error::Error;
pub use header::{DeviceName, Header, Timestamp, HEADER_SIZE};
pub use messages::{
    Message, PointElement, PointList, PolyData, Position, Status, StatusCode, StringMessage,
    Transform,
};
pub use text::TextEncoding;
