//! Reading a `needle plan --json` object back for plotting. The best path carries its points; a
//! form entry is drawn from its `points`, or rebuilt from `insertion` and `segments` when present,
//! and otherwise only listed in the legend.

use super::plot::{colour_of, PlotPath};
use anyhow::{bail, Result};
use planner_core::check::{rebuild, sample_points};
use planner_core::report::{Insertion, SegmentPlan};
use planner_core::{Form, Scenario, SegmentKind};
use serde_json::Value;

fn points_of(v: &Value) -> Option<Vec<[f32; 3]>> {
    let arr = v.get("points")?.as_array()?;
    arr.iter()
        .map(|p| {
            let c = p.as_array()?;
            Some([
                c.first()?.as_f64()? as f32,
                c.get(1)?.as_f64()? as f32,
                c.get(2)?.as_f64()? as f32,
            ])
        })
        .collect()
}

fn rebuilt(scenario: &Scenario, form: Form, v: &Value) -> Option<Vec<[f32; 3]>> {
    let ins = v.get("insertion")?;
    let insertion = Insertion {
        theta1_deg: ins.get("theta1_deg")?.as_f64()? as f32,
        theta2_deg: ins.get("theta2_deg")?.as_f64()? as f32,
        ..Insertion::default()
    };
    let mut segments = Vec::new();
    for s in v.get("segments")?.as_array()? {
        segments.push(SegmentPlan {
            kind: match s.get("kind")?.as_str()? {
                "R" => SegmentKind::Arc,
                _ => SegmentKind::Line,
            },
            length: s.get("length")?.as_f64()? as f32,
            bevel_deg: s.get("bevel_deg")?.as_f64()? as f32,
        });
    }
    if segments.len() != form.len() {
        return None;
    }
    let geo = rebuild(scenario, form, &insertion, &segments);
    let mut pts = Vec::new();
    sample_points(&geo, 1.0, |p| pts.push([p.x, p.y, p.z]));
    Some(pts)
}

/// Paths and legend notes from a plan object.
pub fn scene_paths(scenario: &Scenario, plan: &Value) -> Result<(Vec<PlotPath>, Vec<String>)> {
    let Some(best) = plan.get("best").filter(|b| !b.is_null()) else {
        bail!("the plan has no `best` path");
    };
    let best_form = best
        .get("form")
        .and_then(Value::as_str)
        .and_then(Form::parse);
    let mut paths = Vec::new();
    let mut notes = Vec::new();
    let empty = Vec::new();
    let forms = plan
        .get("forms")
        .and_then(Value::as_array)
        .unwrap_or(&empty);
    let mut entries: Vec<&Value> = forms.iter().collect();
    if entries.is_empty() {
        entries.push(best);
    }
    for f in entries {
        let Some(form) = f.get("form").and_then(Value::as_str).and_then(Form::parse) else {
            continue;
        };
        let feasible = f.get("feasible").and_then(Value::as_bool).unwrap_or(true);
        if !feasible {
            notes.push(format!("{form}: no feasible path"));
            continue;
        }
        let is_best = Some(form) == best_form;
        let source = if is_best { best } else { f };
        let objective = source
            .get("objective")
            .and_then(Value::as_f64)
            .unwrap_or(f64::NAN);
        let length = source
            .get("length")
            .and_then(Value::as_f64)
            .unwrap_or(f64::NAN);
        let label = format!(
            "{form}{}: F = {objective:.2}, L = {length:.1} mm",
            if is_best { " (best)" } else { "" }
        );
        match points_of(source).or_else(|| rebuilt(scenario, form, source)) {
            Some(points) => paths.push(PlotPath {
                label,
                form: form.to_string(),
                colour: colour_of(form),
                points,
                best: is_best,
            }),
            None => notes.push(format!("{label} (no geometry in the plan file)")),
        }
    }
    Ok((paths, notes))
}
