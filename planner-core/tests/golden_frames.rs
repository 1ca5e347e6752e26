//! Frames on the line stay byte for byte what they were when the protocol was first fielded
//! (planner-core/tests/data/golden_frames.txt): a host or device built before a change to the
//! framing code (COBS, CRC-32, postcard layout) still understands one built after it.
//!
//! `GOLDEN_BLESS=1 cargo test --test golden_frames` rewrites the file; do that only for a change
//! that also raises `PROTOCOL_VERSION` (or, as for the schedule in the result, one made to a
//! version not yet released).

use needle_motion::{Axis, FaultCause, MotionError, State};
use planner_core::chance::ChanceFigures;
use planner_core::execute::perturbation::Perturbation;
use planner_core::execute::risk::Execution;
use planner_core::execute::schedule::{Op, Posture, Schedule, Step, Steps};
use planner_core::report::{FormOutcomes, Segments};
use planner_core::steer::NoiseModel;
use planner_core::wire::crc::crc32;
use planner_core::wire::{
    encode_frame, ChanceRequest, Chunk, DevicePlan, Directed, Fault, Header, PlanRequest,
    PlanResult, Reply, ReplyBody, Request, RequestBody, ENCODE_SCRATCH, MAX_CHUNK,
};
use planner_core::wire::{MotionFault, MotionRequest, MotionStatus};
use planner_core::{
    Form, FormOutcome, Insertion, PlanError, PlanReport, Scenario, ScheduledPlan, SegmentKind,
    SegmentPlan, SolveStatus,
};
use serde::Serialize;
use std::fmt::Write;

fn frame<T: Serialize + Directed>(msg: &T) -> String {
    let mut bytes = Vec::new();
    let mut scratch = [0u8; ENCODE_SCRATCH];
    encode_frame(msg, &mut scratch, &mut |b: &[u8]| {
        bytes.extend_from_slice(b)
    })
    .unwrap();
    bytes.iter().fold(String::new(), |mut s, b| {
        write!(s, "{b:02x}").unwrap();
        s
    })
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn chunk(bytes: &[u8]) -> Chunk {
    Chunk::from_slice(&bytes[..bytes.len().min(MAX_CHUNK)]).unwrap()
}

/// A finished plan with numbers written out here (not planned, so the line shows the layout only):
/// one RL form and a schedule with each kind of step.
fn fixed_plan() -> ScheduledPlan {
    let seg = |kind, length, bevel_deg| SegmentPlan {
        kind,
        length,
        bevel_deg,
    };
    let mut segments = Segments::new();
    segments.push(seg(SegmentKind::Arc, 40.5, 180.0)).unwrap();
    segments.push(seg(SegmentKind::Line, 51.25, 90.0)).unwrap();
    let mut forms = FormOutcomes::new();
    forms
        .push(FormOutcome {
            form: Form::parse("RL").unwrap(),
            status: SolveStatus::Converged,
            feasible: true,
            length: 91.75,
            risk: 0.375,
            penalty: 0.0,
            objective: 96.125,
            min_clearance: 1.0,
            target_error: 0.0001,
            insertion: Insertion {
                theta1_deg: 28.5,
                theta2_deg: 0.0,
                tilt_deg: 28.5,
                direction: [0.0, -0.5, 0.875],
            },
            segments,
            kkt_residual: 0.001,
            iterations: 13,
            evaluations: 140,
        })
        .unwrap();
    let step = |op, duration_s| Step { op, duration_s };
    let mut steps = Steps::new();
    steps
        .push(step(Op::Insert { length_mm: 40.5 }, 16.2))
        .unwrap();
    steps
        .push(step(Op::Rotate { angle_deg: 90.0 }, 0.25))
        .unwrap();
    steps
        .push(step(
            Op::InsertSpin {
                length_mm: 51.25,
                turns: 82,
            },
            20.5,
        ))
        .unwrap();
    let schedule = Schedule {
        posture: Posture {
            entry: [0.0; 3],
            theta1_deg: 28.5,
            theta2_deg: 0.0,
            direction: [0.0, -0.5, 0.875],
            roll_deg: 180.0,
        },
        steps,
        duration_s: 36.95,
        max_twist_deg: 360.0,
    };
    ScheduledPlan {
        report: PlanReport {
            forms,
            best: Some(0),
        },
        schedule: Some(Ok(schedule)),
    }
}

/// The frames of a whole exchange for the paper's scenario, one `name hex` line each.
// Test code: one exchange, read top to bottom as it happens on the wire.
/// A move of the fixed plan's steps with the paper's driver.
fn motion_move_request() -> MotionRequest {
    MotionRequest::Move {
        driver: Scenario::paper().driver,
        needle_mm: 150.0,
        steps: fixed_plan().schedule.unwrap().unwrap().steps,
    }
}

/// A status after an e-stop, every field present.
fn motion_status() -> MotionStatus {
    MotionStatus {
        state: State::Faulted,
        homed: true,
        position: [12.5, -90.0],
        speed: [0.0, 0.0],
        moves_left: 0,
        last_fault: Some(MotionFault {
            cause: FaultCause::EStop,
            position: [12.5, -90.0],
            encoder: [Some(20_000), None],
            at_ms: 4242,
        }),
    }
}

#[allow(clippy::too_many_lines)]
fn exchange() -> String {
    let scenario = Scenario::paper();
    let request = postcard::to_stdvec(&PlanRequest::new(&scenario)).unwrap();
    // The plan itself may improve; the layout of a result must not: a typed error stands in.
    let result: PlanResult = Err(PlanError::TooManyObstacles {
        given: 40,
        capacity: 32,
    });
    let result = postcard::to_stdvec(&result).unwrap();
    let plan_ok: PlanResult = Ok(DevicePlan {
        planned: fixed_plan(),
        chance: None,
    });
    let mut margins = heapless::Vec::new();
    margins.extend_from_slice(&[0.0, 1.25, 0.5]).unwrap();
    let plan_bounded: PlanResult = Ok(DevicePlan {
        planned: fixed_plan(),
        chance: Some(ChanceFigures {
            collision_probability: Some(0.0075),
            target_error_p95: Some(1.5),
            margins,
            rounds: 2,
            within_bound: true,
        }),
    });
    let bounded_request = PlanRequest::bounded(
        &scenario,
        ChanceRequest {
            bound: 0.01,
            model: Perturbation::default(),
            execution: Execution::Steered(NoiseModel::DEFAULT),
        },
    );
    let req = |id, body| Request {
        header: Header::new(id),
        body,
    };
    let rep = |id, body| Reply {
        header: Header::new(id),
        body,
    };
    let lines = [
        ("hello", frame(&req(1, RequestBody::Hello))),
        (
            "ping",
            frame(&req(2, RequestBody::Ping { nonce: 0xDEAD_BEEF })),
        ),
        (
            "upload",
            frame(&req(
                3,
                RequestBody::Upload {
                    offset: 0,
                    total: request.len() as u16,
                    crc: crc32(&request),
                    data: chunk(&request),
                },
            )),
        ),
        ("status", frame(&req(3, RequestBody::Status))),
        (
            "fetch",
            frame(&req(
                3,
                RequestBody::Fetch {
                    offset: 192,
                    max_len: 192,
                },
            )),
        ),
        ("cancel", frame(&req(3, RequestBody::Cancel))),
        (
            "pong",
            frame(&rep(2, ReplyBody::Pong { nonce: 0xDEAD_BEEF })),
        ),
        (
            "uploaded",
            frame(&rep(
                3,
                ReplyBody::Uploaded {
                    received: 192,
                    total: request.len() as u16,
                },
            )),
        ),
        (
            "progress",
            frame(&rep(
                3,
                ReplyBody::Progress {
                    round: 2,
                    done: 4,
                    total: 10,
                    form: Form::parse("RL"),
                    feasible: true,
                },
            )),
        ),
        (
            "finished",
            frame(&rep(
                3,
                ReplyBody::Finished {
                    len: result.len() as u16,
                    crc: crc32(&result),
                },
            )),
        ),
        (
            "part",
            frame(&rep(
                3,
                ReplyBody::Part {
                    offset: 0,
                    total: result.len() as u16,
                    data: chunk(&result),
                },
            )),
        ),
        ("result", hex(&result)),
        ("fault", frame(&rep(9, ReplyBody::Fault(Fault::BadCrc)))),
        ("result_plan", hex(&postcard::to_stdvec(&plan_ok).unwrap())),
        (
            "result_plan_bounded",
            hex(&postcard::to_stdvec(&plan_bounded).unwrap()),
        ),
        (
            "request_bounded",
            hex(&postcard::to_stdvec(&bounded_request).unwrap()),
        ),
        (
            "motion_arm",
            frame(&req(4, RequestBody::Motion(MotionRequest::Arm))),
        ),
        (
            "motion_move",
            frame(&req(5, RequestBody::Motion(motion_move_request()))),
        ),
        (
            "motion_status",
            frame(&rep(5, ReplyBody::Motion(motion_status()))),
        ),
        (
            "motion_refused",
            frame(&rep(
                6,
                ReplyBody::Fault(Fault::Motion(MotionError::SoftLimit(Axis::Rotation))),
            )),
        ),
        (
            "steer_drive",
            frame(&req(7, RequestBody::SteerDrive { piece_mm: 1.0 })),
        ),
        (
            "piece_moving",
            frame(&rep(7, ReplyBody::Fault(Fault::PieceMoving))),
        ),
    ];
    lines.iter().fold(String::new(), |mut s, (name, hex)| {
        writeln!(s, "{name} {hex}").unwrap();
        s
    })
}

#[test]
fn frames_are_byte_for_byte_the_fielded_ones() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/golden_frames.txt");
    let now = exchange();
    if std::env::var_os("GOLDEN_BLESS").is_some() {
        std::fs::write(path, &now).unwrap();
    }
    let stored = std::fs::read_to_string(path).expect("golden frames");
    for (a, b) in stored.lines().zip(now.lines()) {
        assert_eq!(a, b, "frame changed");
    }
    assert_eq!(stored.lines().count(), now.lines().count());
}
