//! The motor schedule as `needle` shows it: `best.schedule` in the JSON report and the table
//! `needle plan --schedule` prints after the plan.

use planner_core::execute::schedule::{Op, Schedule};
use planner_core::model::scenario::Driver;
use serde::{Deserialize, Serialize};

/// `best.schedule`: what the driver executes for the best form.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ScheduleJson {
    /// The posture set before the needle enters.
    pub posture: PostureJson,
    /// The commands, in order.
    pub steps: Vec<StepJson>,
    /// Total time (s).
    pub duration_s: f64,
    /// Largest accumulated shaft twist (degrees, absolute).
    pub max_twist_deg: f64,
}

/// `best.schedule.posture`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PostureJson {
    /// Entry point (mm).
    pub entry: [f64; 3],
    /// First insertion angle (degrees), as `best.insertion.theta1_deg`.
    pub theta1_deg: f64,
    /// Second insertion angle (degrees).
    pub theta2_deg: f64,
    /// Unit insertion direction.
    pub direction: [f64; 3],
    /// Bevel roll about the insertion direction before entering (degrees).
    pub roll_deg: f64,
}

/// One entry of `best.schedule.steps`: `op` is `rotate` (with `angle_deg`), `insert` (with
/// `length_mm`), `insert_spin` (with `length_mm` and `turns`) or, in a steered run's steps,
/// `insert_duty` (with `length_mm` and `duty`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StepJson {
    /// `rotate`, `insert` or `insert_spin`.
    pub op: String,
    /// Signed shaft rotation (degrees): `rotate` only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_deg: Option<f64>,
    /// Insertion (mm): `insert` and `insert_spin`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_mm: Option<f64>,
    /// Whole spin turns, alternating direction: `insert_spin` only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turns: Option<u32>,
    /// Share of the push with the bevel held (the rest spun): `insert_duty` only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duty: Option<f64>,
    /// How long the step takes (s).
    pub duration_s: f64,
}

/// The name of a step's command in the JSON and the table.
pub fn op_name(op: &Op) -> &'static str {
    match op {
        Op::Rotate { .. } => "rotate",
        Op::Insert { .. } => "insert",
        Op::InsertSpin { .. } => "insert_spin",
        Op::InsertDuty { .. } => "insert_duty",
    }
}

impl ScheduleJson {
    /// The JSON form of `s` (the `f32` values widened, so they print exactly).
    pub fn of(s: &Schedule) -> ScheduleJson {
        let p = &s.posture;
        ScheduleJson {
            posture: PostureJson {
                entry: p.entry.map(f64::from),
                theta1_deg: f64::from(p.theta1_deg),
                theta2_deg: f64::from(p.theta2_deg),
                direction: p.direction.map(f64::from),
                roll_deg: f64::from(p.roll_deg),
            },
            steps: s
                .steps
                .iter()
                .map(|st| StepJson::of(&st.op, st.duration_s))
                .collect(),
            duration_s: f64::from(s.duration_s),
            max_twist_deg: f64::from(s.max_twist_deg),
        }
    }
}

impl StepJson {
    /// The JSON form of one step (`best.schedule` and `simulate --detail` share it).
    pub fn of(op: &Op, duration_s: f32) -> StepJson {
        let (angle_deg, length_mm, turns) = match *op {
            Op::Rotate { angle_deg } => (Some(angle_deg), None, None),
            Op::Insert { length_mm } | Op::InsertDuty { length_mm, .. } => {
                (None, Some(length_mm), None)
            }
            Op::InsertSpin { length_mm, turns } => (None, Some(length_mm), Some(turns)),
        };
        let duty = match *op {
            Op::InsertDuty { duty, .. } => Some(f64::from(duty)),
            _ => None,
        };
        StepJson {
            op: op_name(op).to_owned(),
            angle_deg: angle_deg.map(f64::from),
            length_mm: length_mm.map(f64::from),
            turns,
            duty,
            duration_s: f64::from(duration_s),
        }
    }
}

fn or_dash(v: Option<String>) -> String {
    v.unwrap_or_else(|| "-".to_owned())
}

/// The table `needle plan --schedule` prints: the driver, the posture, one row per step, then
/// the total duration and the peak twist.
pub fn schedule_table(s: &Schedule, driver: &Driver) -> String {
    let p = &s.posture;
    let v3 =
        |v: [f32; 3], prec: usize| format!("({:.prec$}, {:.prec$}, {:.prec$})", v[0], v[1], v[2]);
    let mut out = format!(
        "\nschedule (driver: insert {} mm/s, rotate {} deg/s, spin {} rev/s, twist limit {} deg)\n",
        driver.insert_speed, driver.rotate_speed, driver.spin_rate, driver.max_twist_deg
    );
    out.push_str(&format!(
        "posture: entry {} mm, theta1 {:.2} deg, theta2 {:.2} deg, direction {}, roll {:.1} deg\n",
        v3(p.entry, 2),
        p.theta1_deg,
        p.theta2_deg,
        v3(p.direction, 4),
        p.roll_deg
    ));
    out.push_str(&format!(
        "{:>4}  {:<11} {:>11} {:>11} {:>6} {:>12}\n",
        "step", "op", "angle (deg)", "length (mm)", "turns", "duration (s)"
    ));
    for (i, st) in s.steps.iter().enumerate() {
        let j = StepJson::of(&st.op, st.duration_s);
        out.push_str(&format!(
            "{:>4}  {:<11} {:>11} {:>11} {:>6} {:>12.2}\n",
            i + 1,
            j.op,
            or_dash(j.angle_deg.map(|a| format!("{a:.1}"))),
            or_dash(j.length_mm.map(|l| format!("{l:.2}"))),
            or_dash(j.turns.map(|t| t.to_string())),
            st.duration_s
        ));
    }
    out.push_str(&format!(
        "total {:.2} s, peak twist {:.1} deg\n",
        s.duration_s, s.max_twist_deg
    ));
    out
}
