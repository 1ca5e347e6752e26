//! STATUS (`Documents/Protocol/status.md`): code u16, subcode i64, error name char[20], then
//! the status message, which the reference library sends NUL-terminated.

use crate::bytes::{Reader, Writer};
use crate::text::{bounded, fixed, put_fixed, until_nul};
use crate::Error;
use heapless::String;

/// Bytes of a STATUS body before its message text.
pub const STATUS_HEADER_SIZE: usize = 30;
/// Bytes of the error name field.
pub const ERROR_NAME_SIZE: usize = 20;
/// Bytes of status message text kept.
pub const MAX_STATUS_TEXT: usize = 256;

/// A status code; the spec's codes as constants, any other value kept as sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StatusCode(pub u16);

#[allow(missing_docs)] // The names are the spec's list.
impl StatusCode {
    pub const INVALID: StatusCode = StatusCode(0);
    pub const OK: StatusCode = StatusCode(1);
    pub const UNKNOWN_ERROR: StatusCode = StatusCode(2);
    pub const PANIC: StatusCode = StatusCode(3);
    pub const NOT_FOUND: StatusCode = StatusCode(4);
    pub const ACCESS_DENIED: StatusCode = StatusCode(5);
    pub const BUSY: StatusCode = StatusCode(6);
    pub const TIME_OUT: StatusCode = StatusCode(7);
    pub const OVERFLOW: StatusCode = StatusCode(8);
    pub const CHECKSUM_ERROR: StatusCode = StatusCode(9);
    pub const CONFIGURATION_ERROR: StatusCode = StatusCode(10);
    pub const NOT_ENOUGH_RESOURCE: StatusCode = StatusCode(11);
    pub const UNKNOWN_INSTRUCTION: StatusCode = StatusCode(12);
    pub const NOT_READY: StatusCode = StatusCode(13);
    pub const MANUAL_MODE: StatusCode = StatusCode(14);
    pub const DISABLED: StatusCode = StatusCode(15);
    pub const NOT_PRESENT: StatusCode = StatusCode(16);
    pub const UNKNOWN_VERSION: StatusCode = StatusCode(17);
    pub const HARDWARE_FAILURE: StatusCode = StatusCode(18);
    pub const SHUTTING_DOWN: StatusCode = StatusCode(19);
}

/// A device's status.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Status {
    /// The status code.
    pub code: StatusCode,
    /// A device-specific sub code.
    pub subcode: i64,
    /// A short name ("OK", "Error", …); the spec says not to rely on it.
    pub error_name: String<ERROR_NAME_SIZE>,
    /// Free text (without its terminating NUL).
    pub message: String<MAX_STATUS_TEXT>,
}

impl Status {
    /// A status with a code and no sub code, name or text.
    pub fn new(code: StatusCode) -> Self {
        Status {
            code,
            subcode: 0,
            error_name: String::new(),
            message: String::new(),
        }
    }

    /// Writes the body (30 bytes, the text, a NUL); `Malformed` if the name or text holds a NUL.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        if self.message.as_bytes().contains(&0) {
            return Err(Error::Malformed);
        }
        let mut w = Writer::new(out);
        w.u16(self.code.0)?;
        w.i64(self.subcode)?;
        put_fixed(&mut w, &self.error_name, ERROR_NAME_SIZE)?;
        w.put(self.message.as_bytes())?;
        w.u8(0)?;
        Ok(w.len())
    }

    /// Reads a body of at least 30 bytes (`BadBodySize` if shorter); the text runs to the first
    /// NUL or the end of the body.
    pub fn decode(content: &[u8]) -> Result<Self, Error> {
        if content.len() < STATUS_HEADER_SIZE {
            return Err(Error::BadBodySize);
        }
        let mut r = Reader::new(content);
        let code = StatusCode(r.u16()?);
        let subcode = r.i64()?;
        let error_name = fixed(r.take(ERROR_NAME_SIZE)?)?;
        let message = bounded(until_nul(r.take(r.remaining())?))?;
        Ok(Status {
            code,
            subcode,
            error_name,
            message,
        })
    }
}
