//! Bad input over the wire: each gets its typed error reply, and the next good request is served.

mod wire_support;

use hil_sim::InProcess;
use needle_e2e::request_with_obstacles;
use needle_link::{Client, ClientConfig, LinkError};
use planner_core::device::plan_as_device;
use planner_core::wire::{
    encode_frame, encode_payload, Fault, Header, Reply, ReplyBody, Request, RequestBody,
    ENCODE_SCRATCH, MAX_FRAME, MAX_PLAN_REQUEST, PROTOCOL_VERSION, WIRE_MAX_OBSTACLES,
};
use planner_core::{Field, PlanError, Scenario, DEVICE_MAX_OBSTACLES};
use std::time::Duration;
use wire_support::Sim;

fn client() -> Client<Sim> {
    let config = ClientConfig {
        timeout: Duration::from_millis(100),
        retries: 2,
        deadline: None,
    };
    Client::new(Sim(InProcess::new()), config)
}

fn frame(req: &Request) -> Vec<u8> {
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let mut out = Vec::new();
    encode_frame(req, &mut scratch, &mut |b: &[u8]| out.extend_from_slice(b)).unwrap();
    out
}

/// Frames a raw payload with a valid CRC (for payloads that are not messages).
fn frame_payload(payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut scratch = [0u8; ENCODE_SCRATCH];
    encode_payload(1, payload, &mut scratch, &mut |b: &[u8]| {
        out.extend_from_slice(b)
    })
    .unwrap();
    out
}

/// Every reply until silence.
fn replies(c: &mut Client<Sim>) -> Vec<Reply> {
    let mut out = Vec::new();
    while let Some(r) = c.next_reply().unwrap() {
        out.push(r);
    }
    out
}

fn faults(c: &mut Client<Sim>) -> Vec<(u16, Fault)> {
    replies(c)
        .into_iter()
        .map(|r| match r.body {
            ReplyBody::Fault(f) => (r.header.id, f),
            other => panic!("expected a fault, got {other:?}"),
        })
        .collect()
}

/// A good request after the bad one: planned exactly as locally.
fn assert_still_serves(c: &mut Client<Sim>) {
    let mut s = Scenario::paper();
    s.options.forms = planner_core::model::form::FormSet::default();
    s.options.max_control_degree = 2;
    let local = plan_as_device(&s, None);
    let remote = c.plan(&s, &mut |_| {}).expect("the device serves again");
    assert_eq!(
        postcard::to_stdvec(&remote).unwrap(),
        postcard::to_stdvec(&local).unwrap()
    );
    assert!(c.ping().is_ok());
}

#[test]
fn a_frame_over_the_maximum_size() {
    let mut c = client();
    let mut bytes = vec![0u8];
    bytes.extend(std::iter::repeat_n(0x42, MAX_FRAME * 3));
    bytes.push(0);
    c.send_raw(&bytes).unwrap();
    assert_eq!(faults(&mut c), vec![(0, Fault::FrameTooLong)]);
    assert_eq!(c.link().0.device_stats().too_long, 1);
    assert_still_serves(&mut c);
}

#[test]
fn random_garbage() {
    let mut c = client();
    let mut x: u32 = 0x1234_5678;
    let garbage: Vec<u8> = (0..5000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as u8
        })
        .collect();
    let zeros = garbage.iter().filter(|&&b| b == 0).count();
    c.send_raw(&garbage).unwrap();
    c.send_raw(&[0]).unwrap();
    let got = faults(&mut c);
    assert!(!got.is_empty() && got.len() <= zeros + 1, "{}", got.len());
    for (id, f) in &got {
        assert_eq!(*id, 0);
        assert!(
            matches!(f, Fault::BadCrc | Fault::Truncated | Fault::FrameTooLong),
            "{f:?}"
        );
    }
    assert_still_serves(&mut c);
}

#[test]
fn truncated_frames() {
    let mut c = client();
    let whole = frame(&Request {
        header: Header::new(9),
        body: RequestBody::Ping { nonce: 99 },
    });
    for cut in [2, whole.len() / 2, whole.len() - 2] {
        let mut bytes = whole[..cut].to_vec();
        bytes.push(0);
        c.send_raw(&bytes).unwrap();
        let got = faults(&mut c);
        assert_eq!(got.len(), 1, "cut at {cut}");
        assert!(
            matches!(got[0], (0, Fault::BadCrc | Fault::Truncated)),
            "{got:?}"
        );
    }
    assert_still_serves(&mut c);
}

#[test]
fn a_frame_with_a_good_crc_that_is_no_message() {
    let mut c = client();
    c.send_raw(&frame_payload(&[PROTOCOL_VERSION, 7, 0xEE, 0xEE]))
        .unwrap();
    assert_eq!(faults(&mut c), vec![(7, Fault::Undecodable)]);
    c.send_raw(&frame_payload(&[0xFF])).unwrap();
    assert_eq!(faults(&mut c), vec![(0, Fault::Undecodable)]);
    assert_still_serves(&mut c);
}

#[test]
fn wrong_protocol_version() {
    let mut c = client();
    let req = Request {
        header: Header {
            version: PROTOCOL_VERSION + 1,
            id: 77,
        },
        body: RequestBody::Hello,
    };
    c.send_raw(&frame(&req)).unwrap();
    assert_eq!(
        faults(&mut c),
        vec![(
            77,
            Fault::UnsupportedVersion {
                supported: PROTOCOL_VERSION,
                got: PROTOCOL_VERSION + 1
            }
        )]
    );
    assert_still_serves(&mut c);
}

#[test]
fn a_scenario_over_the_devices_capacity() {
    let mut c = client();
    // Over the device's capacity but within the wire's: the planner's typed error (hil-sim runs
    // on the host, whose planner holds more, and still refuses what the board refuses).
    let n = DEVICE_MAX_OBSTACLES + 8;
    let result = c
        .plan_encoded(&request_with_obstacles(n), &mut |_| {})
        .unwrap();
    assert_eq!(
        result,
        Err(PlanError::TooManyObstacles {
            given: n as u16,
            capacity: DEVICE_MAX_OBSTACLES as u16
        })
    );
    assert_still_serves(&mut c);
    // Over what the device can even receive: refused before the upload.
    let big = request_with_obstacles(WIRE_MAX_OBSTACLES + 10);
    assert!(big.len() > MAX_PLAN_REQUEST);
    match c.plan_encoded(&big, &mut |_| {}) {
        Err(LinkError::Device(Fault::TooLarge { len, capacity })) => {
            assert_eq!(usize::from(len), big.len());
            assert_eq!(usize::from(capacity), MAX_PLAN_REQUEST);
        }
        other => panic!("{other:?}"),
    }
    assert_still_serves(&mut c);
    // A request that passed every CRC but is not a scenario.
    match c.plan_encoded(&[0xFF; 40], &mut |_| {}) {
        Err(LinkError::Device(Fault::BadScenario)) => {}
        other => panic!("{other:?}"),
    }
    assert_still_serves(&mut c);
}

#[test]
fn nans_in_a_scenario() {
    let mut c = client();
    let mut s = Scenario::paper();
    s.target.position[2] = f32::NAN;
    let result = c.plan(&s, &mut |_| {}).unwrap();
    assert_eq!(result, Err(PlanError::NotFinite(Field::TargetPosition)));
    let mut s = Scenario::paper();
    s.obstacles[1].radius = f32::INFINITY;
    let result = c.plan(&s, &mut |_| {}).unwrap();
    assert_eq!(result, Err(PlanError::NotFinite(Field::ObstacleRadius(1))));
    assert_still_serves(&mut c);
}

#[test]
fn progress_arrives_once_per_form() {
    let mut c = client();
    let s = Scenario::paper();
    let mut seen = Vec::new();
    let result = c.plan(&s, &mut |p| seen.push(p)).unwrap();
    let forms = result.unwrap().planned.report.forms.len();
    let done: Vec<u8> = seen.iter().map(|p| p.done).filter(|&d| d > 0).collect();
    assert_eq!(done, (1..=forms as u8).collect::<Vec<_>>());
    assert!(seen.iter().all(|p| usize::from(p.total) == forms));
}
