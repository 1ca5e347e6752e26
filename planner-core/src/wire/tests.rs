//! Size bounds, framing round trips and the decoder's faults.

use super::*;
use crate::chance::ChanceFigures;
use crate::execute::schedule::{Op, Posture, Schedule, ScheduleError, Step, Steps, MAX_STEPS};
use crate::execute::ScheduledPlan;
use crate::model::form::{Form, FormSet, SegmentKind};
use crate::model::scenario::{Obstacle, Scenario};
use crate::report::{FormOutcome, Insertion, PlanReport, SegmentPlan, SolveStatus};
use crate::{Field, PlanError};
use serde::Serialize;

fn encoded_len<T: Serialize>(v: &T) -> usize {
    let mut buf = [0u8; 16384];
    postcard::to_slice(v, &mut buf).expect("fits").len()
}

fn worst_outcome() -> FormOutcome {
    let mut segments = crate::report::Segments::new();
    for _ in 0..crate::MAX_CONTROL_DEGREE {
        segments
            .push(SegmentPlan {
                kind: SegmentKind::Arc,
                length: 1.0,
                bevel_deg: 2.0,
            })
            .unwrap();
    }
    FormOutcome {
        form: Form::new(4, 0b1111).unwrap(),
        status: SolveStatus::BudgetExhausted,
        feasible: true,
        length: 1.0,
        risk: 2.0,
        penalty: 3.0,
        objective: 4.0,
        min_clearance: 5.0,
        target_error: 6.0,
        insertion: Insertion {
            theta1_deg: 1.0,
            theta2_deg: 2.0,
            tilt_deg: 3.0,
            direction: [1.0, 0.0, 0.0],
        },
        segments,
        kkt_residual: 7.0,
        iterations: u32::MAX,
        evaluations: u32::MAX,
    }
}

fn worst_report() -> PlanReport {
    let mut forms = crate::report::FormOutcomes::new();
    while forms.push(worst_outcome()).is_ok() {}
    PlanReport {
        forms,
        best: Some(255),
    }
}

/// Every step the widest (a spin with the most turns), every number present.
fn worst_schedule() -> Schedule {
    let mut steps = Steps::new();
    while steps
        .push(Step {
            op: Op::InsertSpin {
                length_mm: 1.0,
                turns: u32::MAX,
            },
            duration_s: 2.0,
        })
        .is_ok()
    {}
    assert_eq!(steps.len(), MAX_STEPS);
    Schedule {
        posture: Posture {
            entry: [1.0; 3],
            theta1_deg: 2.0,
            theta2_deg: 3.0,
            direction: [0.0, 0.6, 0.8],
            roll_deg: 4.0,
        },
        steps,
        duration_s: 5.0,
        max_twist_deg: 6.0,
    }
}

fn worst_figures() -> ChanceFigures {
    let mut margins = heapless::Vec::new();
    while margins.push(1.0f32).is_ok() {}
    ChanceFigures {
        collision_probability: Some(0.5),
        target_error_p95: Some(1.5),
        margins,
        rounds: u32::MAX,
        within_bound: true,
    }
}

fn worst_chance_request() -> ChanceRequest {
    ChanceRequest {
        bound: 0.01,
        model: crate::execute::perturbation::Perturbation::default(),
        execution: crate::execute::risk::Execution::Steered(crate::steer::NoiseModel::DEFAULT),
    }
}

#[test]
// Test code: one worst case per type, read top to bottom.
#[allow(clippy::too_many_lines)]
fn bounds_are_exact_for_worst_case_values() {
    assert_eq!(encoded_len(&worst_outcome()), FormOutcome::MAX_SIZE);
    assert_eq!(encoded_len(&worst_report()), PlanReport::MAX_SIZE);
    let op = Op::InsertSpin {
        length_mm: 1.0,
        turns: u32::MAX,
    };
    assert_eq!(encoded_len(&op), Op::MAX_SIZE);
    assert_eq!(encoded_len(&worst_schedule()), Schedule::MAX_SIZE);
    let driver = ScheduleError::Driver(PlanError::TooManyObstacles {
        given: u16::MAX,
        capacity: u16::MAX,
    });
    assert_eq!(encoded_len(&driver), ScheduleError::MAX_SIZE);
    let planned = ScheduledPlan {
        report: worst_report(),
        schedule: Some(Ok(worst_schedule())),
    };
    assert_eq!(encoded_len(&planned), ScheduledPlan::MAX_SIZE);
    let figures = worst_figures();
    assert_eq!(encoded_len(&figures), ChanceFigures::MAX_SIZE);
    let result: PlanResult = Ok(DevicePlan {
        planned,
        chance: Some(figures),
    });
    assert_eq!(encoded_len(&result), MAX_PLAN_RESULT);
    let err = PlanError::TooManyObstacles {
        given: u16::MAX,
        capacity: u16::MAX,
    };
    assert_eq!(encoded_len(&err), PlanError::MAX_SIZE);
    assert_eq!(
        encoded_len(&PlanError::NotFinite(Field::ObstacleCenter(u16::MAX))),
        PlanError::MAX_SIZE - 2
    );

    let mut s = Scenario::paper();
    s.options.forms = FormSet(u32::MAX);
    s.options.risk_within_mm = Some(20.0);
    let mut req = PlanRequest::new(&s);
    let mut big = heapless::Vec::<Obstacle, WIRE_MAX_OBSTACLES>::new();
    while big
        .push(Obstacle {
            center: [1.0; 3],
            radius: 1.0,
        })
        .is_ok()
    {}
    // The wire list serialises as a plain sequence, so a full Vec stands in for it.
    let full = (
        &req.needle,
        &req.entry,
        &req.target,
        &big,
        &req.weights,
        &req.options,
        &req.driver,
        Some(worst_chance_request()),
    );
    assert_eq!(encoded_len(&full), MAX_PLAN_REQUEST);
    req.obstacles = WireObstacles::default();
    assert!(encoded_len(&req) < MAX_PLAN_REQUEST);

    let mut chunk = Chunk::new();
    chunk.resize(MAX_CHUNK, 0xAB).unwrap();
    let upload = Request {
        header: Header {
            version: 255,
            id: u16::MAX,
        },
        body: RequestBody::Upload {
            offset: u16::MAX,
            total: u16::MAX,
            crc: u32::MAX,
            data: chunk.clone(),
        },
    };
    assert_eq!(encoded_len(&upload), Request::MAX_SIZE);
    let part = Reply {
        header: Header {
            version: 255,
            id: u16::MAX,
        },
        body: ReplyBody::Part {
            offset: u16::MAX,
            total: u16::MAX,
            data: chunk,
        },
    };
    assert_eq!(encoded_len(&part), Reply::MAX_SIZE);
    let mut name = heapless::String::<16>::new();
    while name.push('x').is_ok() {}
    let mut build = heapless::String::<32>::new();
    while build.push('y').is_ok() {}
    let info = DeviceInfo {
        protocol: 255,
        name: name.clone(),
        firmware: name,
        build,
        max_obstacles: u16::MAX,
        max_control_degree: 255,
        form_count: 255,
        max_chunk: u16::MAX,
        upload_capacity: u16::MAX,
    };
    assert_eq!(encoded_len(&info), DeviceInfo::MAX_SIZE);
}

#[test]
fn frames_take_one_cobs_block() {
    assert_eq!(MAX_FRAME, MAX_PAYLOAD + frame::CRC_LEN + 1);
}

fn frame_bytes<T: Serialize + frame::Directed>(msg: &T) -> std::vec::Vec<u8> {
    extern crate std;
    let mut out = std::vec::Vec::new();
    let mut scratch = [0u8; ENCODE_SCRATCH];
    encode_frame(msg, &mut scratch, &mut |b: &[u8]| out.extend_from_slice(b)).unwrap();
    out
}

extern crate std;
use std::vec::Vec;

fn decode_all(bytes: &[u8]) -> Vec<Result<Vec<u8>, FrameError>> {
    let mut d = FrameDecoder::<MAX_FRAME>::for_requests();
    let mut out = Vec::new();
    for &b in bytes {
        if let Some(ev) = d.push(b) {
            out.push(ev.map(|p| p.to_vec()));
        }
    }
    out
}

#[test]
fn frame_round_trip_and_garbage_between_frames() {
    let req = Request {
        header: Header::new(7),
        body: RequestBody::Ping { nonce: 0 },
    };
    let f = frame_bytes(&req);
    assert_eq!(f[0], 0);
    assert_eq!(*f.last().unwrap(), 0);
    assert!(!f[1..f.len() - 1].contains(&0));
    let mut stream = f.clone();
    stream.extend_from_slice(&[0x13, 0x37, 0x99]); // garbage without a delimiter
    stream.extend_from_slice(&f);
    let events = decode_all(&stream);
    assert_eq!(events.len(), 3, "{events:?}");
    let payload = events[0].clone().unwrap();
    let back: Request = postcard::from_bytes(&payload).unwrap();
    assert_eq!(back, req);
    assert_eq!(events[1], Err(FrameError::Truncated));
    assert_eq!(events[2].clone().unwrap(), payload);
}

#[test]
fn every_single_bit_flip_is_detected() {
    let req = Request {
        header: Header::new(300),
        body: RequestBody::Fetch {
            offset: 1000,
            max_len: 64,
        },
    };
    let f = frame_bytes(&req);
    for i in 1..f.len() - 1 {
        for bit in 0..8 {
            let mut g = f.clone();
            g[i] ^= 1 << bit;
            for ev in decode_all(&g) {
                assert!(ev.is_err(), "flip at byte {i} bit {bit} accepted");
            }
        }
    }
}

#[test]
fn over_long_frames_are_dropped_and_the_decoder_resynchronises() {
    let mut stream = Vec::from([0u8]);
    stream.extend(std::iter::repeat_n(0x55, MAX_FRAME + 10));
    stream.push(0);
    let good = frame_bytes(&Request {
        header: Header::new(1),
        body: RequestBody::Hello,
    });
    stream.extend_from_slice(&good);
    let events = decode_all(&stream);
    assert_eq!(events.len(), 2);
    assert_eq!(events[0], Err(FrameError::TooLong));
    assert!(events[1].is_ok());
}

#[test]
fn too_many_obstacles_decode_into_a_typed_error() {
    let mut s = Scenario::paper();
    let base = PlanRequest::new(&s);
    let mut many = heapless::Vec::<Obstacle, WIRE_MAX_OBSTACLES>::new();
    let n = crate::DEVICE_MAX_OBSTACLES + 8;
    for i in 0..n {
        many.push(Obstacle {
            center: [0.0, 100.0 + (i % 30) as f32 * 30.0, 0.0],
            radius: 1.0,
        })
        .unwrap();
    }
    let shaped = (
        &base.needle,
        &base.entry,
        &base.target,
        &many,
        &base.weights,
        &base.options,
        &base.driver,
        &base.chance,
    );
    let mut buf = [0u8; MAX_PLAN_REQUEST];
    let bytes = postcard::to_slice(&shaped, &mut buf).unwrap();
    let req: PlanRequest = postcard::from_bytes(bytes).unwrap();
    assert_eq!(usize::from(req.obstacles.given()), n);
    // Refused at the device's capacity, even where the host's planner would hold them.
    assert_eq!(
        req.into_scenario(),
        Err(PlanError::TooManyObstacles {
            given: n as u16,
            capacity: crate::DEVICE_MAX_OBSTACLES as u16
        })
    );
    s.obstacles.clear();
    let req = PlanRequest::new(&s);
    let bytes = postcard::to_slice(&req, &mut buf).unwrap();
    let back: PlanRequest = postcard::from_bytes(bytes).unwrap();
    assert_eq!(back.into_scenario().unwrap(), s);
}

#[test]
fn an_echoed_request_is_never_taken_for_a_reply() {
    // Every request, looped back to the host, fails the reply decoder's CRC.
    let req = Request {
        header: Header::new(3),
        body: RequestBody::Fetch {
            offset: 0,
            max_len: 64,
        },
    };
    let f = frame_bytes(&req);
    let mut host = FrameDecoder::<MAX_FRAME>::for_replies();
    let events: Vec<_> = f
        .iter()
        .filter_map(|&b| host.push(b).map(|e| e.map(|_| ())))
        .collect();
    assert_eq!(events, [Err(FrameError::BadCrc)]);
}
