//! A whole message: the header, then the body (v1/v2: the content; v3: extended header,
//! content, metadata), checked by the header's CRC-64 of the body.

use crate::bytes::Writer;
use crate::crc::crc64;
use crate::extended::{Extended, EXTENDED_HEADER_SIZE};
use crate::header::{
    DeviceName, Header, Timestamp, TypeName, HEADER_SIZE, HEADER_VERSION_1, HEADER_VERSION_2,
};
use crate::messages::Message;
use crate::Error;

/// Everything about a message besides its content.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FrameInfo {
    /// The device name.
    pub device_name: DeviceName,
    /// When the data was generated (all zero: unused).
    pub timestamp: Timestamp,
    /// `Some` for a protocol v3 message (header version 2) with its message id and metadata;
    /// `None` for v1/v2 (header version 1).
    pub extended: Option<Extended>,
}

impl FrameInfo {
    /// A v1/v2 frame's info with no timestamp; `TooLarge` for a name over 20 bytes.
    pub fn new(device_name: &str) -> Result<Self, Error> {
        Ok(FrameInfo {
            device_name: DeviceName::try_from(device_name).map_err(|_| Error::TooLarge)?,
            timestamp: Timestamp::default(),
            extended: None,
        })
    }

    /// The header version these frames are sent with.
    pub fn header_version(&self) -> u16 {
        if self.extended.is_some() {
            HEADER_VERSION_2
        } else {
            HEADER_VERSION_1
        }
    }
}

/// A decoded message with its info.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Device name, timestamp, v3 extension.
    pub info: FrameInfo,
    /// The content.
    pub message: Message,
}

/// Encodes header and body into `out`; returns the frame's length or `BufferTooSmall`.
///
/// ```
/// use needle_igtl::{decode_frame, encode_frame, FrameInfo, Message, Transform};
///
/// let pose = Transform::new(
///     [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], // 90° about z
///     [10.0, 20.0, 30.0],
/// )?;
/// let mut buf = [0u8; 256];
/// let len = encode_frame(&FrameInfo::new("NeedleTip")?, &Message::Transform(pose), &mut buf)?;
/// assert_eq!(len, 58 + 48);
///
/// let (frame, used) = decode_frame(&buf[..len])?;
/// assert_eq!(used, len);
/// assert_eq!(frame.info.device_name.as_str(), "NeedleTip");
/// let Message::Transform(back) = frame.message else { panic!("not a TRANSFORM") };
/// assert_eq!(back.rotation()[0][1], -1.0);
/// assert_eq!(back.translation(), [10.0, 20.0, 30.0]);
/// # Ok::<(), needle_igtl::Error>(())
/// ```
pub fn encode_frame(info: &FrameInfo, message: &Message, out: &mut [u8]) -> Result<usize, Error> {
    let (head, body) = out
        .split_at_mut_checked(HEADER_SIZE)
        .ok_or(Error::BufferTooSmall)?;
    let body_len = encode_body(info, message, body)?;
    let body = body.get(..body_len).ok_or(Error::BufferTooSmall)?;
    let header = Header {
        version: info.header_version(),
        type_name: TypeName::try_from(message.type_name()).map_err(|_| Error::TooLarge)?,
        device_name: info.device_name.clone(),
        timestamp: info.timestamp,
        body_size: body_len as u64,
        crc: crc64(body),
    };
    header.encode(head)?;
    Ok(HEADER_SIZE + body_len)
}

fn encode_body(info: &FrameInfo, message: &Message, body: &mut [u8]) -> Result<usize, Error> {
    let Some(ext) = &info.extended else {
        return message.encode(body);
    };
    let (head, rest) = body
        .split_at_mut_checked(EXTENDED_HEADER_SIZE)
        .ok_or(Error::BufferTooSmall)?;
    ext.encode_head(&mut Writer::new(head))?;
    let content_len = message.encode(rest)?;
    let mut tail = Writer::new(rest.get_mut(content_len..).ok_or(Error::BufferTooSmall)?);
    ext.encode_tail(&mut tail)?;
    Ok(EXTENDED_HEADER_SIZE + content_len + tail.len())
}

/// Decodes the frame at the start of `bytes`; returns it and the bytes it took.
///
/// `Truncated` if `bytes` ends inside the frame; `UnknownType` (after the CRC check) for a type
/// this codec does not read.
pub fn decode_frame(bytes: &[u8]) -> Result<(Frame, usize), Error> {
    let header = Header::decode(bytes)?;
    let total = usize::try_from(header.body_size)
        .ok()
        .and_then(|b| b.checked_add(HEADER_SIZE))
        .ok_or(Error::Truncated)?;
    let body = bytes.get(HEADER_SIZE..total).ok_or(Error::Truncated)?;
    decode_body(&header, body).map(|frame| (frame, total))
}

/// Decodes a body already read after `header` (a caller that reads the header first and then
/// exactly `header.body_size` bytes): CRC, v3 extension, content.
pub fn decode_body(header: &Header, body: &[u8]) -> Result<Frame, Error> {
    if body.len() as u64 != header.body_size {
        return Err(Error::Truncated);
    }
    if crc64(body) != header.crc {
        return Err(Error::BadCrc);
    }
    let (extended, content) = match header.version {
        HEADER_VERSION_1 => (None, body),
        HEADER_VERSION_2 => {
            let (ext, content) = Extended::split(body)?;
            (Some(ext), content)
        }
        other => return Err(Error::UnsupportedVersion(other)),
    };
    let message = Message::decode(&header.type_name, content)?;
    let info = FrameInfo {
        device_name: header.device_name.clone(),
        timestamp: header.timestamp,
        extended,
    };
    Ok(Frame { info, message })
}
