//! STRING (`Documents/Protocol/string.md`): encoding u16 (IANA MIBenum), length u16, bytes.

use crate::bytes::{Reader, Writer};
use crate::text::TextEncoding;
use crate::Error;
use heapless::String;

/// Bytes of STRING text kept (the protocol allows up to 65 535).
pub const MAX_STRING: usize = 1024;

/// A text message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StringMessage {
    /// The encoding sent; US-ASCII is the spec's recommendation.
    pub encoding: TextEncoding,
    /// The text.
    pub text: String<MAX_STRING>,
}

impl StringMessage {
    /// US-ASCII text; `NotAscii` or `TooLarge` if it is not or does not fit.
    pub fn ascii(text: &str) -> Result<Self, Error> {
        TextEncoding::UsAscii.check(text)?;
        Ok(StringMessage {
            encoding: TextEncoding::UsAscii,
            text: String::try_from(text).map_err(|_| Error::TooLarge)?,
        })
    }

    /// Writes the body (4 + length bytes); `NotAscii` for US-ASCII text that is not.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.encoding.check(&self.text)?;
        let len = u16::try_from(self.text.len()).map_err(|_| Error::TooLarge)?;
        let mut w = Writer::new(out);
        w.u16(self.encoding.mib())?;
        w.u16(len)?;
        w.put(self.text.as_bytes())?;
        Ok(w.len())
    }

    /// Reads a body whose size is 4 + its length field (`BadBodySize` otherwise).
    pub fn decode(content: &[u8]) -> Result<Self, Error> {
        let mut r = Reader::new(content);
        let (mib, len) = match (r.u16(), r.u16()) {
            (Ok(mib), Ok(len)) => (mib, usize::from(len)),
            _ => return Err(Error::BadBodySize),
        };
        if r.remaining() != len {
            return Err(Error::BadBodySize);
        }
        let encoding = TextEncoding::from_mib(mib)?;
        let text = encoding.decode(r.take(len)?)?;
        Ok(StringMessage { encoding, text })
    }
}
