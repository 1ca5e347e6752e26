//! The firmware on QEMU's mps2-an386 drives simulated axes: over its emulated UART the host
//! arms, homes and moves the paper's schedule, and the board ends on the step where the host's
//! simulation of the same moves (`hil-sim --axes`) ends; an e-stop sent over the link
//! mid-insertion stops both axes at once and latches until cleared; so does the e-stop input
//! pressed mid-insertion (written through QEMU's debugger stub), which no clear lifts while it
//! stays pressed.

mod firmware_support;

use firmware_support::{build_firmware, emulator_ready, Qemu};
use hil_sim::{answer, DeviceService, SimulatedAxes, IDENTITY};
use needle_devtools::{elf, gdb_remote};
use needle_link::{open, Client, ClientConfig, LinkError, LinkTarget, Transport};
use needle_motion::{FaultCause, MotionError, State};
use planner_core::execute::schedule::{schedule, Op, Step};
use planner_core::wire::{Fault, MotionRequest, MotionStatus, ReplyBody, RequestBody};
use planner_core::{plan, Scenario};
use std::time::{Duration, Instant};

type Link = Client<Box<dyn Transport>>;

fn connect(addr: &str) -> Link {
    let config = ClientConfig {
        timeout: Duration::from_secs(10),
        retries: 2,
        deadline: None,
    };
    Client::new(
        open(&LinkTarget::Tcp(addr.into())).expect("connect to QEMU"),
        config,
    )
}

fn ask(link: &mut Link, req: MotionRequest) -> MotionStatus {
    link.motion(req.clone())
        .unwrap_or_else(|e| panic!("{req:?}: {e}"))
}

/// Status requests every 20 ms (the host's heartbeat) until the core is at rest, resuming after
/// a hold of the link watchdog (a loaded machine may delay the host); the last status.
fn wait_at_rest(link: &mut Link, limit: Duration) -> MotionStatus {
    let end = Instant::now() + limit;
    loop {
        std::thread::sleep(Duration::from_millis(20));
        let s = ask(link, MotionRequest::Status);
        match s.state {
            State::Holding if s.last_fault.is_none() => {
                ask(link, MotionRequest::Resume);
            }
            State::Homing | State::Moving | State::Holding => {}
            _ => return s,
        }
        assert!(Instant::now() < end, "not at rest after {limit:?}: {s:?}");
    }
}

/// Homes the armed stage. A loaded machine may keep this test from the board long enough for
/// the link watchdog to hold, which ends a homing unhomed: then it homes again.
fn home(link: &mut Link) {
    let mut homed = ask(link, MotionRequest::Status);
    for _ in 0..3 {
        assert_eq!(ask(link, MotionRequest::Home).state, State::Homing);
        homed = wait_at_rest(link, Duration::from_secs(60));
        if homed.homed {
            break;
        }
    }
    assert_eq!(
        (homed.state, homed.homed, homed.position),
        (State::Armed, true, [0.0, 0.0])
    );
}

/// The host's simulation of the same requests: the simulated device with `hil-sim --axes`.
fn host_simulation(job: &MotionRequest) -> MotionStatus {
    let mut dev = DeviceService::with_identity(IDENTITY);
    let mut axes = SimulatedAxes::attach(&mut dev).unwrap();
    let mut last = None;
    for req in [MotionRequest::Arm, MotionRequest::Home, job.clone()] {
        let mut pending = Some(req);
        for _ in 0..100_000 {
            let body = local_ask(&mut dev, pending.take().unwrap_or(MotionRequest::Status));
            let ReplyBody::Motion(s) = body else {
                panic!("host simulation refused: {body:?}")
            };
            last = Some(s);
            if !matches!(s.state, State::Homing | State::Moving) {
                break;
            }
            axes.advance(&mut dev, 20);
        }
    }
    last.expect("a status")
}

fn local_ask(dev: &mut DeviceService, req: MotionRequest) -> ReplyBody {
    let mut replies = answer(dev, 1, RequestBody::Motion(req));
    assert_eq!(replies.len(), 1, "one reply");
    replies.remove(0).body
}

fn refused(result: Result<MotionStatus, LinkError>) -> Fault {
    match result {
        Err(LinkError::Device(f)) => f,
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn the_qemu_board_moves_the_papers_schedule_like_the_host_and_obeys_an_estop() {
    if !emulator_ready("the_qemu_board_moves_the_papers_schedule_like_the_host_and_obeys_an_estop")
    {
        return;
    }
    let image = build_firmware("mps2-an386", "mps2-an386");
    let mut qemu = Qemu::start("mps2-an386", &image);
    let mut link = connect(&qemu.addr);

    let scenario = Scenario::paper();
    let report = plan(&scenario).unwrap();
    let sched = schedule(&scenario, report.best().unwrap()).unwrap();
    let job = MotionRequest::Move {
        driver: scenario.driver,
        needle_mm: scenario.needle.length,
        steps: sched.steps.clone(),
    };
    // Power-up: disarmed, nothing moves.
    let s = ask(&mut link, MotionRequest::Status);
    assert_eq!((s.state, s.homed), (State::Disarmed, false));
    assert_eq!(
        refused(link.motion(job.clone())),
        Fault::Motion(MotionError::NotAllowed(State::Disarmed))
    );
    ask(&mut link, MotionRequest::Arm);
    assert_eq!(
        refused(link.motion(job.clone())),
        Fault::Motion(MotionError::NotHomed)
    );
    home(&mut link);

    // The paper's schedule, on the board and in the host's simulation. A loaded machine may
    // keep this test from the board past the watchdog's second (LinkLost): homed again, the
    // move is made again.
    let mut board = ask(&mut link, MotionRequest::Status);
    for _ in 0..3 {
        assert_eq!(ask(&mut link, job.clone()).state, State::Moving);
        board = wait_at_rest(&mut link, Duration::from_secs(600));
        if board
            .last_fault
            .is_none_or(|f| f.cause != FaultCause::LinkLost)
        {
            break;
        }
        ask(&mut link, MotionRequest::ClearFault);
        ask(&mut link, MotionRequest::Arm);
        home(&mut link);
    }
    let host = host_simulation(&job);
    assert_eq!((board.state, board.last_fault), (State::Armed, None));
    assert_eq!(
        board.position, host.position,
        "the board ends where the host's simulation ends"
    );
    let inserted: f32 = sched.steps.iter().map(|st| st.op.inserted_mm()).sum();
    assert!(
        (board.position[0] - inserted).abs() <= 1.0 / 1600.0,
        "{board:?}, {inserted} mm commanded"
    );

    // An e-stop over the link while the needle goes in (and spins).
    let spin = MotionRequest::Move {
        driver: scenario.driver,
        needle_mm: 200.0,
        steps: [Step {
            op: Op::InsertSpin {
                length_mm: 10.0,
                turns: 16,
            },
            duration_s: 4.0,
        }]
        .into_iter()
        .collect(),
    };
    ask(&mut link, spin.clone());
    // 600 ms in, the host's heartbeat every 20 ms (silent for 200 ms, the board would hold).
    for _ in 0..30 {
        std::thread::sleep(Duration::from_millis(20));
        ask(&mut link, MotionRequest::Status);
    }
    let moving = ask(&mut link, MotionRequest::Status);
    assert_eq!(moving.state, State::Moving, "{moving:?}");
    let stopped = ask(&mut link, MotionRequest::EStop);
    let fault = stopped.last_fault.expect("the e-stop is reported");
    assert_eq!(
        (stopped.state, fault.cause),
        (State::Faulted, FaultCause::EStop)
    );
    assert!(
        fault.position[0] > board.position[0] && fault.position[0] < board.position[0] + 10.0,
        "stopped mid-insertion: {fault:?}"
    );
    // Not a step more on either axis (the watchdog has nothing to stop), and the fault outlives
    // a reset.
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        ask(&mut link, MotionRequest::Status).position,
        fault.position
    );
    assert_eq!(
        refused(link.motion(MotionRequest::Reset)),
        Fault::Motion(MotionError::Faulted(FaultCause::EStop))
    );
    let cleared = ask(&mut link, MotionRequest::ClearFault);
    assert_eq!((cleared.state, cleared.homed), (State::Disarmed, false));

    estop_input_stops_and_latches(&mut link, &qemu, &image, &spin);
    assert!(qemu.running(), "the firmware stopped QEMU (a fault)");
}

/// The e-stop input pressed while the needle goes in and spins: both axes stop at once, the
/// fault latches, no clear lifts it while the input stays pressed; released, a clear does.
fn estop_input_stops_and_latches(
    link: &mut Link,
    qemu: &Qemu,
    image: &std::path::Path,
    spin: &MotionRequest,
) {
    let input = elf::symbol_address(image, "ESTOP_INPUT").expect("the e-stop input's address");
    let press = |v: u32| {
        gdb_remote::write_word(&qemu.debugger, input, v)
            .unwrap_or_else(|e| panic!("writing the e-stop input: {e:#}"))
    };
    ask(link, MotionRequest::Arm);
    home(link);
    ask(link, spin.clone());
    for _ in 0..30 {
        std::thread::sleep(Duration::from_millis(20));
        ask(link, MotionRequest::Status);
    }
    let before = ask(link, MotionRequest::Status);
    assert_eq!(before.state, State::Moving, "{before:?}");
    press(1);
    let stopped = ask(link, MotionRequest::Status);
    let fault = stopped.last_fault.expect("the e-stop input is reported");
    assert_eq!(
        (stopped.state, fault.cause),
        (State::Faulted, FaultCause::EStop)
    );
    assert!(
        fault.position[0] >= before.position[0] && fault.position[0] < 10.0,
        "stopped mid-insertion: {before:?} then {fault:?}"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(ask(link, MotionRequest::Status).position, fault.position);
    assert_eq!(
        refused(link.motion(MotionRequest::ClearFault)),
        Fault::Motion(MotionError::CauseActive(FaultCause::EStop)),
        "cleared while the e-stop is pressed"
    );
    assert_eq!(
        refused(link.motion(MotionRequest::Arm)),
        Fault::Motion(MotionError::Faulted(FaultCause::EStop))
    );
    press(0);
    std::thread::sleep(Duration::from_millis(50));
    let cleared = ask(link, MotionRequest::ClearFault);
    assert_eq!((cleared.state, cleared.homed), (State::Disarmed, false));
    assert_eq!(cleared.position, fault.position);
}
