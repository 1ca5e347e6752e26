//! The seeds of the `service` fuzz target (`fuzz/seeds/`): byte streams of valid request frames of
//! the current protocol, so the fuzzer starts past the CRC and the version check, steering
//! included. Written by this test with `FUZZ_SEEDS_BLESS=1` (after a protocol change), checked
//! byte for byte otherwise, and each one fed to the service: it must be answered as intended.

use planner_core::device::DeviceService;
use planner_core::execute::nominal::posture_frame;
use planner_core::execute::schedule::schedule;
use planner_core::model::form::{Form, FormSet};
use planner_core::steer::{Pose, SteerConfig, TipMeasurement};
use planner_core::wire::crc::crc32;
use planner_core::wire::{
    encode_frame, Chunk, FrameDecoder, Header, PlanRequest, Reply, ReplyBody, Request, RequestBody,
    ENCODE_SCRATCH, MAX_FRAME, MAX_PLAN_REQUEST,
};
use planner_core::{plan, Scenario, SegmentKind};
use std::path::PathBuf;

/// First byte of every seed: the fuzz target's chunk-size selector.
const SPLIT: u8 = 17;

fn frame(version: u8, id: u16, body: RequestBody) -> Vec<u8> {
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let mut out = Vec::new();
    let mut header = Header::new(id);
    header.version = version;
    let req = Request { header, body };
    encode_frame(&req, &mut scratch, &mut |b: &[u8]| out.extend_from_slice(b)).unwrap();
    out
}

fn current(id: u16, body: RequestBody) -> Vec<u8> {
    frame(Header::new(0).version, id, body)
}

fn upload(id: u16, s: &Scenario) -> Vec<u8> {
    let mut buf = [0u8; MAX_PLAN_REQUEST];
    let bytes = postcard::to_slice(&PlanRequest::new(s), &mut buf)
        .unwrap()
        .to_vec();
    let crc = crc32(&bytes);
    let mut out = Vec::new();
    for (i, c) in bytes.chunks(120).enumerate() {
        out.extend(current(
            id,
            RequestBody::Upload {
                offset: (i * 120) as u16,
                total: bytes.len() as u16,
                crc,
                data: Chunk::from_slice(c).unwrap(),
            },
        ));
    }
    out
}

fn only(s: &mut Scenario, word: &str) {
    let mut forms = FormSet::default();
    forms.insert(Form::parse(word).unwrap());
    s.options.forms = forms;
}

fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    let fetch = |id| {
        current(
            id,
            RequestBody::Fetch {
                offset: 0,
                max_len: 192,
            },
        )
    };
    let mut nan = Scenario::paper();
    nan.target.position[2] = f32::NAN;
    let mut r = Scenario::paper();
    only(&mut r, "R");
    let mut rl = Scenario::paper();
    only(&mut rl, "RL");
    // Readings along the RL plan: one exact, one without a fix, one repeated, one far off.
    let sched = schedule(&rl, plan(&rl).unwrap().best().unwrap()).unwrap();
    let tip = posture_frame(&rl, &sched).advanced(SegmentKind::Arc, 1.0, 63.7);
    let at = |v: planner_core::model::kinematics::V3| [v.x, v.y, v.z];
    let fix = TipMeasurement::fix(1, 1.0, 0.0, at(tip.p), at(tip.e3()), at(tip.e2()));
    let blind = TipMeasurement {
        seq: 2,
        depth_mm: 2.0,
        pose: None,
        ..fix
    };
    let far = TipMeasurement {
        seq: 3,
        depth_mm: 3.0,
        pose: Some(Pose {
            position: [40.0, 0.0, 3.0],
            heading: at(tip.e3()),
            bevel: None,
        }),
        target: Some(rl.target.position),
        ..fix
    };
    let mut steer = upload(7, &rl);
    steer.extend(fetch(7));
    steer.extend(current(
        7,
        RequestBody::SteerStart {
            config: SteerConfig::DEFAULT,
            max_len: 16,
        },
    ));
    steer.extend(current(
        7,
        RequestBody::SteerFetch {
            offset: 0,
            max_len: 16,
        },
    ));
    for m in [fix, blind, blind, far] {
        let max_len = if m == far { 24 } else { 1000 };
        steer.extend(current(
            7,
            RequestBody::SteerReading {
                reading: m,
                max_len,
            },
        ));
    }
    steer.extend(current(7, RequestBody::SteerStatus));
    // The board asked to drive the insertion: a device without axes refuses, bad pieces too.
    let mut drive = steer.clone();
    for piece_mm in [1.0, 0.0, f32::NAN] {
        drive.extend(current(7, RequestBody::SteerDrive { piece_mm }));
    }
    let mut status = current(3, RequestBody::Status);
    status.extend(fetch(3));
    status.extend(current(3, RequestBody::Cancel));
    let mut upload_nan = upload(5, &nan);
    upload_nan.extend(current(5, RequestBody::Status));
    upload_nan.extend(fetch(5));
    let mut upload_r = upload(6, &r);
    upload_r.extend(fetch(6));
    vec![
        ("hello", current(1, RequestBody::Hello)),
        ("ping", current(2, RequestBody::Ping { nonce: 12345 })),
        ("status_fetch_cancel", status),
        ("wrong_version", frame(1, 4, RequestBody::Hello)),
        ("upload_nan", upload_nan),
        ("upload_plan_r", upload_r),
        ("steer_rl", steer),
        ("steer_drive", drive),
        (
            "steer_without_plan",
            current(
                8,
                RequestBody::SteerReading {
                    reading: fix,
                    max_len: 1000,
                },
            ),
        ),
    ]
}

fn replies(data: &[u8]) -> (Vec<Reply>, planner_core::device::DeviceStats) {
    let mut dev = Box::new(DeviceService::new());
    let mut out = Vec::new();
    for chunk in data.chunks(usize::from(SPLIT)) {
        dev.receive(chunk);
        let mut polls = 0;
        while dev.poll(&mut |b: &[u8]| out.extend_from_slice(b)) {
            polls += 1;
            assert!(polls < 100_000, "the service never went idle");
        }
    }
    let mut d = FrameDecoder::<MAX_FRAME>::for_replies();
    let mut replies = Vec::new();
    for &b in &out {
        if let Some(ev) = d.push(b) {
            replies.push(postcard::from_bytes::<Reply>(ev.unwrap()).unwrap());
        }
    }
    (replies, dev.stats())
}

#[test]
fn the_fuzz_seeds_are_requests_of_the_current_protocol() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/seeds");
    let bless = std::env::var_os("FUZZ_SEEDS_BLESS").is_some();
    for (name, frames) in seeds() {
        let mut data = vec![SPLIT];
        data.extend(&frames);
        let path = dir.join(name);
        if bless {
            std::fs::write(&path, &data).unwrap();
        }
        let stored = std::fs::read(&path).unwrap_or_default();
        assert!(
            stored == data,
            "fuzz/seeds/{name} is stale: run with FUZZ_SEEDS_BLESS=1"
        );
        let (replies, stats) = replies(&frames);
        assert!(!replies.is_empty(), "{name}: no answer");
        assert_eq!(stats.bad_crc + stats.truncated, 0, "{name}");
        let expected_undecodable = u32::from(name == "wrong_version");
        assert_eq!(stats.undecodable, expected_undecodable, "{name}");
        if name == "steer_rl" {
            let steered = replies
                .iter()
                .filter(|r| matches!(r.body, ReplyBody::Steer(_)))
                .count();
            assert_eq!(steered, 4, "{name}: {replies:?}");
            assert!(replies
                .iter()
                .any(|r| matches!(r.body, ReplyBody::SteerStatus { .. })));
        }
    }
    let names: Vec<_> = seeds().iter().map(|(n, _)| *n).collect();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let file = entry.unwrap().file_name().into_string().unwrap();
        assert!(
            names.contains(&file.as_str()),
            "fuzz/seeds/{file} is no seed of this test"
        );
    }
}
