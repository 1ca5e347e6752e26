//! The message types this codec reads and writes, one module each, and [`Message`], which is
//! any one of them.
//!
//! Each type's `encode` writes its content (the v1/v2 body, the v3 content section) into a
//! buffer and returns its length; `decode` reads exactly one content slice.

pub mod point;
pub mod polydata;
pub mod position;
pub mod status;
pub mod string;
pub mod transform;

use crate::Error;
pub use point::{PointElement, PointList};
pub use polydata::PolyData;
pub use position::Position;
pub use status::{Status, StatusCode};
pub use string::StringMessage;
pub use transform::Transform;

/// Type names as sent in the header.
pub mod type_names {
    /// TRANSFORM.
    pub const TRANSFORM: &str = "TRANSFORM";
    /// POSITION.
    pub const POSITION: &str = "POSITION";
    /// STATUS.
    pub const STATUS: &str = "STATUS";
    /// STRING.
    pub const STRING: &str = "STRING";
    /// POINT.
    pub const POINT: &str = "POINT";
    /// POLYDATA.
    pub const POLYDATA: &str = "POLYDATA";
    /// Every type this codec decodes.
    pub const ALL: [&str; 6] = [TRANSFORM, POSITION, STATUS, STRING, POINT, POLYDATA];
}

/// One decoded message content.
// The bounded lists make `PolyData` and `Point` the large variants: one message lives at a time
// and there is no heap to box into.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    /// TRANSFORM: a rigid pose.
    Transform(Transform),
    /// POSITION: position and quaternion.
    Position(Position),
    /// STATUS: a device status.
    Status(Status),
    /// STRING: text.
    String(StringMessage),
    /// POINT: fiducials.
    Point(PointList),
    /// POLYDATA: points and a polyline.
    PolyData(PolyData),
}

impl Message {
    /// The header type name of this message.
    pub fn type_name(&self) -> &'static str {
        match self {
            Message::Transform(_) => type_names::TRANSFORM,
            Message::Position(_) => type_names::POSITION,
            Message::Status(_) => type_names::STATUS,
            Message::String(_) => type_names::STRING,
            Message::Point(_) => type_names::POINT,
            Message::PolyData(_) => type_names::POLYDATA,
        }
    }

    /// Whether `type_name` is one this codec decodes.
    pub fn is_known(type_name: &str) -> bool {
        type_names::ALL.contains(&type_name)
    }

    /// Writes the content into `out`; returns its length or `BufferTooSmall`.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        match self {
            Message::Transform(m) => m.encode(out),
            Message::Position(m) => m.encode(out),
            Message::Status(m) => m.encode(out),
            Message::String(m) => m.encode(out),
            Message::Point(m) => m.encode(out),
            Message::PolyData(m) => m.encode(out),
        }
    }

    /// Reads the content of a message of type `type_name` (`UnknownType` for others).
    pub fn decode(type_name: &str, content: &[u8]) -> Result<Self, Error> {
        Ok(match type_name {
            type_names::TRANSFORM => Message::Transform(Transform::decode(content)?),
            type_names::POSITION => Message::Position(Position::decode(content)?),
            type_names::STATUS => Message::Status(Status::decode(content)?),
            type_names::STRING => Message::String(StringMessage::decode(content)?),
            type_names::POINT => Message::Point(PointList::decode(content)?),
            type_names::POLYDATA => Message::PolyData(PolyData::decode(content)?),
            _ => return Err(Error::UnknownType),
        })
    }
}

macro_rules! into_message {
    ($($variant:ident($ty:ty)),*) => {$(
        impl From<$ty> for Message {
            fn from(m: $ty) -> Self {
                Message::$variant(m)
            }
        }
    )*};
}

into_message!(
    Transform(Transform),
    Position(Position),
    Status(Status),
    String(StringMessage),
    Point(PointList),
    PolyData(PolyData)
);
