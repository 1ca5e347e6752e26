//! Every way a request of the motion core can fail.

use crate::fields::{Axis, ConfigField};
use crate::safety::{FaultCause, State};

/// Why a request was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MotionError {
    /// A configuration value is unusable.
    Config(ConfigField),
    /// A move's amount is not finite, or a duty outside [0, 1].
    BadMove,
    /// The move would take this axis past its soft limit.
    SoftLimit(Axis),
    /// More moves than the queue holds.
    QueueFull,
    /// Not in a state that allows it (it is in this one).
    NotAllowed(State),
    /// Moves need homing first.
    NotHomed,
    /// A fault is latched: clear it first.
    Faulted(FaultCause),
    /// The fault's cause is still present (e-stop pressed, switch closed).
    CauseActive(FaultCause),
}

impl core::fmt::Display for MotionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MotionError::Config(field) => write!(f, "unusable motion setting: {field}"),
            MotionError::BadMove => {
                f.write_str("a move's amount is not finite or its duty not in [0, 1]")
            }
            MotionError::SoftLimit(a) => write!(f, "the move passes the {a} axis' soft limit"),
            MotionError::QueueFull => f.write_str("more moves than the queue holds"),
            MotionError::NotAllowed(s) => write!(f, "not allowed while {s}"),
            MotionError::NotHomed => f.write_str("the axes are not homed"),
            MotionError::Faulted(c) => write!(f, "a fault is latched ({c}): clear it first"),
            MotionError::CauseActive(c) => write!(f, "the fault's cause is still present ({c})"),
        }
    }
}

impl core::error::Error for MotionError {}
