//! The plan's posture on a board that turns and inserts only. The tilt is the needle guide's: a
//! plan that tilts the needle moves only when the operator says the guide is set so
//! (`--tilt-set`), else it is refused naming the posture (a plan with its heading fixed,
//! `entry.max_tilt_deg = 0`, needs no tilt). The roll is the rotation axis': the shaft turns to
//! the posture's roll (the shorter way) before the first step, the axis' 0 being the bevel at
//! the entry frame's roll 0 (docs/motion.md).

use anyhow::{bail, Result};
use planner_core::execute::schedule::{Op, Posture, Step, Steps};
use planner_core::model::scenario::Driver;

/// A tilt below this (degrees) is none: the rounding of the plan's angles.
const NO_TILT_DEG: f32 = 0.01;

/// The tilt of a posture from the entry axis (degrees): cos(tilt) = cos(theta1) cos(theta2).
pub fn tilt_deg(theta1_deg: f32, theta2_deg: f32) -> f32 {
    let c = f64::from(theta1_deg).to_radians().cos() * f64::from(theta2_deg).to_radians().cos();
    c.clamp(-1.0, 1.0).acos().to_degrees() as f32
}

/// The turn (degrees, in (-180, 180]) from a shaft at `rotation_deg` to the roll `roll_deg`.
pub fn turn_to_roll(rotation_deg: f32, roll_deg: f32) -> f32 {
    let d = f64::from(roll_deg) - f64::from(rotation_deg);
    (180.0 - (180.0 - d).rem_euclid(360.0)) as f32
}

/// The steps a board executes for a plan of `posture` and `steps` with its shaft at
/// `rotation_deg`: the turn to the posture's roll (none when already there), then the plan's.
/// Refused when the plan tilts the needle and `tilt_set` is false, or the turn leaves no room.
pub fn board_steps(
    posture: &Posture,
    steps: &Steps,
    driver: &Driver,
    rotation_deg: f32,
    tilt_set: bool,
) -> Result<Steps> {
    let tilt = tilt_deg(posture.theta1_deg, posture.theta2_deg);
    if tilt >= NO_TILT_DEG && !tilt_set {
        bail!(
            "the plan tilts the needle {tilt:.2} deg from the entry axis (theta1 {} deg, theta2 \
             {} deg), and this board only turns and inserts: set the needle guide to that \
             posture and say so with --tilt-set, or plan with the heading fixed \
             (entry.max_tilt_deg = 0)",
            posture.theta1_deg,
            posture.theta2_deg
        );
    }
    let turn = turn_to_roll(rotation_deg, posture.roll_deg);
    let mut out = Steps::new();
    if turn.abs() > 1e-3 {
        let first = Step {
            op: Op::Rotate { angle_deg: turn },
            duration_s: turn.abs() / driver.rotate_speed,
        };
        // An empty list has room for one.
        let _ = out.push(first);
    }
    for s in steps {
        if out.push(*s).is_err() {
            bail!(
                "the turn to the plan's roll and its {} steps are more than a move holds ({})",
                steps.len(),
                out.capacity()
            );
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn posture(theta1_deg: f32, roll_deg: f32) -> Posture {
        Posture {
            entry: [0.0; 3],
            theta1_deg,
            theta2_deg: 0.0,
            direction: [0.0, 0.0, 1.0],
            roll_deg,
        }
    }

    fn insert(mm: f32) -> Step {
        Step {
            op: Op::Insert { length_mm: mm },
            duration_s: mm / 2.5,
        }
    }

    /// The turn is the shorter way to the roll, whole turns of the shaft ignored.
    #[test]
    fn the_shaft_turns_the_shorter_way() {
        assert_eq!(turn_to_roll(0.0, 180.0), 180.0);
        assert_eq!(turn_to_roll(0.0, -65.8), -65.8);
        assert_eq!(turn_to_roll(350.0, 10.0), 20.0);
        assert_eq!(turn_to_roll(-170.0, 170.0), -20.0);
        assert_eq!(turn_to_roll(720.0, 0.0), 0.0);
        assert!((turn_to_roll(1.5, 181.5) - 180.0).abs() < 1e-4);
    }

    /// A tilted plan is refused unless the guide is said to be set; the roll's turn goes first,
    /// none when the shaft is there; a full list has no room for it.
    #[test]
    fn the_posture_comes_before_the_plan() {
        let driver = Driver::default();
        let mut steps = Steps::new();
        steps.push(insert(10.0)).unwrap();
        let tilted = posture(-28.67, 180.0);
        let err = board_steps(&tilted, &steps, &driver, 0.0, false).unwrap_err();
        assert!(
            format!("{err}").contains("tilts the needle 28.67 deg"),
            "{err}"
        );
        let out = board_steps(&tilted, &steps, &driver, 0.0, true).unwrap();
        assert_eq!(out[0].op, Op::Rotate { angle_deg: 180.0 });
        assert_eq!(out[0].duration_s, 0.5);
        assert_eq!(&out[1..], &steps[..]);
        let straight = posture(0.0, 90.0);
        let there = board_steps(&straight, &steps, &driver, 450.0, false).unwrap();
        assert_eq!(&there[..], &steps[..], "already at the roll: no turn");
        let mut full = Steps::new();
        while full.push(insert(1.0)).is_ok() {}
        let err = board_steps(&straight, &full, &driver, 0.0, false).unwrap_err();
        assert!(format!("{err}").contains("more than a move holds"), "{err}");
    }
}
