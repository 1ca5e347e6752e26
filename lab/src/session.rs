//! One steered insertion over the lab link: tracker poses and robot progress in, the in-process
//! controller's answers out to the robot, and the interlocks that stop it when something goes
//! quiet.
//!
//! The robot reports each piece it finished (`progress`) and waits for a word. A reading is the
//! newest tip pose that arrived after the previous reading (older ones are counted as
//! superseded: [`super::tracker`]), with the depth and base roll of the reported piece; its
//! answer is the word (`go`, a new step list, or `stop`). A pose flagged invalid (v3 metadata
//! `TransformStatus` other than `OK`, or after a `STATUS` of the tip that is not OK) is a reading
//! without a pose, as a tracker dropout is in the simulation.

use super::fresh::{seconds, HostClock, Offset};
use super::log::InsertionLog;
pub use super::outcome::ReadingTimes;
pub use super::outcome::{Class, Ending, LabController, SessionOutcome};
use super::progress::Commanded;
use super::robot::{step_list, RobotCommand, RobotReport, COMMAND_DEVICE, REPORT_DEVICE};
use super::slicer::Slicer;
use super::tracker::{TrackerCounts, TrackerState};
use super::wire::{registered_point, registered_pose, send_text, Arrival};
use needle_igtl::{Message, Timestamp, Transform};
use planner_core::execute::schedule::Posture;
use planner_core::steer::{Command, Pose, StopReason, TipMeasurement};
use serde_json::json;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

#[path = "interlocks.rs"]
mod interlocks;
#[path = "start.rs"]
mod start;

/// A piece the robot reported, waiting for a fresh pose.
#[derive(Clone, Copy, Debug)]
struct Reported {
    /// Commanded depth (mm).
    depth_mm: f32,
    /// Commanded base roll from the posture's (degrees).
    base_deg: f32,
    /// When the piece ended, by the robot's clock (its report's header timestamp).
    end_s: Option<f64>,
    /// When the report arrived.
    at: Instant,
}

/// What arrives while steering.
pub enum Event {
    /// The tracker's state changed (at most one notice waits: the state itself is in
    /// [`TrackerState`]).
    Tracker,
    /// A frame from the robot (boxed: a frame is about 5 KiB, the other events nothing).
    Robot(Box<Arrival>),
    /// The tracker's connection ended.
    TrackerClosed,
    /// The robot's connection ended.
    RobotClosed,
}

/// What a session reads: the events, the tracker's shared state, and the bytes each connection
/// delivered (to tell a peer that sends no OpenIGTLink from one that sends nothing).
pub struct Inputs {
    /// The session's events.
    pub events: Receiver<Event>,
    /// The tracker's state, kept by its reader thread.
    pub tracker: Arc<Mutex<TrackerState>>,
    /// Bytes received from the tracker.
    pub tracker_bytes: Arc<AtomicU64>,
    /// Bytes received from the robot.
    pub robot_bytes: Arc<AtomicU64>,
}

/// The names and limits of a session.
#[derive(Clone, Debug)]
pub struct SessionConfig {
    /// No tip pose for longer than this: hold, then stop.
    pub tracking_timeout: Duration,
    /// No report from the robot for longer than this after a command: stop.
    pub robot_timeout: Duration,
    /// The needle's arc radius (mm), to draw continuations for Slicer.
    pub arc_radius_mm: f32,
    /// The tracker's reference frame to the scenario's (none: the same frame, or the stream's).
    pub registration: Option<Transform>,
    /// The registration comes by the tracker stream, under this name: steering waits for it.
    pub registration_name: Option<String>,
    /// How long to wait for the stream's registration before giving up.
    pub registration_timeout: Duration,
    /// The tip sensor measures the roll (6-DOF); a 5-DOF sensor's roll is left out of every
    /// reading (the controller infers it from how the path bends).
    pub roll_measured: bool,
    /// The plan's posture, the robot's first command.
    pub posture: Posture,
}

/// Set by a Ctrl-C handler: the session stops the robot and ends.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Longest wait between two looks at the interrupt flag and the timeouts.
const POLL: Duration = Duration::from_millis(10);

/// A steered insertion in progress.
pub struct Session<'a> {
    config: SessionConfig,
    controller: &'a mut dyn LabController,
    robot: TcpStream,
    log: &'a mut InsertionLog,
    slicer: &'a mut Slicer,
    events: Receiver<Event>,
    tracker: Arc<Mutex<TrackerState>>,
    tracker_bytes: Arc<AtomicU64>,
    robot_bytes: Arc<AtomicU64>,
    /// Robot frames that decoded, of any name.
    robot_frames: u32,
    /// The registration in use (the file's, or the first the stream sent).
    registration: Option<Transform>,
    /// Superseded poses counted at the previous reading.
    superseded_before: u32,
    /// The robot reported a piece that is not answered yet.
    pending: Option<Reported>,
    /// This program's clock, the tracker's reader's too.
    clock: HostClock,
    /// The robot clock's offset from this program's, from its stamped reports.
    robot_offset: Offset,
    /// What the robot was commanded, to check its progress against.
    commanded: Commanded,
    /// The robot's absolute base roll once the posture was taken: the zero of the rolls the
    /// controller is given.
    base0_deg: f64,
    /// When the tracker was last given cause to send a new pose (a command, or the robot's
    /// report of a piece); a tip pose since then also counts.
    tracker_clock: Instant,
    /// When the robot was last commanded, while its report is awaited.
    robot_clock: Option<Instant>,
    seq: u32,
    outcome: SessionOutcome,
}

impl<'a> Session<'a> {
    /// A session commanding `robot`, woken by `events`, reading the tracker's `tracker`.
    pub fn new(
        config: SessionConfig,
        controller: &'a mut dyn LabController,
        robot: TcpStream,
        log: &'a mut InsertionLog,
        slicer: &'a mut Slicer,
        inputs: Inputs,
    ) -> Self {
        let steering = controller.stats().unwrap_or_default();
        let clock = inputs
            .tracker
            .lock()
            .map_or_else(|p| p.into_inner().clock, |s| s.clock);
        Session {
            registration: config.registration,
            config,
            controller,
            robot,
            log,
            slicer,
            events: inputs.events,
            tracker: inputs.tracker,
            tracker_bytes: inputs.tracker_bytes,
            robot_bytes: inputs.robot_bytes,
            robot_frames: 0,
            superseded_before: 0,
            pending: None,
            clock,
            robot_offset: Offset::default(),
            commanded: Commanded::default(),
            base0_deg: 0.0,
            tracker_clock: Instant::now(),
            robot_clock: None,
            seq: 0,
            outcome: SessionOutcome {
                outcome: Class::Reached,
                stop_reason: None,
                why: None,
                predicted_miss_mm: None,
                steering,
                tracker: TrackerCounts::default(),
                latencies_ms: Vec::new(),
                times: Vec::new(),
                clock_offset_ms: None,
                clock_offset_applied: false,
                robot_stopped: false,
                on_board: false,
            },
        }
    }

    fn command(&mut self, c: RobotCommand) -> std::io::Result<()> {
        let text = c.to_string();
        self.log.write("command", json!({ "text": text }));
        send_text(&mut self.robot, COMMAND_DEVICE, &text)
    }

    /// Runs the insertion of `steps` to its end; the robot is told to stop (or hold then stop)
    /// whatever ended it, and the log's last line is the stop.
    pub fn run(mut self, steps: &[planner_core::execute::schedule::Step]) -> SessionOutcome {
        self.slicer.state(None, false);
        let ending = self.steer(steps);
        self.stop_robot(ending);
        let stats = self.controller.stats().unwrap_or(self.outcome.steering);
        self.outcome.steering = stats;
        self.outcome.stop_reason = ending.stop_reason();
        self.outcome.outcome = ending.class();
        self.look_at_tracker();
        let tracker = self.state().offset;
        let delays = tracker.get().zip(self.robot_offset.get());
        self.outcome.clock_offset_ms = delays.map(|(t, r)| (t - r) * 1e3);
        self.outcome.clock_offset_applied =
            tracker.correction() != 0.0 || self.robot_offset.correction() != 0.0;
        let counts = self.outcome.tracker;
        self.log.write(
            "stop",
            json!({
                "outcome": self.outcome.outcome,
                "stop_reason": self.outcome.stop_reason,
                "ending": format!("{ending:?}"),
                "predicted_miss_mm": self.outcome.predicted_miss_mm,
                "robot_stopped": self.outcome.robot_stopped,
                "steering": stats,
                "rejected_frames": counts.rejected_frames,
                "invalid_poses": counts.invalid_poses,
                "superseded_poses": counts.superseded_poses,
                "repeated_poses": counts.repeated_poses,
                "ignored_frames": counts.ignored_frames,
                "registrations_refused": counts.registrations_refused,
                "stale_poses": counts.stale_poses,
                "clock_offset_ms": self.outcome.clock_offset_ms,
            }),
        );
        self.slicer.state(self.outcome.stop_reason, true);
        self.outcome
    }

    fn state(&self) -> MutexGuard<'_, TrackerState> {
        // A reader thread that panicked left the state as it was: still the newest.
        self.tracker.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Takes the tracker's news: its counts, and its log lines (written here, in order with the
    /// session's own). Clears the notice, so the reader sends the next one.
    fn look_at_tracker(&mut self) {
        let (counts, notes) = {
            let mut s = self.state();
            s.notice_pending = false;
            (s.counts, std::mem::take(&mut s.notes))
        };
        self.outcome.tracker = counts;
        for (event, fields) in notes {
            self.log.write(event, fields);
        }
    }

    fn steer(&mut self, steps: &[planner_core::execute::schedule::Step]) -> Ending {
        if let Some(ending) = self.await_registration() {
            return ending;
        }
        if let Some(ending) = self.set_posture() {
            return ending;
        }
        if let Some(ending) = self.exchange_clocks() {
            return ending;
        }
        self.commanded.list_sent(steps);
        for c in step_list(steps) {
            if self.command(c).is_err() {
                return Ending::RobotDisconnected;
            }
        }
        self.robot_clock = Some(Instant::now());
        self.tracker_clock = Instant::now();
        loop {
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Ending::Interrupted;
            }
            self.look_at_tracker();
            if let Some(ending) = self.answer_if_ready() {
                return ending;
            }
            // Looked at on every turn: a tracker streaming fast never lets the wait time out.
            if let Some(ending) = self.timed_out() {
                return ending;
            }
            match self.events.recv_timeout(POLL) {
                Ok(Event::Tracker) | Err(RecvTimeoutError::Timeout) => {}
                Ok(Event::TrackerClosed) => return Ending::TrackerDisconnected,
                Ok(Event::RobotClosed) | Err(RecvTimeoutError::Disconnected) => {
                    return Ending::RobotDisconnected
                }
                Ok(Event::Robot(arrival)) => {
                    let (frame, at) = *arrival;
                    if let Some(ending) = self.on_robot(frame, at) {
                        return ending;
                    }
                }
            }
        }
    }

    fn registered(&self, pose: Pose) -> Pose {
        match &self.registration {
            Some(reg) => registered_pose(reg, pose),
            None => pose,
        }
    }

    fn registered_target(&self, p: [f32; 3]) -> [f32; 3] {
        match &self.registration {
            Some(reg) => registered_point(reg, p),
            None => p,
        }
    }

    fn on_robot(
        &mut self,
        frame: Result<needle_igtl::Frame, needle_igtl::Error>,
        at: Instant,
    ) -> Option<Ending> {
        let (report, stamp) = self.report_of(frame)?;
        match report {
            RobotReport::Progress {
                depth_mm, base_deg, ..
            } => {
                // The robot reports its absolute roll; the controller counts from the posture.
                let base_deg = (base_deg - self.base0_deg) as f32;
                self.robot_clock = None;
                self.tracker_clock = Instant::now();
                if let Err(why) = self.commanded.check(depth_mm, base_deg) {
                    self.log.write("robot_disagrees", json!({ "why": why }));
                    self.outcome.why = Some(why);
                    return Some(Ending::RobotDisagrees);
                }
                let end_s = seconds(stamp);
                if let Some(e) = end_s {
                    self.robot_offset.observe(self.clock.unix(at), e);
                }
                self.pending = Some(Reported {
                    depth_mm,
                    base_deg,
                    end_s,
                    at,
                });
                None
            }
            RobotReport::Done => Some(Ending::StepsRanOut),
            RobotReport::Holding => None,
            RobotReport::Stopped => Some(Ending::RobotStopped),
            RobotReport::Collided { depth_mm } => {
                self.log
                    .write("robot_sensed_collision", json!({ "depth_mm": depth_mm }));
                Some(Ending::RobotCollided)
            }
            RobotReport::PostureSet { .. } | RobotReport::PostureRefused { .. } => {
                let why = format!("`{report}` after the posture was taken");
                self.log.write("robot_disagrees", json!({ "why": why }));
                self.outcome.why = Some(why);
                Some(Ending::RobotDisagrees)
            }
        }
    }

    /// The robot's report a frame carries, if it is one; a text that is not in the grammar is
    /// logged (`robot_refused`) and read past.
    fn report_of(
        &mut self,
        frame: Result<needle_igtl::Frame, needle_igtl::Error>,
    ) -> Option<(RobotReport, Timestamp)> {
        if frame.is_ok() {
            self.robot_frames = self.robot_frames.saturating_add(1);
        }
        let (text, stamp) = match frame {
            Ok(f) if f.info.device_name == REPORT_DEVICE => match f.message {
                Message::String(s) => (s.text, f.info.timestamp),
                _ => return None,
            },
            _ => return None,
        };
        match text.parse::<RobotReport>() {
            Ok(r) => Some((r, stamp)),
            Err(e) => {
                self.log.write(
                    "robot_refused",
                    json!({ "text": text.as_str(), "error": e.to_string() }),
                );
                None
            }
        }
    }

    /// Answers the reported piece once a new tip pose is in.
    fn answer_if_ready(&mut self) -> Option<Ending> {
        let reported = self.pending?;
        let (depth_mm, base_deg) = (reported.depth_mm, reported.base_deg);
        let robot_offset = self.robot_offset;
        let (tip, target, superseded, tracker_offset) = {
            let mut s = self.state();
            let tip = s.take_fresh_tip(reported.end_s, robot_offset)?;
            // An image of the target is used once: a reading after none new carries none.
            (tip, s.take_target(), s.counts.superseded_poses, s.offset)
        };
        let superseded_poses = superseded.saturating_sub(self.superseded_before);
        self.superseded_before = superseded;
        let roll = self.config.roll_measured;
        let sensed = tip.pose.map(|p| Pose {
            bevel: p.bevel.filter(|_| roll),
            ..p
        });
        let (pose, at) = (sensed.map(|p| self.registered(p)), tip.at);
        self.pending = None;
        self.seq += 1;
        let m = TipMeasurement {
            seq: self.seq,
            depth_mm,
            base_deg,
            pose,
            target: pose.and(target.map(|t| self.registered_target(t))),
        };
        let reply = match self.controller.update(&m) {
            Ok(r) => r,
            Err(e) => {
                self.log.write("controller_failed", json!({ "error": e }));
                return Some(Ending::ControllerNotAnswering);
            }
        };
        let (words, ending) = match &reply.command {
            Command::Continue => (vec![RobotCommand::Go], None),
            Command::Replace(s) => {
                self.commanded.list_sent(s);
                (step_list(s), None)
            }
            Command::Stop(reason) => {
                self.outcome.predicted_miss_mm =
                    Some(reply.predicted_error_mm).filter(|e| e.is_finite());
                // Tracking lost: the robot holds, then stops, as when the poses stop coming.
                let words = if *reason == StopReason::TrackingLost {
                    vec![RobotCommand::Hold, RobotCommand::Stop]
                } else {
                    vec![RobotCommand::Stop]
                };
                (words, Some(Ending::Controller(*reason)))
            }
        };
        for w in words {
            if self.command(w).is_err() {
                return Some(Ending::RobotDisconnected);
            }
        }
        let sent = Instant::now();
        let latency_ms = ms(sent.duration_since(at));
        let times = ReadingTimes {
            reaction_ms: ms(sent.duration_since(at.max(reported.at))),
            waited_ms: ms(at.saturating_duration_since(reported.at)),
            pose_age_ms: seconds(tip.stamp)
                .map(|s| (self.clock.unix(sent) - (s + tracker_offset.correction())) * 1e3),
        };
        self.outcome.latencies_ms.push(latency_ms);
        self.outcome.times.push(times);
        // After the commands it caused, with the time from the pose to them.
        self.log.write(
            "reading",
            json!({
                "measurement": m,
                "reply": reply,
                "latency_ms": latency_ms,
                "reaction_ms": times.reaction_ms,
                "waited_ms": times.waited_ms,
                "pose_age_ms": times.pose_age_ms,
                "pose_sampled_s": seconds(tip.stamp),
                "piece_ended_s": reported.end_s,
                "superseded_poses": superseded_poses,
            }),
        );
        let replaced = match &reply.command {
            Command::Replace(s) => Some(&s[..]),
            _ => None,
        };
        if let Some(tip) = self
            .slicer
            .shown()
            .then(|| self.controller.estimated_tip())
            .flatten()
        {
            self.slicer
                .reading(&tip, replaced, self.config.arc_radius_mm);
        }
        self.robot_clock = Some(Instant::now());
        self.tracker_clock = Instant::now();
        ending
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
