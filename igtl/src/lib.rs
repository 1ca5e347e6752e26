//! OpenIGTLink codec: `no_std`, no heap, every capacity fixed in the types.
//!
//! The slice of the protocol that steering a needle from a tracker stream and showing it in 3D
//! Slicer needs: the 58-byte [`Header`], protocol v3's extended header and key/value
//! [`Metadata`], the messages TRANSFORM, POSITION, STATUS, STRING, POINT and POLYDATA
//! ([`messages`]), whole frames ([`encode_frame`], [`decode_frame`]) and a [`FrameDecoder`]
//! for a TCP byte stream. No networking.
//!
//! Header version 1 frames (protocols v1 and v2) carry the content as their body; header
//! version 2 frames (protocol v3) wrap it in an extended header and metadata, which
//! [`FrameInfo::extended`] holds.
//!
//! The bounds (`MAX_*` constants next to each type) make a decoded [`Frame`] about 6.5 KiB, most
//! of it the 256 points and 512 triangles of a POLYDATA: a decoder on a small stack holds one
//! frame at a time.
//!
//! ```
//! use needle_igtl::{decode_frame, encode_frame, Extended, FrameInfo, Message, TextEncoding};
//! use needle_igtl::{Status, StatusCode};
//!
//! let mut info = FrameInfo::new("Tracker")?;
//! let mut ext = Extended { message_id: 7, ..Extended::default() };
//! ext.metadata.insert("Status", TextEncoding::UsAscii, "OK")?;
//! info.extended = Some(ext);
//!
//! let mut buf = [0u8; 512];
//! let n = encode_frame(&info, &Message::Status(Status::new(StatusCode::NOT_READY)), &mut buf)?;
//! let (frame, _) = decode_frame(&buf[..n])?;
//! assert_eq!(frame.info.extended.unwrap().metadata.get("Status"), Some("OK"));
//! # Ok::<(), needle_igtl::Error>(())
//! ```
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Matrices on fixed arrays read best with explicit row and column indices.
#![allow(clippy::needless_range_loop)]

mod bytes;
pub mod crc;
pub mod error;
pub mod extended;
pub mod frame;
pub mod header;
pub mod messages;
pub mod stream;
mod text;

pub use error::Error;
pub use extended::{Extended, MetaEntry, Metadata};
pub use frame::{decode_body, decode_frame, encode_frame, Frame, FrameInfo};
pub use header::{DeviceName, Header, Timestamp, HEADER_SIZE};
pub use messages::{
    Message, PointElement, PointList, PolyData, Position, Status, StatusCode, StringMessage,
    Transform,
};
pub use stream::{FrameDecoder, Stats};
pub use text::TextEncoding;
