//! How the core's states, causes and fields read in messages.

use crate::fields::{Axis, ConfigField};
use crate::safety::{FaultCause, State};
use core::fmt::{Display, Formatter, Result};

impl Display for Axis {
    fn fmt(&self, f: &mut Formatter<'_>) -> Result {
        f.write_str(match self {
            Axis::Insertion => "insertion",
            Axis::Rotation => "rotation",
        })
    }
}

impl Display for State {
    fn fmt(&self, f: &mut Formatter<'_>) -> Result {
        f.write_str(match self {
            State::Disarmed => "disarmed",
            State::Armed => "armed",
            State::Homing => "homing",
            State::Moving => "moving",
            State::Holding => "holding",
            State::Faulted => "faulted",
        })
    }
}

impl Display for FaultCause {
    fn fmt(&self, f: &mut Formatter<'_>) -> Result {
        match self {
            FaultCause::EStop => f.write_str("e-stop"),
            FaultCause::LimitSwitch => f.write_str("limit switch"),
            FaultCause::HomeSwitch => f.write_str("home switch met while retracting"),
            FaultCause::FollowingError(a) => write!(f, "following error on the {a} axis"),
            FaultCause::LinkLost => f.write_str("host link lost"),
            FaultCause::HomingFailed => f.write_str("home switch not found"),
        }
    }
}

impl Display for ConfigField {
    fn fmt(&self, f: &mut Formatter<'_>) -> Result {
        match self {
            ConfigField::TickRate => f.write_str("tick rate"),
            ConfigField::StepsPerUnit(a) => write!(f, "{a} steps per unit"),
            ConfigField::MaxSpeed(a) => write!(f, "{a} maximum speed"),
            ConfigField::MaxAccel(a) => write!(f, "{a} maximum acceleration"),
            ConfigField::SoftLimits(a) => write!(f, "{a} soft limits"),
            ConfigField::Rate => f.write_str("driver rate"),
            ConfigField::Homing => f.write_str("homing speed or travel"),
        }
    }
}
