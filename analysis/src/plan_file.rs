//! Drawing a saved `needle plan --json` report. The best path carries its points; a form entry is
//! drawn from its `points`, or rebuilt from `insertion` and `segments` when present, and
//! otherwise only listed in the legend.

use super::plot::{colour_of, PlotPath};
use anyhow::{bail, Result};
use needle_report::json::{FormEntry, PlanJson};
use planner_core::check::{rebuild, sample_points};
use planner_core::report::{Insertion, SegmentPlan};
use planner_core::{Form, Scenario};

/// The entry's own points, narrowed back to the planner's `f32` (they were widened from it).
fn points_of(entry: &FormEntry) -> Option<Vec<[f32; 3]>> {
    let points = entry.points.as_ref()?;
    Some(points.iter().map(|p| p.map(|c| c as f32)).collect())
}

/// The path rebuilt from the entry's insertion and segments, when they are complete.
fn rebuilt(scenario: &Scenario, form: Form, entry: &FormEntry) -> Option<Vec<[f32; 3]>> {
    let ins = entry.insertion.as_ref()?;
    let insertion = Insertion {
        theta1_deg: ins.theta1_deg? as f32,
        theta2_deg: ins.theta2_deg? as f32,
        ..Insertion::default()
    };
    let segments = entry
        .segments
        .as_ref()?
        .iter()
        .map(|s| {
            Some(SegmentPlan {
                kind: s.segment_kind(),
                length: s.length? as f32,
                bevel_deg: s.bevel_deg? as f32,
            })
        })
        .collect::<Option<Vec<_>>>()?;
    if segments.len() != form.len() {
        return None;
    }
    let geo = rebuild(scenario, form, &insertion, &segments);
    let mut pts = Vec::new();
    sample_points(&geo, 1.0, |p| pts.push([p.x, p.y, p.z]));
    Some(pts)
}

/// Paths and legend notes from a plan report.
pub fn scene_paths(scenario: &Scenario, plan: &PlanJson) -> Result<(Vec<PlotPath>, Vec<String>)> {
    let Some(best) = &plan.best else {
        bail!("the plan has no `best` path");
    };
    let best = &best.path;
    let best_form = Form::parse(&best.form);
    let mut paths = Vec::new();
    let mut notes = Vec::new();
    let mut entries: Vec<&FormEntry> = plan.forms.iter().collect();
    if entries.is_empty() {
        entries.push(best);
    }
    for f in entries {
        let Some(form) = Form::parse(&f.form) else {
            continue;
        };
        if !f.feasible {
            notes.push(format!("{form}: no feasible path"));
            continue;
        }
        let is_best = Some(form) == best_form;
        let source = if is_best { best } else { f };
        let objective = source.objective.unwrap_or(f64::NAN);
        let length = source.length.unwrap_or(f64::NAN);
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
