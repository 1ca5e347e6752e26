//! The typed `needle plan --json` report. Its keys and nesting are a contract: scripts, the golden
//! tests and `needle plot --plan` read them.
//!
//! Numbers are the planner's `f32` values widened to `f64` (so they print exactly, e.g.
//! `91.85139465332031`), and `null` where the value is not finite or the form is infeasible. The
//! reading side takes every key as optional, so a trimmed or hand-written plan still plots.

use super::schedule::ScheduleJson;
use planner_core::check::{rebuild, sample_points};
use planner_core::execute::perturbation::Perturbation;
use planner_core::execute::schedule::Schedule;
use planner_core::model::kinematics::V3;
use planner_core::{FormOutcome, PlanReport, Scenario, SegmentKind};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Timing and effort figures shown in `stats`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stats {
    /// Wall-clock planning time (µs).
    pub time_us: u64,
}

/// A finite `f32` as the `f64` the report carries, anything else as `None` (`null`).
pub fn finite(v: f32) -> Option<f64> {
    v.is_finite().then_some(f64::from(v))
}

fn widened(p: [f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// The `needle plan --json` object.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PlanJson {
    /// The best form's path, `null` when there is none.
    pub best: Option<BestPath>,
    /// With an `[execution]` table or a collision bound: the world assumed and what the plan
    /// predicts in it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub execution: Option<ExecutionJson>,
    /// One entry per form tried, in catalogue order.
    pub forms: Vec<FormEntry>,
    /// Time and effort of the whole plan.
    pub stats: StatsJson,
}

/// `best`: a form's entry with the figures only the chosen path carries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BestPath {
    /// The same keys as a `forms` entry.
    #[serde(flatten)]
    pub path: FormEntry,
    /// H: the obstacle-entry penalty.
    pub penalty: Option<f64>,
    /// N: the number of segments.
    #[serde(default)]
    pub control_degree: usize,
    /// The driver's motor schedule for this path (absent from reports written before it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub schedule: Option<ScheduleJson>,
    /// With `[[anatomy]]`: the path's least distance (mm) to the covered segments' voxels
    /// themselves, measured on the label maps (`anatomy::distance`), not on the spheres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label_map_clearance_mm: Option<f64>,
}

/// One form's outcome.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FormEntry {
    /// The form word, e.g. `RL`.
    pub form: String,
    /// Whether the form has a collision-free path to the target; absent reads as feasible.
    #[serde(default = "feasible_unless_told")]
    pub feasible: bool,
    /// The solver's status, e.g. `Converged`.
    pub status: String,
    /// L (mm).
    pub length: Option<f64>,
    /// D.
    pub risk: Option<f64>,
    /// F.
    pub objective: Option<f64>,
    /// Smallest clearance to an obstacle surface (mm).
    pub min_clearance: Option<f64>,
    /// Distance from the path's end to the target (mm).
    pub target_error: Option<f64>,
    /// Optimality residual of the solution.
    pub kkt_residual: Option<f64>,
    /// Solver iterations.
    pub iterations: u32,
    /// Objective and constraint evaluations.
    pub evaluations: u32,
    /// The insertion posture, `null` for an infeasible form.
    pub insertion: Option<InsertionJson>,
    /// The segments, `null` for an infeasible form.
    pub segments: Option<Vec<SegmentJson>>,
    /// Points at most 1 mm apart from the entry to the end: written for the best path only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<[f64; 3]>>,
    /// Predicted probability that the executed path enters an obstacle (first order, open
    /// loop; with an `[execution]` table or a bound, feasible forms only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collision_probability: Option<f64>,
    /// Predicted 95th percentile of the executed path's miss (mm; as `collision_probability`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_error_p95: Option<f64>,
}

/// `insertion`: the posture of the needle at the entry.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct InsertionJson {
    /// Rotation about the entry frame's first axis (degrees).
    pub theta1_deg: Option<f64>,
    /// Rotation about the entry frame's second axis (degrees).
    pub theta2_deg: Option<f64>,
    /// Angle between the insertion direction and the nominal axis (degrees).
    pub tilt_deg: Option<f64>,
    /// Unit insertion direction.
    pub direction: [f64; 3],
}

/// One entry of `segments`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SegmentJson {
    /// `R` (arc) or `L` (line).
    pub kind: String,
    /// Length (mm).
    pub length: Option<f64>,
    /// Bevel rotation before the segment (degrees).
    pub bevel_deg: Option<f64>,
}

/// `stats`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StatsJson {
    /// Wall-clock planning time (µs).
    pub time_us: u64,
    /// Solver iterations over all forms.
    pub iterations: u32,
    /// Evaluations over all forms.
    pub evaluations: u32,
}

impl SegmentJson {
    /// The segment's kind: `R` is an arc, anything else a line.
    pub fn segment_kind(&self) -> SegmentKind {
        if self.kind == "R" {
            SegmentKind::Arc
        } else {
            SegmentKind::Line
        }
    }
}

impl FormEntry {
    /// A form's entry; an infeasible form's numbers, posture and segments are `null`.
    pub fn of(o: &FormOutcome) -> FormEntry {
        entry(o, o.feasible)
    }
}

/// `o`'s entry, with its numbers, posture and segments only when `shown`.
fn entry(o: &FormOutcome, shown: bool) -> FormEntry {
    let number = |v: f32| finite(v).filter(|_| shown);
    FormEntry {
        form: o.form.to_string(),
        feasible: o.feasible,
        status: format!("{:?}", o.status),
        length: number(o.length),
        risk: number(o.risk),
        objective: number(o.objective),
        min_clearance: number(o.min_clearance),
        target_error: number(o.target_error),
        kkt_residual: number(o.kkt_residual),
        iterations: o.iterations,
        evaluations: o.evaluations,
        insertion: shown.then(|| InsertionJson {
            theta1_deg: finite(o.insertion.theta1_deg),
            theta2_deg: finite(o.insertion.theta2_deg),
            tilt_deg: finite(o.insertion.tilt_deg),
            direction: widened(o.insertion.direction),
        }),
        segments: shown.then(|| {
            o.segments
                .iter()
                .map(|s| SegmentJson {
                    kind: s.kind.letter().to_string(),
                    length: finite(s.length),
                    bevel_deg: finite(s.bevel_deg),
                })
                .collect()
        }),
        points: None,
        collision_probability: None,
        target_error_p95: None,
    }
}

impl BestPath {
    /// The chosen path with its points and, when given, its motor schedule. Its numbers are
    /// written whatever `feasible` says (the planner only chooses feasible forms, and a reader
    /// wants the figures of the path drawn).
    pub fn of(scenario: &Scenario, o: &FormOutcome, schedule: Option<&Schedule>) -> BestPath {
        let mut path = entry(o, true);
        path.points = Some(path_points(scenario, o).into_iter().map(widened).collect());
        BestPath {
            path,
            penalty: finite(o.penalty),
            control_degree: o.form.len(),
            schedule: schedule.map(ScheduleJson::of),
            label_map_clearance_mm: None,
        }
    }
}

/// Path points no more than 1 mm apart, entry to end.
pub fn path_points(scenario: &Scenario, o: &FormOutcome) -> Vec<[f32; 3]> {
    let geo = rebuild(scenario, o.form, &o.insertion, &o.segments);
    let mut pts = Vec::new();
    sample_points(&geo, 1.0, |p: V3| pts.push([p.x, p.y, p.z]));
    pts
}

/// A reader takes an entry without `feasible` as feasible, so a trimmed plan still draws.
fn feasible_unless_told() -> bool {
    true
}

/// The `needle plan --json` report of `report`, with `schedule` (the best form's) as
/// `best.schedule`.
pub fn plan_json(
    scenario: &Scenario,
    report: &PlanReport,
    schedule: Option<&Schedule>,
    stats: Stats,
) -> PlanJson {
    PlanJson {
        best: report.best().map(|b| BestPath::of(scenario, b, schedule)),
        execution: None,
        forms: report.forms.iter().map(FormEntry::of).collect(),
        stats: StatsJson {
            time_us: stats.time_us,
            iterations: report.iterations(),
            evaluations: report.evaluations(),
        },
    }
}

impl fmt::Display for PlanJson {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_sorted(self, f)
    }
}

/// Writes `report` as one line of JSON with its keys sorted, as `needle` has always printed its
/// reports (a [`serde_json::Value`] map sorts its keys; a struct writes them in field order).
pub fn write_sorted(report: &impl Serialize, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let value = serde_json::to_value(report).map_err(|_| fmt::Error)?;
    write!(f, "{value}")
}

/// `execution` in `needle plan --json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExecutionJson {
    /// `open_loop` or `closed_loop`.
    pub mode: String,
    /// The perturbation model the predictions assume.
    pub perturbation: Perturbation,
    /// The bound, `null` when off.
    pub max_collision_probability: Option<f64>,
    /// Whether the best form's predicted collision probability is within the bound (`null`
    /// without a bound or a best form).
    pub within_bound: Option<bool>,
    /// Plans made to find the margins (`null` without a bound).
    pub rounds: Option<u32>,
    /// How far each obstacle was grown for the plan (mm, scenario order; `null` without a bound).
    pub margins: Option<Vec<f64>>,
    /// The share of the curvature the plan leaves for steering (`planner.curvature_reserve`,
    /// lowered where no path kept what was asked: `needle_scenario::reserve`).
    #[serde(default)]
    pub curvature_reserve: Option<f64>,
    /// The share asked for: the scenario's, before any was given up.
    #[serde(default)]
    pub curvature_reserve_asked: Option<f64>,
}
