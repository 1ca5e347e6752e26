//! What a plan predicts about its execution, as `needle plan` shows it for every plan, bounded
//! or not: each feasible form's predicted collision
//! probability and 95th percentile of the miss (first order, open loop, re-derived here from
//! each form's own schedule on the true obstacles, not taken from the planner's rounds), and the
//! bound with the margins the plan kept.

use super::json::{finite, ExecutionJson, PlanJson};
use needle_scenario::Execution;
use planner_core::chance::ChancePlan;
use planner_core::execute::risk::{risk_by_obstacle, ExecutionRisk, ObstacleRisk};
use planner_core::execute::schedule::schedule;
use planner_core::{PlanReport, Scenario};

/// Each form's predicted risk (`None` for an infeasible form or one the driver cannot
/// execute), in the report's order.
pub fn form_risks(
    scenario: &Scenario,
    report: &PlanReport,
    execution: &Execution,
) -> Vec<Option<ExecutionRisk>> {
    let mut by_obstacle = [ObstacleRisk::default(); planner_core::MAX_OBSTACLES];
    report
        .forms
        .iter()
        .map(|o| {
            let s = o.feasible.then(|| schedule(scenario, o).ok()).flatten()?;
            Some(risk_by_obstacle(
                scenario,
                &s,
                &execution.model,
                execution.predicted_as(),
                &mut by_obstacle,
            ))
        })
        .collect()
}

/// Adds the predictions to a plan's JSON (`scenario` as planned, its reserve perhaps lowered
/// from `reserve_asked`).
pub fn add_to_json(
    json: &mut PlanJson,
    scenario: &Scenario,
    reserve_asked: f32,
    execution: &Execution,
    risks: &[Option<ExecutionRisk>],
    chance: Option<&ChancePlan>,
    report: &PlanReport,
) {
    for (entry, risk) in json.forms.iter_mut().zip(risks) {
        entry.collision_probability = risk.and_then(|r| finite(r.collision_probability));
        entry.target_error_p95 = risk.and_then(|r| finite(r.target_error_p95));
    }
    if let (Some(best), Some(i)) = (json.best.as_mut(), report.best) {
        let risk = risks.get(usize::from(i)).copied().flatten();
        best.path.collision_probability = risk.and_then(|r| finite(r.collision_probability));
        best.path.target_error_p95 = risk.and_then(|r| finite(r.target_error_p95));
    }
    json.execution = Some(ExecutionJson {
        mode: execution.mode.name().to_string(),
        perturbation: execution.model,
        max_collision_probability: execution.max_collision_probability.map(f64::from),
        within_bound: chance.filter(|c| c.risk.is_some()).map(|c| c.within_bound),
        rounds: chance.map(|c| c.rounds),
        margins: chance.map(|c| {
            c.margins[..scenario.obstacles.len()]
                .iter()
                .map(|m| f64::from(*m))
                .collect()
        }),
        curvature_reserve: Some(share(scenario.options.curvature_reserve)),
        curvature_reserve_asked: Some(share(reserve_asked)),
    });
}

/// A share of the curvature as the JSON gives it: to a millionth, so a reserve lowered in steps
/// of 0.05 reads 0.25, not the f32's 0.2499999850988388.
fn share(v: f32) -> f64 {
    (f64::from(v) * 1e6).round() / 1e6
}

/// The lines `needle plan` prints under its table.
pub fn execution_lines(
    report: &PlanReport,
    execution: &Execution,
    risks: &[Option<ExecutionRisk>],
    chance: Option<&ChancePlan>,
) -> String {
    let mut s = format!(
        "predicted execution ({}, first order): collision probability and 95th percentile of the miss per form\n",
        execution.mode.name()
    );
    for (o, risk) in report.forms.iter().zip(risks) {
        if let Some(r) = risk {
            s.push_str(&format!(
                "  {:<5} collision {:>7.4}  miss p95 {:>6.2} mm\n",
                o.form.to_string(),
                r.collision_probability,
                r.target_error_p95
            ));
        }
    }
    if execution.max_collision_probability.is_none() {
        s.push_str(
            "unbounded: planner.max_collision_probability = \"off\", so no plan is refused for its \
             predicted collision probability\n",
        );
    }
    if let (Some(bound), Some(c)) = (execution.max_collision_probability, chance) {
        let verdict = if c.within_bound {
            "within"
        } else {
            "NOT within"
        };
        let grown: Vec<String> = c
            .margins
            .iter()
            .enumerate()
            .filter(|(_, m)| **m > 0.0)
            .map(|(i, m)| format!("#{i} {m:.2}"))
            .collect();
        s.push_str(&format!(
            "bound {bound}: the best form is {verdict} it after {} plan(s); obstacles grown (mm): {} \
             (the table's clearances are to the grown obstacles)\n",
            c.rounds,
            if grown.is_empty() { "none".to_string() } else { grown.join(", ") }
        ));
    }
    s
}
