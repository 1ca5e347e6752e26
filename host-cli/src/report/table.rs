//! Rendering a [`PlanReport`] as the `needle plan` table or its JSON object.
//!
//! `needle send` prints through the same functions, so a plan from a device reads exactly like a
//! local one.

use planner_core::kinematics::V3;
use planner_core::verify::{rebuild, sample_points};
use planner_core::{FormOutcome, PlanReport, Scenario, SegmentKind};
use serde_json::{json, Value};

/// Timing and effort figures shown in `stats`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stats {
    /// Wall-clock planning time (µs).
    pub time_us: u64,
}

/// Finite numbers as JSON numbers, everything else as `null`.
fn num(v: f32) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// Path points no more than 1 mm apart, entry to end.
pub fn path_points(scenario: &Scenario, o: &FormOutcome) -> Vec<[f32; 3]> {
    let geo = rebuild(scenario, o.form, &o.insertion, &o.segments);
    let mut pts = Vec::new();
    sample_points(&geo, 1.0, |p: V3| pts.push([p.x, p.y, p.z]));
    pts
}

/// The full description of one form's path.
pub fn outcome_json(scenario: &Scenario, o: &FormOutcome, with_points: bool) -> Value {
    let segments: Vec<Value> = o
        .segments
        .iter()
        .map(|s| {
            json!({
                "kind": match s.kind { SegmentKind::Arc => "R", SegmentKind::Line => "L" },
                "length": num(s.length),
                "bevel_deg": num(s.bevel_deg),
            })
        })
        .collect();
    let mut v = json!({
        "form": o.form.to_string(),
        "feasible": o.feasible,
        "status": format!("{:?}", o.status),
        "length": num(o.length),
        "risk": num(o.risk),
        "penalty": num(o.penalty),
        "control_degree": o.form.len(),
        "objective": num(o.objective),
        "min_clearance": num(o.min_clearance),
        "target_error": num(o.target_error),
        "insertion": {
            "theta1_deg": num(o.insertion.theta1_deg),
            "theta2_deg": num(o.insertion.theta2_deg),
            "tilt_deg": num(o.insertion.tilt_deg),
            "direction": o.insertion.direction,
        },
        "segments": segments,
        "kkt_residual": num(o.kkt_residual),
        "iterations": o.iterations,
        "evaluations": o.evaluations,
    });
    if with_points {
        v["points"] = json!(path_points(scenario, o));
    }
    v
}

/// The `needle plan --json` object.
pub fn plan_json(scenario: &Scenario, report: &PlanReport, stats: Stats) -> Value {
    let forms: Vec<Value> = report
        .forms
        .iter()
        .map(|o| {
            let f = o.feasible;
            let full = outcome_json(scenario, o, false);
            json!({
                "insertion": if f { full["insertion"].clone() } else { Value::Null },
                "segments": if f { full["segments"].clone() } else { Value::Null },
                "form": o.form.to_string(),
                "feasible": f,
                "status": format!("{:?}", o.status),
                "length": if f { num(o.length) } else { Value::Null },
                "risk": if f { num(o.risk) } else { Value::Null },
                "objective": if f { num(o.objective) } else { Value::Null },
                "min_clearance": if f { num(o.min_clearance) } else { Value::Null },
                "target_error": if f { num(o.target_error) } else { Value::Null },
                "kkt_residual": if f { num(o.kkt_residual) } else { Value::Null },
                "iterations": o.iterations,
                "evaluations": o.evaluations,
            })
        })
        .collect();
    let best = report
        .best()
        .map(|b| outcome_json(scenario, b, true))
        .unwrap_or(Value::Null);
    json!({
        "best": best,
        "forms": forms,
        "stats": {
            "time_us": stats.time_us,
            "iterations": report.iterations(),
            "evaluations": report.evaluations(),
        },
    })
}

fn cell(v: f32, feasible: bool, prec: usize) -> String {
    if feasible && v.is_finite() {
        format!("{v:.prec$}")
    } else {
        "-".to_string()
    }
}

/// The human-readable table: one row per form, then the overall best.
pub fn plan_table(report: &PlanReport, stats: Stats) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<5} {:>3} {:>8} {:>9} {:>8} {:>9} {:>10} {:>12}  {}\n",
        "form", "N", "feasible", "L (mm)", "D", "F", "clear (mm)", "target (mm)", "status"
    ));
    for o in &report.forms {
        let f = o.feasible;
        s.push_str(&format!(
            "{:<5} {:>3} {:>8} {:>9} {:>8} {:>9} {:>10} {:>12}  {:?}\n",
            o.form.to_string(),
            o.form.len(),
            if f { "yes" } else { "no" },
            cell(o.length, f, 2),
            cell(o.risk, f, 4),
            cell(o.objective, f, 3),
            cell(o.min_clearance, f, 2),
            cell(o.target_error, f, 5),
            o.status,
        ));
    }
    if let Some(b) = report.best() {
        s.push_str(&format!(
            "\nbest: {} (N = {}), F = {:.3}, L = {:.2} mm, D = {:.4}, insertion tilt {:.2} deg\n",
            b.form,
            b.form.len(),
            b.objective,
            b.length,
            b.risk,
            b.insertion.tilt_deg
        ));
        for (i, seg) in b.segments.iter().enumerate() {
            s.push_str(&format!(
                "  segment {}: {} {:.2} mm, bevel {:.1} deg\n",
                i + 1,
                seg.kind.letter(),
                seg.length,
                seg.bevel_deg
            ));
        }
    }
    s.push_str(&format!(
        "planned in {} us, {} iterations, {} evaluations\n",
        stats.time_us,
        report.iterations(),
        report.evaluations()
    ));
    s
}
