//! Closed-loop steering: the plan being executed, re-planned from each measured tip pose.
//!
//! A [`Steering`] holds the continuation being executed (its motor steps and how far the robot
//! has got) and the [`Estimate`] of the tip, the tissue's curvature and the target. Each
//! [`TipMeasurement`] carries the robot's own progress (insertion depth and base rotation: what
//! drives the kinematic prediction) and, when the tracker has a fix, the tip pose and the target
//! as imaging sees them. [`Steering::update`] fuses it, predicts where the rest of the
//! continuation ends and how close it passes every obstacle, and re-plans when the prediction
//! misses the target or the clearance (same objective and constraints as the plan, bounded work).
//! Every continuation it commands first passes [`replan::predict`], the nominal execution of its
//! motor steps; where nothing safe remains it stops and says why.
//!
//! ```
//! use planner_core::execute::schedule::schedule;
//! use planner_core::steer::{Command, SteerConfig, Steering, TipMeasurement};
//! use planner_core::{plan, Scenario};
//!
//! let scenario = Scenario::paper();
//! let best = plan(&scenario).unwrap().best().unwrap().clone();
//! let s = schedule(&scenario, &best).unwrap();
//! let mut steering = Steering::start(&scenario, &s, &SteerConfig::DEFAULT).unwrap();
//! // The robot has pushed 1 mm and the tracker sees the tip where the plan has it.
//! let planned = steering.estimate().tip;
//! let mut at = planned.advanced(planner_core::SegmentKind::Arc, 1.0, 63.7);
//! let m = TipMeasurement::fix(1, 1.0, 0.0, at.p.into(), at.e3().into(), at.e2().into());
//! let reply = steering.update(&m);
//! assert!(matches!(reply.command, Command::Continue | Command::Replace(_)));
//! ```

mod aimed;
mod attempt;
mod continuation;
mod early;
mod predict;
pub mod replan;
mod state;
mod turns;
mod warm;

pub use crate::estimate::{self, target, Estimate, NoiseModel, STEER_MARGIN_SDS};
pub use crate::execute::apriori;
pub use state::Steering;

use crate::execute::schedule::Steps;
use crate::model::kinematics::{Frame, V3};
use serde::{Deserialize, Serialize};

/// Why the controller stopped the insertion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StopReason {
    /// The continuation is executed and the estimate puts the tip within the reach tolerance
    /// ([`SteerConfig::reach_tolerance_mm`]) of the target as last seen.
    TargetReached,
    /// The continuation being executed is predicted to come too close to an obstacle and no
    /// replan passes the check.
    NoSafeContinuation,
    /// No tracker fix was accepted over more than the configured gap of insertion; or the
    /// estimate may have lost the tip (a fix rejected while the fused ones are inconsistent,
    /// `steer::lost`) and the continuation passes an obstacle within the margin plus how far
    /// that fix put the tip.
    TrackingLost,
    /// The robot's progress is not a number or went backwards: the device cannot know where
    /// the needle is.
    BadMeasurement,
    /// The continuation is executed but the estimate puts the tip farther than the reach
    /// tolerance from the target as last seen (the reply's `predicted_error_mm` says how far).
    Missed,
}

impl StopReason {
    /// The snake-case name used in JSON.
    pub fn name(self) -> &'static str {
        match self {
            StopReason::TargetReached => "target_reached",
            StopReason::NoSafeContinuation => "no_safe_continuation",
            StopReason::TrackingLost => "tracking_lost",
            StopReason::BadMeasurement => "bad_measurement",
            StopReason::Missed => "missed",
        }
    }
}

/// One tracker reading with the robot's progress.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TipMeasurement {
    /// Sequence number, increasing by one per reading (a repeat is answered, not applied).
    pub seq: u32,
    /// Insertion depth the robot has commanded so far (mm).
    pub depth_mm: f32,
    /// Base rotation the robot has commanded so far (degrees, accumulated).
    pub base_deg: f32,
    /// The tracker's fix, if it has one.
    pub pose: Option<Pose>,
    /// The target as imaging sees it, if it does.
    pub target: Option<[f32; 3]>,
}

/// A measured tip pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose {
    /// Tip position (mm).
    pub position: [f32; 3],
    /// Unit heading.
    pub heading: [f32; 3],
    /// Unit bevel direction, where the sensor measures the roll (a 6-DOF coil).
    pub bevel: Option<[f32; 3]>,
}

impl Pose {
    /// The pose of the tip frame `f`, its bevel direction included.
    pub fn of_frame(f: &Frame) -> Pose {
        Pose {
            position: f.p.into(),
            heading: f.e3().into(),
            bevel: Some(f.e2().into()),
        }
    }

    /// The tip frame of this pose (the bending-plane normal completing the right-handed
    /// columns); `None` without a bevel direction.
    pub fn frame(&self) -> Option<Frame> {
        let e2 = V3::from(self.bevel?);
        let e3 = V3::from(self.heading);
        Some(Frame::from_columns(
            V3::from(self.position),
            e2.cross(&e3),
            e2,
            e3,
        ))
    }
}

impl TipMeasurement {
    /// A reading with a full 6-DOF fix and no target.
    pub fn fix(
        seq: u32,
        depth_mm: f32,
        base_deg: f32,
        position: [f32; 3],
        heading: [f32; 3],
        bevel: [f32; 3],
    ) -> TipMeasurement {
        TipMeasurement {
            seq,
            depth_mm,
            base_deg,
            pose: Some(Pose {
                position,
                heading,
                bevel: Some(bevel),
            }),
            target: None,
        }
    }
}

/// What the controller does with the needle after a reading.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// Keep executing the steps commanded last.
    Continue,
    /// Break off the step being executed and execute these instead (from where the tip is).
    Replace(Steps),
    /// Stop inserting.
    Stop(StopReason),
}

/// How a reading was used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reading {
    /// Its fix was fused.
    Fused,
    /// It had no fix: the prediction bridges the gap.
    NoFix,
    /// Its fix was rejected as an outlier (or was not a number): bridged like a missing one.
    Outlier,
    /// Its sequence number was older than the last one: ignored.
    Stale,
    /// Its sequence number was the last one's: the last reply is repeated, nothing applied.
    Repeated,
}

/// The controller's answer to a reading.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SteerReply {
    /// The reading's sequence number.
    pub seq: u32,
    /// What to do.
    pub command: Command,
    /// How the reading was used.
    pub reading: Reading,
    /// Whether a new continuation was planned on this reading.
    pub replanned: bool,
    /// Predicted distance from the continuation's end to the estimated target (mm).
    pub predicted_error_mm: f32,
    /// Predicted smallest clearance of the continuation (mm; infinite without obstacles).
    pub predicted_clearance_mm: f32,
    /// Path evaluations this reading cost (the replan's budget used).
    pub evaluations: u32,
}

/// Counters over one insertion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SteerStats {
    /// Readings applied.
    pub readings: u32,
    /// New continuations commanded.
    pub replans: u32,
    /// Replans that found nothing passing the check (the last continuation kept).
    pub replan_failures: u32,
    /// Readings without a fix.
    pub no_fix: u32,
    /// Fixes rejected as outliers.
    pub outliers: u32,
    /// Readings older than the last one (ignored).
    pub stale: u32,
    /// Imaged targets rejected as outliers (outside the gate of the target's estimate).
    pub target_outliers: u32,
    /// Times the imaged target moved: fixes that agreed with one another and not with the
    /// estimate, which then followed them (each one a move the run reports).
    pub target_jumps: u32,
    /// Readings with the last one's sequence number, answered again without applying them: a
    /// tracker's duplicate, or the link sending a reading again after its answer was lost or
    /// late (so the count depends on the transport, not only on the insertion).
    pub repeated: u32,
}

/// The miss a continuation may predict before it is re-planned grows by this much per
/// millimetre still to insert (mm/mm; [`SteerConfig::replan_error_mm`] is the least): an error
/// far from the target is corrected later with the same turn of the bevel, so the controller
/// does not turn at every reading. Measured on the paper's insertion and three generated
/// families (docs/execution.md): 0.003 left 33 turns per insertion, 0.005 21, 0.008 13 with
/// more runs missing.
pub const REPLAN_DEFER_PER_MM: f32 = 0.005;

/// How the controller works: the estimator's noise model, when to re-plan and its budget.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SteerConfig {
    /// The estimator's noise model.
    pub noise: NoiseModel,
    /// Re-plan when the predicted end misses the estimated target by more than this (mm), or
    /// by [`REPLAN_DEFER_PER_MM`] per millimetre still to insert when that is more.
    pub replan_error_mm: f32,
    /// SQP iterations per replan attempt.
    pub iterations: u32,
    /// Stop with [`StopReason::TrackingLost`] after this much insertion without a fix (mm).
    pub max_gap_mm: f32,
    /// When the continuation is executed, the tip counts as at the target if the estimate puts
    /// it this close to the target as last seen (mm); farther, the run ends
    /// [`StopReason::Missed`].
    pub reach_tolerance_mm: f32,
    /// A continuation turns the bevel only by more than this (degrees): a smaller turn is left
    /// out (and the continuation checked without it). Below the shaft's torsional play a turn
    /// of the base does not reach the tip at all; above it, a controller that turns by tenths of
    /// a degree at every reading only wears the driver.
    pub rotation_dead_band_deg: f32,
}

impl SteerConfig {
    /// The defaults: the literature noise model, re-plan beyond 0.05 mm, 10 iterations per
    /// attempt, tracking lost after 10 mm without a fix, the target reached within 1 mm, no turn
    /// of the bevel under 2 degrees.
    pub const DEFAULT: SteerConfig = SteerConfig {
        noise: NoiseModel::DEFAULT,
        replan_error_mm: 0.05,
        iterations: 10,
        max_gap_mm: 10.0,
        reach_tolerance_mm: 1.0,
        rotation_dead_band_deg: 2.0,
    };

    /// Every figure finite and positive.
    pub fn is_valid(&self) -> bool {
        self.noise.is_valid()
            && self.replan_error_mm.is_finite()
            && self.replan_error_mm > 0.0
            && self.iterations > 0
            && self.max_gap_mm.is_finite()
            && self.max_gap_mm > 0.0
            && self.reach_tolerance_mm.is_finite()
            && self.reach_tolerance_mm > 0.0
            && self.rotation_dead_band_deg.is_finite()
            && (0.0..180.0).contains(&self.rotation_dead_band_deg)
    }
}

impl Default for SteerConfig {
    fn default() -> Self {
        SteerConfig::DEFAULT
    }
}

/// Why steering cannot start.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SteerError {
    /// The schedule has no steps.
    EmptySchedule,
    /// A configuration figure is not finite and positive.
    BadConfig,
    /// The scenario is invalid (the validation's error).
    Scenario(crate::PlanError),
}

impl core::fmt::Display for SteerError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SteerError::EmptySchedule => f.write_str("the schedule has no steps to steer"),
            SteerError::BadConfig => {
                f.write_str("a steering setting is not a finite, positive number")
            }
            SteerError::Scenario(e) => write!(f, "invalid scenario: {e}"),
        }
    }
}
