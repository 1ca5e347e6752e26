//! What comes before the first step list: the registration awaited (with
//! `--registration-name`), then the posture, the robot's first command: the needle at the entry
//! tilted and rolled as planned, before any insertion. The robot answers with its absolute base
//! roll, which must be the posture's up to whole turns and is the zero of the rolls the
//! controller is given; a robot that cannot tilt that far (a fixed guide) refuses, and steering
//! stops naming the posture.

use super::{Ending, Event, Session, INTERRUPTED, POLL};
use crate::robot::{posture_command, tilt_deg, RobotReport};
use serde_json::json;
use std::sync::atomic::Ordering;
use std::sync::mpsc::RecvTimeoutError;
use std::time::Instant;

/// How far the depth of the posture taken may be from the entry (mm), and its roll from the
/// posture's up to whole turns (degrees): the rounding of a printed number.
const POSTURE_ROUNDING: f64 = 1e-2;

impl Session<'_> {
    /// With `--registration-name`: waits for the stream's first registration (nothing is sent to
    /// the robot before it); `None` once it is in, or the ending if it does not come.
    pub(super) fn await_registration(&mut self) -> Option<Ending> {
        let name = self.config.registration_name.clone()?;
        let deadline = Instant::now() + self.config.registration_timeout;
        loop {
            self.look_at_tracker();
            let received = self.state().registration;
            if let Some(reg) = received {
                let (rotation, translation_mm) = (reg.rotation(), reg.translation());
                self.log.write(
                    "registration",
                    json!({ "name": name, "rotation": rotation, "translation_mm": translation_mm }),
                );
                self.registration = Some(reg);
                return None;
            }
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Some(Ending::Interrupted);
            }
            if Instant::now() > deadline {
                let waited_ms = self.config.registration_timeout.as_millis() as u64;
                self.log.write(
                    "no_registration",
                    json!({ "name": name, "waited_ms": waited_ms }),
                );
                return Some(Ending::NoRegistration);
            }
            match self.events.recv_timeout(POLL) {
                Ok(Event::TrackerClosed) => return Some(Ending::TrackerDisconnected),
                Ok(Event::RobotClosed) | Err(RecvTimeoutError::Disconnected) => {
                    return Some(Ending::RobotDisconnected)
                }
                Ok(_) | Err(RecvTimeoutError::Timeout) => {}
            }
        }
    }

    /// Sends the plan's posture and waits up to the robot timeout for the robot to take it:
    /// `None` once taken, else the ending.
    pub(super) fn set_posture(&mut self) -> Option<Ending> {
        if self.command(posture_command(&self.config.posture)).is_err() {
            return Some(Ending::RobotDisconnected);
        }
        let deadline = Instant::now() + self.config.robot_timeout;
        loop {
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Some(Ending::Interrupted);
            }
            let Some(left) = deadline.checked_duration_since(Instant::now()) else {
                return Some(self.robot_silence());
            };
            match self.events.recv_timeout(left.min(POLL)) {
                Ok(Event::Robot(arrival)) => {
                    if let Some((report, _)) = self.report_of(arrival.0) {
                        return self.posture_answer(report);
                    }
                }
                Ok(Event::TrackerClosed) => return Some(Ending::TrackerDisconnected),
                Ok(Event::RobotClosed) | Err(RecvTimeoutError::Disconnected) => {
                    return Some(Ending::RobotDisconnected)
                }
                Ok(Event::Tracker) | Err(RecvTimeoutError::Timeout) => {}
            }
        }
    }

    /// The robot's answer to the posture: taken where it was sent (`None`), or the ending.
    fn posture_answer(&mut self, report: RobotReport) -> Option<Ending> {
        let p = self.config.posture;
        let why = match report {
            RobotReport::PostureSet { depth_mm, base_deg } => {
                let off = (base_deg - f64::from(p.roll_deg)).rem_euclid(360.0);
                let off = off.min(360.0 - off);
                if depth_mm.abs() <= POSTURE_ROUNDING && off <= POSTURE_ROUNDING {
                    self.base0_deg = base_deg;
                    self.log.write(
                        "posture_set",
                        json!({ "depth_mm": depth_mm, "base_deg": base_deg }),
                    );
                    return None;
                }
                format!(
                    "the posture taken (depth {depth_mm} mm, base roll {base_deg} deg) is not the \
                     one commanded (depth 0 mm, roll {} deg up to whole turns)",
                    p.roll_deg
                )
            }
            RobotReport::PostureRefused { max_tilt_deg } => {
                let why = format!(
                    "the robot cannot take the plan's posture: tilted {:.2} deg from the entry \
                     axis (theta1 {} deg, theta2 {} deg), bevel rolled {} deg; it tilts at most \
                     {max_tilt_deg} deg. Plan with the heading fixed (entry.max_tilt_deg = \
                     {max_tilt_deg}) for this robot",
                    tilt_deg(p.theta1_deg, p.theta2_deg),
                    p.theta1_deg,
                    p.theta2_deg,
                    p.roll_deg
                );
                self.log.write(
                    "posture_refused",
                    json!({ "max_tilt_deg": max_tilt_deg, "why": why }),
                );
                self.outcome.why = Some(why);
                return Some(Ending::PostureRefused);
            }
            other => format!("`{other}` before the posture was taken"),
        };
        self.log.write("robot_disagrees", json!({ "why": why }));
        self.outcome.why = Some(why);
        Some(Ending::RobotDisagrees)
    }
}
