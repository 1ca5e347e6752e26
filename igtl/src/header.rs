//! The 58-byte header every OpenIGTLink message starts with (`Documents/Protocol/header.md`):
//! version u16, type char[12], device name char[20], timestamp u64, body size u64, CRC-64 u64,
//! all big-endian.

use crate::bytes::{Reader, Writer};
use crate::text::{fixed, put_fixed, until_nul};
use crate::Error;
use heapless::String;

/// Bytes of the header.
pub const HEADER_SIZE: usize = 58;
/// Bytes of the type name field.
pub const TYPE_NAME_SIZE: usize = 12;
/// Bytes of the device name field.
pub const DEVICE_NAME_SIZE: usize = 20;
/// Header version of protocols v1 and v2: the body is the content alone.
pub const HEADER_VERSION_1: u16 = 1;
/// Header version of protocol v3: the body is extended header, content and metadata.
pub const HEADER_VERSION_2: u16 = 2;

/// A message type name such as `"TRANSFORM"`.
pub type TypeName = String<TYPE_NAME_SIZE>;
/// A device name; all 20 bytes may be used (the field then has no NUL).
pub type DeviceName = String<DEVICE_NAME_SIZE>;

/// The header's timestamp: seconds since 1970-01-01 UTC and a binary fraction of a second.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Timestamp {
    /// Whole seconds since 1970-01-01 00:00:00 UTC (the high 32 bits on the wire).
    pub seconds: u32,
    /// Fraction of a second in units of 2^-32 s (the low 32 bits on the wire).
    pub fraction: u32,
}

impl Timestamp {
    /// The 64-bit field as sent: seconds high, fraction low. 0 means "unused".
    pub const fn to_bits(self) -> u64 {
        ((self.seconds as u64) << 32) | self.fraction as u64
    }

    /// The timestamp of a 64-bit field.
    pub const fn from_bits(bits: u64) -> Self {
        Timestamp {
            seconds: (bits >> 32) as u32,
            fraction: bits as u32,
        }
    }

    /// From seconds and nanoseconds (nanoseconds past 999 999 999 saturate just below a second).
    pub const fn from_secs_nanos(seconds: u32, nanos: u32) -> Self {
        let nanos = if nanos > 999_999_999 {
            999_999_999
        } else {
            nanos
        };
        // Rounded to the nearest 2^-32 s: 1 ns is about 4.3 units, so the round trip is exact.
        let fraction = (((nanos as u64) << 32) + 500_000_000) / 1_000_000_000;
        Timestamp {
            seconds,
            fraction: fraction as u32,
        }
    }

    /// The fraction in nanoseconds (rounded to the nearest, at most 999 999 999).
    pub const fn subsec_nanos(self) -> u32 {
        let nanos = (self.fraction as u64 * 1_000_000_000 + (1 << 31)) >> 32;
        if nanos > 999_999_999 {
            999_999_999
        } else {
            nanos as u32
        }
    }
}

/// A decoded message header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// [`HEADER_VERSION_1`] or [`HEADER_VERSION_2`].
    pub version: u16,
    /// The message type, e.g. `"TRANSFORM"`.
    pub type_name: TypeName,
    /// The device (or message) name.
    pub device_name: DeviceName,
    /// When the data was generated.
    pub timestamp: Timestamp,
    /// Bytes of the body that follows the header.
    pub body_size: u64,
    /// CRC-64/ECMA-182 of the body.
    pub crc: u64,
}

impl Header {
    /// Writes the header into `out[..58]`; returns 58 or `BufferTooSmall`.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut w = Writer::new(out);
        w.u16(self.version)?;
        put_fixed(&mut w, &self.type_name, TYPE_NAME_SIZE)?;
        put_fixed(&mut w, &self.device_name, DEVICE_NAME_SIZE)?;
        w.u64(self.timestamp.to_bits())?;
        w.u64(self.body_size)?;
        w.u64(self.crc)?;
        Ok(w.len())
    }

    /// Reads the header from the first 58 bytes of `bytes` (`Truncated` if fewer).
    ///
    /// Errors in the order a stream needs them: `UnsupportedVersion` and `BadHeader` mean the
    /// bytes are not a header at all; `NotUtf8` (device name) comes from a real header whose
    /// body size can still be trusted.
    pub fn decode(bytes: &[u8]) -> Result<Header, Error> {
        let bytes = bytes.get(..HEADER_SIZE).ok_or(Error::Truncated)?;
        let mut r = Reader::new(bytes);
        let version = r.u16()?;
        if version != HEADER_VERSION_1 && version != HEADER_VERSION_2 {
            return Err(Error::UnsupportedVersion(version));
        }
        let type_field = r.take(TYPE_NAME_SIZE)?;
        let device_field = r.take(DEVICE_NAME_SIZE)?;
        let timestamp = Timestamp::from_bits(r.u64()?);
        let body_size = r.u64()?;
        let crc = r.u64()?;
        let type_name = type_name(type_field)?;
        let device_name = fixed(device_field)?;
        Ok(Header {
            version,
            type_name,
            device_name,
            timestamp,
            body_size,
            crc,
        })
    }
}

/// The body size of a header whose device name failed to decode, to skip its body.
pub(crate) fn body_size_of(header: &[u8; HEADER_SIZE]) -> u64 {
    let mut size = [0u8; 8];
    size.copy_from_slice(&header[42..50]);
    u64::from_be_bytes(size)
}

/// A type name must be printable ASCII padded with NULs only: this is what tells a header from
/// stray bytes, since the protocol has no sync marker.
fn type_name(field: &[u8]) -> Result<TypeName, Error> {
    let name = until_nul(field);
    let padding = &field[name.len()..];
    let printable = name.iter().all(|b| (0x20..0x7F).contains(b));
    if name.is_empty() || !printable || padding.iter().any(|&b| b != 0) {
        return Err(Error::BadHeader);
    }
    fixed(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Header {
        Header {
            version: HEADER_VERSION_1,
            type_name: TypeName::try_from("TRANSFORM").unwrap(),
            device_name: DeviceName::try_from("Tracker").unwrap(),
            timestamp: Timestamp::from_secs_nanos(1_700_000_000, 250_000_000),
            body_size: 48,
            crc: 0x0123_4567_89AB_CDEF,
        }
    }

    #[test]
    fn fields_sit_where_the_spec_puts_them() {
        let mut out = [0xAAu8; HEADER_SIZE];
        assert_eq!(sample().encode(&mut out), Ok(HEADER_SIZE));
        assert_eq!(&out[0..2], &[0, 1]);
        assert_eq!(&out[2..11], b"TRANSFORM");
        assert!(out[11..14].iter().all(|&b| b == 0));
        assert_eq!(&out[14..21], b"Tracker");
        assert!(out[21..34].iter().all(|&b| b == 0));
        assert_eq!(&out[34..38], &1_700_000_000u32.to_be_bytes());
        assert_eq!(&out[38..42], &0x4000_0000u32.to_be_bytes());
        assert_eq!(&out[42..50], &48u64.to_be_bytes());
        assert_eq!(&out[50..58], &0x0123_4567_89AB_CDEFu64.to_be_bytes());
        assert_eq!(Header::decode(&out), Ok(sample()));
    }

    #[test]
    fn a_device_name_filling_all_20_bytes_needs_no_nul() {
        let mut h = sample();
        h.device_name = DeviceName::try_from("ABCDEFGHIJKLMNOPQRST").unwrap();
        let mut out = [0u8; HEADER_SIZE];
        h.encode(&mut out).unwrap();
        assert_eq!(&out[14..34], b"ABCDEFGHIJKLMNOPQRST");
        assert_eq!(Header::decode(&out).unwrap().device_name, h.device_name);
    }

    #[test]
    fn rejects_what_is_not_a_header() {
        let mut out = [0u8; HEADER_SIZE];
        sample().encode(&mut out).unwrap();
        assert_eq!(Header::decode(&out[..57]), Err(Error::Truncated));
        let mut v = out;
        v[1] = 3;
        assert_eq!(Header::decode(&v), Err(Error::UnsupportedVersion(3)));
        let mut t = out;
        t[12] = b'X'; // text after the NUL padding
        assert_eq!(Header::decode(&t), Err(Error::BadHeader));
        let mut t = out;
        t[2] = 0x07;
        assert_eq!(Header::decode(&t), Err(Error::BadHeader));
        let mut d = out;
        d[14] = 0xFF;
        assert_eq!(Header::decode(&d), Err(Error::NotUtf8));
        assert_eq!(body_size_of(&d), 48);
        let mut small = [0u8; 57];
        assert_eq!(sample().encode(&mut small), Err(Error::BufferTooSmall));
    }

    #[test]
    fn timestamp_fraction_is_binary() {
        let t = Timestamp::from_secs_nanos(7, 500_000_000);
        assert_eq!(t.to_bits(), (7 << 32) | 0x8000_0000);
        assert_eq!(Timestamp::from_bits(t.to_bits()), t);
        for nanos in [0, 1, 2, 999, 123_456_789, 999_999_999] {
            assert_eq!(Timestamp::from_secs_nanos(0, nanos).subsec_nanos(), nanos);
        }
    }
}
