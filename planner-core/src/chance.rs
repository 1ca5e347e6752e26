//! Planning under a bound on the predicted probability of collision (a chance constraint).
//!
//! The optimiser treats the path as exact; executed, the tip strays by the spread the
//! perturbation model predicts ([`execute::risk`](crate::execute::risk)). Each obstacle's
//! clearance must exceed its margin under that spread along the direction to it, the margins
//! chosen so that the probabilities, added over obstacles, stay under the bound (risk allocated
//! evenly over the obstacles that matter, as in Blackmore et al., IEEE T-RO 2011). The margins
//! depend on the path, so the plan is made again with each obstacle grown by its margin until
//! the predicted probability of the plan, measured on the true obstacles, is within the bound,
//! or the margins stop growing, or the rounds run out. Whatever the rounds did, the figure
//! reported is that of the final plan: the bound is met only when it says so.

use crate::execute::perturbation::Perturbation;
use crate::execute::risk::{risk_by_obstacle, Execution, ExecutionRisk, ObstacleRisk};
use crate::execute::schedule::schedule;
use crate::execute::ScheduledPlan;
use crate::model::form::FORM_COUNT;
use crate::model::scenario::Scenario;
use crate::{plan_scheduled, Field, PlanError, MAX_OBSTACLES};

/// Plans made at most while searching for margins that meet the bound.
pub const MAX_ROUNDS: u32 = 10;

/// An obstacle whose probability is below this share of the bound gets no share of it.
const NEGLIGIBLE_SHARE: f32 = 0.01;

/// A plan made under a chance constraint, and what it achieved.
#[derive(Clone, Debug, PartialEq)]
pub struct ChancePlan {
    /// The plan of the last round (made with the obstacles grown by `margins`; its best form
    /// passed the check on those, so also on the true ones).
    pub planned: ScheduledPlan,
    /// The best form's predicted risk on the true obstacles; `None` without a best form.
    pub risk: Option<ExecutionRisk>,
    /// How far each obstacle was grown (mm), in the scenario's order.
    pub margins: [f32; MAX_OBSTACLES],
    /// Plans made.
    pub rounds: u32,
    /// The best form's predicted collision probability is within the bound.
    pub within_bound: bool,
}

/// The standard normal quantile of `1 − tail` for a tail in (0, 0.5] (Abramowitz and Stegun
/// 26.2.23: within 4.5e-4).
pub fn upper_quantile(tail: f32) -> f32 {
    let tail = crate::fmath::clamp(tail, 1e-12, 0.5);
    let t = crate::fmath::sqrt(-2.0 * libm::logf(tail));
    let num = 2.515_517 + t * (0.802_853 + t * 0.010_328);
    let den = 1.0 + t * (1.432_788 + t * (0.189_269 + t * 0.001_308));
    t - num / den
}

/// `scenario` with each obstacle grown by its margin.
fn grown(scenario: &Scenario, margins: &[f32; MAX_OBSTACLES]) -> Scenario {
    let mut s = scenario.clone();
    for (ob, m) in s.obstacles.iter_mut().zip(margins) {
        ob.radius += m;
    }
    s
}

/// The largest margin obstacle `ob` may take and still leave the entry and the target outside
/// it (nine tenths of the smaller gap): near the target, the bound may be out of reach.
fn margin_cap(scenario: &Scenario, i: usize) -> f32 {
    let Some(ob) = scenario.obstacles.get(i) else {
        return 0.0;
    };
    let gap = |p: [f32; 3]| {
        let d: f32 = (0..3)
            .map(|k| (p[k] - ob.center[k]) * (p[k] - ob.center[k]))
            .sum();
        crate::fmath::sqrt(d) - ob.radius
    };
    0.9 * gap(scenario.entry.position)
        .min(gap(scenario.target.position))
        .max(0.0)
}

/// Raises the margins of the obstacles that matter so that each would keep its share of the
/// bound at the spread just measured. Returns whether any margin grew.
fn raise_margins(
    scenario: &Scenario,
    bound: f32,
    by_obstacle: &[ObstacleRisk; MAX_OBSTACLES],
    margins: &mut [f32; MAX_OBSTACLES],
) -> bool {
    let count = scenario.obstacles.len().min(MAX_OBSTACLES);
    let mut matters = [false; MAX_OBSTACLES];
    for i in 0..count {
        matters[i] = by_obstacle[i].probability > NEGLIGIBLE_SHARE * bound || margins[i] > 0.0;
    }
    let active = matters.iter().filter(|m| **m).count().max(1);
    let k = upper_quantile(bound / active as f32);
    let mut raised = false;
    for i in (0..count).filter(|&i| matters[i]) {
        let o = &by_obstacle[i];
        let wanted = (k * o.sd + o.steering_margin).min(margin_cap(scenario, i));
        if wanted > margins[i] + 1e-3 {
            margins[i] = wanted;
            raised = true;
        }
    }
    raised
}

/// Plans `scenario` so that the best form's predicted probability of entering an obstacle
/// under `model` is at most `bound` (in (0, 1)). `Ok` with `within_bound` false when no plan
/// met it; `Err` only when the scenario or the bound is invalid.
///
/// ```
/// use planner_core::chance::plan_within_risk;
/// use planner_core::execute::perturbation::Perturbation;
/// use planner_core::Scenario;
///
/// let scenario = Scenario::paper();
/// let safe = plan_within_risk(&scenario, &Perturbation::default(), 0.01).unwrap();
/// assert!(safe.within_bound);
/// let risk = safe.risk.unwrap();
/// assert!(risk.collision_probability <= 0.01);
/// // The safe plan keeps its distance: longer than the unconstrained optimum.
/// let free = planner_core::plan(&scenario).unwrap();
/// let length = safe.planned.report.best().unwrap().length;
/// assert!(length >= free.best().unwrap().length);
/// ```
pub fn plan_within_risk(
    scenario: &Scenario,
    model: &Perturbation,
    bound: f32,
) -> Result<ChancePlan, PlanError> {
    plan_within_risk_as(scenario, model, bound, Execution::OpenLoop)
}

/// [`plan_within_risk`] for the plan executed as `execution` says: steered, the spread is the
/// one the closed loop leaves.
pub fn plan_within_risk_as(
    scenario: &Scenario,
    model: &Perturbation,
    bound: f32,
    execution: Execution,
) -> Result<ChancePlan, PlanError> {
    if !bound.is_finite() {
        return Err(PlanError::NotFinite(Field::MaxCollisionProbability));
    }
    if !(bound > 0.0 && bound < 1.0) {
        return Err(PlanError::OutOfRange(Field::MaxCollisionProbability));
    }
    scenario.validate()?;
    let mut margins = [0.0f32; MAX_OBSTACLES];
    // The margins of the last round that found a path: a round whose grown obstacles leave none
    // backs off half way towards them.
    let mut found = [0.0f32; MAX_OBSTACLES];
    let mut last: Option<ChancePlan> = None;
    for round in 1..=MAX_ROUNDS {
        let planned = plan_scheduled(&grown(scenario, &margins))?;
        let mut by_obstacle = [ObstacleRisk::default(); MAX_OBSTACLES];
        let risk = match &planned.schedule {
            Some(Ok(schedule)) => Some(risk_by_obstacle(
                scenario,
                schedule,
                model,
                execution,
                &mut by_obstacle,
            )),
            _ => None,
        };
        let within_bound = risk.is_some_and(|r| r.collision_probability <= bound);
        let outcome = ChancePlan {
            planned,
            risk,
            margins,
            rounds: round,
            within_bound,
        };
        if within_bound {
            return Ok(outcome);
        }
        if risk.is_none() {
            let Some(l) = last.as_mut() else {
                return Ok(outcome); // no path even without margins
            };
            l.rounds = round;
            if margins == found {
                break;
            }
            for (m, f) in margins.iter_mut().zip(&found) {
                *m = 0.5 * (*m + f);
            }
            continue;
        }
        found = margins;
        last = Some(outcome);
        if !raise_margins(scenario, bound, &by_obstacle, &mut margins) {
            break;
        }
    }
    // `last` is set: the first round either returned or set it.
    let mut last = last.ok_or(PlanError::Unreachable)?;
    within_bound_by_another_form(scenario, model, bound, execution, &mut last);
    Ok(last)
}

/// Where the best form misses the bound, the form of lowest objective among those of the same
/// plan that keep it becomes the best (a longer form may pass the spheres where the spread is
/// smaller), if any does.
fn within_bound_by_another_form(
    scenario: &Scenario,
    model: &Perturbation,
    bound: f32,
    execution: Execution,
    plan: &mut ChancePlan,
) {
    let report = &plan.planned.report;
    let mut order = [0u8; FORM_COUNT];
    let mut n = 0;
    for (i, o) in report.forms.iter().enumerate() {
        if o.feasible && Some(i as u8) != report.best && n < order.len() {
            order[n] = i as u8;
            n += 1;
        }
    }
    let forms = &report.forms;
    order[..n].sort_unstable_by(|&a, &b| {
        let f = |i: u8| {
            forms
                .get(usize::from(i))
                .map_or(f32::INFINITY, |o| o.objective)
        };
        f(a).total_cmp(&f(b))
    });
    let mut by_obstacle = [ObstacleRisk::default(); MAX_OBSTACLES];
    for &i in &order[..n] {
        let Some(outcome) = forms.get(usize::from(i)) else {
            continue;
        };
        let Ok(s) = schedule(scenario, outcome) else {
            continue;
        };
        let risk = risk_by_obstacle(scenario, &s, model, execution, &mut by_obstacle);
        if risk.collision_probability <= bound {
            plan.planned.report.best = Some(i);
            plan.planned.schedule = Some(Ok(s));
            plan.risk = Some(risk);
            plan.within_bound = true;
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quantile_inverts_the_normal_distribution() {
        for tail in [0.5, 0.1, 0.05, 0.01, 1e-3, 1e-5] {
            let x = upper_quantile(tail);
            let back = 1.0 - crate::execute::risk::normal_cdf(x);
            assert!(
                (back - tail).abs() <= 5e-4 * tail.max(0.01) * 10.0,
                "{tail}: {x} gives {back}"
            );
        }
        assert!((upper_quantile(0.05) - 1.6449).abs() < 1e-3);
    }

    #[test]
    fn a_bound_outside_zero_to_one_is_refused() {
        let s = Scenario::paper();
        let p = Perturbation::default();
        for bad in [0.0, 1.0, -0.1, 2.0] {
            assert_eq!(
                plan_within_risk(&s, &p, bad).unwrap_err(),
                PlanError::OutOfRange(Field::MaxCollisionProbability)
            );
        }
        assert_eq!(
            plan_within_risk(&s, &p, f32::NAN).unwrap_err(),
            PlanError::NotFinite(Field::MaxCollisionProbability)
        );
    }
}
