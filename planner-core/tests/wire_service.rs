//! The device service fed directly: state machine behaviour and random byte streams.

use planner_core::device::DeviceService;
use planner_core::wire::crc::crc32;
use planner_core::wire::{
    encode_frame, Chunk, Fault, FrameDecoder, Header, PlanRequest, Reply, ReplyBody, Request,
    RequestBody, ENCODE_SCRATCH, MAX_FRAME,
};
use planner_core::Scenario;
use proptest::prelude::*;

fn frame(id: u16, body: RequestBody) -> Vec<u8> {
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let mut out = Vec::new();
    let req = Request {
        header: Header::new(id),
        body,
    };
    encode_frame(&req, &mut scratch, &mut |b: &[u8]| out.extend_from_slice(b)).unwrap();
    out
}

/// Polls until idle (bounded) and decodes every reply; panics on a damaged or foreign frame.
fn run(dev: &mut DeviceService) -> Vec<Reply> {
    let mut out = Vec::new();
    let mut polls = 0;
    while dev.poll(&mut |b: &[u8]| out.extend_from_slice(b)) {
        polls += 1;
        assert!(polls < 100_000, "the service never went idle");
    }
    decode(&out)
}

fn decode(bytes: &[u8]) -> Vec<Reply> {
    let mut d = FrameDecoder::<MAX_FRAME>::for_replies();
    let mut replies = Vec::new();
    for &b in bytes {
        if let Some(ev) = d.push(b) {
            let payload = ev.expect("the device sends only intact frames");
            replies.push(postcard::from_bytes::<Reply>(payload).expect("a reply"));
        }
    }
    replies
}

fn upload_frames(id: u16, scenario: &Scenario) -> Vec<Vec<u8>> {
    let mut buf = [0u8; planner_core::wire::MAX_PLAN_REQUEST];
    let bytes = postcard::to_slice(&PlanRequest::new(scenario), &mut buf)
        .unwrap()
        .to_vec();
    let crc = crc32(&bytes);
    bytes
        .chunks(50)
        .enumerate()
        .map(|(i, c)| {
            frame(
                id,
                RequestBody::Upload {
                    offset: (i * 50) as u16,
                    total: bytes.len() as u16,
                    crc,
                    data: Chunk::from_slice(c).unwrap(),
                },
            )
        })
        .collect()
}

fn small_scenario() -> Scenario {
    let mut s = Scenario::paper();
    s.options.max_control_degree = 1;
    s
}

#[test]
fn busy_while_planning_then_cancel_frees_the_device() {
    let mut dev = Box::new(DeviceService::new());
    for f in upload_frames(1, &small_scenario()) {
        dev.receive(&f);
    }
    // Handle the upload frames only: the plan has started, no form done yet.
    let mut out = Vec::new();
    while !dev.is_planning() {
        assert!(dev.poll(&mut |b: &[u8]| out.extend_from_slice(b)));
    }
    for f in upload_frames(2, &small_scenario()).into_iter().take(1) {
        dev.receive(&f);
    }
    dev.receive(&frame(1, RequestBody::Cancel));
    let replies = run(&mut dev);
    assert!(replies
        .iter()
        .any(|r| r.header.id == 2 && r.body == ReplyBody::Fault(Fault::Busy { active: 1 })));
    assert!(replies
        .iter()
        .any(|r| r.header.id == 1 && r.body == ReplyBody::Cancelled { was_active: true }));
    assert!(!dev.is_planning());
    assert_eq!(dev.stats().plans, 0, "the cancelled plan did not finish");
    // Free again: a new upload is taken and planned to the end.
    for f in upload_frames(3, &small_scenario()) {
        dev.receive(&f);
    }
    let replies = run(&mut dev);
    assert!(replies
        .iter()
        .any(|r| r.header.id == 3 && matches!(r.body, ReplyBody::Finished { .. })));
}

#[test]
fn a_repeated_upload_is_acknowledged_not_replanned() {
    let mut dev = Box::new(DeviceService::new());
    let frames = upload_frames(5, &small_scenario());
    for f in &frames {
        dev.receive(f);
    }
    run(&mut dev);
    assert_eq!(dev.stats().plans, 1);
    dev.receive(frames.last().unwrap());
    let replies = run(&mut dev);
    assert!(
        matches!(replies[0].body, ReplyBody::Uploaded { received, total } if received == total)
    );
    assert_eq!(dev.stats().plans, 1);
    // The same id with another scenario is a new request, not a repeat.
    let mut other = small_scenario();
    other.target.tolerance = 0.2;
    for f in upload_frames(5, &other) {
        dev.receive(&f);
    }
    run(&mut dev);
    assert_eq!(dev.stats().plans, 2);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Random bytes never panic the service, it always goes idle, sends only intact reply
    /// frames, and answers a ping that follows the noise.
    #[test]
    fn random_streams_then_a_ping(
        noise in proptest::collection::vec(any::<u8>(), 0..3000),
        split in 1usize..300,
        nonce in any::<u32>(),
    ) {
        let mut dev = Box::new(DeviceService::new());
        for chunk in noise.chunks(split) {
            dev.receive(chunk);
            run(&mut dev);
        }
        dev.receive(&frame(42, RequestBody::Ping { nonce }));
        let replies = run(&mut dev);
        let pong = ReplyBody::Pong { nonce };
        prop_assert!(replies.iter().any(|r| r.header.id == 42 && r.body == pong), "no pong");
    }

    /// Valid frames with random bytes flipped: every damaged frame is rejected (never answered
    /// as if intact), and the device answers the intact ones.
    #[test]
    fn damaged_frames_are_rejected(
        flips in proptest::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 1..4),
        nonce in any::<u32>(),
    ) {
        let good = frame(7, RequestBody::Ping { nonce });
        let mut bad = good.clone();
        for (i, mask) in &flips {
            let at = 1 + i.index(bad.len() - 2);
            bad[at] ^= mask;
        }
        // Two equal flips of one byte cancel out.
        prop_assume!(bad != good);
        let mut dev = Box::new(DeviceService::new());
        dev.receive(&bad);
        let replies = run(&mut dev);
        prop_assert!(replies.iter().all(|r| matches!(r.body, ReplyBody::Fault(_))), "{replies:?}");
        dev.receive(&good);
        let replies = run(&mut dev);
        prop_assert_eq!(replies.len(), 1);
        prop_assert_eq!(&replies[0].body, &ReplyBody::Pong { nonce });
    }
}

/// Uploads `scenario`, lets the service plan it and fetches the encoded result back.
fn plan_on_service(scenario: &Scenario) -> planner_core::wire::PlanResult {
    let mut dev = Box::new(DeviceService::new());
    let mut replies = Vec::new();
    for f in upload_frames(9, scenario) {
        dev.receive(&f);
        replies.extend(run(&mut dev));
    }
    let len = replies
        .iter()
        .find_map(|r| match r.body {
            ReplyBody::Finished { len, .. } => Some(len),
            _ => None,
        })
        .expect("the plan finishes");
    let mut bytes = Vec::new();
    while bytes.len() < usize::from(len) {
        let offset = bytes.len() as u16;
        dev.receive(&frame(
            9,
            RequestBody::Fetch {
                offset,
                max_len: 192,
            },
        ));
        for r in run(&mut dev) {
            if let ReplyBody::Part { data, .. } = r.body {
                bytes.extend_from_slice(&data);
            }
        }
    }
    postcard::from_bytes(&bytes).expect("a plan result")
}

#[test]
fn the_device_refuses_bad_scenarios_with_the_same_typed_errors_as_the_host() {
    use planner_core::{Field, PlanError};
    let mut far = Scenario::paper();
    far.obstacles.clear();
    far.target.position = [0.0, 0.0, 1e12];
    let mut fine = Scenario::paper();
    fine.target.tolerance = 1e-9;
    let mut weight = Scenario::paper();
    weight.weights.penalty = -1.0;
    let mut driver = Scenario::paper();
    driver.driver.spin_rate = 0.0;
    for (s, want) in [
        (&far, PlanError::OutOfRange(Field::TargetPosition)),
        (&weight, PlanError::OutOfRange(Field::WeightPenalty)),
        (&driver, PlanError::NotPositive(Field::SpinRate)),
    ] {
        assert_eq!(s.validate(), Err(want));
        assert_eq!(plan_on_service(s).err(), Some(want));
    }
    let host = fine.validate().unwrap_err();
    assert!(matches!(host, PlanError::ToleranceTooFine { .. }));
    assert_eq!(plan_on_service(&fine).err(), Some(host));
}

#[test]
fn the_device_answers_an_unreachable_target_with_every_form_and_no_best() {
    use planner_core::model::scenario::Obstacle;
    use planner_core::SolveStatus;
    // Only a straight line, and a sphere on the way: no form reaches the target.
    let mut s = Scenario::paper();
    s.options.max_control_degree = 1;
    s.obstacles
        .push(Obstacle {
            center: [0.0, 0.0, 70.0],
            radius: 15.0,
        })
        .unwrap();
    let mut lines_only = planner_core::model::form::FormSet(0);
    lines_only.insert(planner_core::Form::parse("L").unwrap());
    s.options.forms = lines_only;
    let on_device = plan_on_service(&s)
        .expect("a finished plan, not an error")
        .planned;
    assert_eq!(on_device.report.best, None);
    assert_eq!(on_device.schedule, None);
    assert!(!on_device.report.forms.is_empty());
    assert!(on_device
        .report
        .forms
        .iter()
        .all(|o| !o.feasible && o.status == SolveStatus::Infeasible));
    // Exactly what the host plans (compared encoded: the absent numbers are NaN).
    assert_eq!(
        postcard::to_stdvec(&on_device).unwrap(),
        postcard::to_stdvec(&planner_core::plan_scheduled(&s).unwrap()).unwrap()
    );
}

/// Sends one request and returns the device's one answer to it.
fn ask(dev: &mut DeviceService, id: u16, body: RequestBody) -> ReplyBody {
    dev.receive(&frame(id, body));
    let mut replies = run(dev);
    assert_eq!(replies.len(), 1, "{replies:?}");
    replies.remove(0).body
}

#[test]
fn a_long_steering_answer_is_announced_and_fetched_in_parts() {
    use planner_core::steer::SteerConfig;
    let mut dev = Box::new(DeviceService::new());
    for f in upload_frames(4, &small_scenario()) {
        dev.receive(&f);
        run(&mut dev);
    }
    let config = SteerConfig::DEFAULT;
    let whole = ask(
        &mut dev,
        4,
        RequestBody::SteerStart {
            config,
            max_len: 1000,
        },
    );
    assert!(matches!(whole, ReplyBody::SteerStarted { .. }), "{whole:?}");
    // The same start (a repeat restarts from the entry) allowed 8 bytes: announced instead.
    let ReplyBody::SteerPending {
        reading: None,
        len,
        crc,
    } = ask(&mut dev, 4, RequestBody::SteerStart { config, max_len: 8 })
    else {
        panic!("a long answer is announced");
    };
    assert!(usize::from(len) > 8);
    let mut bytes = Vec::new();
    while bytes.len() < usize::from(len) {
        let offset = bytes.len() as u16;
        match ask(&mut dev, 4, RequestBody::SteerFetch { offset, max_len: 8 }) {
            ReplyBody::Part {
                offset: o,
                total,
                data,
            } => {
                assert_eq!((o, total), (offset, len));
                assert!(!data.is_empty() && data.len() <= 8);
                bytes.extend_from_slice(&data);
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(crc32(&bytes), crc);
    assert_eq!(postcard::from_bytes::<ReplyBody>(&bytes).unwrap(), whole);
    let past = ask(
        &mut dev,
        4,
        RequestBody::SteerFetch {
            offset: len + 1,
            max_len: 8,
        },
    );
    assert_eq!(
        past,
        ReplyBody::Fault(Fault::BadOffset {
            offset: len + 1,
            len
        })
    );
    let other = ask(
        &mut dev,
        5,
        RequestBody::SteerFetch {
            offset: 0,
            max_len: 8,
        },
    );
    assert_eq!(other, ReplyBody::Fault(Fault::NotSteering));
}
