//! Text fields: NUL-padded `char[N]` arrays and the two encodings this codec reads.

use crate::bytes::Writer;
use crate::Error;
use heapless::String;

/// A text encoding by its IANA MIBenum, as STRING messages and v3 metadata values carry it.
///
/// Only the two the spec names are read: US-ASCII (its recommended default) and UTF-8.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TextEncoding {
    /// US-ASCII, MIBenum 3.
    UsAscii,
    /// UTF-8, MIBenum 106.
    Utf8,
}

impl TextEncoding {
    /// The MIBenum sent on the wire.
    pub const fn mib(self) -> u16 {
        match self {
            TextEncoding::UsAscii => 3,
            TextEncoding::Utf8 => 106,
        }
    }

    /// The encoding of a MIBenum, or `UnsupportedEncoding`.
    pub const fn from_mib(mib: u16) -> Result<Self, Error> {
        match mib {
            3 => Ok(TextEncoding::UsAscii),
            106 => Ok(TextEncoding::Utf8),
            other => Err(Error::UnsupportedEncoding(other)),
        }
    }

    /// `bytes` as text of this encoding, bounded to `N` bytes.
    pub(crate) fn decode<const N: usize>(self, bytes: &[u8]) -> Result<String<N>, Error> {
        if self == TextEncoding::UsAscii && !bytes.is_ascii() {
            return Err(Error::NotAscii);
        }
        bounded(bytes)
    }

    /// Whether `text` can be sent in this encoding (every `str` is UTF-8).
    pub(crate) fn check(self, text: &str) -> Result<(), Error> {
        if self == TextEncoding::UsAscii && !text.is_ascii() {
            Err(Error::NotAscii)
        } else {
            Ok(())
        }
    }
}

/// UTF-8 `bytes` as a bounded string.
pub(crate) fn bounded<const N: usize>(bytes: &[u8]) -> Result<String<N>, Error> {
    let s = core::str::from_utf8(bytes).map_err(|_| Error::NotUtf8)?;
    String::try_from(s).map_err(|_| Error::TooLarge)
}

/// The text of a NUL-padded field: up to the first NUL, or all of it (a name that fills the
/// field needs no terminator, as the spec's 20-byte device names show).
pub(crate) fn until_nul(field: &[u8]) -> &[u8] {
    match field.iter().position(|&b| b == 0) {
        Some(end) => &field[..end],
        None => field,
    }
}

/// A NUL-padded `char[N]` field as a bounded string.
pub(crate) fn fixed<const N: usize>(field: &[u8]) -> Result<String<N>, Error> {
    bounded(until_nul(field))
}

/// Writes `text` NUL-padded to `width` bytes; a NUL inside would cut it short on decoding.
pub(crate) fn put_fixed(w: &mut Writer<'_>, text: &str, width: usize) -> Result<(), Error> {
    let bytes = text.as_bytes();
    if bytes.contains(&0) {
        return Err(Error::Malformed);
    }
    let pad = width.checked_sub(bytes.len()).ok_or(Error::TooLarge)?;
    w.put(bytes)?;
    w.zeros(pad)
}
