//! What comes before the first step list: the registration awaited (with
//! `--registration-name`), then the posture, the robot's first command: the needle at the entry
//! tilted and rolled as planned, before any insertion. The robot answers with its absolute base
//! roll, which must be the posture's up to whole turns and is the zero of the rolls the
//! controller is given; a robot that cannot tilt that far (a fixed guide) refuses, and steering
//! stops naming the posture. Then a few `hold`/`holding` exchanges bound the robot's clock.

use super::{Ending, Event, Session, INTERRUPTED, POLL};
use crate::fresh::seconds;
use crate::robot::{posture_command, tilt_deg, RobotCommand, RobotReport};
use needle_igtl::Timestamp;
use serde_json::json;
use std::sync::atomic::Ordering;
use std::sync::mpsc::RecvTimeoutError;
use std::time::Instant;

/// How far the depth of the posture taken may be from the entry (mm), and its roll from the
/// posture's up to whole turns (degrees): the rounding of a printed number.
const POSTURE_ROUNDING: f64 = 1e-2;

/// `hold`/`holding` exchanges that bound the robot's clock: the tightest bounds of a few, so
/// that one reply delayed by the machine does not loosen them.
const CLOCK_EXCHANGES: usize = 3;

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
                self.log.registration(&name, &reg);
                self.registration = Some(reg);
                return None;
            }
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Some(Ending::Interrupted);
            }
            if Instant::now() > deadline {
                self.log
                    .no_registration(&name, self.config.registration_timeout);
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
        match self.next_report() {
            Ok((report, _, _)) => self.posture_answer(report),
            Err(ending) => Some(ending),
        }
    }

    /// Bounds the robot's clock from both sides before the first piece: `hold` answered by
    /// `holding`, [`CLOCK_EXCHANGES`] times; each `holding` is stamped after its `hold` was sent
    /// and before it arrived (docs/lab.md, "Fresh poses"). `None` when done (a reply stamped 0
    /// bounds nothing), else the ending.
    pub(super) fn exchange_clocks(&mut self) -> Option<Ending> {
        for _ in 0..CLOCK_EXCHANGES {
            let sent = self.clock.unix(Instant::now());
            if self.command(RobotCommand::Hold).is_err() {
                return Some(Ending::RobotDisconnected);
            }
            match self.next_report() {
                Ok((RobotReport::Holding, stamp, at)) => {
                    if let Some(h) = seconds(stamp) {
                        self.robot_offset.observe_sent(sent, h);
                        self.robot_offset.observe(self.clock.unix(at), h);
                    }
                }
                Ok((other, _, _)) => {
                    let why = format!("`{other}` in answer to `hold` before the first piece");
                    self.log.write("robot_disagrees", json!({ "why": why }));
                    self.outcome.why = Some(why);
                    return Some(Ending::RobotDisagrees);
                }
                Err(ending) => return Some(ending),
            }
        }
        let ms = |b: Option<f64>| b.map(|s| s * 1e3);
        self.log.write(
            "robot_clock",
            json!({
                "offset_ms_at_least": ms(self.robot_offset.lower()),
                "offset_ms_at_most": ms(self.robot_offset.get()),
                "correction_ms": self.robot_offset.correction() * 1e3,
            }),
        );
        None
    }

    /// The robot's next report within the robot timeout, its stamp and arrival; else the
    /// ending (Ctrl-C, a connection lost, a robot silent).
    fn next_report(&mut self) -> Result<(RobotReport, Timestamp, Instant), Ending> {
        let deadline = Instant::now() + self.config.robot_timeout;
        loop {
            if INTERRUPTED.load(Ordering::SeqCst) {
                return Err(Ending::Interrupted);
            }
            let Some(left) = deadline.checked_duration_since(Instant::now()) else {
                return Err(self.robot_silence());
            };
            match self.events.recv_timeout(left.min(POLL)) {
                Ok(Event::Robot(arrival)) => {
                    let (frame, at) = *arrival;
                    if let Some((report, stamp)) = self.report_of(frame) {
                        return Ok((report, stamp, at));
                    }
                }
                Ok(Event::TrackerClosed) => return Err(Ending::TrackerDisconnected),
                Ok(Event::RobotClosed) | Err(RecvTimeoutError::Disconnected) => {
                    return Err(Ending::RobotDisconnected)
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
