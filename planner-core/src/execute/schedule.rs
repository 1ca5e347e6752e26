//! The motor schedule: a plan becomes the driver's commands.
//!
//! The posture (entry point, insertion direction and the first segment's bevel roll) is set
//! before the needle enters tissue, where turning it costs nothing; then per segment a `rotate`
//! (turn the shaft by a signed angle, no insertion) where the bevel must turn, and an `insert`
//! (an arc: push, no rotation) or an `insert_spin` (a line: push while spinning at least
//! [`MIN_SPIN_RAD_PER_MM`], the paper's u2 >= 5 u1). A spin is a whole, even number of turns whose
//! direction alternates turn by turn (as duty-cycled steering does), so it leaves the bevel and
//! the shaft's twist where they were. Rotations take the short way unless that would push the
//! accumulated twist past the driver's `max_twist_deg`; then they take the long way round.

use crate::check::ARC_JOIN_DEG;
use crate::model::form::{SegmentKind, MAX_CONTROL_DEGREE};
use crate::model::scenario::{Driver, Scenario};
use crate::report::{FormOutcome, SegmentPlan};
use crate::{Field, PlanError};
use core::f32::consts::PI;
use serde::{Deserialize, Serialize};

/// Least spin per millimetre of a line (rad/mm): the paper's u2 >= 5 u1.
pub const MIN_SPIN_RAD_PER_MM: f32 = 5.0;

/// Most steps of any schedule: a rotation and an insertion per segment.
pub const MAX_STEPS: usize = 2 * MAX_CONTROL_DEGREE;

/// One command of the driver.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Op {
    /// Turn the shaft by `angle_deg` (signed, degrees), no insertion.
    Rotate {
        /// Signed angle (degrees).
        angle_deg: f32,
    },
    /// Push the needle `length_mm` without rotating: an arc.
    Insert {
        /// Insertion (mm).
        length_mm: f32,
    },
    /// Push `length_mm` while spinning `turns` whole turns, alternating direction: a line.
    InsertSpin {
        /// Insertion (mm).
        length_mm: f32,
        /// Whole turns (even, so the spin ends where it began).
        turns: u32,
    },
    /// Push `length_mm` duty-cycled: the share `duty` of it with the bevel held where it is, the
    /// rest spinning (whole turns at the driver's spin rate, alternating, interleaved finely): an
    /// arc of curvature `duty` times the needle's towards the bevel (Minhas et al. 2007; the seed
    /// paper's DR paths). The arcs of a plan with a curvature reserve, and the steering's
    /// corrections.
    InsertDuty {
        /// Insertion (mm).
        length_mm: f32,
        /// Share of the push with the bevel held, in [0, 1].
        duty: f32,
    },
}

impl Op {
    /// The needle this step inserts (mm; 0 for a rotation).
    pub fn inserted_mm(&self) -> f32 {
        match *self {
            Op::Rotate { .. } => 0.0,
            Op::Insert { length_mm }
            | Op::InsertSpin { length_mm, .. }
            | Op::InsertDuty { length_mm, .. } => length_mm,
        }
    }

    /// The path this step drives on a needle of arc radius `radius`: the kind, length and
    /// radius of its segment (`None` for a rotation).
    pub fn segment(&self, radius: f32) -> Option<(SegmentKind, f32, f32)> {
        match *self {
            Op::Rotate { .. } => None,
            Op::Insert { length_mm } => Some((SegmentKind::Arc, length_mm, radius)),
            Op::InsertSpin { length_mm, .. } => Some((SegmentKind::Line, length_mm, radius)),
            Op::InsertDuty { length_mm, duty } if duty > 0.0 => {
                Some((SegmentKind::Arc, length_mm, radius / duty.min(1.0)))
            }
            Op::InsertDuty { length_mm, .. } => Some((SegmentKind::Line, length_mm, radius)),
        }
    }
}

/// A command and how long the driver takes for it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Step {
    /// What the driver does.
    pub op: Op,
    /// How long it takes (s).
    pub duration_s: f32,
}

/// Where and how the needle is set before it enters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Posture {
    /// Entry point (mm).
    pub entry: [f32; 3],
    /// The plan's insertion angles (degrees): see [`crate::Insertion`].
    pub theta1_deg: f32,
    /// Second insertion angle (degrees).
    pub theta2_deg: f32,
    /// Unit insertion direction.
    pub direction: [f32; 3],
    /// Bevel roll about the insertion direction from the insertion frame (degrees).
    pub roll_deg: f32,
}

/// Fixed-capacity step list.
pub type Steps = heapless::Vec<Step, MAX_STEPS>;

/// What the driver executes for one plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    /// The posture set before insertion.
    pub posture: Posture,
    /// The commands, in order.
    pub steps: Steps,
    /// Total time (s).
    pub duration_s: f32,
    /// Largest accumulated shaft twist reached (degrees, absolute).
    pub max_twist_deg: f32,
}

/// Why no schedule can be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ScheduleError {
    /// The outcome has no feasible path to execute.
    NoPath,
    /// A driver setting is unusable (a zero speed, a twist limit under one turn, ...).
    Driver(PlanError),
    /// More steps than [`MAX_STEPS`] (cannot happen: at most two per segment).
    Capacity,
}

impl core::fmt::Display for ScheduleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ScheduleError::NoPath => f.write_str("the plan has no feasible path to execute"),
            ScheduleError::Driver(e) => write!(f, "unusable driver setting: {e}"),
            ScheduleError::Capacity => write!(f, "more than {MAX_STEPS} steps"),
        }
    }
}

impl core::error::Error for ScheduleError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            ScheduleError::Driver(e) => Some(e),
            _ => None,
        }
    }
}

/// Tracks the shaft's accumulated twist as commands are added.
struct Twist {
    now: f32,
    peak: f32,
    limit: f32,
}

impl Twist {
    /// The twist of a shaft already turned by `twist_deg`, under a validated `driver`'s limit.
    fn continuing(driver: &Driver, twist_deg: f32) -> Result<Twist, ScheduleError> {
        driver.validate().map_err(ScheduleError::Driver)?;
        Ok(Twist {
            now: twist_deg,
            peak: libm::fabsf(twist_deg),
            limit: driver.max_twist_deg,
        })
    }

    /// The rotation by `angle` (degrees, in [-180, 180]) the short way, or the long way when the
    /// short one would pass the limit.
    fn rotation(&mut self, angle: f32) -> f32 {
        let long = if angle > 0.0 {
            angle - 360.0
        } else {
            angle + 360.0
        };
        let a = if libm::fabsf(self.now + angle) > self.limit {
            long
        } else {
            angle
        };
        self.now += a;
        self.peak = self.peak.max(libm::fabsf(self.now));
        a
    }

    /// A spin's whole turns alternate from the side of zero twist, so it reaches one turn away.
    fn spin(&mut self) {
        let away = if self.now > 0.0 { -360.0 } else { 360.0 };
        self.peak = self.peak.max(libm::fabsf(self.now + away));
    }
}

/// The smallest even whole number not below `x`; `None` past what a step holds (a validated
/// driver never gets there: found by fuzzing with unbounded speeds).
fn even_turns(x: f32) -> Option<u32> {
    let n = libm::ceilf(x).max(2.0);
    if !(n < 4e9) {
        return None;
    }
    let n = n as u32;
    Some(n + n % 2)
}

/// The schedule of `outcome`'s path with the scenario's driver.
///
/// ```
/// use planner_core::execute::schedule::{schedule, Op};
/// use planner_core::{plan, Scenario};
///
/// let scenario = Scenario::paper();
/// let report = plan(&scenario).unwrap();
/// let s = schedule(&scenario, report.best().unwrap()).unwrap();
/// // RL: the arc is pushed, then the line is spun in.
/// assert!(matches!(s.steps[0].op, Op::Insert { .. }));
/// assert!(matches!(s.steps[1].op, Op::InsertSpin { .. }));
/// assert!(s.max_twist_deg <= scenario.driver.max_twist_deg);
/// ```
pub fn schedule(scenario: &Scenario, outcome: &FormOutcome) -> Result<Schedule, ScheduleError> {
    let d: &Driver = &scenario.driver;
    d.validate().map_err(ScheduleError::Driver)?;
    if !outcome.feasible || outcome.segments.is_empty() {
        return Err(ScheduleError::NoPath);
    }
    let ins = &outcome.insertion;
    let posture = Posture {
        entry: scenario.entry.position,
        theta1_deg: ins.theta1_deg,
        theta2_deg: ins.theta2_deg,
        direction: ins.direction,
        roll_deg: outcome.segments[0].bevel_deg,
    };
    let mut twist = Twist {
        now: 0.0,
        peak: 0.0,
        limit: d.max_twist_deg,
    };
    let steps = segment_steps(d, &outcome.segments, false, scenario.arc_duty(), &mut twist)?;
    let duration_s = steps.iter().map(|s| s.duration_s).sum();
    Ok(Schedule {
        posture,
        steps,
        duration_s,
        max_twist_deg: twist.peak,
    })
}

/// The steps that continue from a tip in tissue along `segments` (each bevel the rotation
/// before its segment, the first one included), with the shaft twisted `twist_deg` already,
/// each arc pushed at `arc_duty` (1: a plain push). Returns the steps and the largest
/// accumulated twist they reach.
pub fn continuation_steps(
    driver: &Driver,
    segments: &[SegmentPlan],
    twist_deg: f32,
    arc_duty: f32,
) -> Result<(Steps, f32), ScheduleError> {
    let mut twist = Twist::continuing(driver, twist_deg)?;
    let steps = segment_steps(driver, segments, true, arc_duty, &mut twist)?;
    Ok((steps, twist.peak))
}

/// A rotation (where the bevel turns; before the first segment only with `rotate_first`) and
/// an insertion per segment, arcs pushed at `arc_duty` (duty-cycled below 1).
fn segment_steps(
    d: &Driver,
    segments: &[SegmentPlan],
    rotate_first: bool,
    arc_duty: f32,
    twist: &mut Twist,
) -> Result<Steps, ScheduleError> {
    let mut steps = Steps::new();
    for (i, seg) in segments.iter().enumerate() {
        let turn = libm::fmodf(libm::fabsf(seg.bevel_deg), 360.0);
        let turns = turn >= ARC_JOIN_DEG && 360.0 - turn >= ARC_JOIN_DEG;
        if (i > 0 || rotate_first) && turns {
            let angle_deg = twist.rotation(seg.bevel_deg);
            let duration_s = libm::fabsf(angle_deg) / d.rotate_speed;
            push(&mut steps, Op::Rotate { angle_deg }, duration_s)?;
        }
        if !(seg.length > 0.0) {
            continue;
        }
        let duty_cycled = seg.kind == SegmentKind::Arc && arc_duty < 1.0;
        if seg.kind == SegmentKind::Line || duty_cycled {
            twist.spin();
        }
        let step = if duty_cycled {
            duty_step(d, seg.length, arc_duty)
        } else {
            insertion_step(d, seg.kind, seg.length)?
        };
        push(&mut steps, step.op, step.duration_s)?;
    }
    Ok(steps)
}

/// The driver's step that inserts `length_mm` along a segment of `kind`: a push for an arc, a
/// spun push (whole turns, an even number, fast enough to straighten the line) for a line, with
/// the time it takes.
pub fn insertion_step(
    d: &Driver,
    kind: SegmentKind,
    length_mm: f32,
) -> Result<Step, ScheduleError> {
    let push_s = length_mm / d.insert_speed;
    Ok(match kind {
        SegmentKind::Arc => Step {
            op: Op::Insert { length_mm },
            duration_s: push_s,
        },
        SegmentKind::Line => {
            let least = MIN_SPIN_RAD_PER_MM * length_mm / (2.0 * PI);
            let turns = even_turns((d.spin_rate * push_s).max(least)).ok_or(
                ScheduleError::Driver(PlanError::OutOfRange(Field::SpinRate)),
            )?;
            Step {
                op: Op::InsertSpin { length_mm, turns },
                duration_s: push_s.max(turns as f32 / d.spin_rate),
            }
        }
    })
}

/// `step` with its insertion (or rotation) changed to `amount` (mm, or degrees), its time and a
/// spin's turns made consistent with it.
pub fn resized_step(d: &Driver, step: &Step, amount: f32) -> Result<Step, ScheduleError> {
    match step.op {
        Op::Rotate { .. } => Ok(Step {
            op: Op::Rotate { angle_deg: amount },
            duration_s: libm::fabsf(amount) / d.rotate_speed,
        }),
        Op::Insert { .. } => insertion_step(d, SegmentKind::Arc, amount),
        Op::InsertSpin { .. } => insertion_step(d, SegmentKind::Line, amount),
        Op::InsertDuty { duty, .. } => Ok(duty_step(d, amount, duty)),
    }
}

/// The steps of a duty-cycled correction from a shaft twisted by `twist_deg`: the bevel turned
/// by `bevel_deg` (left out when 0), then `length_mm` pushed at `duty`; with the largest twist
/// they reach.
pub fn duty_continuation(
    driver: &Driver,
    bevel_deg: f32,
    length_mm: f32,
    duty: f32,
    twist_deg: f32,
) -> Result<(Steps, f32), ScheduleError> {
    let mut twist = Twist::continuing(driver, twist_deg)?;
    let mut steps = Steps::new();
    if bevel_deg != 0.0 {
        let angle_deg = twist.rotation(bevel_deg);
        let duration_s = libm::fabsf(angle_deg) / driver.rotate_speed;
        push(&mut steps, Op::Rotate { angle_deg }, duration_s)?;
    }
    twist.spin();
    let step = duty_step(driver, length_mm, duty);
    push(&mut steps, step.op, step.duration_s)?;
    Ok((steps, twist.peak))
}

/// A duty-cycled push of `length_mm` at `duty` (clamped to [0, 1]), with the time it takes:
/// the insertion's, the spins riding on it.
pub fn duty_step(d: &Driver, length_mm: f32, duty: f32) -> Step {
    Step {
        op: Op::InsertDuty {
            length_mm,
            duty: crate::fmath::clamp(duty, 0.0, 1.0),
        },
        duration_s: length_mm / d.insert_speed,
    }
}

fn push(steps: &mut Steps, op: Op, duration_s: f32) -> Result<(), ScheduleError> {
    steps
        .push(Step { op, duration_s })
        .map_err(|_| ScheduleError::Capacity)
}
