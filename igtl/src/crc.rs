//! CRC-64/ECMA-182 (poly 0x42F0E1EBA9EA3693, init 0, not reflected, no final xor), the body check
//! of every OpenIGTLink header, from the `crc` crate's catalogue.

use crc::{Crc, CRC_64_ECMA_182};

/// The algorithm; its table is computed at compile time and lives in flash.
pub static CRC64: Crc<u64> = Crc::<u64>::new(&CRC_64_ECMA_182);

/// The CRC-64 of `bytes`, as an OpenIGTLink header carries it for its body.
///
/// ```
/// assert_eq!(needle_igtl::crc::crc64(b"123456789"), 0x6C40_DF5F_0B49_7347);
/// ```
pub fn crc64(bytes: &[u8]) -> u64 {
    CRC64.checksum(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_of_ecma_182() {
        // The catalogue's check value; OpenIGTLink's igtl_util.c crc64() gives the same.
        assert_eq!(crc64(b"123456789"), 0x6C40_DF5F_0B49_7347);
        assert_eq!(crc64(b""), 0);
    }

    #[test]
    fn matches_the_bitwise_definition() {
        // MSB-first long division by the ECMA-182 polynomial, as the spec defines it.
        let mut crc = 0u64;
        for &b in b"OpenIGTLink body" {
            crc ^= u64::from(b) << 56;
            for _ in 0..8 {
                crc = if crc & (1 << 63) != 0 {
                    (crc << 1) ^ 0x42F0_E1EB_A9EA_3693
                } else {
                    crc << 1
                };
            }
        }
        assert_eq!(crc64(b"OpenIGTLink body"), crc);
    }
}
