//! The robot's side of the lab link, as text: what `needle steer` tells the insertion robot and
//! what the robot reports back, each one OpenIGTLink `STRING` (US-ASCII) so that a ROS 2 node
//! behind ros2_igtl_bridge can serve it with a string topic. No I/O here: formatting and parsing
//! only (docs/lab.md has the grammar with examples).
//!
//! A message is a word and `key=value` pairs separated by single spaces. Numbers are decimal, as
//! Rust prints an `f32` (the shortest text that reads back to the same bits), so a step list
//! crosses the link unchanged.
//!
//! Host to robot (device name [`COMMAND_DEVICE`]):
//! - `posture theta1_deg=A theta2_deg=B roll_deg=R`: before the first step list, set the needle
//!   at the entry (not inserted) to the plan's posture: tilted from the entry axis by B about
//!   the entry frame's e2, then by A about its e1, and the bevel rolled to R about the needle
//!   (docs/lab.md, "The posture");
//! - `steps count=N`, then N step messages: the step list to execute, replacing what is left of
//!   the current one at the next piece boundary (N at most the planner's `MAX_STEPS`, so that a
//!   robot can hold any list it is sent);
//! - a step: `insert length_mm=L duration_s=T speed_mm_s=V` (an arc, bevel held),
//!   `rotate angle_deg=A duration_s=T speed_deg_s=W` (the base, signed, no insertion),
//!   `spin-insert length_mm=L turns=N duration_s=T speed_mm_s=V` (N whole turns alternating
//!   direction while inserting: a line), `duty-insert length_mm=L duty=D duration_s=T
//!   speed_mm_s=V` (the share D with the bevel held in the direction the last rotation left it,
//!   the rest spinning). The robot takes `duration_s` when given, else derives it from the speed;
//! - `go`: carry on after the piece just reported; `hold`: stay where it is and wait;
//!   `stop`: stop the insertion (the robot holds and reports `stopped`).
//!
//! Robot to host (device name [`REPORT_DEVICE`]):
//! - `posture-set depth_mm=X base_deg=Y`: the posture is taken; X the depth (0: at the entry),
//!   Y the robot's absolute base roll, equal to the posture's roll up to whole turns;
//! - `posture-refused max_tilt_deg=T`: the robot cannot tilt the needle that far (a fixed
//!   guide: 0); nothing moved;
//! - `progress piece=K depth_mm=X base_deg=Y`: piece K (counted from 1 over the insertion) is
//!   done; X the commanded insertion from the entry, Y the commanded absolute base roll (the
//!   posture's `base_deg` plus the rotations since, accumulated, not wrapped);
//! - `done`: the step list ran out; `holding`; `stopped`.

/// The tilt of a posture from the entry axis, as the board's `needle motion` judges it.
pub use needle_device::posture::tilt_deg;
use planner_core::execute::schedule::{Op, Posture, Step, MAX_STEPS};
use std::fmt;

/// Device name of the host's commands.
pub const COMMAND_DEVICE: &str = "NeedleRobotCommand";
/// Device name of the robot's reports.
pub const REPORT_DEVICE: &str = "NeedleRobotState";

/// What the host tells the robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RobotCommand {
    /// Set the needle at the entry to the plan's posture.
    Posture {
        /// Tilt about the entry frame's e1 (degrees), applied after `theta2_deg`.
        theta1_deg: f32,
        /// Tilt about the entry frame's e2 (degrees).
        theta2_deg: f32,
        /// The bevel's roll about the needle (degrees).
        roll_deg: f32,
    },
    /// A step list of this many steps follows.
    Steps {
        /// Number of step messages that follow.
        count: usize,
    },
    /// One step of the list being sent.
    Step(Step),
    /// Carry on.
    Go,
    /// Stay and wait for the next word.
    Hold,
    /// End the insertion.
    Stop,
}

/// What the robot tells the host.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RobotReport {
    /// The posture is taken.
    PostureSet {
        /// Depth (mm): 0, at the entry.
        depth_mm: f64,
        /// The absolute base roll (degrees), the posture's up to whole turns.
        base_deg: f64,
    },
    /// The posture cannot be taken: the robot tilts at most this much (degrees).
    PostureRefused {
        /// The largest tilt from the entry axis the robot can take (degrees).
        max_tilt_deg: f32,
    },
    /// A piece of insertion (or a rotation) is done.
    Progress {
        /// Pieces done so far in the insertion, this one included.
        piece: u32,
        /// Commanded insertion so far (mm).
        depth_mm: f32,
        /// Commanded absolute base roll (degrees, accumulated): the posture's `base_deg` plus the
        /// rotations since. Read as an `f64`, so a large absolute roll keeps the rotations'
        /// bits.
        base_deg: f64,
    },
    /// The step list ran out.
    Done,
    /// Holding after `hold`.
    Holding,
    /// Stopped after `stop`.
    Stopped,
    /// The robot sensed the needle in an obstacle (a contact or force sensor) and stopped; the
    /// insertion is over.
    Collided {
        /// Commanded insertion when it was sensed (mm).
        depth_mm: f32,
    },
}

/// Why a text is not a robot message.
#[derive(Clone, Debug, PartialEq)]
pub enum GrammarError {
    /// No word at all.
    Empty,
    /// The first word is no message of this grammar.
    UnknownWord(String),
    /// A token is not `key=value`.
    NotKeyValue(String),
    /// A key the message does not have.
    UnknownKey(String),
    /// A key the message needs is missing.
    MissingKey(&'static str),
    /// A value is not a finite number in range.
    BadNumber {
        /// The key.
        key: String,
        /// The text given.
        value: String,
    },
}

impl fmt::Display for GrammarError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GrammarError::Empty => write!(f, "empty robot message"),
            GrammarError::UnknownWord(w) => write!(f, "unknown robot message `{w}`"),
            GrammarError::NotKeyValue(t) => write!(f, "`{t}` is not key=value"),
            GrammarError::UnknownKey(k) => write!(f, "unknown key `{k}`"),
            GrammarError::MissingKey(k) => write!(f, "missing key `{k}`"),
            GrammarError::BadNumber { key, value } => {
                write!(f, "{key}: `{value}` is not a valid number")
            }
        }
    }
}

impl std::error::Error for GrammarError {}

/// Speed of a motion over `duration_s` (0 for an instant one).
fn speed(amount: f32, duration_s: f32) -> f32 {
    if duration_s > 0.0 {
        amount.abs() / duration_s
    } else {
        0.0
    }
}

impl fmt::Display for RobotCommand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            RobotCommand::Posture {
                theta1_deg,
                theta2_deg,
                roll_deg,
            } => write!(
                f,
                "posture theta1_deg={theta1_deg} theta2_deg={theta2_deg} roll_deg={roll_deg}"
            ),
            RobotCommand::Steps { count } => write!(f, "steps count={count}"),
            RobotCommand::Go => write!(f, "go"),
            RobotCommand::Hold => write!(f, "hold"),
            RobotCommand::Stop => write!(f, "stop"),
            RobotCommand::Step(Step { op, duration_s: t }) => match op {
                Op::Insert { length_mm: l } => write!(
                    f,
                    "insert length_mm={l} duration_s={t} speed_mm_s={}",
                    speed(l, t)
                ),
                Op::Rotate { angle_deg: a } => write!(
                    f,
                    "rotate angle_deg={a} duration_s={t} speed_deg_s={}",
                    speed(a, t)
                ),
                Op::InsertSpin {
                    length_mm: l,
                    turns,
                } => write!(
                    f,
                    "spin-insert length_mm={l} turns={turns} duration_s={t} speed_mm_s={}",
                    speed(l, t)
                ),
                Op::InsertDuty { length_mm: l, duty } => write!(
                    f,
                    "duty-insert length_mm={l} duty={duty} duration_s={t} speed_mm_s={}",
                    speed(l, t)
                ),
            },
        }
    }
}

impl fmt::Display for RobotReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            RobotReport::Progress {
                piece,
                depth_mm,
                base_deg,
            } => write!(
                f,
                "progress piece={piece} depth_mm={depth_mm} base_deg={base_deg}"
            ),
            RobotReport::PostureSet { depth_mm, base_deg } => {
                write!(f, "posture-set depth_mm={depth_mm} base_deg={base_deg}")
            }
            RobotReport::PostureRefused { max_tilt_deg } => {
                write!(f, "posture-refused max_tilt_deg={max_tilt_deg}")
            }
            RobotReport::Done => write!(f, "done"),
            RobotReport::Holding => write!(f, "holding"),
            RobotReport::Stopped => write!(f, "stopped"),
            RobotReport::Collided { depth_mm } => write!(f, "collided depth_mm={depth_mm}"),
        }
    }
}

/// The `key=value` pairs of a message after its word, each key allowed once.
struct Pairs<'a> {
    pairs: Vec<(&'a str, &'a str)>,
}

impl<'a> Pairs<'a> {
    fn of(tokens: impl Iterator<Item = &'a str>, allowed: &[&str]) -> Result<Self, GrammarError> {
        let mut pairs: Vec<(&str, &str)> = Vec::new();
        for t in tokens {
            let (k, v) = t
                .split_once('=')
                .ok_or_else(|| GrammarError::NotKeyValue(t.to_string()))?;
            if !allowed.contains(&k) || pairs.iter().any(|(seen, _)| *seen == k) {
                return Err(GrammarError::UnknownKey(k.to_string()));
            }
            pairs.push((k, v));
        }
        Ok(Pairs { pairs })
    }

    fn text(&self, key: &str) -> Option<&'a str> {
        self.pairs.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }

    fn number<T: std::str::FromStr>(
        &self,
        key: &'static str,
        ok: impl Fn(&T) -> bool,
    ) -> Result<Option<T>, GrammarError> {
        let Some(v) = self.text(key) else {
            return Ok(None);
        };
        match v.parse::<T>() {
            Ok(n) if ok(&n) => Ok(Some(n)),
            _ => Err(GrammarError::BadNumber {
                key: key.to_string(),
                value: v.to_string(),
            }),
        }
    }

    fn required<T: std::str::FromStr>(
        &self,
        key: &'static str,
        ok: impl Fn(&T) -> bool,
    ) -> Result<T, GrammarError> {
        self.number(key, ok)?.ok_or(GrammarError::MissingKey(key))
    }

    /// `duration_s`, or the amount over the speed under `speed_key`.
    fn duration(&self, amount: f32, speed_key: &'static str) -> Result<f32, GrammarError> {
        let non_negative = |v: &f32| v.is_finite() && *v >= 0.0;
        if let Some(t) = self.number("duration_s", non_negative)? {
            return Ok(t);
        }
        let v = self.required(speed_key, |v: &f32| v.is_finite() && *v > 0.0)?;
        Ok(amount.abs() / v)
    }
}

fn finite(v: &f32) -> bool {
    v.is_finite()
}

fn finite64(v: &f64) -> bool {
    v.is_finite()
}

fn length(v: &f32) -> bool {
    v.is_finite() && *v >= 0.0
}

/// The first word and the rest of a message.
fn split(text: &str) -> Result<(&str, std::str::SplitAsciiWhitespace<'_>), GrammarError> {
    let mut tokens = text.split_ascii_whitespace();
    let word = tokens.next().ok_or(GrammarError::Empty)?;
    Ok((word, tokens))
}

impl std::str::FromStr for RobotCommand {
    type Err = GrammarError;

    fn from_str(text: &str) -> Result<Self, GrammarError> {
        let (word, rest) = split(text)?;
        let step = |op: Op, p: &Pairs<'_>, speed_key| -> Result<RobotCommand, GrammarError> {
            let amount = match op {
                Op::Rotate { angle_deg } => angle_deg,
                _ => op.inserted_mm(),
            };
            let duration_s = p.duration(amount, speed_key)?;
            Ok(RobotCommand::Step(Step { op, duration_s }))
        };
        match word {
            "go" | "hold" | "stop" => {
                Pairs::of(rest, &[])?;
                Ok(match word {
                    "go" => RobotCommand::Go,
                    "hold" => RobotCommand::Hold,
                    _ => RobotCommand::Stop,
                })
            }
            "posture" => {
                let p = Pairs::of(rest, &["theta1_deg", "theta2_deg", "roll_deg"])?;
                Ok(RobotCommand::Posture {
                    theta1_deg: p.required("theta1_deg", finite)?,
                    theta2_deg: p.required("theta2_deg", finite)?,
                    roll_deg: p.required("roll_deg", finite)?,
                })
            }
            "steps" => {
                let p = Pairs::of(rest, &["count"])?;
                let count = p.required("count", |n: &usize| *n <= MAX_STEPS)?;
                Ok(RobotCommand::Steps { count })
            }
            "insert" => {
                let p = Pairs::of(rest, &["length_mm", "duration_s", "speed_mm_s"])?;
                let length_mm = p.required("length_mm", length)?;
                step(Op::Insert { length_mm }, &p, "speed_mm_s")
            }
            "rotate" => {
                let p = Pairs::of(rest, &["angle_deg", "duration_s", "speed_deg_s"])?;
                let angle_deg = p.required("angle_deg", finite)?;
                step(Op::Rotate { angle_deg }, &p, "speed_deg_s")
            }
            "spin-insert" => {
                let keys = ["length_mm", "turns", "duration_s", "speed_mm_s"];
                let p = Pairs::of(rest, &keys)?;
                let length_mm = p.required("length_mm", length)?;
                let turns = p.required("turns", |_: &u32| true)?;
                step(Op::InsertSpin { length_mm, turns }, &p, "speed_mm_s")
            }
            "duty-insert" => {
                let keys = ["length_mm", "duty", "duration_s", "speed_mm_s"];
                let p = Pairs::of(rest, &keys)?;
                let length_mm = p.required("length_mm", length)?;
                let duty = p.required("duty", |d: &f32| (0.0..=1.0).contains(d))?;
                step(Op::InsertDuty { length_mm, duty }, &p, "speed_mm_s")
            }
            other => Err(GrammarError::UnknownWord(other.to_string())),
        }
    }
}

impl std::str::FromStr for RobotReport {
    type Err = GrammarError;

    fn from_str(text: &str) -> Result<Self, GrammarError> {
        let (word, rest) = split(text)?;
        match word {
            "progress" => {
                let p = Pairs::of(rest, &["piece", "depth_mm", "base_deg"])?;
                Ok(RobotReport::Progress {
                    piece: p.required("piece", |_: &u32| true)?,
                    depth_mm: p.required("depth_mm", finite)?,
                    base_deg: p.required("base_deg", finite64)?,
                })
            }
            "posture-set" => {
                let p = Pairs::of(rest, &["depth_mm", "base_deg"])?;
                Ok(RobotReport::PostureSet {
                    depth_mm: p.required("depth_mm", finite64)?,
                    base_deg: p.required("base_deg", finite64)?,
                })
            }
            "posture-refused" => {
                let p = Pairs::of(rest, &["max_tilt_deg"])?;
                Ok(RobotReport::PostureRefused {
                    max_tilt_deg: p
                        .required("max_tilt_deg", |t: &f32| t.is_finite() && *t >= 0.0)?,
                })
            }
            "collided" => {
                let p = Pairs::of(rest, &["depth_mm"])?;
                Ok(RobotReport::Collided {
                    depth_mm: p.required("depth_mm", finite)?,
                })
            }
            "done" | "holding" | "stopped" => {
                Pairs::of(rest, &[])?;
                Ok(match word {
                    "done" => RobotReport::Done,
                    "holding" => RobotReport::Holding,
                    _ => RobotReport::Stopped,
                })
            }
            other => Err(GrammarError::UnknownWord(other.to_string())),
        }
    }
}

/// The command that sets `posture`.
pub fn posture_command(posture: &Posture) -> RobotCommand {
    RobotCommand::Posture {
        theta1_deg: posture.theta1_deg,
        theta2_deg: posture.theta2_deg,
        roll_deg: posture.roll_deg,
    }
}

/// The messages that send a whole step list: `steps count=N`, then each step.
pub fn step_list(steps: &[Step]) -> Vec<RobotCommand> {
    std::iter::once(RobotCommand::Steps { count: steps.len() })
        .chain(steps.iter().map(|s| RobotCommand::Step(*s)))
        .collect()
}

#[cfg(test)]
#[path = "robot_tests.rs"]
mod tests;
