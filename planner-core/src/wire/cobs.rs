//! Consistent Overhead Byte Stuffing: removes every 0x00 from a frame so that 0x00 can delimit
//! frames on the line. Overhead is one byte per 254 bytes (at least one).

/// Encoded length bound for `n` raw bytes (without delimiters).
pub const fn max_encoded_len(n: usize) -> usize {
    n + n / 254 + 1
}

/// Encodes `raw`, handing the encoded bytes to `out` block by block (no output buffer needed).
///
/// Each block is a code byte (distance to the next zero, or 0xFF for a full block without one)
/// followed by up to 254 non-zero bytes.
pub fn encode(raw: &[u8], out: &mut dyn FnMut(&[u8])) {
    let mut rest = raw;
    loop {
        let run = rest.iter().take(254).position(|&b| b == 0);
        match run {
            Some(n) => {
                out(&[(n + 1) as u8]);
                out(&rest[..n]);
                rest = &rest[n + 1..];
            }
            None if rest.len() >= 254 => {
                out(&[0xFF]);
                out(&rest[..254]);
                rest = &rest[254..];
                // A full block carries no implied zero; an empty tail still needs its code byte
                // only if the data did not end exactly here.
                if rest.is_empty() {
                    return;
                }
            }
            None => {
                out(&[(rest.len() + 1) as u8]);
                out(rest);
                return;
            }
        }
    }
}

/// Why a received block sequence is not valid COBS.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CobsError {
    /// A code byte points past the end of the frame (the frame was cut short).
    Truncated,
    /// A zero byte inside the frame (cannot happen after delimiting, kept for direct callers).
    ZeroInside,
}

/// Decodes `buf[..len]` in place and returns the decoded length.
///
/// In-place is safe because output never overtakes input: each code byte yields at most as many
/// bytes as it occupies.
pub fn decode_in_place(buf: &mut [u8], len: usize) -> Result<usize, CobsError> {
    let len = len.min(buf.len());
    let mut read = 0;
    let mut write = 0;
    while read < len {
        let code = buf[read];
        if code == 0 {
            return Err(CobsError::ZeroInside);
        }
        read += 1;
        let n = usize::from(code) - 1;
        if read + n > len {
            return Err(CobsError::Truncated);
        }
        for k in 0..n {
            let b = buf[read + k];
            if b == 0 {
                return Err(CobsError::ZeroInside);
            }
            buf[write] = b;
            write += 1;
        }
        read += n;
        if code != 0xFF && read < len {
            buf[write] = 0;
            write += 1;
        }
    }
    Ok(write)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(raw: &[u8]) {
        let mut enc = [0u8; 1200];
        let mut n = 0;
        encode(raw, &mut |chunk: &[u8]| {
            enc[n..n + chunk.len()].copy_from_slice(chunk);
            n += chunk.len();
        });
        assert!(
            n <= max_encoded_len(raw.len()),
            "{n} > bound for {}",
            raw.len()
        );
        assert!(!enc[..n].contains(&0));
        let m = decode_in_place(&mut enc, n).unwrap();
        assert_eq!(&enc[..m], raw);
    }

    #[test]
    fn known_vectors() {
        let mut enc = [0u8; 16];
        let mut n = 0;
        encode(&[0x11, 0x22, 0x00, 0x33], &mut |c: &[u8]| {
            enc[n..n + c.len()].copy_from_slice(c);
            n += c.len();
        });
        assert_eq!(&enc[..n], &[0x03, 0x11, 0x22, 0x02, 0x33]);
    }

    #[test]
    fn round_trips_at_block_edges() {
        let mut data = [0u8; 1000];
        for (i, b) in data.iter_mut().enumerate() {
            *b = (i % 251) as u8 + 1;
        }
        for len in [0, 1, 2, 253, 254, 255, 508, 509, 1000] {
            round_trip(&data[..len]);
        }
        data[253] = 0;
        data[600] = 0;
        for len in [254, 255, 601, 1000] {
            round_trip(&data[..len]);
        }
        round_trip(&[0, 0, 0]);
    }

    #[test]
    fn truncated_input_is_an_error() {
        let mut buf = [0x05, 1, 2];
        assert_eq!(decode_in_place(&mut buf, 3), Err(CobsError::Truncated));
    }
}
