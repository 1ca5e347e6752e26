//! `needle steer` with a driver board instead of a robot (`--tcp` or `--port` and no `--robot`):
//! the board plans, steers and moves the needle itself (`SteerDrive`, docs/motion.md "The board
//! steers"); this program relays the tracker's poses and shows and logs the insertion.
//!
//! The board moves one piece at a time. This program asks its status every 10 ms (the board's
//! link watchdog counts that as the host's heartbeat); once the piece has ended it waits for a
//! tip pose sampled after that moment (a pose stamped before it is stale, as for a robot's piece),
//! relays it, and the board answers and moves the next piece. The interlocks are the robot
//! session's: no fresh pose within the tracking timeout stops the board; so does Ctrl-C; a fault
//! of the board (its e-stop, a limit switch, its watchdog) ends the insertion with the cause.

use super::fresh::Offset;
use super::log::InsertionLog;
use super::outcome::{Class, Ending, SessionOutcome};
use super::session::{Event, SessionConfig, INTERRUPTED};
use super::slicer::Slicer;
use super::steer_setup::{
    connect, forward_tracker, report_viewers, session_config, set_up, tracker_names, viewers,
    SteerOptions, EVENTS_WAITING,
};
use super::tracker::{TipArrival, TrackerCounts, TrackerState};
use super::wire::{registered_point, registered_pose};
use anyhow::{anyhow, Context, Result};
use needle_device::posture::board_steps;
use needle_link::{Client, LinkError, Transport};
use needle_motion::State;
use needle_simulate::device::{device_planning, start_steering};
use planner_core::execute::perturbation::MAX_PIECE_MM as MAX_BOARD_PIECE_MM;
use planner_core::execute::pieces::Pieces;
use planner_core::execute::schedule::Step;
use planner_core::execute::schedule::Steps;
use planner_core::model::scenario::Driver;
use planner_core::steer::{Command, Pose, SteerReply, TipMeasurement};
use planner_core::wire::{Fault, MotionRequest};
use serde_json::json;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How often the board is asked for its status while a piece moves.
const POLL: Duration = Duration::from_millis(10);

/// `needle steer` with the board at `a.link` moving the needle: planned and steered on the
/// board, the shaft turned to the plan's roll, then the insertion driven by the board.
pub(crate) fn steer_on_board(
    a: &SteerOptions,
    form_steered: &mut Option<String>,
) -> Result<SessionOutcome> {
    let link = a
        .link
        .as_ref()
        .ok_or_else(|| anyhow!("no board to steer on"))?;
    let setup = set_up(a)?;
    let config = session_config(a, &setup)?;
    let schedule = &setup.prepared.schedule;
    let mut device = device_planning(&setup, link)?;
    let status = device
        .motion(MotionRequest::Status)
        .context("the board at --tcp/--port drives no axes (it cannot move the needle)")?;
    let driver = setup.scenario.driver;
    let turn = board_steps(
        &schedule.posture,
        &Steps::new(),
        &driver,
        status.position[1],
        a.tilt_set,
    )
    .map_err(|e| e.to_string());
    start_steering(&mut device, &setup)?;
    let (mut log, mut slicer) = viewers(a, &setup, form_steered)?;
    let tracker = connect("tracker", &a.tracker)?;
    let (tx, rx) = sync_channel(EVENTS_WAITING);
    let (tracker_state, _) = forward_tracker(&tracker, &tx, tracker_names(a))?;
    drop(tx);
    // A second handler cannot be set (a test calling twice): the first one still flags.
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    let session = BoardSession {
        client: &mut device,
        config,
        tracker: tracker_state,
        events: rx,
        log: &mut log,
        slicer: &mut slicer,
    };
    let start = Start {
        turn,
        driver,
        needle_mm: setup.scenario.needle.length,
    };
    let outcome = session.run(&start, &schedule.steps);
    let _ = tracker.shutdown(std::net::Shutdown::Both);
    report_viewers(&slicer, &log);
    Ok(outcome)
}

/// What comes before the drive: the turn to the plan's roll (or why the posture is refused),
/// with the plan's driver and needle.
pub struct Start {
    /// The turn, none when the shaft is there; `Err`: the plan tilts the needle and the guide
    /// is not said to be set.
    pub turn: Result<Steps, String>,
    /// The plan's driver (speeds, twist limit).
    pub driver: Driver,
    /// The needle's insertable length (mm).
    pub needle_mm: f32,
}

/// A steered insertion the board moves.
pub struct BoardSession<'a, T: Transport> {
    /// The board, steering started.
    pub client: &'a mut Client<T>,
    /// The session's limits and names (the robot's timeout is not used).
    pub config: SessionConfig,
    /// The tracker's state, kept by its reader thread.
    pub tracker: Arc<Mutex<TrackerState>>,
    /// The tracker's events.
    pub events: Receiver<Event>,
    /// The insertion log.
    pub log: &'a mut InsertionLog,
    /// 3D Slicer, if shown.
    pub slicer: &'a mut Slicer,
}

impl<T: Transport> BoardSession<'_, T> {
    /// Runs the insertion of `steps` (the steering's first continuation) from `start` to its
    /// end; the board is stopped whatever ended it, and the log's last line is the stop.
    pub fn run(mut self, start: &Start, steps: &[Step]) -> SessionOutcome {
        self.slicer.state(None, false);
        let mut outcome = SessionOutcome {
            outcome: Class::Reached,
            stop_reason: None,
            why: None,
            predicted_miss_mm: None,
            steering: Default::default(),
            tracker: TrackerCounts::default(),
            latencies_ms: Vec::new(),
            times: Vec::new(),
            clock_offset_ms: None,
            clock_offset_applied: false,
            robot_stopped: false,
            on_board: true,
        };
        let ending = match self.await_registration().map(|()| self.take_posture(start)) {
            Err(ending) | Ok(Ok(Some(ending))) => ending,
            Ok(Err(why)) => {
                outcome.why = Some(why);
                Ending::PostureRefused
            }
            Ok(Ok(None)) => self.steer(steps, &mut outcome),
        };
        // At rest after a piece, or mid-piece: the board decelerates and drops its moves.
        outcome.robot_stopped = self.client.motion(MotionRequest::Stop).is_ok() && self.at_rest();
        if let Ok((stats, _)) = self.client.steer_status() {
            outcome.steering = stats;
        }
        outcome.stop_reason = ending.stop_reason();
        outcome.outcome = ending.class();
        outcome.tracker = self.state().counts;
        let counts = outcome.tracker;
        self.log.write(
            "stop",
            json!({
                "outcome": outcome.outcome,
                "stop_reason": outcome.stop_reason,
                "ending": format!("{ending:?}"),
                "predicted_miss_mm": outcome.predicted_miss_mm,
                "robot_stopped": outcome.robot_stopped,
                "steering": outcome.steering,
                "rejected_frames": counts.rejected_frames,
                "invalid_poses": counts.invalid_poses,
                "stale_poses": counts.stale_poses,
            }),
        );
        self.slicer.state(outcome.stop_reason, true);
        outcome
    }

    /// With `--registration-name`: waits for the stream's first registration, which then maps
    /// every reading (the board does not move before it); `Err` the ending if it does not come.
    fn await_registration(&mut self) -> Result<(), Ending> {
        let Some(name) = self.config.registration_name.clone() else {
            return Ok(());
        };
        let deadline = Instant::now() + self.config.registration_timeout;
        loop {
            let received = self.state().registration;
            if let Some(reg) = received {
                self.log.registration(&name, &reg);
                self.config.registration = Some(reg);
                return Ok(());
            }
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Err(Ending::Interrupted);
            }
            if Instant::now() > deadline {
                self.log
                    .no_registration(&name, self.config.registration_timeout);
                return Err(Ending::NoRegistration);
            }
            if let Ok(Event::TrackerClosed) = self.events.recv_timeout(POLL) {
                return Err(Ending::TrackerDisconnected);
            }
        }
    }

    /// Turns the shaft to the plan's roll: `Ok(None)` once there, `Ok(Some)` when the board
    /// refuses or faults, `Err` why the posture is refused.
    fn take_posture(&mut self, start: &Start) -> Result<Option<Ending>, String> {
        let turn = start.turn.clone().inspect_err(|why| {
            self.log.write("posture_refused", json!({ "why": why }));
        })?;
        if turn.is_empty() {
            return Ok(None);
        }
        let request = MotionRequest::Move {
            driver: start.driver,
            needle_mm: start.needle_mm,
            steps: turn,
        };
        if let Err(e) = self.client.motion(request) {
            return Ok(Some(self.refused(&e)));
        }
        Ok(self.piece_end().err())
    }

    /// Waits (asking every 10 ms, the board's heartbeat) until the axes are at rest after a
    /// stop: whether they came to rest within 10 s.
    fn at_rest(&mut self) -> bool {
        let end = Instant::now() + Duration::from_secs(10);
        while Instant::now() < end {
            match self.client.motion(MotionRequest::Status) {
                Ok(s) if !matches!(s.state, State::Moving | State::Holding | State::Homing) => {
                    return true
                }
                Ok(_) => std::thread::sleep(POLL),
                Err(_) => return false,
            }
        }
        false
    }

    fn state(&self) -> MutexGuard<'_, TrackerState> {
        self.tracker.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn steer(&mut self, steps: &[Step], outcome: &mut SessionOutcome) -> Ending {
        let Ok(mut pieces) = Pieces::new(steps, MAX_BOARD_PIECE_MM) else {
            return Ending::ControllerNotAnswering;
        };
        match self.client.steer_drive(MAX_BOARD_PIECE_MM) {
            Ok(status) => self
                .log
                .write("board_drive", json!({ "position": status.position })),
            Err(e) => return self.refused(&e),
        }
        let mut seq = 0u32;
        while pieces.next_piece().is_some() {
            let ended = match self.piece_end() {
                Ok(at) => at,
                Err(ending) => return ending,
            };
            let tip = match self.fresh_tip(ended) {
                Ok(tip) => tip,
                Err(ending) => return ending,
            };
            seq += 1;
            let m = self.measurement(seq, &pieces, &tip);
            let reply = match self.client.steer(&m) {
                Ok(r) => r,
                Err(e) => return self.refused(&e),
            };
            let latency_ms = tip.at.elapsed().as_secs_f64() * 1e3;
            outcome.latencies_ms.push(latency_ms);
            // Asked while the board moves the next piece: the estimate the reading left.
            let estimate = self.client.steer_estimate().ok();
            self.log.write(
                "reading",
                json!({
                    "measurement": m,
                    "reply": reply,
                    "latency_ms": latency_ms,
                    "estimate": estimate,
                }),
            );
            self.show(estimate, &reply);
            if let Some(ending) = follow(&reply, &mut pieces, outcome) {
                return ending;
            }
        }
        Ending::StepsRanOut
    }

    /// The board's estimated tip in Slicer, and the continuation it planned from there.
    fn show(&mut self, estimate: Option<Pose>, reply: &SteerReply) {
        let Some(tip) = estimate.and_then(|e| e.frame()) else {
            return;
        };
        let replaced = match &reply.command {
            Command::Replace(s) => Some(&s[..]),
            _ => None,
        };
        self.slicer
            .reading(&tip, replaced, self.config.arc_radius_mm);
    }

    /// Waits for the piece moving to end: the moment a status said so, or why the insertion
    /// ends instead.
    fn piece_end(&mut self) -> Result<Instant, Ending> {
        loop {
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Err(Ending::Interrupted);
            }
            match self.events.recv_timeout(POLL) {
                Ok(Event::TrackerClosed) => return Err(Ending::TrackerDisconnected),
                Ok(_) | Err(RecvTimeoutError::Timeout) | Err(RecvTimeoutError::Disconnected) => {}
            }
            let status = match self.client.motion(MotionRequest::Status) {
                Ok(s) => s,
                Err(e) => return Err(self.refused(&e)),
            };
            match (status.state, status.last_fault) {
                (State::Armed, _) if status.moves_left == 0 => return Ok(Instant::now()),
                (State::Faulted, Some(f)) => {
                    self.log
                        .write("board_fault", json!({ "fault": format!("{f:?}") }));
                    return Err(Ending::BoardFaulted);
                }
                (State::Moving, _) => {}
                (state, _) => {
                    let why = format!("the board left the insertion: {state:?}");
                    self.log.write("board_fault", json!({ "why": why }));
                    return Err(Ending::BoardFaulted);
                }
            }
        }
    }

    /// The first tip pose sampled once the piece ended at `ended`, within the tracking timeout.
    fn fresh_tip(&mut self, ended: Instant) -> Result<TipArrival, Ending> {
        let end_s = Some(self.state().clock.unix(ended));
        loop {
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Err(Ending::Interrupted);
            }
            if let Some(tip) = self.state().take_fresh_tip(end_s, Offset::default()) {
                return Ok(tip);
            }
            if ended.elapsed() > self.config.tracking_timeout {
                self.log.write(
                    "tracking_lost",
                    json!({ "waited_ms": ended.elapsed().as_millis() as u64 }),
                );
                return Err(Ending::TrackingLost);
            }
            // The board's heartbeat while it waits at rest.
            if let Err(e) = self.client.motion(MotionRequest::Status) {
                return Err(self.refused(&e));
            }
            match self.events.recv_timeout(POLL) {
                Ok(Event::TrackerClosed) => return Err(Ending::TrackerDisconnected),
                Ok(_) | Err(RecvTimeoutError::Timeout) | Err(RecvTimeoutError::Disconnected) => {}
            }
        }
    }

    /// The reading of `tip` (in the scenario's frame; the board fills in its own depth and roll).
    fn measurement(&mut self, seq: u32, pieces: &Pieces, tip: &TipArrival) -> TipMeasurement {
        let roll = self.config.roll_measured;
        let registration = self.config.registration;
        let pose = tip.pose.map(|p| {
            let p = Pose {
                bevel: p.bevel.filter(|_| roll),
                ..p
            };
            registration.as_ref().map_or(p, |r| registered_pose(r, p))
        });
        let target = self.state().take_target();
        TipMeasurement {
            seq,
            depth_mm: pieces.depth_mm(),
            base_deg: pieces.base_deg(),
            pose,
            target: pose
                .and(target.map(|t| registration.as_ref().map_or(t, |r| registered_point(r, t)))),
        }
    }

    /// How the insertion ends when the board refuses a request or goes quiet.
    fn refused(&mut self, e: &LinkError) -> Ending {
        self.log
            .write("board_refused", json!({ "error": e.to_string() }));
        if INTERRUPTED.load(Ordering::SeqCst) {
            // Ctrl-C broke off the exchange it came in.
            return Ending::Interrupted;
        }
        match e {
            LinkError::Device(Fault::Motion(_) | Fault::NoMotion) => Ending::BoardFaulted,
            _ => Ending::ControllerNotAnswering,
        }
    }
}

/// Follows the board's answer in the mirrored pieces: `Some` when it ends the insertion.
fn follow(reply: &SteerReply, pieces: &mut Pieces, outcome: &mut SessionOutcome) -> Option<Ending> {
    match &reply.command {
        Command::Continue => None,
        Command::Replace(s) => {
            // Cannot fail: a continuation holds at most as many steps as the pieces.
            let _ = pieces.replace(s);
            None
        }
        Command::Stop(reason) => {
            outcome.predicted_miss_mm = Some(reply.predicted_error_mm).filter(|e| e.is_finite());
            Some(Ending::Controller(*reason))
        }
    }
}
