//! The simulated device drives simulated motors: motion requests on the link move the
//! simulated stages behind its motion core as simulated time passes.

use hil_sim::{answer, DeviceService, SimulatedAxes, IDENTITY};
use needle_motion::{FaultCause, MotionError, State};
use planner_core::execute::schedule::schedule;
use planner_core::wire::{Fault, MotionRequest, MotionStatus, ReplyBody, RequestBody};
use planner_core::{plan, Scenario};

fn ask(dev: &mut DeviceService, req: MotionRequest) -> ReplyBody {
    let mut replies = answer(dev, 1, RequestBody::Motion(req));
    assert_eq!(replies.len(), 1);
    replies.remove(0).body
}

fn status(dev: &mut DeviceService) -> MotionStatus {
    match ask(dev, MotionRequest::Status) {
        ReplyBody::Motion(s) => s,
        other => panic!("not a status: {other:?}"),
    }
}

/// Simulated time in steps of 100 ms, the host's status request (its heartbeat) between them,
/// until the motion core is at rest or `limit_ms` have passed; the last status.
fn wait_at_rest(dev: &mut DeviceService, axes: &mut SimulatedAxes, limit_ms: u32) -> MotionStatus {
    for _ in 0..limit_ms / 100 {
        axes.advance(dev, 100);
        let s = status(dev);
        if !matches!(s.state, State::Homing | State::Moving) {
            return s;
        }
    }
    status(dev)
}

#[test]
fn a_move_request_drives_the_simulated_motors() {
    let mut dev = DeviceService::with_identity(IDENTITY);
    let mut axes = SimulatedAxes::attach(&mut dev).unwrap();
    ask(&mut dev, MotionRequest::Arm);
    ask(&mut dev, MotionRequest::Home);
    let homed = wait_at_rest(&mut dev, &mut axes, 10_000);
    assert_eq!((homed.state, homed.homed), (State::Armed, true));
    assert_eq!(axes.plant().actual(), [0, 0]);
    let scenario = Scenario::paper();
    let report = plan(&scenario).unwrap();
    let sched = schedule(&scenario, report.best().unwrap()).unwrap();
    let job = MotionRequest::Move {
        driver: scenario.driver,
        needle_mm: scenario.needle.length,
        steps: sched.steps.clone(),
    };
    assert!(matches!(ask(&mut dev, job), ReplyBody::Motion(_)));
    // Part of the way, the host asking every 100 ms: the stage has moved, and the e-stop stops
    // it where it is.
    for _ in 0..50 {
        axes.advance(&mut dev, 100);
        status(&mut dev);
    }
    let moving = status(&mut dev);
    assert_eq!(moving.state, State::Moving);
    assert!(moving.position[0] > 5.0, "{moving:?}");
    axes.plant_mut().estop = true;
    axes.advance(&mut dev, 1);
    let stopped = status(&mut dev);
    let fault = stopped.last_fault.unwrap();
    assert_eq!(
        (stopped.state, fault.cause),
        (State::Faulted, FaultCause::EStop)
    );
    let latched = ReplyBody::Fault(Fault::Motion(MotionError::Faulted(FaultCause::EStop)));
    assert_eq!(ask(&mut dev, MotionRequest::Reset), latched);
    // The stage settles within its lag of where the core stopped commanding it.
    axes.advance(&mut dev, 200);
    let at = axes.plant().actual()[0] as f32 / 1600.0;
    assert!((at - fault.position[0]).abs() < 0.05, "{at} {fault:?}");
}

#[test]
fn a_silent_host_holds_then_stops_the_simulated_motors() {
    let mut dev = DeviceService::with_identity(IDENTITY);
    let mut axes = SimulatedAxes::attach(&mut dev).unwrap();
    ask(&mut dev, MotionRequest::Arm);
    ask(&mut dev, MotionRequest::Home);
    wait_at_rest(&mut dev, &mut axes, 10_000);
    let job = MotionRequest::Move {
        driver: Scenario::paper().driver,
        needle_mm: 100.0,
        steps: [planner_core::execute::schedule::Step {
            op: planner_core::execute::schedule::Op::Insert { length_mm: 20.0 },
            duration_s: 8.0,
        }]
        .into_iter()
        .collect(),
    };
    ask(&mut dev, job);
    axes.advance(&mut dev, 150);
    assert_eq!(status(&mut dev).state, State::Moving);
    // No word from the host for 300 ms: held.
    axes.advance(&mut dev, 300);
    assert_eq!(status(&mut dev).state, State::Holding);
    // Silent for a second: stopped with the link lost.
    axes.advance(&mut dev, 1100);
    let s = status(&mut dev);
    assert_eq!(
        (s.state, s.last_fault.unwrap().cause),
        (State::Faulted, FaultCause::LinkLost)
    );
}
