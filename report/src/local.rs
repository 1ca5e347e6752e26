//! `needle plan` as a library call: the plan made on this machine (under the scenario's collision
//! bound when it has one), its motor schedule and predictions, the JSON report the command prints,
//! and the verdict it exits with. The command and the Python package both go through here, so
//! they give the same report and the same messages.

use super::execution::{add_to_json, execution_lines, form_risks};
use super::json::{plan_json, PlanJson, Stats};
use anyhow::{anyhow, Context, Result};
use needle_scenario::reserve::{is_unreachable, keeping_reserve, reserve_line, Shortfall};
use needle_scenario::Execution;
use planner_core::chance::{plan_within_risk_as, ChancePlan};
use planner_core::execute::risk::ExecutionRisk;
use planner_core::execute::schedule::Schedule;
use planner_core::{PlanReport, Scenario, ScheduledPlan};
use std::time::Instant;

/// A plan made here, with everything `needle plan` prints of it.
pub struct LocalPlan {
    /// The scenario as planned: its curvature reserve is the one the plan keeps, lowered from
    /// the one asked for where no path kept that (`needle_scenario::reserve`).
    pub scenario: Scenario,
    /// The curvature reserve the scenario asked for.
    pub reserve_asked: f32,
    /// The report and the best form's schedule.
    pub planned: ScheduledPlan,
    /// With a collision bound: the rounds that kept it.
    pub chance: Option<ChancePlan>,
    /// Each form's predicted risk, when the scenario has an `[execution]` table or a bound.
    pub risks: Option<Vec<Option<ExecutionRisk>>>,
    /// The wall-clock time of the planning.
    pub stats: Stats,
    /// `planner.max_collision_probability`.
    bound: Option<f32>,
}

/// Plans `scenario` as `needle plan` does: under `execution`'s collision bound when it has one,
/// keeping as much of the curvature reserve as a path allows (`needle_scenario::reserve`), the
/// best form scheduled. Errors are those the command stops on before printing anything.
pub fn plan_locally(scenario: &Scenario, execution: &Execution) -> Result<LocalPlan> {
    let start = Instant::now();
    let (_, made) = keeping_reserve(
        scenario,
        |s| plan_once(s, execution),
        |made| match made {
            Ok(m) => m.shortfall(),
            Err(e) => is_unreachable(e).then_some(Shortfall::Unreachable),
        },
    );
    let mut made = made?;
    made.reserve_asked = scenario.options.curvature_reserve;
    made.judge(execution);
    // Every plan made to keep the reserve counts in the time.
    made.stats.time_us = start.elapsed().as_micros() as u64;
    made.schedule()?;
    Ok(made)
}

/// One plan of `scenario` as it is.
fn plan_once(scenario: &Scenario, execution: &Execution) -> Result<LocalPlan> {
    let start = Instant::now();
    let chance = match execution.max_collision_probability {
        Some(bound) => Some(
            plan_within_risk_as(scenario, &execution.model, bound, execution.predicted_as())
                .context("planning failed")?,
        ),
        None => None,
    };
    let planned = match &chance {
        Some(c) => c.planned.clone(),
        None => planner_core::plan_scheduled(scenario).context("planning failed")?,
    };
    let stats = Stats {
        time_us: start.elapsed().as_micros() as u64,
    };
    Ok(LocalPlan::new(scenario, execution, planned, chance, stats))
}

impl LocalPlan {
    /// A plan made of `scenario` (here, or on a device: `chance`, its figures under the bound,
    /// checked here), without this machine's predictions of each form yet ([`LocalPlan::judge`]):
    /// a plan made at a reserve that is then given up needs none.
    pub fn new(
        scenario: &Scenario,
        execution: &Execution,
        planned: ScheduledPlan,
        chance: Option<ChancePlan>,
        stats: Stats,
    ) -> LocalPlan {
        LocalPlan {
            scenario: scenario.clone(),
            reserve_asked: scenario.options.curvature_reserve,
            planned,
            chance,
            risks: None,
            stats,
            bound: execution.max_collision_probability,
        }
    }

    /// Adds this machine's predictions of each form (every plan says how likely its execution
    /// is to enter an obstacle, bounded or not), so the plan is printed and judged as `needle
    /// plan` prints and judges its own.
    pub fn judge(&mut self, execution: &Execution) {
        self.risks = Some(form_risks(&self.scenario, &self.planned.report, execution));
    }

    /// The report of every form.
    pub fn report(&self) -> &PlanReport {
        &self.planned.report
    }

    /// The best form's motor schedule (`None` without a best form); an error when the best path
    /// cannot be scheduled.
    pub fn schedule(&self) -> Result<Option<&Schedule>> {
        match &self.planned.schedule {
            Some(made) => {
                Ok(Some(made.as_ref().map_err(|e| {
                    anyhow!("no motor schedule for the best path: {e}")
                })?))
            }
            None => Ok(None),
        }
    }

    /// Why this plan falls short in a way a lower curvature reserve might mend: no best form,
    /// or none within the collision bound.
    pub fn shortfall(&self) -> Option<Shortfall> {
        if self.report().best().is_none() {
            return Some(Shortfall::Unreachable);
        }
        match (&self.chance, self.bound) {
            (Some(c), Some(_)) if !c.within_bound => Some(Shortfall::MissesBound),
            _ => None,
        }
    }

    /// The `needle plan --json` report.
    pub fn json(&self, execution: &Execution) -> PlanJson {
        let schedule = self.schedule().ok().flatten();
        let mut json = plan_json(&self.scenario, self.report(), schedule, self.stats);
        if let Some(risks) = &self.risks {
            let (chance, asked) = (self.chance.as_ref(), self.reserve_asked);
            let report = self.report();
            add_to_json(
                &mut json,
                &self.scenario,
                asked,
                execution,
                risks,
                chance,
                report,
            );
        }
        json
    }

    /// The `needle plan` table: every form, the predictions when there are any, and the
    /// reserve when less was kept than asked.
    pub fn table(&self, execution: &Execution) -> String {
        let mut text = super::plan_table(self.report(), self.stats);
        if let Some(risks) = &self.risks {
            let chance = self.chance.as_ref();
            text.push_str(&execution_lines(self.report(), execution, risks, chance));
        }
        let planned = self.scenario.options.curvature_reserve;
        text.push_str(&reserve_line(planned, self.reserve_asked));
        text
    }

    /// Why the command fails after printing the report: no feasible form, or no plan within the
    /// collision bound.
    pub fn verdict(&self) -> Result<()> {
        if self.report().best().is_none() {
            return Err(anyhow!(planner_core::PlanError::Unreachable));
        }
        match (&self.chance, self.bound) {
            (Some(c), Some(bound)) if !c.within_bound => Err(anyhow!(
                "no plan keeps the predicted collision probability within {bound}: the best \
                 found has {:.4} (with obstacles grown by up to {:.2} mm)",
                c.risk.map_or(f32::NAN, |r| r.collision_probability),
                c.margins.iter().fold(0.0f32, |a, m| a.max(*m))
            )),
            _ => Ok(()),
        }
    }
}
