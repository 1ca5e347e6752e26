//! The driver board steers and moves the needle itself (simulated): the simulated device plans
//! the paper's scenario, starts steering, and with `SteerDrive` moves the continuation on its
//! simulated stages one piece at a time; the host only relays the tracker's readings of the
//! simulated world, which takes each piece the board moved. The board's insertion ends where
//! the host's simulation of the same board ends (the in-process controller, the same pieces), bit
//! for bit, and its stages where the executed steps put them, to a step.

mod wire_support;

use hil_sim::InProcess;
use needle_link::{Client, ClientConfig, LinkError};
use needle_motion::{FaultCause, MotionError, State};
use needle_sim::{
    closed_loop, driven_loop, in_process, Board, ClosedRun, Conditions, Perturbation, Planned,
    TrackerFaults, WorldEffects,
};
use planner_core::execute::schedule::Schedule;
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, TipMeasurement};
use planner_core::wire::{Fault, MotionRequest, MotionStatus};
use planner_core::{plan, Scenario};
use std::time::Duration;
use wire_support::Sim;

/// Steps per mm of the bench's insertion stage (`needle_motion::bench`).
const STEPS_PER_MM: f32 = 1600.0;
/// Steps per degree of the bench's shaft (3200 a turn).
const STEPS_PER_DEG: f32 = 3200.0 / 360.0;

/// The simulated device with simulated stages, reached through the protocol client; simulated
/// time passes 10 ms per status request while a piece moves.
struct SimBoard {
    client: Client<Sim>,
    /// Press the e-stop input after this many pieces.
    estop_after: Option<u32>,
    pieces: u32,
}

impl SimBoard {
    fn status(&mut self) -> Result<MotionStatus, LinkError> {
        self.client.motion(MotionRequest::Status)
    }

    fn advance(&mut self, ms: u32) {
        self.client.link_mut().0.advance(ms);
    }
}

impl Board for SimBoard {
    type Error = LinkError;
    fn drive(&mut self, piece_mm: f32) -> Result<(), LinkError> {
        self.client.steer_drive(piece_mm).map(|_| ())
    }
    fn piece_ended(&mut self) -> Result<(), LinkError> {
        self.pieces += 1;
        if self.estop_after == Some(self.pieces) {
            self.advance(30);
            self.client.link_mut().0.press_estop();
        }
        // A piece is at most a millimetre or one rotation: seconds at the bench's speeds.
        for _ in 0..3000 {
            let s = self.status()?;
            if s.state == State::Armed && s.moves_left == 0 {
                return Ok(());
            }
            if let (State::Faulted, Some(f)) = (s.state, s.last_fault) {
                return Err(LinkError::Device(Fault::Motion(MotionError::Faulted(
                    f.cause,
                ))));
            }
            self.advance(10);
        }
        panic!("a piece did not end in 30 s: {:?}", self.status());
    }
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.client.steer(m)
    }
    fn stats(&mut self) -> Result<SteerStats, LinkError> {
        self.client.steer_status().map(|(s, _)| s)
    }
}

/// The paper's plan on a simulated board with stages, steering started, armed and homed.
fn board(s: &Scenario, config: &SteerConfig) -> (SimBoard, Schedule) {
    let device = InProcess::new().with_axes().expect("bench axes");
    let link = ClientConfig {
        timeout: Duration::from_millis(100),
        retries: 3,
        deadline: None,
    };
    let mut b = SimBoard {
        client: Client::new(Sim(device), link),
        estop_after: None,
        pieces: 0,
    };
    let result = b
        .client
        .plan(s, &mut |_| {})
        .expect("planned on the device");
    let planned = result.expect("a plan").planned;
    let sched = planned.schedule.expect("a schedule").expect("schedulable");
    let steps = b.client.steer_start(config).expect("steering starts");
    assert_eq!(steps, sched.steps);
    b.client.motion(MotionRequest::Arm).unwrap();
    b.client.motion(MotionRequest::Home).unwrap();
    for _ in 0..2000 {
        b.advance(10);
        if b.status().unwrap().state == State::Armed {
            break;
        }
    }
    assert!(b.status().unwrap().homed);
    (b, sched)
}

/// A reading without a pose (the board fills in its depth and roll).
fn blind(seq: u32) -> TipMeasurement {
    TipMeasurement {
        seq,
        depth_mm: 0.0,
        base_deg: 0.0,
        pose: None,
        target: None,
    }
}

/// The insertion of `s` on the simulated board with seed `seed`'s world, asserted bit for bit
/// the host's simulation of the same board (the in-process controller on the same pieces); the
/// board, the schedule it steered and the run.
fn board_as_host(
    s: &Scenario,
    planned: &Planned,
    config: &SteerConfig,
    world: &Conditions<'_>,
    seed: u64,
) -> (SimBoard, Schedule, ClosedRun) {
    let (mut b, sched) = board(s, config);
    let on_board = driven_loop(s, planned, &sched, world, &mut b, seed, 1.0)
        .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
    let mut here = in_process(s, &sched, config).unwrap();
    let expected = driven_loop(s, planned, &sched, world, &mut here, seed, 1.0).unwrap();
    assert!(
        on_board == expected,
        "seed {seed}: the board's run is not the host's"
    );
    (b, sched, on_board)
}

fn conditions<'a>(p: &'a Perturbation, faults: &'a TrackerFaults) -> Conditions<'a> {
    static NO_EFFECTS: std::sync::OnceLock<WorldEffects> = std::sync::OnceLock::new();
    Conditions {
        perturbation: p,
        effects: NO_EFFECTS.get_or_init(WorldEffects::default),
        faults,
    }
}

fn inserted(run: &ClosedRun) -> f32 {
    run.run.steps.iter().map(|s| s.op.inserted_mm()).sum()
}

#[test]
fn the_board_steers_the_paper_insertion_as_the_host_simulates_it() {
    let s = Scenario::paper();
    let best = plan(&s).unwrap().best().unwrap().clone();
    let planned = Planned::of(&s, &best);
    let config = SteerConfig::DEFAULT;
    let p = Perturbation::default();
    let faults = TrackerFaults::default();
    let world = conditions(&p, &faults);
    for seed in 1..=3 {
        let (mut b, sched, on_board) = board_as_host(&s, &planned, &config, &world, seed);
        assert_eq!(on_board.stop_reason, None, "seed {seed}: reached");
        // The stages are where the board's pieces put them: a step of the executed insertion.
        let end = b.status().unwrap();
        let depth = inserted(&on_board);
        assert!(
            (end.position[0] - depth).abs() <= 1.0 / STEPS_PER_MM,
            "seed {seed}: stage {} mm, steps {depth} mm",
            end.position[0]
        );
        let turned: f32 = on_board
            .run
            .steps
            .iter()
            .map(|s| match s.op {
                planner_core::execute::schedule::Op::Rotate { angle_deg } => angle_deg,
                _ => 0.0,
            })
            .sum();
        let off = (end.position[1] - turned).rem_euclid(360.0);
        assert!(
            off.min(360.0 - off) <= 1.0 / STEPS_PER_DEG,
            "seed {seed}: shaft {} deg, rotations {turned} deg",
            end.position[1]
        );
        let plant = b.client.link().0.axes().unwrap().plant();
        assert_eq!(plant.missed(), [0, 0], "seed {seed}");
        // Beside the host's own closed loop (readings where the world's pieces end): the same
        // controller, pieces cut by the commanded length instead.
        let mut classic = in_process(&s, &sched, &config).unwrap();
        let host = closed_loop(&s, &planned, &sched, &p, &faults, &mut classic, seed).unwrap();
        println!(
            "seed {seed}: board {:.3} mm in {} readings, host closed loop {:.3} mm in {}",
            on_board.run.target_error,
            on_board.stats.readings,
            host.run.target_error,
            host.stats.readings
        );
    }
}

#[test]
fn the_e_stop_input_ends_a_board_driven_insertion_where_it_is() {
    let s = Scenario::paper();
    let best = plan(&s).unwrap().best().unwrap().clone();
    let planned = Planned::of(&s, &best);
    let p = Perturbation::default();
    let faults = TrackerFaults::default();
    let (mut b, sched) = board(&s, &SteerConfig::DEFAULT);
    b.estop_after = Some(20);
    let e = driven_loop(
        &s,
        &planned,
        &sched,
        &conditions(&p, &faults),
        &mut b,
        4,
        1.0,
    )
    .expect_err("the e-stop ends it");
    assert!(
        e.to_string().contains("e-stop") || format!("{e:?}").contains("EStop"),
        "{e}"
    );
    let end = b.status().unwrap();
    let fault = end.last_fault.expect("a fault");
    assert_eq!(
        (end.state, fault.cause),
        (State::Faulted, FaultCause::EStop)
    );
    // Not a step more, and the insertion cannot go on: a reading is refused.
    b.advance(500);
    assert_eq!(b.status().unwrap().position, fault.position);
    let m = blind(1000);
    assert!(matches!(
        b.client.steer(&m),
        Err(LinkError::Device(Fault::Motion(MotionError::Faulted(
            FaultCause::EStop
        ))))
    ));
}

#[test]
fn a_reading_while_the_piece_moves_is_refused_and_a_repeat_is_answered_again() {
    let s = Scenario::paper();
    let config = SteerConfig::DEFAULT;
    let (mut b, _) = board(&s, &config);
    let first = b.client.steer_drive(1.0).expect("the first piece");
    assert_eq!(first.state, State::Moving);
    // The answer was lost and the host asks again: the piece is not queued twice.
    let again = b.client.steer_drive(1.0).expect("answered again");
    assert_eq!(again.moves_left, 1);
    let m = blind(1);
    assert!(matches!(
        b.client.steer(&m),
        Err(LinkError::Device(Fault::PieceMoving))
    ));
    b.piece_ended().unwrap();
    let answer = b.client.steer(&m).expect("answered once the piece ended");
    assert_eq!(answer.seq, 1);
    assert_eq!(b.status().unwrap().moves_left, 1, "the next piece moves");
    // The same reading again is answered and moves nothing more.
    b.client.steer(&m).expect("answered again");
    assert_eq!(b.status().unwrap().moves_left, 1);
    // Bad piece lengths are refused.
    let (mut fresh, _) = board(&s, &config);
    for bad in [0.0, -1.0, 1.5, f32::NAN] {
        assert!(matches!(
            fresh.client.steer_drive(bad),
            Err(LinkError::Device(Fault::BadPieceLength))
        ));
    }
}

/// The generated family `needle benchmark` steers (`needle_scenario::unseen`, seeds 101-108), as
/// plain files plan them: wherever the host plans one, the board steers it as the host's
/// simulation of the same board does, bit for bit, and no true path enters an obstacle.
#[test]
fn the_board_steers_the_unseen_family_as_the_host_simulates_it() {
    let config = SteerConfig::DEFAULT;
    let p = Perturbation::default();
    let faults = TrackerFaults::default();
    let world = conditions(&p, &faults);
    let (mut steered, mut reached) = (0, 0);
    for seed in 101..=108 {
        let s = needle_scenario::unseen::unseen_scenario(seed);
        let Some(best) = plan(&s).ok().and_then(|r| r.best().cloned()) else {
            continue;
        };
        let planned = Planned::of(&s, &best);
        let (mut b, _, on_board) = board_as_host(&s, &planned, &config, &world, seed);
        assert!(!on_board.run.collided, "seed {seed}: into an obstacle");
        let end = b.status().unwrap();
        assert!(
            (end.position[0] - inserted(&on_board)).abs() <= 1.0 / STEPS_PER_MM,
            "seed {seed}: {end:?}"
        );
        steered += 1;
        reached += usize::from(on_board.stop_reason.is_none());
        println!(
            "unseen {seed}: {:.3} mm, {:?}, {} readings",
            on_board.run.target_error, on_board.stop_reason, on_board.stats.readings
        );
    }
    println!("{reached} of {steered} board-steered insertions reached");
    assert!(steered >= 4, "only {steered} of the family planned");
}
