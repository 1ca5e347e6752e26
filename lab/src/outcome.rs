//! How a steered insertion ends and what it gives back, and the controller it consults (in
//! process, or a device behind the link).

use super::tracker::TrackerCounts;
use needle_link::Transport;
use needle_simulate::device::LinkController;
use planner_core::model::kinematics::Frame;
use planner_core::steer::{SteerReply, SteerStats, Steering, StopReason, TipMeasurement};
use serde::Serialize;

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
    /// The registration named by `--registration-name` did not arrive in time.
    NoRegistration,
    /// Bytes came from the tracker, but not one OpenIGTLink frame.
    TrackerNotOpenIgtlink,
    /// Bytes came from the robot, but not one OpenIGTLink frame.
    RobotNotOpenIgtlink,
    /// The robot cannot take the plan's posture (a fixed guide asked to tilt).
    PostureRefused,
    /// The robot sensed the needle in an obstacle and stopped.
    RobotCollided,
    /// The driver board that moves the needle faulted (its e-stop, a limit switch, its
    /// watchdog) or refused to move on.
    BoardFaulted,
}

/// How an insertion ended, in the four ways a run ends plus the link breaking; each has its own
/// exit status of `needle steer`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    /// The controller judged the target reached (exit status 0).
    Reached,
    /// The steps ran out, or the controller judged the target missed (3).
    Missed,
    /// The needle entered an obstacle (4), as the robot's contact or force sensor said
    /// (`collided`): only the lab sees the true path.
    Collided,
    /// Stopped by an interlock, a refusal or the operator (5).
    Stopped,
    /// The link broke: the tracker or robot unreachable, disconnected, not answering or not
    /// speaking OpenIGTLink; or a device controller not answering (6).
    LinkBroken,
}

impl Class {
    /// Its name in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Class::Reached => "reached",
            Class::Missed => "missed",
            Class::Collided => "collided",
            Class::Stopped => "stopped",
            Class::LinkBroken => "link_broken",
        }
    }

    /// `needle steer`'s exit status for it.
    pub fn exit_code(self) -> u8 {
        match self {
            Class::Reached => 0,
            Class::Missed => 3,
            Class::Collided => 4,
            Class::Stopped => 5,
            Class::LinkBroken => 6,
        }
    }
}

/// `needle steer` ended without reaching the target: the exit status to give, and why.
#[derive(Debug)]
pub struct SteerEnded {
    /// The exit status.
    pub code: u8,
    /// What to say on stderr.
    pub message: String,
}

impl std::fmt::Display for SteerEnded {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for SteerEnded {}

/// The exit status for a failed command: `needle steer`'s own for an insertion that ended
/// without reaching the target, else 1.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    e.downcast_ref::<SteerEnded>().map_or(1, |s| s.code)
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
            Ending::NoRegistration => Some("no_registration"),
            Ending::TrackerNotOpenIgtlink => Some("tracker_not_openigtlink"),
            Ending::RobotNotOpenIgtlink => Some("robot_not_openigtlink"),
            Ending::PostureRefused => Some("posture_refused"),
            Ending::RobotCollided => Some("robot_sensed_collision"),
            Ending::BoardFaulted => Some("board_faulted"),
        }
    }

    /// Which of the ways an insertion ends this is.
    pub fn class(self) -> Class {
        match self {
            Ending::Controller(StopReason::TargetReached) => Class::Reached,
            Ending::Controller(StopReason::Missed) | Ending::StepsRanOut => Class::Missed,
            Ending::RobotCollided => Class::Collided,
            Ending::Controller(_)
            | Ending::TrackingLost
            | Ending::Interrupted
            | Ending::RobotStopped
            | Ending::RobotDisagrees
            | Ending::NoRegistration
            | Ending::PostureRefused
            | Ending::BoardFaulted => Class::Stopped,
            Ending::RobotNotAnswering
            | Ending::RobotDisconnected
            | Ending::TrackerDisconnected
            | Ending::ControllerNotAnswering
            | Ending::TrackerNotOpenIgtlink
            | Ending::RobotNotOpenIgtlink => Class::LinkBroken,
        }
    }
}

/// What a session gives back.
#[derive(Clone, Debug, Serialize)]
pub struct SessionOutcome {
    /// How it ended: reached, missed, collided, stopped or link_broken.
    pub outcome: Class,
    /// Why it stopped; null: the target was reached.
    pub stop_reason: Option<&'static str>,
    /// Why, in words, when a stop needs more than its name (the posture refused).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
    /// The controller's estimate of the miss when it stopped (mm), if it gave a verdict.
    pub predicted_miss_mm: Option<f32>,
    /// The controller's counters.
    pub steering: SteerStats,
    /// What the tracker sent that was not used as sent: `rejected_frames` (the codec refused
    /// them: bad CRC, bad size, not rigid, ...), `invalid_poses`, `superseded_poses`,
    /// `repeated_poses`, `ignored_frames`, `registrations_refused`.
    #[serde(flatten)]
    pub tracker: TrackerCounts,
    /// Per reading: tip pose received to the robot's command sent (ms).
    #[serde(skip)]
    pub latencies_ms: Vec<f64>,
    /// Per reading: the program's reaction, the pose's age and the wait for a fresh pose.
    #[serde(skip)]
    pub times: Vec<ReadingTimes>,
    /// The smallest `arrival - stamp` of the tracker's poses less that of the robot's reports
    /// (ms; null without stamps on both): the tracker's lag behind the robot, or its clock's
    /// behind the robot's, which one-way stamps cannot tell apart.
    pub clock_offset_ms: Option<f64>,
    /// A peer's clock was proven ahead of this program's (a frame arrived before its stamp) and
    /// its stamps were moved back to judge the poses' freshness.
    pub clock_offset_applied: bool,
    /// The robot confirmed the stop (`stopped`); with a driver board, the board came to rest.
    pub robot_stopped: bool,
    /// A driver board moved the needle, not a robot (the words of the summary).
    #[serde(skip)]
    pub on_board: bool,
}

/// The times of one reading.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ReadingTimes {
    /// This program's own time: from the later of the pose's and the report's arrival to the
    /// robot's command sent (ms).
    pub reaction_ms: f64,
    /// From the robot's report to the arrival of the fresh pose used (0: it was in first), ms.
    pub waited_ms: f64,
    /// The pose's age when the command went out: from its sample time (its stamp, on this
    /// program's clock) to the command (ms); none without a stamp.
    pub pose_age_ms: Option<f64>,
}

/// The controller a session consults: in-process, or on a device behind the link.
pub trait LabController {
    /// Answers one reading; an error (the device gone quiet) stops the insertion.
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, String>;
    /// Its counters, if it can still give them.
    fn stats(&mut self) -> Option<SteerStats>;
    /// Its estimated tip after the last reading, if it can still give it (a device is asked).
    fn estimated_tip(&mut self) -> Option<Frame>;
}

impl LabController for Steering {
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, String> {
        Ok(Steering::update(self, m))
    }
    fn stats(&mut self) -> Option<SteerStats> {
        Some(Steering::stats(self))
    }
    fn estimated_tip(&mut self) -> Option<Frame> {
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
    fn estimated_tip(&mut self) -> Option<Frame> {
        self.0.steer_estimate().ok()?.frame()
    }
}
