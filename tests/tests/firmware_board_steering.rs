//! The firmware on QEMU's mps2-an386 steers and moves the needle itself (simulated axes, a
//! simulated world): the host relays the tracker's readings of the world, which takes each piece
//! the board moved; the board plans, answers each reading and moves the next piece. The
//! insertion ends as the host's simulation of the same board ends (the in-process controller
//! on the same pieces), bit for bit, and the board's stages where its executed steps put them.
//! The paper's scenario with the bench's fastest insertion (10 mm/s), so the emulated insertion
//! takes seconds.

mod firmware_support;

use firmware_support::{build_firmware, emulator_ready, Qemu};
use needle_link::{open, Client, ClientConfig, LinkError, LinkTarget, Transport};
use needle_motion::{MotionError, State};
use needle_sim::{
    driven_loop, in_process, Board, Conditions, Perturbation, Planned, TrackerFaults, WorldEffects,
};
use planner_core::execute::schedule::Op;
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, TipMeasurement};
use planner_core::wire::{Fault, MotionRequest, MotionStatus};
use planner_core::{plan, Scenario};
use std::time::{Duration, Instant};

/// The emulated board behind its UART; a piece has ended when a status says so (asked every
/// 10 ms: the host's heartbeat too).
struct QemuBoard(Client<Box<dyn Transport>>);

impl QemuBoard {
    fn status(&mut self) -> Result<MotionStatus, LinkError> {
        self.0.motion(MotionRequest::Status)
    }
}

impl Board for QemuBoard {
    type Error = LinkError;
    fn drive(&mut self, piece_mm: f32) -> Result<(), LinkError> {
        self.0.steer_drive(piece_mm).map(|_| ())
    }
    fn piece_ended(&mut self) -> Result<(), LinkError> {
        let end = Instant::now() + Duration::from_secs(60);
        loop {
            let s = self.status()?;
            if s.state == State::Armed && s.moves_left == 0 {
                return Ok(());
            }
            if s.state == State::Holding && s.last_fault.is_none() {
                // The link watchdog's hold: a loaded machine kept the host from the board for
                // 200 ms of its time. The piece goes on to the same end.
                self.0.motion(MotionRequest::Resume)?;
                continue;
            }
            if let (State::Faulted, Some(f)) = (s.state, s.last_fault) {
                let refused = Fault::Motion(MotionError::Faulted(f.cause));
                return Err(LinkError::Device(refused));
            }
            assert!(Instant::now() < end, "a piece did not end: {s:?}");
            std::thread::sleep(Duration::from_millis(10));
        }
    }
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.0.steer(m)
    }
    fn stats(&mut self) -> Result<SteerStats, LinkError> {
        self.0.steer_status().map(|(s, _)| s)
    }
}

/// Arms and homes the board (again after a hold of the link watchdog on a loaded machine).
fn arm_and_home(b: &mut QemuBoard) {
    b.0.motion(MotionRequest::Arm).expect("armed");
    for _ in 0..3 {
        b.0.motion(MotionRequest::Home).expect("homing");
        let end = Instant::now() + Duration::from_secs(60);
        let mut s = b.status().unwrap();
        while matches!(s.state, State::Homing) && Instant::now() < end {
            std::thread::sleep(Duration::from_millis(20));
            s = b.status().unwrap();
        }
        if s.homed && s.state == State::Armed {
            return;
        }
        let _ = b.0.motion(MotionRequest::ClearFault);
        let _ = b.0.motion(MotionRequest::Arm);
    }
    panic!("the board did not home: {:?}", b.status());
}

#[test]
fn the_qemu_board_steers_the_papers_insertion_as_the_host_simulates_it() {
    if !emulator_ready("the_qemu_board_steers_the_papers_insertion_as_the_host_simulates_it") {
        return;
    }
    let image = build_firmware("mps2-an386", "mps2-an386");
    let qemu = Qemu::start("mps2-an386", &image);
    let config = ClientConfig {
        timeout: Duration::from_secs(10),
        retries: 2,
        deadline: None,
    };
    let link = open(&LinkTarget::Tcp(qemu.addr.clone())).expect("connect to QEMU");
    let mut b = QemuBoard(Client::new(link, config));

    let mut s = Scenario::paper();
    s.driver.insert_speed = 10.0;
    let best = plan(&s).unwrap().best().unwrap().clone();
    let planned = Planned::of(&s, &best);
    let result = b.0.plan(&s, &mut |_| {}).expect("planned on the board");
    let sched = result.expect("a plan").planned.schedule.unwrap().unwrap();
    let steer = SteerConfig::DEFAULT;
    assert_eq!(
        b.0.steer_start(&steer).expect("steering starts"),
        sched.steps
    );
    arm_and_home(&mut b);

    let (p, faults, effects) = (
        Perturbation::default(),
        TrackerFaults::default(),
        WorldEffects::default(),
    );
    let world = Conditions {
        perturbation: &p,
        effects: &effects,
        faults: &faults,
    };
    let seed = 5;
    let started = Instant::now();
    let on_board = driven_loop(&s, &planned, &sched, &world, &mut b, seed, 1.0)
        .unwrap_or_else(|e| panic!("the board's insertion: {e}"));
    let took = started.elapsed();
    let mut here = in_process(&s, &sched, &steer).unwrap();
    let expected = driven_loop(&s, &planned, &sched, &world, &mut here, seed, 1.0).unwrap();
    println!(
        "QEMU board: {:.3} mm from the target, {} readings, {} replans, {took:.1?}",
        on_board.run.target_error, on_board.stats.readings, on_board.stats.replans
    );
    // Only the count of repeated readings may differ: the transport's resends.
    let mut same = on_board.clone();
    same.stats.repeated = expected.stats.repeated;
    assert!(
        same == expected,
        "the board's insertion is not the host's simulation: {:.6} mm after {} steps, the host's \
         {:.6} mm after {}",
        on_board.run.target_error,
        on_board.run.steps.len(),
        expected.run.target_error,
        expected.run.steps.len()
    );
    assert_eq!(on_board.stop_reason, None, "reached");
    let end = b.status().unwrap();
    let depth: f32 = on_board.run.steps.iter().map(|s| s.op.inserted_mm()).sum();
    assert!(
        (end.position[0] - depth).abs() <= 1.0 / 1600.0,
        "{end:?}, {depth} mm"
    );
    let turned: f32 = on_board
        .run
        .steps
        .iter()
        .map(|s| match s.op {
            Op::Rotate { angle_deg } => angle_deg,
            _ => 0.0,
        })
        .sum();
    let off = (end.position[1] - turned).rem_euclid(360.0);
    assert!(
        off.min(360.0 - off) <= 360.0 / 3200.0,
        "{end:?}, {turned} deg"
    );
    assert_eq!((end.state, end.last_fault), (State::Armed, None));
}
