//! How a steered insertion ends and what it gives back, and the controller it consults (in
//! process, or a device behind the link).

use super::tracker::TrackerCounts;
use crate::simulate::device::LinkController;
use needle_link::Transport;
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
    /// What the tracker sent that was not used as sent: `rejected_frames` (the codec refused
    /// them: bad CRC, bad size, not rigid, ...), `invalid_poses`, `superseded_poses`,
    /// `repeated_poses`, `ignored_frames`, `registrations_refused`.
    #[serde(flatten)]
    pub tracker: TrackerCounts,
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
