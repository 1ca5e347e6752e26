//! How a steered run ended, judged on the world's truth: the true path and the true tip against
//! where the target truly ended, never the controller's estimate. The controller's own verdict
//! (its stop reason, or none) stays beside it under its own name, so a run the controller
//! believed it reached but whose true path entered an obstacle reads "collided", not "reached".

use crate::ClosedRun;
use planner_core::steer::StopReason;

/// The ending of one steered run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The true path kept clear of every obstacle and the true tip ended within the tolerance
    /// of the true target.
    Reached,
    /// The true path kept clear, the insertion went through (the controller did not stop it
    /// early), and the true tip ended farther than the tolerance from the true target.
    Missed,
    /// The true path entered an obstacle, whatever the controller concluded.
    Collided,
    /// The controller stopped the insertion before the target, for this reason, and the true
    /// path kept clear.
    Stopped(StopReason),
}

impl Outcome {
    /// Every name [`Outcome::name`] gives, in the order tables list them.
    pub const NAMES: [&'static str; 4] = ["reached", "missed", "collided", "stopped"];

    /// The ending of `run`, the true tip counted as at the target within `tolerance_mm`.
    ///
    /// ```
    /// use needle_sim::Outcome;
    /// # use needle_sim::{ClosedRun, Run};
    /// # fn run(collided: bool, error: f32, stop: Option<planner_core::steer::StopReason>) -> ClosedRun {
    /// #     let mut r: ClosedRun = ClosedRun::default();
    /// #     r.run.collided = collided;
    /// #     r.run.target_error = error;
    /// #     r.stop_reason = stop;
    /// #     r
    /// # }
    /// use planner_core::steer::StopReason;
    /// assert_eq!(Outcome::of(&run(false, 0.4, None), 1.0), Outcome::Reached);
    /// assert_eq!(Outcome::of(&run(false, 1.4, None), 1.0), Outcome::Missed);
    /// // The controller believed it reached; the true path says otherwise.
    /// assert_eq!(Outcome::of(&run(true, 0.4, None), 1.0), Outcome::Collided);
    /// let stop = Some(StopReason::TrackingLost);
    /// assert_eq!(Outcome::of(&run(false, 9.0, stop), 1.0), Outcome::Stopped(StopReason::TrackingLost));
    /// // A controller that ran out of steps farther than its tolerance went through: judged on the tip.
    /// assert_eq!(Outcome::of(&run(false, 0.2, Some(StopReason::Missed)), 1.0), Outcome::Reached);
    /// ```
    pub fn of(run: &ClosedRun, tolerance_mm: f32) -> Outcome {
        if run.run.collided {
            return Outcome::Collided;
        }
        match run.stop_reason {
            None | Some(StopReason::Missed | StopReason::TargetReached) => {
                // A NaN error is not within any tolerance.
                if run.run.target_error <= tolerance_mm {
                    Outcome::Reached
                } else {
                    Outcome::Missed
                }
            }
            Some(reason) => Outcome::Stopped(reason),
        }
    }

    /// `reached`, `missed`, `collided` or `stopped`.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Reached => Self::NAMES[0],
            Outcome::Missed => Self::NAMES[1],
            Outcome::Collided => Self::NAMES[2],
            Outcome::Stopped(_) => Self::NAMES[3],
        }
    }

    /// The controller's reason, for a stopped run.
    pub fn stop_reason(self) -> Option<StopReason> {
        match self {
            Outcome::Stopped(reason) => Some(reason),
            _ => None,
        }
    }
}

/// The controller's own verdict on `run`: `reached` when it let the insertion end at the target
/// as it estimated it, else its stop reason's name.
pub fn controller_verdict(run: &ClosedRun) -> &'static str {
    match run.stop_reason {
        None | Some(StopReason::TargetReached) => "reached",
        Some(reason) => reason.name(),
    }
}
