//! Typed errors of the planner. They travel on the wire unchanged, so they are plain data.

use serde::{Deserialize, Serialize};

/// Which input a validation error speaks of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Field {
    /// `needle.curvature_radius`
    CurvatureRadius,
    /// `needle.max_arc_deg`
    MaxArc,
    /// `needle.max_line_length`
    MaxLineLength,
    /// `entry.position`
    EntryPosition,
    /// `entry.direction`
    EntryDirection,
    /// `entry.max_tilt_deg`
    MaxTilt,
    /// `target.position`
    TargetPosition,
    /// `target.tolerance`
    TargetTolerance,
    /// `obstacles[i].center`
    ObstacleCenter(u16),
    /// `obstacles[i].radius`
    ObstacleRadius(u16),
    /// `weights.length` (a1)
    WeightLength,
    /// `weights.risk` (a2)
    WeightRisk,
    /// `weights.penalty` (a3)
    WeightPenalty,
    /// `weights.control` (a4)
    WeightControl,
    /// `planner.min_clearance`
    MinClearance,
    /// `planner.max_control_degree`
    ControlDegree,
    /// `driver.insert_speed`
    InsertSpeed,
    /// `driver.rotate_speed`
    RotateSpeed,
    /// `driver.spin_rate`
    SpinRate,
    /// `driver.max_twist_deg` (at least 360)
    MaxTwist,
    /// `needle.length` (the insertable length)
    NeedleLength,
    /// `planner.max_collision_probability`
    MaxCollisionProbability,
    /// `planner.curvature_reserve`
    CurvatureReserve,
    /// `planner.risk_within_mm`
    RiskWithin,
}

impl Field {
    /// What the planner accepts for this input, for error messages.
    pub fn allowed(&self) -> &'static str {
        match self {
            Field::CurvatureRadius => {
                "5 to 1000 mm (a bevel-tip needle bends with a radius of tens to hundreds of mm)"
            }
            Field::MaxArc => "more than 0 and at most 360 degrees",
            Field::MaxLineLength => "0 (automatic) or more, in mm",
            Field::EntryPosition | Field::TargetPosition | Field::ObstacleCenter(_) => {
                "coordinates within 1000 mm of the origin"
            }
            Field::EntryDirection => "a non-zero vector",
            Field::MaxTilt => "0 to 89 degrees",
            Field::TargetTolerance => "more than 0 mm, and less than the entry-target distance",
            Field::ObstacleRadius(_) => "more than 0 and at most 1000 mm",
            Field::WeightLength
            | Field::WeightRisk
            | Field::WeightPenalty
            | Field::WeightControl
            | Field::MinClearance => "0 or more",
            Field::ControlDegree => "1 to the planner's largest degree",
            Field::InsertSpeed => "0.001 to 1000 mm/s",
            Field::RotateSpeed => "0.01 to 100000 deg/s",
            Field::SpinRate => "0.01 to 1000 rev/s",
            Field::MaxTwist => "at least 360 degrees (a spun line turns the shaft whole turns)",
            Field::NeedleLength => "the entry-target distance to 5000 mm",
            Field::MaxCollisionProbability => "more than 0 and less than 1",
            Field::CurvatureReserve => {
                "0 to 0.5 (the share of the needle's curvature kept in hand)"
            }
            Field::RiskWithin => "at least planner.min_clearance + 0.01 mm, at most 1000 mm",
        }
    }
}

impl core::fmt::Display for Field {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Field::CurvatureRadius => f.write_str("needle.curvature_radius"),
            Field::MaxArc => f.write_str("needle.max_arc_deg"),
            Field::MaxLineLength => f.write_str("needle.max_line_length"),
            Field::EntryPosition => f.write_str("entry.position"),
            Field::EntryDirection => f.write_str("entry.direction"),
            Field::MaxTilt => f.write_str("entry.max_tilt_deg"),
            Field::TargetPosition => f.write_str("target.position"),
            Field::TargetTolerance => f.write_str("target.tolerance"),
            Field::ObstacleCenter(i) => write!(f, "obstacles[{i}].center"),
            Field::ObstacleRadius(i) => write!(f, "obstacles[{i}].radius"),
            Field::WeightLength => f.write_str("weights.length"),
            Field::WeightRisk => f.write_str("weights.risk"),
            Field::WeightPenalty => f.write_str("weights.penalty"),
            Field::WeightControl => f.write_str("weights.control"),
            Field::MinClearance => f.write_str("planner.min_clearance"),
            Field::ControlDegree => f.write_str("planner.max_control_degree"),
            Field::InsertSpeed => f.write_str("driver.insert_speed"),
            Field::RotateSpeed => f.write_str("driver.rotate_speed"),
            Field::SpinRate => f.write_str("driver.spin_rate"),
            Field::MaxTwist => f.write_str("driver.max_twist_deg"),
            Field::NeedleLength => f.write_str("needle.length"),
            Field::MaxCollisionProbability => f.write_str("planner.max_collision_probability"),
            Field::CurvatureReserve => f.write_str("planner.curvature_reserve"),
            Field::RiskWithin => f.write_str("planner.risk_within_mm"),
        }
    }
}

/// Why a scenario cannot be planned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PlanError {
    /// A number is NaN or infinite.
    NotFinite(Field),
    /// A number that must be positive is zero or negative.
    NotPositive(Field),
    /// A number is outside the range the planner accepts (a negative weight, a tilt over 89 degrees, ...).
    OutOfRange(Field),
    /// The entry direction is the zero vector.
    ZeroDirection,
    /// More obstacles than the planner has room for.
    TooManyObstacles {
        /// Obstacles in the scenario.
        given: u16,
        /// Obstacles the planner can hold.
        capacity: u16,
    },
    /// A control degree beyond what the planner has room for, or zero.
    ControlDegreeOutOfRange {
        /// Degree asked for.
        requested: u8,
        /// Largest degree supported.
        max: u8,
    },
    /// No path form is selected (an empty form list, or forms all above the degree limit).
    NoForms,
    /// The entry point lies inside (or on) this obstacle.
    EntryInsideObstacle(u16),
    /// The target lies inside (or on) this obstacle.
    TargetInsideObstacle(u16),
    /// The target lies within its tolerance of the entry point.
    TargetAtEntry,
    /// `target.tolerance` is finer than f32 arithmetic resolves at the scenario's coordinates.
    ToleranceTooFine {
        /// The finest tolerance that can be honoured here (nanometres).
        least_nm: u32,
    },
    /// Plane mode was asked for but the entry, its direction or the target leave the y-z plane.
    NotInPlane(Field),
    /// No selected form gives a collision-free path that reaches the target. The planner does not
    /// return it (a plan with no feasible form is a [`crate::PlanReport`] without a best, which
    /// keeps every form's outcome); it is the error a caller reports for such a plan, as `needle
    /// plan` does.
    Unreachable,
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanError::NotFinite(field) => write!(f, "{field} is not a finite number"),
            PlanError::NotPositive(field) => write!(f, "{field} must be positive"),
            PlanError::OutOfRange(field) => {
                write!(f, "{field} is out of range: allowed is {}", field.allowed())
            }
            PlanError::ZeroDirection => f.write_str("entry.direction is the zero vector"),
            PlanError::TooManyObstacles { given, capacity } => write!(
                f,
                "{given} obstacles given but the planner holds at most {capacity} \
                 (obstacle {capacity} is the first that does not fit)"
            ),
            PlanError::ControlDegreeOutOfRange { requested, max } => write!(
                f,
                "control degree {requested} is not supported (1 to {max})"
            ),
            PlanError::NoForms => f.write_str("no path form selected"),
            PlanError::EntryInsideObstacle(i) => {
                write!(f, "the entry point lies inside obstacle {i}")
            }
            PlanError::TargetInsideObstacle(i) => write!(f, "the target lies inside obstacle {i}"),
            PlanError::TargetAtEntry => f.write_str(
                "the target lies within target.tolerance of the entry point: nothing to plan",
            ),
            PlanError::ToleranceTooFine { least_nm } => write!(
                f,
                "target.tolerance is finer than the planner's f32 arithmetic resolves at these \
                 coordinates: use at least {:.6} mm",
                *least_nm as f32 * 1e-6
            ),
            PlanError::NotInPlane(field) => write!(
                f,
                "plane = \"yz\" needs x = entry x for {field} (and no x component in the direction)"
            ),
            PlanError::Unreachable => f.write_str(
                "the target is unreachable: no selected path form gives a collision-free path \
                 within the bounds",
            ),
        }
    }
}

impl core::error::Error for PlanError {}
