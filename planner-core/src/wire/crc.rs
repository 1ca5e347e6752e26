//! CRC-32 (IEEE 802.3 / zlib, the catalogue's CRC-32/ISO-HDLC) from the `crc` crate, with its
//! 256-entry table in flash: one lookup per byte.
//!
//! CRC-32 rather than CRC-16: on a noisy line a 16-bit check lets about one corrupted frame in
//! 65 536 through, which a bench that sends thousands of frames would eventually hit.

use crc::{Crc, CRC_32_ISO_HDLC};

/// The algorithm; its table is computed at compile time and lives in flash.
pub static CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// The CRC-32 of `bytes`.
///
/// ```
/// assert_eq!(planner_core::wire::crc::crc32(b"123456789"), 0xCBF4_3926);
/// ```
pub fn crc32(bytes: &[u8]) -> u32 {
    CRC32.checksum(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_of_the_standard() {
        // The catalogue's check value for CRC-32/ISO-HDLC.
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn incremental_equals_one_shot() {
        let mut c = CRC32.digest();
        c.update(b"12345");
        c.update(b"6789");
        assert_eq!(c.finalize(), crc32(b"123456789"));
    }
}
