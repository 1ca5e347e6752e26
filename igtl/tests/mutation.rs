//! A seeded mutation loop: 100 000 inputs (valid frames mutated, with and without a repaired
//! CRC, and plain noise) through `decode_frame` and `FrameDecoder` never panic, and whatever
//! decodes re-encodes to the same frame.

mod common;

use common::*;
use needle_igtl::{decode_frame, encode_frame, Error, Frame, FrameDecoder};

const INPUTS: usize = 100_000;

fn corpus() -> Vec<Vec<u8>> {
    let mut c = Vec::new();
    for (i, m) in samples().iter().enumerate() {
        c.push(encoded(&info_v1("Tracker"), m));
        c.push(encoded(&info_v3("Tracker", i as u32), m));
    }
    c.push(raw_frame(1, "IMAGE", b"US", &[3u8; 64]));
    c
}

/// Sets the header's CRC to that of the body it announces, when the bytes hold it: without
/// this almost every mutation would stop at the CRC and never reach the content decoders.
fn repair_crc(bytes: &mut [u8]) {
    if bytes.len() < 58 {
        return;
    }
    let size = u64::from_be_bytes(bytes[42..50].try_into().unwrap());
    let Some(end) = usize::try_from(size).ok().and_then(|s| s.checked_add(58)) else {
        return;
    };
    if end <= bytes.len() {
        let crc = crc64_bitwise(&bytes[58..end]);
        bytes[50..58].copy_from_slice(&crc.to_be_bytes());
    }
}

fn mutate(rng: &mut XorShift, corpus: &[Vec<u8>]) -> Vec<u8> {
    if rng.below(8) == 0 {
        let len = rng.below(300);
        return (0..len).map(|_| rng.next() as u8).collect();
    }
    let mut b = corpus[rng.below(corpus.len())].clone();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len().max(1));
        match rng.below(7) {
            0 if !b.is_empty() => b[at] ^= 1 << rng.below(8),
            1 if !b.is_empty() => b[at] = rng.next() as u8,
            2 => b.truncate(at),
            3 => {
                let extra: Vec<u8> = (0..rng.below(16)).map(|_| rng.next() as u8).collect();
                b.splice(at.min(b.len())..at.min(b.len()), extra);
            }
            // A count or size field (u16/u32 inside the body) set to a boundary value.
            4 if b.len() >= at + 4 => {
                let v: [u32; 5] = [0, 1, 0xFFFF, 0x7FFF_FFFF, u32::MAX];
                b[at..at + 4].copy_from_slice(&v[rng.below(5)].to_be_bytes());
            }
            5 if b.len() >= 50 => {
                let size = (rng.below(600) as u64).to_be_bytes();
                b[42..50].copy_from_slice(&size);
            }
            _ => {}
        }
    }
    if rng.below(2) == 0 {
        repair_crc(&mut b);
    }
    b
}

/// A decoded frame written out again decodes to itself (metadata entries that were dropped on
/// the way in are simply absent).
fn check_reencodes(frame: &Frame) {
    let mut buf = vec![0u8; 64 * 1024];
    let n = encode_frame(&frame.info, &frame.message, &mut buf).expect("a decoded frame encodes");
    let (again, used) = decode_frame(&buf[..n]).expect("a re-encoded frame decodes");
    assert_eq!(used, n);
    assert_eq!(again.message, frame.message);
    assert_eq!(again.info.device_name, frame.info.device_name);
    assert_eq!(again.info.timestamp, frame.info.timestamp);
    let entries = |f: &Frame| {
        f.info
            .extended
            .as_ref()
            .map(|e| e.metadata.entries().to_vec())
    };
    assert_eq!(entries(&again), entries(frame));
}

#[test]
fn a_hundred_thousand_mutated_inputs_never_panic() {
    let corpus = corpus();
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let mut decoded = 0usize;
    let mut errors = std::collections::BTreeSet::new();
    let mut decoder = FrameDecoder::<700>::new();
    for _ in 0..INPUTS {
        let input = mutate(&mut rng, &corpus);
        match decode_frame(&input) {
            Ok((frame, used)) => {
                assert!(used <= input.len());
                check_reencodes(&frame);
                decoded += 1;
            }
            Err(e) => {
                errors.insert(format!("{:?}", core::mem::discriminant(&e)));
            }
        }
        // The same bytes through one long-lived decoder, in random pieces.
        let mut rest = input.as_slice();
        while !rest.is_empty() {
            let (mut piece, tail) = rest.split_at(1 + rng.below(rest.len()));
            rest = tail;
            while let Some(r) = decoder.feed(&mut piece) {
                if let Ok(frame) = r {
                    check_reencodes(&frame);
                }
            }
            assert!(piece.is_empty());
        }
    }
    // The loop reached the content decoders, not only the framing.
    assert!(decoded > INPUTS / 50, "only {decoded} inputs decoded");
    for e in [
        Error::BadCrc,
        Error::Truncated,
        Error::BadBodySize,
        Error::Malformed,
        Error::UnknownType,
        Error::NotRigid,
        Error::BadHeader,
    ] {
        let d = format!("{:?}", core::mem::discriminant(&e));
        assert!(errors.contains(&d), "{e:?} never seen");
    }
}
