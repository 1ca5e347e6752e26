//! Whole frames: built by hand from the spec, round trips of every type in header versions 1
//! and 2, and the rejections.

mod common;

use common::*;
use needle_igtl::{decode_frame, encode_frame, Error, FrameInfo, Message, Transform};

#[test]
fn a_transform_frame_built_byte_by_byte_from_the_spec_decodes() {
    // 90° about z: R = [[0, -1, 0], [1, 0, 0], [0, 0, 1]], translation (10, 20, 30) mm.
    // The body is column by column: R11 R21 R31, R12 R22 R32, R13 R23 R33, TX TY TZ.
    #[rustfmt::skip]
    let body: [u8; 48] = [
        0x00, 0x00, 0x00, 0x00, /* R11 0 */  0x3F, 0x80, 0x00, 0x00, /* R21 1 */
        0x00, 0x00, 0x00, 0x00, /* R31 0 */  0xBF, 0x80, 0x00, 0x00, /* R12 -1 */
        0x00, 0x00, 0x00, 0x00, /* R22 0 */  0x00, 0x00, 0x00, 0x00, /* R32 0 */
        0x00, 0x00, 0x00, 0x00, /* R13 0 */  0x00, 0x00, 0x00, 0x00, /* R23 0 */
        0x3F, 0x80, 0x00, 0x00, /* R33 1 */  0x41, 0x20, 0x00, 0x00, /* TX 10 */
        0x41, 0xA0, 0x00, 0x00, /* TY 20 */  0x41, 0xF0, 0x00, 0x00, /* TZ 30 */
    ];
    #[rustfmt::skip]
    let mut wire = vec![
        0x00, 0x01, // header version 1
        b'T', b'R', b'A', b'N', b'S', b'F', b'O', b'R', b'M', 0, 0, 0, // type char[12]
        b'T', b'i', b'p', 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, // device char[20]
        0x65, 0x53, 0xF1, 0x00, 0x80, 0x00, 0x00, 0x00, // 1 700 000 000.5 s
        0, 0, 0, 0, 0, 0, 0, 48, // body size
    ];
    wire.extend_from_slice(&crc64_bitwise(&body).to_be_bytes());
    wire.extend_from_slice(&body);
    assert_eq!(wire.len(), 58 + 48);

    let (frame, used) = decode_frame(&wire).unwrap();
    assert_eq!(used, wire.len());
    assert_eq!(frame.info.device_name.as_str(), "Tip");
    assert_eq!(frame.info.timestamp.seconds, 1_700_000_000);
    assert_eq!(frame.info.timestamp.subsec_nanos(), 500_000_000);
    assert_eq!(frame.info.extended, None);
    let Message::Transform(t) = frame.message else {
        panic!("not a TRANSFORM: {:?}", frame.message)
    };
    assert_eq!(
        t.rotation(),
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    );
    assert_eq!(t.translation(), [10.0, 20.0, 30.0]);

    // The codec writes the same bytes back.
    let mut info = FrameInfo::new("Tip").unwrap();
    info.timestamp = frame.info.timestamp;
    assert_eq!(encoded(&info, &Message::Transform(t)), wire);
}

#[test]
fn every_type_round_trips_in_header_version_1() {
    for m in samples() {
        let wire = encoded(&info_v1("Tracker"), &m);
        assert_eq!(&wire[0..2], &[0, 1]);
        let (back, used) = decode_frame(&wire).unwrap();
        assert_eq!(used, wire.len());
        assert_eq!(back.message, m);
        assert_eq!(back.info, info_v1("Tracker"));
    }
}

#[test]
fn every_type_round_trips_in_header_version_2_with_metadata() {
    for (i, m) in samples().into_iter().enumerate() {
        let info = info_v3("ABCDEFGHIJKLMNOPQRST", 1000 + i as u32);
        let wire = encoded(&info, &m);
        assert_eq!(&wire[0..2], &[0, 2]);
        // The extended header opens the body: its size, then the metadata header size (2 + 8 per
        // entry), then the metadata size (keys and values).
        assert_eq!(&wire[58..60], &[0, 12]);
        assert_eq!(&wire[60..62], &[0, 18]);
        let meta = ("TransformStatus".len() + 2 + "Operator".len() + "Dr. Müller".len()) as u32;
        assert_eq!(&wire[62..66], &meta.to_be_bytes());
        let (back, used) = decode_frame(&wire).unwrap();
        assert_eq!(used, wire.len());
        assert_eq!(back.message, m);
        assert_eq!(back.info, info);
        let ext = back.info.extended.unwrap();
        assert_eq!(ext.metadata.get("TransformStatus"), Some("OK"));
        assert_eq!(ext.metadata.get("Operator"), Some("Dr. Müller"));
    }
}

#[test]
fn a_v3_frame_built_by_hand_exposes_id_metadata_and_content() {
    let content = be_f32s(&[1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0]);
    let mut body = vec![0, 12, 0, 10, 0, 0, 0, 13, 0, 0, 0, 42];
    body.extend_from_slice(&content);
    body.extend_from_slice(&[0, 1, 0, 6, 0, 3, 0, 0, 0, 7]); // one entry: key 6, US-ASCII, value 7
    body.extend_from_slice(b"StatusMissing");
    let wire = raw_frame(2, "POSITION", b"Probe", &body);
    let (frame, _) = decode_frame(&wire).unwrap();
    let ext = frame.info.extended.unwrap();
    assert_eq!(ext.message_id, 42);
    assert_eq!(ext.metadata.get("Status"), Some("Missing"));
    assert_eq!(ext.metadata.dropped(), 0);
    let Message::Position(p) = frame.message else {
        panic!("not a POSITION")
    };
    assert_eq!(p.position(), [1.0, 2.0, 3.0]);
    assert_eq!(p.quaternion(), [0.0, 0.0, 0.0, 1.0]);

    // A longer extended header (a later protocol's) is passed over; sizes that overrun the body
    // are malformed.
    let mut longer = vec![0, 16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0xEE, 0xEE, 0xEE, 0xEE];
    longer.extend_from_slice(&content);
    assert!(decode_frame(&raw_frame(2, "POSITION", b"P", &longer)).is_ok());
    let mut overrun = body.clone();
    overrun[7] = 14;
    let wire = raw_frame(2, "POSITION", b"P", &overrun);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::Malformed);
}

#[test]
fn a_corrupted_body_fails_the_crc() {
    let mut wire = encoded(&info_v1("T"), &samples()[0]);
    let last = wire.len() - 1;
    wire[last] ^= 0x01;
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::BadCrc);
    let mut wire = encoded(&info_v1("T"), &samples()[0]);
    wire[57] ^= 0x80; // the CRC field itself
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::BadCrc);
}

#[test]
fn fixed_size_types_of_the_wrong_size_are_rejected() {
    let zeros = vec![0u8; 300];
    for (ty, good) in [("TRANSFORM", 48), ("POSITION", 28)] {
        for len in [0, 12, 24, good - 1, good + 1, good + 4] {
            let wire = raw_frame(1, ty, b"d", &zeros[..len]);
            assert_eq!(
                decode_frame(&wire).unwrap_err(),
                Error::BadBodySize,
                "{ty} {len}"
            );
        }
    }
    for len in [1, 135, 137, 271] {
        let wire = raw_frame(1, "POINT", b"d", &zeros[..len]);
        assert_eq!(
            decode_frame(&wire).unwrap_err(),
            Error::BadBodySize,
            "POINT {len}"
        );
    }
    let wire = raw_frame(1, "STATUS", b"d", &zeros[..29]);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::BadBodySize);
    // STRING: length field 5 with 4 bytes of text, then with 6.
    for text in [&b"abcd"[..], b"abcdef"] {
        let mut body = vec![0, 3, 0, 5];
        body.extend_from_slice(text);
        let wire = raw_frame(1, "STRING", b"d", &body);
        assert_eq!(decode_frame(&wire).unwrap_err(), Error::BadBodySize);
    }
    // POLYDATA: two points announced, one sent.
    let mut body = vec![0u8; 40];
    body[3] = 2;
    body.extend_from_slice(&be_f32s(&[1.0, 2.0, 3.0]));
    let wire = raw_frame(1, "POLYDATA", b"d", &body);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::BadBodySize);
}

#[test]
fn a_transform_that_is_not_rigid_is_rejected() {
    let scaled = [2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0];
    let reflected = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0];
    let sheared = [1.0, 0.0, 0.0, 0.01, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
    let mut nan = reflected;
    nan[8] = f32::NAN;
    for m in [scaled, reflected, sheared, nan] {
        let wire = raw_frame(1, "TRANSFORM", b"d", &be_f32s(&m));
        assert_eq!(decode_frame(&wire).unwrap_err(), Error::NotRigid);
    }
    let off_unit = be_f32s(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.1]);
    let wire = raw_frame(1, "POSITION", b"d", &off_unit);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::NotRigid);
}

#[test]
fn status_text_is_nul_terminated_and_names_may_fill_their_fields() {
    let mut body = vec![0, 18]; // hardware failure
    body.extend_from_slice(&(-7i64).to_be_bytes());
    body.extend_from_slice(b"TwentyCharacterName!"); // char[20] with no NUL
    body.extend_from_slice(b"motor stalled\0");
    let wire = raw_frame(1, "STATUS", b"ABCDEFGHIJKLMNOPQRST", &body);
    let (frame, _) = decode_frame(&wire).unwrap();
    assert_eq!(frame.info.device_name.as_str(), "ABCDEFGHIJKLMNOPQRST");
    let Message::Status(s) = frame.message else {
        panic!("not a STATUS")
    };
    assert_eq!(s.code, needle_igtl::StatusCode::HARDWARE_FAILURE);
    assert_eq!(s.subcode, -7);
    assert_eq!(s.error_name.as_str(), "TwentyCharacterName!");
    assert_eq!(s.message.as_str(), "motor stalled");
}

#[test]
fn text_must_match_its_encoding() {
    let mut body = vec![0, 3, 0, 2];
    body.extend_from_slice("é".as_bytes());
    assert_eq!(
        decode_frame(&raw_frame(1, "STRING", b"d", &body)).unwrap_err(),
        Error::NotAscii
    );
    body[1] = 106;
    assert!(decode_frame(&raw_frame(1, "STRING", b"d", &body)).is_ok());
    body[2..].copy_from_slice(&[0, 2, 0xC3, 0x28]);
    assert_eq!(
        decode_frame(&raw_frame(1, "STRING", b"d", &body)).unwrap_err(),
        Error::NotUtf8
    );
    body[1] = 4; // ISO-8859-1
    let err = decode_frame(&raw_frame(1, "STRING", b"d", &body)).unwrap_err();
    assert_eq!(err, Error::UnsupportedEncoding(4));
    let wire = raw_frame(1, "STRING", &[b'a', 0xFF], &[0, 3, 0, 0]);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::NotUtf8);
}

#[test]
fn polydata_skips_other_cells_and_checks_its_line() {
    // 3 points; one vertex cell (1, 0); the line 0-1-2; one triangle (3, 0, 1, 2).
    let header = |nlines: u32, size_lines: u32| -> Vec<u8> {
        [3u32, 1, 8, nlines, size_lines, 1, 16, 0, 0, 0]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect()
    };
    let points = be_f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
    let cells = |line: &[u32]| -> Vec<u8> {
        let mut c: Vec<u8> = [1u32, 0].iter().flat_map(|v| v.to_be_bytes()).collect();
        c.extend(line.iter().flat_map(|v| v.to_be_bytes()));
        c.extend([3u32, 0, 1, 2].iter().flat_map(|v| v.to_be_bytes()));
        c
    };
    let body = [header(1, 16), points.clone(), cells(&[3, 0, 1, 2])].concat();
    let (frame, _) = decode_frame(&raw_frame(1, "POLYDATA", b"path", &body)).unwrap();
    let Message::PolyData(p) = frame.message else {
        panic!("not POLYDATA")
    };
    assert_eq!(p.points().len(), 3);
    assert_eq!(p.points()[2], [1.0, 1.0, 0.0]);
    assert_eq!(p.line(), &[0, 1, 2]);

    let bad_index = [header(1, 16), points.clone(), cells(&[3, 0, 1, 3])].concat();
    let wire = raw_frame(1, "POLYDATA", b"p", &bad_index);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::Malformed);
    let two_lines = [header(2, 20), points.clone(), cells(&[2, 0, 1, 1, 2])].concat();
    let wire = raw_frame(1, "POLYDATA", b"p", &two_lines);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::Unsupported);
    let miscounted = [header(1, 16), points, cells(&[2, 0, 1, 2])].concat();
    let wire = raw_frame(1, "POLYDATA", b"p", &miscounted);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::Malformed);
}

#[test]
fn unknown_types_truncation_and_small_buffers() {
    let wire = raw_frame(1, "IMAGE", b"d", &[1, 2, 3]);
    assert_eq!(decode_frame(&wire).unwrap_err(), Error::UnknownType);
    let good = encoded(&info_v1("T"), &samples()[0]);
    for cut in [0, 10, 57, 58, good.len() - 1] {
        assert_eq!(decode_frame(&good[..cut]).unwrap_err(), Error::Truncated);
    }
    let m = Message::Transform(Transform::IDENTITY);
    let mut small = [0u8; 58 + 47];
    assert_eq!(
        encode_frame(&info_v1("T"), &m, &mut small),
        Err(Error::BufferTooSmall)
    );
    let mut small = [0u8; 58 + 12 + 48 + 10];
    assert_eq!(
        encode_frame(&info_v3("T", 1), &m, &mut small),
        Err(Error::BufferTooSmall)
    );
}
