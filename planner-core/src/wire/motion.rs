//! Motion and safety on the link: the host arms, homes, moves by a schedule's steps, holds,
//! stops and clears faults; every request is answered with the motion core's status (and counts
//! as the host's heartbeat for the link watchdog) or with the reason it was refused.

use super::max_size::{max, MaxSize};
use crate::execute::schedule::{Op, Steps};
use crate::model::scenario::Driver;
use needle_motion::{Axis, ConfigField, FaultCause, MotionError, Move, Rates, State, Status};
use serde::{Deserialize, Serialize};

/// A motion or safety request.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MotionRequest {
    /// The status alone (a heartbeat).
    Status,
    /// Allow motion (from disarmed).
    Arm,
    /// Forbid motion: both axes stop at once.
    Disarm,
    /// Seek the insertion stage's home switch (armed, at rest).
    Home,
    /// Execute these steps with the plan's driver and needle (armed, homed, at rest).
    Move {
        /// The plan's driver: its speeds, and the twist limit.
        driver: Driver,
        /// The needle's insertable length (mm): the insertion's soft limit.
        needle_mm: f32,
        /// The steps, in order.
        steps: Steps,
    },
    /// Decelerate to rest, keeping the rest of the moves.
    Hold,
    /// Continue after a hold.
    Resume,
    /// Decelerate to rest and drop the moves.
    Stop,
    /// End a latched fault whose cause is gone.
    ClearFault,
    /// Back to the power-up state (a latched fault stays).
    Reset,
    /// The e-stop, sent over the link: both axes stop at once, in any state, and the fault
    /// latches (cause `EStop`) until cleared, as the board's e-stop input does.
    EStop,
}

/// A fault as reported: its cause and where both axes were.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionFault {
    /// Why.
    pub cause: FaultCause,
    /// Commanded positions (mm, degrees).
    pub position: [f32; 2],
    /// The encoders' readings (motor steps), where fitted.
    pub encoder: [Option<i32>; 2],
    /// When (the board's milliseconds).
    pub at_ms: u32,
}

/// The motion core's status.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionStatus {
    /// State.
    pub state: State,
    /// Whether the axes are homed.
    pub homed: bool,
    /// Commanded positions (insertion mm, rotation degrees).
    pub position: [f32; 2],
    /// Speeds (mm/s, deg/s).
    pub speed: [f32; 2],
    /// Moves not yet finished.
    pub moves_left: u8,
    /// The latched fault, or the last one cleared.
    pub last_fault: Option<MotionFault>,
}

impl From<Status> for MotionStatus {
    fn from(s: Status) -> MotionStatus {
        MotionStatus {
            state: s.state,
            homed: s.homed,
            position: s.position,
            speed: s.speed,
            moves_left: s.moves_left,
            last_fault: s.last_fault.map(|f| MotionFault {
                cause: f.cause,
                position: f.position,
                encoder: f.encoder,
                at_ms: f.at_ms,
            }),
        }
    }
}

/// A schedule's command as the motion core's move.
pub fn motion_move(op: &Op) -> Move {
    match *op {
        Op::Rotate { angle_deg } => Move::Rotate { angle_deg },
        Op::Insert { length_mm } => Move::Insert { length_mm },
        Op::InsertSpin { length_mm, turns } => Move::InsertSpin { length_mm, turns },
        Op::InsertDuty { length_mm, duty } => Move::InsertDuty { length_mm, duty },
    }
}

/// A driver's speeds as the motion core's rates.
pub fn motion_rates(driver: &Driver) -> Rates {
    Rates {
        insert_mm_s: driver.insert_speed,
        rotate_deg_s: driver.rotate_speed,
        spin_rev_s: driver.spin_rate,
    }
}

impl MaxSize for MotionRequest {
    const MAX_SIZE: usize = 1 + Driver::MAX_SIZE + f32::MAX_SIZE + Steps::MAX_SIZE;
}

// Unit-only enums and enums of them: a varint tag each.
impl MaxSize for State {
    const MAX_SIZE: usize = 1;
}

impl MaxSize for Axis {
    const MAX_SIZE: usize = 1;
}

impl MaxSize for FaultCause {
    const MAX_SIZE: usize = 1 + Axis::MAX_SIZE;
}

impl MaxSize for ConfigField {
    const MAX_SIZE: usize = 1 + Axis::MAX_SIZE;
}

impl MaxSize for MotionError {
    const MAX_SIZE: usize = 1 + max(ConfigField::MAX_SIZE, FaultCause::MAX_SIZE);
}

/// An `i32` as postcard writes it (zigzag varint).
const I32_MAX_SIZE: usize = 5;

impl MaxSize for MotionFault {
    const MAX_SIZE: usize =
        FaultCause::MAX_SIZE + 2 * f32::MAX_SIZE + 2 * (1 + I32_MAX_SIZE) + u32::MAX_SIZE;
}

impl MaxSize for MotionStatus {
    const MAX_SIZE: usize = State::MAX_SIZE
        + bool::MAX_SIZE
        + 4 * f32::MAX_SIZE
        + u8::MAX_SIZE
        + Option::<MotionFault>::MAX_SIZE;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_largest_messages_fit_their_bounds() {
        let mut buf = [0u8; 512];
        let fault = MotionFault {
            cause: FaultCause::FollowingError(Axis::Rotation),
            position: [1.0, -2.0],
            encoder: [Some(i32::MIN), Some(i32::MAX)],
            at_ms: u32::MAX,
        };
        let status = MotionStatus {
            state: State::Faulted,
            homed: true,
            position: [1.0; 2],
            speed: [2.0; 2],
            moves_left: u8::MAX,
            last_fault: Some(fault),
        };
        let n = postcard::to_slice(&status, &mut buf).unwrap().len();
        assert_eq!(n, MotionStatus::MAX_SIZE);
        let e = MotionError::CauseActive(FaultCause::FollowingError(Axis::Insertion));
        let n = postcard::to_slice(&e, &mut buf).unwrap().len();
        assert_eq!(n, MotionError::MAX_SIZE);
        let e = MotionError::Config(ConfigField::MaxAccel(Axis::Rotation));
        assert!(postcard::to_slice(&e, &mut buf).unwrap().len() <= MotionError::MAX_SIZE);
    }
}
