//! One steered insertion over the lab link: tracker poses and robot progress in, the in-process
//! controller's answers out to the robot, and the interlocks that stop it when something goes
//! quiet.
//!
//! The robot reports each piece it finished (`progress`) and waits for a word. A reading is the
//! newest tip pose that arrived after the previous reading, with the depth and base roll of the
//! reported piece; its answer is the word (`go`, a new step list, or `stop`). A pose flagged
//! invalid (v3 metadata `TransformStatus` other than `OK`, or after a `STATUS` of the tip that is
//! not OK) is a reading without a pose, as a tracker dropout is in the simulation.

use super::log::InsertionLog;
use super::progress::Commanded;
use super::robot::{step_list, RobotCommand, RobotReport, COMMAND_DEVICE, REPORT_DEVICE};
use super::slicer::Slicer;
use super::wire::{registered_point, registered_pose, send_text, tip_pose, Arrival};
use crate::simulate::device::LinkController;
use needle_igtl::{Message, StatusCode, Transform};
use needle_link::Transport;
use planner_core::model::kinematics::Frame;
use planner_core::steer::{
    Command, Pose, SteerReply, SteerStats, Steering, StopReason, TipMeasurement,
};
use serde::Serialize;
use serde_json::json;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

/// What arrives while steering.
pub enum Event {
    /// A frame from the tracker.
    Tracker(Arrival),
    /// A frame from the robot.
    Robot(Arrival),
    /// The tracker's connection ended.
    TrackerClosed,
    /// The robot's connection ended.
    RobotClosed,
}

/// The names and limits of a session.
#[derive(Clone, Debug)]
pub struct SessionConfig {
    /// Device name of the tip's `TRANSFORM`.
    pub tip_name: String,
    /// Device name of the target's `TRANSFORM`.
    pub target_name: String,
    /// No tip pose for longer than this: hold, then stop.
    pub tracking_timeout: Duration,
    /// No report from the robot for longer than this after a command: stop.
    pub robot_timeout: Duration,
    /// The needle's arc radius (mm), to draw continuations for Slicer.
    pub arc_radius_mm: f32,
    /// The tracker's reference frame to the scenario's (none: the same frame).
    pub registration: Option<Transform>,
}

/// How an insertion ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// The controller stopped it (the target reached, or a reason to stop).
    Controller(StopReason),
    /// The robot ran out of steps with the controller's verdict still open: missed.
    StepsRanOut,
    /// No tip pose within the tracking timeout.
    TrackingLost,
    /// No robot report within the robot timeout.
    RobotNotAnswering,
    /// Interrupted (Ctrl-C).
    Interrupted,
    /// The robot's connection ended.
    RobotDisconnected,
    /// The tracker's connection ended.
    TrackerDisconnected,
    /// The robot stopped without being told to.
    RobotStopped,
    /// The controller (a device) did not answer a reading.
    ControllerNotAnswering,
    /// The robot reported progress its commands cannot give.
    RobotDisagrees,
}

impl Ending {
    /// The stop reason as JSON names it; `None`: the target was reached.
    pub fn stop_reason(self) -> Option<&'static str> {
        match self {
            Ending::Controller(StopReason::TargetReached) => None,
            Ending::Controller(r) => Some(r.name()),
            Ending::StepsRanOut => Some(StopReason::Missed.name()),
            Ending::TrackingLost => Some("tracking_lost"),
            Ending::RobotNotAnswering => Some("robot_not_answering"),
            Ending::Interrupted => Some("interrupted"),
            Ending::RobotDisconnected => Some("robot_disconnected"),
            Ending::TrackerDisconnected => Some("tracker_disconnected"),
            Ending::RobotStopped => Some("robot_stopped"),
            Ending::ControllerNotAnswering => Some("device_not_answering"),
            Ending::RobotDisagrees => Some("robot_disagrees"),
        }
    }
}

/// What a session gives back.
#[derive(Clone, Debug, Serialize)]
pub struct SessionOutcome {
    /// Why it stopped; null: the target was reached.
    pub stop_reason: Option<&'static str>,
    /// The controller's estimate of the miss when it stopped (mm), if it gave a verdict.
    pub predicted_miss_mm: Option<f32>,
    /// The controller's counters.
    pub steering: SteerStats,
    /// Tracker frames rejected by the codec (bad CRC, bad size, not rigid, ...).
    pub rejected_frames: u32,
    /// Tip poses flagged invalid and not used.
    pub invalid_poses: u32,
    /// Per reading: tip pose received to the robot's command sent (ms).
    #[serde(skip)]
    pub latencies_ms: Vec<f64>,
    /// The robot confirmed the stop (`stopped`).
    pub robot_stopped: bool,
}

/// The controller a session consults: in-process, or on a device behind the link.
pub trait LabController {
    /// Answers one reading; an error (the device gone quiet) stops the insertion.
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, String>;
    /// Its counters, if it can still give them.
    fn stats(&mut self) -> Option<SteerStats>;
    /// Its estimated tip, if it shares it (a device does not).
    fn estimated_tip(&self) -> Option<Frame>;
}

impl LabController for Steering {
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, String> {
        Ok(Steering::update(self, m))
    }
    fn stats(&mut self) -> Option<SteerStats> {
        Some(Steering::stats(self))
    }
    fn estimated_tip(&self) -> Option<Frame> {
        Some(self.estimate().tip)
    }
}

impl<T: Transport> LabController for LinkController<'_, T> {
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, String> {
        needle_sim::Controller::update(self, m).map_err(|e| e.to_string())
    }
    fn stats(&mut self) -> Option<SteerStats> {
        needle_sim::Controller::stats(self).ok()
    }
    fn estimated_tip(&self) -> Option<Frame> {
        None
    }
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
    target: Option<[f32; 3]>,
    tip: Option<(Option<Pose>, Instant)>,
    tip_status_ok: bool,
    /// The robot reported a piece that is not answered yet: (depth, base roll).
    pending: Option<(f32, f32)>,
    /// What the robot was commanded, to check its progress against.
    commanded: Commanded,
    /// When the tracker was last heard of, or last given cause to move.
    tracker_clock: Instant,
    /// When the robot was last commanded, while its report is awaited.
    robot_clock: Option<Instant>,
    seq: u32,
    outcome: SessionOutcome,
}

impl<'a> Session<'a> {
    /// A session commanding `robot`, fed by `events`.
    pub fn new(
        config: SessionConfig,
        controller: &'a mut dyn LabController,
        robot: TcpStream,
        log: &'a mut InsertionLog,
        slicer: &'a mut Slicer,
        events: Receiver<Event>,
    ) -> Self {
        let steering = controller.stats().unwrap_or_default();
        Session {
            config,
            controller,
            robot,
            log,
            slicer,
            events,
            target: None,
            tip: None,
            tip_status_ok: true,
            pending: None,
            commanded: Commanded::default(),
            tracker_clock: Instant::now(),
            robot_clock: None,
            seq: 0,
            outcome: SessionOutcome {
                stop_reason: None,
                predicted_miss_mm: None,
                steering,
                rejected_frames: 0,
                invalid_poses: 0,
                latencies_ms: Vec::new(),
                robot_stopped: false,
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
        self.log.write(
            "stop",
            json!({
                "stop_reason": self.outcome.stop_reason,
                "ending": format!("{ending:?}"),
                "predicted_miss_mm": self.outcome.predicted_miss_mm,
                "robot_stopped": self.outcome.robot_stopped,
                "steering": stats,
            }),
        );
        self.slicer.state(self.outcome.stop_reason, true);
        self.outcome
    }

    fn steer(&mut self, steps: &[planner_core::execute::schedule::Step]) -> Ending {
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
            if let Some(ending) = self.answer_if_ready() {
                return ending;
            }
            match self.events.recv_timeout(POLL) {
                Ok(event) => {
                    if let Some(ending) = self.on_event(event) {
                        return ending;
                    }
                }
                Err(RecvTimeoutError::Timeout) => {
                    if let Some(ending) = self.timed_out() {
                        return ending;
                    }
                }
                Err(RecvTimeoutError::Disconnected) => return Ending::RobotDisconnected,
            }
        }
    }

    fn timed_out(&self) -> Option<Ending> {
        if self.tracker_clock.elapsed() > self.config.tracking_timeout {
            return Some(Ending::TrackingLost);
        }
        match self.robot_clock {
            Some(t) if t.elapsed() > self.config.robot_timeout => Some(Ending::RobotNotAnswering),
            _ => None,
        }
    }

    fn on_event(&mut self, event: Event) -> Option<Ending> {
        match event {
            Event::TrackerClosed => Some(Ending::TrackerDisconnected),
            Event::RobotClosed => Some(Ending::RobotDisconnected),
            Event::Tracker((Err(e), _)) => {
                self.outcome.rejected_frames += 1;
                self.log
                    .write("rejected", json!({ "error": format!("{e:?}") }));
                None
            }
            Event::Tracker((Ok(frame), at)) => {
                let name = frame.info.device_name.as_str();
                let flagged = frame
                    .info
                    .extended
                    .as_ref()
                    .and_then(|e| e.metadata.get("TransformStatus"))
                    .is_some_and(|s| s != "OK");
                match frame.message {
                    Message::Transform(t) if name == self.config.tip_name => {
                        let valid = self.tip_status_ok && !flagged;
                        if !valid {
                            self.outcome.invalid_poses += 1;
                        }
                        let pose = valid.then(|| self.registered(tip_pose(&t)));
                        self.tip = Some((pose, at));
                        self.tracker_clock = Instant::now();
                    }
                    Message::Transform(t) if name == self.config.target_name => {
                        let p = t.translation();
                        self.target = Some(match &self.config.registration {
                            Some(reg) => registered_point(reg, p),
                            None => p,
                        });
                    }
                    Message::Status(s) if name == self.config.tip_name => {
                        self.tip_status_ok = s.code == StatusCode::OK;
                    }
                    _ => {}
                }
                None
            }
            Event::Robot((frame, _)) => self.on_robot(frame),
        }
    }

    fn registered(&self, pose: Pose) -> Pose {
        match &self.config.registration {
            Some(reg) => registered_pose(reg, pose),
            None => pose,
        }
    }

    fn on_robot(
        &mut self,
        frame: Result<needle_igtl::Frame, needle_igtl::Error>,
    ) -> Option<Ending> {
        let text = match frame {
            Ok(f) if f.info.device_name == REPORT_DEVICE => match f.message {
                Message::String(s) => s.text,
                _ => return None,
            },
            _ => return None,
        };
        match text.parse::<RobotReport>() {
            Ok(RobotReport::Progress {
                depth_mm, base_deg, ..
            }) => {
                self.robot_clock = None;
                if let Err(why) = self.commanded.check(depth_mm, base_deg) {
                    self.log.write("robot_disagrees", json!({ "why": why }));
                    return Some(Ending::RobotDisagrees);
                }
                self.pending = Some((depth_mm, base_deg));
                None
            }
            Ok(RobotReport::Done) => Some(Ending::StepsRanOut),
            Ok(RobotReport::Holding) => None,
            Ok(RobotReport::Stopped) => Some(Ending::RobotStopped),
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
        let (depth_mm, base_deg) = self.pending?;
        let (pose, at) = self.tip.take()?;
        self.pending = None;
        self.seq += 1;
        let m = TipMeasurement {
            seq: self.seq,
            depth_mm,
            base_deg,
            pose,
            target: pose.and(self.target),
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
        let latency_ms = at.elapsed().as_secs_f64() * 1e3;
        self.outcome.latencies_ms.push(latency_ms);
        // After the commands it caused, with the time from the pose to them.
        self.log.write(
            "reading",
            json!({ "measurement": m, "reply": reply, "latency_ms": latency_ms }),
        );
        let replaced = match &reply.command {
            Command::Replace(s) => Some(&s[..]),
            _ => None,
        };
        if let Some(tip) = self.controller.estimated_tip() {
            self.slicer
                .reading(&tip, replaced, self.config.arc_radius_mm);
        }
        self.robot_clock = Some(Instant::now());
        self.tracker_clock = Instant::now();
        ending
    }

    /// Tells the robot to stop (holding first when tracking was lost) and waits for its word.
    fn stop_robot(&mut self, ending: Ending) {
        if ending == Ending::RobotStopped {
            self.outcome.robot_stopped = true;
            return;
        }
        if ending == Ending::RobotDisconnected {
            return;
        }
        if ending == Ending::TrackingLost {
            let _ = self.command(RobotCommand::Hold);
        }
        // The controller's stop went out with its answer.
        let sent = matches!(ending, Ending::Controller(_));
        if !sent && self.command(RobotCommand::Stop).is_err() {
            return;
        }
        let deadline = Instant::now() + self.config.robot_timeout;
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match self.events.recv_timeout(left) {
                Ok(Event::Robot((Ok(f), _))) => {
                    if let Message::String(s) = f.message {
                        if s.text.parse() == Ok(RobotReport::Stopped) {
                            self.outcome.robot_stopped = true;
                            return;
                        }
                    }
                }
                Ok(_) => {}
                Err(_) => return,
            }
        }
    }
}
