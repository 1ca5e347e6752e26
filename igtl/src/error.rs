//! The one error type of the codec.

use core::fmt;

/// Why a frame or message could not be encoded or decoded.
///
/// Decoding never panics: every malformed input ends in one of these.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// The output buffer cannot hold the encoded bytes.
    BufferTooSmall,
    /// The input ends before the frame does (header or body incomplete).
    Truncated,
    /// The header version is neither 1 (protocol v1/v2) nor 2 (protocol v3).
    UnsupportedVersion(u16),
    /// The header's type name is not NUL-padded printable ASCII.
    BadHeader,
    /// The message type is not one this codec decodes.
    UnknownType,
    /// The body does not match the header's CRC-64.
    BadCrc,
    /// The content's size does not match its type: a fixed-size type of the wrong size, or a
    /// variable one whose own counts or lengths say another size.
    BadBodySize,
    /// Inner sizes or indices that contradict each other (v3 extended header or metadata,
    /// POLYDATA cell arrays), or a NUL inside a text sent NUL-terminated.
    Malformed,
    /// More elements or longer text than the bounded type holds.
    TooLarge,
    /// A text field is not valid UTF-8.
    NotUtf8,
    /// A text sent as US-ASCII has a byte above 0x7F.
    NotAscii,
    /// A STRING or metadata value encoding (IANA MIBenum) other than US-ASCII (3) or UTF-8 (106).
    UnsupportedEncoding(u16),
    /// A TRANSFORM rotation that is not orthonormal with determinant +1, or a POSITION quaternion
    /// that is not of unit norm (both within 1e-3).
    NotRigid,
    /// A coordinate that is NaN or infinite.
    NotFinite,
    /// A valid message using a feature this codec leaves out (a POLYDATA with more than one line).
    Unsupported,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::BufferTooSmall => f.write_str("output buffer too small"),
            Error::Truncated => f.write_str("input ends inside the frame"),
            Error::UnsupportedVersion(v) => write!(f, "unsupported header version {v}"),
            Error::BadHeader => f.write_str("type name is not NUL-padded printable ASCII"),
            Error::UnknownType => f.write_str("message type not decoded by this codec"),
            Error::BadCrc => f.write_str("body CRC-64 mismatch"),
            Error::BadBodySize => f.write_str("body size does not match the message type"),
            Error::Malformed => f.write_str("inner sizes or indices contradict each other"),
            Error::TooLarge => f.write_str("more data than the bounded type holds"),
            Error::NotUtf8 => f.write_str("text is not UTF-8"),
            Error::NotAscii => f.write_str("US-ASCII text has a byte above 0x7F"),
            Error::UnsupportedEncoding(e) => write!(f, "unsupported text encoding {e}"),
            Error::NotRigid => f.write_str("rotation is not rigid"),
            Error::NotFinite => f.write_str("coordinate is NaN or infinite"),
            Error::Unsupported => f.write_str("message uses a feature this codec leaves out"),
        }
    }
}

impl core::error::Error for Error {}
