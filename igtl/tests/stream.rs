//! The streaming decoder: skipping, capacity, resynchronisation, and arbitrary splits.

mod common;

use common::*;
use needle_igtl::{Error, Frame, FrameDecoder, Message, Stats};

/// Feeds every chunk to `decoder` until used up; what came out, in order.
fn run<const N: usize>(
    decoder: &mut FrameDecoder<N>,
    chunks: &[&[u8]],
) -> Vec<Result<Frame, Error>> {
    let mut out = Vec::new();
    for chunk in chunks {
        let mut input = *chunk;
        while let Some(r) = decoder.feed(&mut input) {
            out.push(r);
        }
        assert!(input.is_empty(), "feed returned None with input left");
    }
    out
}

/// A frame's message, or why there is none.
type Outcome = Result<Message, Error>;

fn messages(results: &[Result<Frame, Error>]) -> Vec<Outcome> {
    results
        .iter()
        .map(|r| r.clone().map(|f| f.message))
        .collect()
}

/// Frames of every kind a stream may carry, and what a decoder of 1 KiB should make of them.
fn mixed_stream() -> (Vec<u8>, Vec<Outcome>) {
    let s = samples();
    let mut corrupt = encoded(&info_v1("Tip"), &s[0]);
    let last = corrupt.len() - 1;
    corrupt[last] ^= 0xFF;
    let parts: Vec<(Vec<u8>, Option<Outcome>)> = vec![
        (encoded(&info_v1("Tip"), &s[0]), Some(Ok(s[0].clone()))),
        (raw_frame(1, "IMAGE", b"US", &[7u8; 300]), None),
        (
            encoded(&info_v3("Tracker", 9), &s[2]),
            Some(Ok(s[2].clone())),
        ),
        (raw_frame(2, "VIDEO", b"cam", &[]), None),
        (corrupt, Some(Err(Error::BadCrc))),
        (encoded(&info_v1("Probe"), &s[1]), Some(Ok(s[1].clone()))),
        (raw_frame(1, "STRING", b"big", &[0u8; 2000]), None), // over the 1 KiB capacity
        (encoded(&info_v3("Path", 10), &s[6]), Some(Ok(s[6].clone()))),
        (
            raw_frame(1, "TRANSFORM", b"short", &[0u8; 40]),
            Some(Err(Error::BadBodySize)),
        ),
        (encoded(&info_v1("Fid"), &s[5]), Some(Ok(s[5].clone()))),
    ];
    let bytes = parts.iter().flat_map(|(b, _)| b.clone()).collect();
    let expected = parts.into_iter().filter_map(|(_, e)| e).collect();
    (bytes, expected)
}

#[test]
fn a_mixed_stream_decodes_in_order_and_counts_what_it_skipped() {
    let (bytes, expected) = mixed_stream();
    let mut d = FrameDecoder::<1024>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(messages(&out), expected);
    let stats = d.stats();
    assert_eq!(
        stats,
        Stats {
            skipped_unknown: 2,
            skipped_too_large: 1,
            discarded_bytes: 0
        }
    );
}

#[test]
fn an_unknown_type_is_skipped_by_size_between_two_messages() {
    let s = samples();
    // The unknown body is larger than the decoder: it cannot have been buffered.
    let unknown = raw_frame(1, "NDARRAY", b"x", &[0x41u8; 5000]);
    let bytes = [
        encoded(&info_v1("a"), &s[0]),
        unknown,
        encoded(&info_v1("b"), &s[3]),
    ]
    .concat();
    let mut d = FrameDecoder::<64>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(messages(&out), vec![Ok(s[0].clone()), Ok(s[3].clone())]);
    assert_eq!(d.stats().skipped_unknown, 1);
    assert_eq!(d.stats().skipped_too_large, 0);
}

#[test]
fn a_body_over_the_capacity_is_skipped_and_the_next_frame_decodes() {
    let s = samples();
    // 40 points and their polyline: a body of 40 + 40 × 12 + 41 × 4 = 684 bytes.
    let path = encoded(&info_v1("path"), &s[6]);
    assert_eq!(path.len(), 58 + 684);
    let bytes = [path, encoded(&info_v1("tip"), &s[0])].concat();
    let mut d = FrameDecoder::<683>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(messages(&out), vec![Ok(s[0].clone())]);
    assert_eq!(d.stats().skipped_too_large, 1);
    let mut d = FrameDecoder::<684>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(messages(&out), vec![Ok(s[6].clone()), Ok(s[0].clone())]);
    assert_eq!(d.stats().skipped_too_large, 0);
}

#[test]
fn a_corrupted_crc_is_rejected_and_the_stream_resynchronises_on_the_next_frame() {
    let s = samples();
    let mut bad = encoded(&info_v1("tip"), &s[0]);
    bad[70] ^= 0x10;
    let bytes = [
        bad,
        encoded(&info_v1("tip"), &s[1]),
        encoded(&info_v1("tip"), &s[2]),
    ]
    .concat();
    let mut d = FrameDecoder::<512>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(
        messages(&out),
        vec![Err(Error::BadCrc), Ok(s[1].clone()), Ok(s[2].clone())]
    );
}

#[test]
fn garbage_between_frames_is_reported_once_and_slid_past() {
    let s = samples();
    let garbage: Vec<u8> = (0..97u8).map(|i| i.wrapping_mul(37) | 0x80).collect();
    let bytes = [
        encoded(&info_v1("a"), &s[0]),
        garbage.clone(),
        encoded(&info_v1("b"), &s[1]),
    ]
    .concat();
    let mut d = FrameDecoder::<512>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(out.len(), 3);
    assert!(matches!(out[1], Err(Error::UnsupportedVersion(_))));
    assert_eq!(out[2].clone().unwrap().message, s[1]);
    assert_eq!(d.stats().discarded_bytes, garbage.len() as u64);
}

#[test]
fn a_bad_device_name_costs_only_its_own_frame() {
    let s = samples();
    let bytes = [
        raw_frame(1, "STRING", &[b'x', 0xFE], &[0, 3, 0, 2, b'h', b'i']),
        encoded(&info_v1("ok"), &s[3]),
    ]
    .concat();
    let mut d = FrameDecoder::<512>::new();
    let out = run(&mut d, &[&bytes]);
    assert_eq!(messages(&out), vec![Err(Error::NotUtf8), Ok(s[3].clone())]);
    assert_eq!(d.stats().discarded_bytes, 0);
}

#[test]
fn a_stream_split_at_every_position_decodes_the_same() {
    let (bytes, expected) = mixed_stream();
    let mut whole = FrameDecoder::<1024>::new();
    let reference = run(&mut whole, &[&bytes]);
    assert_eq!(messages(&reference), expected);
    for cut in 0..=bytes.len() {
        let mut d = FrameDecoder::<1024>::new();
        let out = run(&mut d, &[&bytes[..cut], &bytes[cut..]]);
        assert_eq!(out, reference, "split at {cut}");
        assert_eq!(d.stats(), whole.stats(), "split at {cut}");
    }
    let mut d = FrameDecoder::<1024>::new();
    let bytewise: Vec<&[u8]> = bytes.chunks(1).collect();
    assert_eq!(run(&mut d, &bytewise), reference);
}

#[test]
fn reset_drops_a_partial_frame() {
    let s = samples();
    let first = encoded(&info_v1("a"), &s[0]);
    let second = encoded(&info_v1("b"), &s[1]);
    let mut d = FrameDecoder::<512>::new();
    assert!(run(&mut d, &[&first[..70]]).is_empty());
    d.reset();
    assert_eq!(messages(&run(&mut d, &[&second])), vec![Ok(s[1].clone())]);
}
