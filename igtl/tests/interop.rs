//! Interoperability with an OpenIGTLink implementation nobody here wrote: the PyPI package
//! pyigtl, pinned in `tests/python/requirements.txt` and installed into `target/python-env` by
//! `scripts/python-env` (which `scripts/test-all` runs).
//!
//! pyigtl plays PLUS (a server streaming TRANSFORMs at 40 Hz, `plus_server.py`) and Slicer (a
//! client receiving what `needle steer` will serve, `slicer_client.py`, which checks each body's
//! CRC since pyigtl itself does not), and packs frames for `decode_frame` (`pack.py`); header
//! versions 1 and 2 each way.

// Not tests/helper.rs: cargo would build that as a test of its own.
#[path = "interop/helper.rs"]
mod helper;

use helper::Helper;
use needle_igtl::{
    decode_frame, encode_frame, Error, Extended, Frame, FrameDecoder, FrameInfo, Header, Message,
    PolyData, Stats, Status, StatusCode, StringMessage, TextEncoding, Timestamp, Transform,
    HEADER_SIZE,
};
use serde_json::{json, Value};
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::thread;
use std::time::{Duration, Instant};

/// Every test's bound, Python's start-up (numpy's import) included.
const TEST_TIME: Duration = Duration::from_secs(10);
/// The helpers' timestamp, 1 700 000 000.25 s.
const SECONDS: u32 = 1_700_000_000;
const NANOS: u32 = 250_000_000;

/// Numbers of a JSON array of arrays (a matrix, a point list).
fn rows(v: &Value) -> Vec<Vec<f64>> {
    let rows = v.as_array().unwrap_or_else(|| panic!("not an array: {v}"));
    rows.iter()
        .map(|r| {
            let r = r.as_array().unwrap_or_else(|| panic!("not an array: {r}"));
            r.iter().map(|x| x.as_f64().expect("a number")).collect()
        })
        .collect()
}

/// Equal within `tol` entry by entry, and of the same shape.
fn assert_close(got: &[Vec<f64>], want: &[Vec<f64>], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: rows");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.len(), w.len(), "{what}: row {i}");
        for (j, (a, b)) in g.iter().zip(w).enumerate() {
            assert!((a - b).abs() <= tol, "{what}[{i}][{j}]: {a} != {b}");
        }
    }
}

/// The upper three rows of a transform's 4x4 matrix.
fn transform_rows(t: &Transform) -> Vec<Vec<f64>> {
    let (r, p) = (t.rotation(), t.translation());
    (0..3)
        .map(|i| [r[i][0], r[i][1], r[i][2], p[i]].map(f64::from).to_vec())
        .collect()
}

// ---------------------------------------------------------------------------------------------
// PLUS side: pyigtl streams TRANSFORMs, FrameDecoder reads them off the socket.

/// The pose plus_server.py sends as frame k: k degrees about z, translation (k, 2k, 3k) mm.
fn plus_pose(k: usize) -> Vec<Vec<f64>> {
    let (s, c) = (k as f64).to_radians().sin_cos();
    let k = k as f64;
    vec![
        vec![c, -s, 0.0, k],
        vec![s, c, 0.0, 2.0 * k],
        vec![0.0, 0.0, 1.0, 3.0 * k],
    ]
}

/// Feeds what `stream` brings into a `FrameDecoder` until `n` frames arrived; returns them with
/// their arrival times. Fails with the server's stderr if it dies first.
fn receive(
    stream: &mut TcpStream,
    server: &mut Helper,
    n: usize,
    deadline: Instant,
) -> Vec<(Frame, Instant)> {
    let mut decoder = FrameDecoder::<1024>::new();
    let mut frames = Vec::new();
    let mut buf = [0u8; 4096];
    while frames.len() < n {
        assert!(
            Instant::now() < deadline,
            "{} of {n} frames in time",
            frames.len()
        );
        let mut input = match stream.read(&mut buf) {
            Ok(0) => panic!("stream closed after {} of {n} frames", frames.len()),
            Ok(len) => &buf[..len],
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                server.check_running();
                continue;
            }
            Err(e) => panic!("read: {e}"),
        };
        while let Some(result) = decoder.feed(&mut input) {
            let frame = result.unwrap_or_else(|e| panic!("frame {}: {e:?}", frames.len()));
            frames.push((frame, Instant::now()));
        }
        assert!(input.is_empty());
    }
    assert_eq!(decoder.stats(), Stats::default(), "nothing skipped");
    frames
}

fn plus_stream(header_version: u16) {
    const N: usize = 40;
    const RATE_HZ: f64 = 40.0;
    let deadline = Instant::now() + TEST_TIME;
    let args = ["0", &N.to_string(), &header_version.to_string()];
    let mut plus = Helper::start("plus_server.py", &args);
    let line = plus.line(deadline);
    let port: u16 = line
        .strip_prefix("port ")
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("plus_server.py said {line:?}, not \"port P\""));
    let mut stream = TcpStream::connect(("127.0.0.1", port)).expect("connect to PLUS");
    stream
        .set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();

    let frames = receive(&mut stream, &mut plus, N, deadline);
    for (k, (frame, _)) in frames.iter().enumerate() {
        assert_eq!(frame.info.device_name.as_str(), "NeedleTipToReference");
        let Message::Transform(t) = &frame.message else {
            panic!("frame {k}: {:?}", frame.message)
        };
        // In order: frame k carries pose k.
        assert_close(
            &transform_rows(t),
            &plus_pose(k),
            1e-5,
            &format!("frame {k}"),
        );
        match &frame.info.extended {
            None => assert_eq!(header_version, 1, "frame {k} has no v3 extension"),
            Some(ext) => {
                assert_eq!(header_version, 2, "frame {k} has a v3 extension");
                assert_eq!(ext.message_id, k as u32);
                assert_eq!(ext.metadata.get("TransformStatus"), Some("OK"));
            }
        }
    }
    let elapsed = frames[N - 1].1 - frames[0].1;
    let nominal = (N - 1) as f64 / RATE_HZ;
    assert!(
        elapsed.as_secs_f64() >= 0.8 * nominal,
        "{N} frames in {elapsed:?}: faster than 40 Hz (nominal {nominal} s)"
    );

    // Nothing more once the server is done: exactly N frames.
    assert!(plus.finish(deadline).is_empty());
    let mut rest = Vec::new();
    stream.set_read_timeout(Some(TEST_TIME)).unwrap();
    stream.read_to_end(&mut rest).expect("read to the end");
    assert!(rest.is_empty(), "{} bytes after frame {N}", rest.len());
}

#[test]
fn plus_stream_of_transforms_at_40_hz_with_header_version_1() {
    plus_stream(1);
}

#[test]
fn plus_stream_of_transforms_at_40_hz_with_header_version_2() {
    plus_stream(2);
}

// ---------------------------------------------------------------------------------------------
// Slicer side: we serve, pyigtl receives and reports what it got.

/// One frame the test serves: its device name, content, and whether its body is corrupted
/// after encoding (the CRC no longer matches).
struct Sent {
    device: &'static str,
    message: Message,
    corrupt: bool,
}

/// The plan as a path: 50 points on an arc of radius 200 mm in the y-z plane.
fn path() -> Vec<[f32; 3]> {
    (0..50)
        .map(|i| {
            let a = 0.01 * i as f32;
            [0.0, 200.0 * (1.0 - a.cos()), 200.0 * a.sin()]
        })
        .collect()
}

/// What `needle steer --serve-slicer` will send, and a STRING whose body is corrupted between
/// two good frames: pyigtl must read past it by its body size.
fn slicer_frames() -> Vec<Sent> {
    let (s, c) = 30f32.to_radians().sin_cos();
    let tip = Transform::new(
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        [1.5, -2.25, 120.0],
    )
    .unwrap();
    let mut status = Status::new(StatusCode::NOT_READY);
    status.subcode = -42;
    status.error_name = "Warming".try_into().unwrap();
    status.message = "tracker warming up".try_into().unwrap();
    let utf8 = StringMessage {
        encoding: TextEncoding::Utf8,
        text: "Nadel → Ziel".try_into().unwrap(),
    };
    let ascii = |text| Message::String(StringMessage::ascii(text).unwrap());
    let sent = |device, message, corrupt| Sent {
        device,
        message,
        corrupt,
    };
    vec![
        sent(
            "NeedlePath",
            PolyData::polyline(&path()).unwrap().into(),
            false,
        ),
        sent("NeedleTipToReference", tip.into(), false),
        sent("Corrupted", ascii("this body is altered"), true),
        sent("NeedleStatus", status.into(), false),
        sent("NeedleMessage", ascii("needle at target"), false),
        sent("NeedleNote", utf8.into(), false),
    ]
}

/// Frame info: header version 1, or 2 with message id `id` and metadata in both encodings.
fn slicer_info(device: &str, version_2: bool, id: u32) -> FrameInfo {
    let mut info = FrameInfo::new(device).unwrap();
    info.timestamp = Timestamp::from_secs_nanos(SECONDS, NANOS);
    if version_2 {
        let mut ext = Extended {
            message_id: id,
            ..Extended::default()
        };
        let meta = &mut ext.metadata;
        meta.insert("PlanStatus", TextEncoding::UsAscii, "OK")
            .unwrap();
        meta.insert("Operator", TextEncoding::Utf8, "Dr. Müller")
            .unwrap();
        info.extended = Some(ext);
    }
    info
}

/// Accepts one connection by `deadline`, failing early if the client died.
fn accept(listener: &TcpListener, client: &mut Helper, deadline: Instant) -> TcpStream {
    listener.set_nonblocking(true).unwrap();
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false).unwrap();
                return stream;
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                assert!(
                    Instant::now() < deadline,
                    "slicer_client.py did not connect"
                );
                client.check_running();
                thread::sleep(Duration::from_millis(10));
            }
            Err(e) => panic!("accept: {e}"),
        }
    }
}

/// The content pyigtl reported for `m` matches it.
fn check_content(got: &Value, m: &Message, what: &str) {
    match m {
        Message::Transform(t) => {
            let mut want = transform_rows(t);
            want.push(vec![0.0, 0.0, 0.0, 1.0]);
            // Python prints the f32 values exactly; 1e-9 only allows for the JSON parser's
            // last bit, far below what an f32 resolves.
            assert_close(&rows(&got["matrix"]), &want, 1e-9, what);
        }
        Message::PolyData(p) => {
            let want: Vec<Vec<f64>> = p
                .points()
                .iter()
                .map(|q| q.map(f64::from).to_vec())
                .collect();
            assert_close(&rows(&got["points"]), &want, 1e-9, what);
            assert_eq!(got["lines"], json!([p.line()]), "{what}: one polyline");
            assert_eq!(
                got["repacked_identical"], true,
                "{what}: pyigtl writes the same bytes"
            );
        }
        Message::Status(s) => {
            assert_eq!(got["code"], s.code.0, "{what}");
            assert_eq!(got["subcode"], s.subcode, "{what}");
            assert_eq!(got["error_name"], s.error_name.as_str(), "{what}");
            assert_eq!(got["text"], s.message.as_str(), "{what}");
        }
        Message::String(s) => assert_eq!(got["string"], s.text.as_str(), "{what}"),
        other => panic!("{what}: not sent here: {other:?}"),
    }
}

/// What pyigtl reported for one frame: header fields, CRC verdict, then the content.
fn check_received(got: &Value, sent: &Sent, info: &FrameInfo) {
    let what = format!("{} ({})", sent.device, sent.message.type_name());
    assert_eq!(got["type"], sent.message.type_name(), "{what}: {got}");
    assert_eq!(got["device"], sent.device, "{what}");
    assert_eq!(got["header_version"], info.header_version(), "{what}");
    assert_eq!(
        got["crc_ok"], !sent.corrupt,
        "{what}: pyigtl's CRC64 verdict"
    );
    assert_eq!(got["error"], Value::Null, "{what}");
    if sent.corrupt {
        return;
    }
    let t = got["timestamp"].as_f64().expect("a timestamp");
    assert!((t - 1_700_000_000.25).abs() < 1e-6, "{what}: timestamp {t}");
    let (id, meta) = match &info.extended {
        None => (0, json!({})),
        Some(ext) => (ext.message_id, {
            let entries = ext.metadata.entries().iter();
            entries
                .map(|e| (e.key.to_string(), json!(e.value.as_str())))
                .collect()
        }),
    };
    assert_eq!(got["message_id"], id, "{what}");
    assert_eq!(got["metadata"], meta, "{what}");
    check_content(got, &sent.message, &what);
}

fn slicer_receives(version_2: bool) {
    let deadline = Instant::now() + TEST_TIME;
    let frames = slicer_frames();
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
    let port = listener.local_addr().unwrap().port().to_string();
    let count = frames.len().to_string();
    let mut slicer = Helper::start("slicer_client.py", &[&port, &count, "8"]);
    let mut stream = accept(&listener, &mut slicer, deadline);
    stream.set_write_timeout(Some(TEST_TIME)).unwrap();

    let mut infos = Vec::new();
    let mut buf = vec![0u8; 4096];
    for (i, sent) in frames.iter().enumerate() {
        let info = slicer_info(sent.device, version_2, i as u32 + 1);
        let n = encode_frame(&info, &sent.message, &mut buf).unwrap();
        if sent.corrupt {
            buf[n - 1] ^= 0x20; // a letter of the text changes case
        }
        // One write per frame: pyigtl 0.3.4 drops a header that arrives in pieces 10 ms apart.
        stream.write_all(&buf[..n]).expect("send");
        infos.push(info);
    }
    for (sent, info) in frames.iter().zip(&infos) {
        let line = slicer.line(deadline);
        let got: Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{line}: {e}"));
        check_received(&got, sent, info);
    }
    assert!(
        slicer.finish(deadline).is_empty(),
        "more than {count} lines"
    );
}

#[test]
fn slicer_receives_plan_tip_status_and_text_with_header_version_1() {
    slicer_receives(false);
}

#[test]
fn slicer_receives_plan_tip_status_and_text_with_header_version_2() {
    slicer_receives(true);
}

// ---------------------------------------------------------------------------------------------
// Frames pyigtl packs, decoded here.

/// The five points and polyline of pack.py's POLYDATA.
const PACKED_PATH: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [0.5, 0.0, 10.0],
    [1.0, 0.25, 20.0],
    [1.5, 0.5, 30.0],
    [2.0, 1.0, 40.0],
];

/// The content of pack.py's frame `device` as decoded here.
fn check_packed(device: &str, decoded: &Result<Frame, Error>) {
    let message = match decoded {
        Ok(frame) => &frame.message,
        // pyigtl's POSITION is a list of POINT-like 152-byte items with a quaternion, not the
        // spec's 28-byte body: rejected by its size.
        Err(e) => {
            assert_eq!((device, e), ("Probe", &Error::BadBodySize));
            return;
        }
    };
    match (device, message) {
        ("Tip", Message::Transform(t)) => {
            assert_eq!(
                t.rotation(),
                [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
            );
            assert_eq!(t.translation(), [10.0, 20.0, 30.0]);
        }
        ("Message", Message::String(s)) => {
            assert_eq!(s.encoding, TextEncoding::UsAscii);
            assert_eq!(s.text.as_str(), "needle at target");
        }
        ("Entry", Message::Point(list)) => {
            let want = [
                ("F-0", [1.0, 2.0, 3.0], 2.5),
                ("F-1", [-4.0, 5.5, 120.25], 3.0),
            ];
            assert_eq!(list.points.len(), want.len());
            for (p, (name, position, diameter)) in list.points.iter().zip(want) {
                assert_eq!(p.name.as_str(), name);
                assert_eq!(p.group.as_str(), "Fiducial");
                assert_eq!(p.rgba, [10, 20, 30, 255]);
                assert_eq!(p.position, position);
                assert_eq!(p.diameter, diameter);
                assert_eq!(p.owner.as_str(), "CT");
            }
        }
        // "Mesh" also has a triangle, a polygon cell, which is skipped by its size.
        ("Path" | "Mesh", Message::PolyData(p)) => {
            assert_eq!(p.points(), PACKED_PATH);
            assert_eq!(p.line(), [0, 1, 2, 3, 4]);
        }
        other => panic!("unexpected frame: {other:?}"),
    }
}

#[test]
fn frames_pyigtl_packs_decode_with_header_versions_1_and_2() {
    const DEVICES: [&str; 6] = ["Tip", "Message", "Entry", "Path", "Mesh", "Probe"];
    let wire = Helper::start("pack.py", &[]).finish(Instant::now() + TEST_TIME);

    let mut at = 0;
    let mut results = Vec::new();
    for version in [1, 2] {
        for (i, device) in DEVICES.into_iter().enumerate() {
            let header = Header::decode(&wire[at..]).expect("a header");
            assert_eq!(
                (header.version, header.device_name.as_str()),
                (version, device)
            );
            assert_eq!(header.timestamp.seconds, SECONDS);
            assert_eq!(header.timestamp.subsec_nanos(), NANOS);
            let len = HEADER_SIZE + header.body_size as usize;
            let decoded = decode_frame(&wire[at..]).map(|(frame, used)| {
                assert_eq!(used, len);
                frame
            });
            check_packed(device, &decoded);
            if let Ok(frame) = &decoded {
                match (&frame.info.extended, version) {
                    (None, 1) => {}
                    (Some(ext), 2) => {
                        assert_eq!(ext.message_id, i as u32 + 1);
                        assert_eq!(ext.metadata.get("TransformStatus"), Some("OK"));
                        assert_eq!(ext.metadata.get("Source"), Some("pyigtl"));
                        assert_eq!(ext.metadata.entries().len(), 2);
                    }
                    (ext, _) => panic!("{device}, header version {version}: {ext:?}"),
                }
            }
            results.push(decoded);
            at += len;
        }
    }
    assert_eq!(at, wire.len(), "nothing after the last frame");

    // The stream decoder, fed a few bytes at a time, finds the same frames and errors.
    let mut decoder = FrameDecoder::<1024>::new();
    let mut streamed = Vec::new();
    for chunk in wire.chunks(7) {
        let mut input = chunk;
        while let Some(result) = decoder.feed(&mut input) {
            streamed.push(result);
        }
    }
    assert_eq!(streamed, results);
    assert_eq!(decoder.stats(), Stats::default());
}
