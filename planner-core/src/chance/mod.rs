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

mod margins;
mod search;

pub use search::{ChanceSearch, ChanceStep};

use crate::execute::perturbation::Perturbation;
use crate::execute::risk::{Execution, ExecutionRisk};
use crate::execute::ScheduledPlan;
use crate::model::scenario::Scenario;
use crate::{PlanError, MAX_OBSTACLES};
use serde::{Deserialize, Serialize};

/// Plans made at most while searching for margins that meet the bound.
pub const MAX_ROUNDS: u32 = 10;

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

/// What a plan under a collision bound achieved, without the plan: what a device reports beside
/// it (the host re-derives the probability and the miss from the plan to check them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChanceFigures {
    /// The best form's predicted probability of entering an obstacle; `None` without a best
    /// form.
    pub collision_probability: Option<f32>,
    /// The best form's predicted 95th percentile of the miss (mm); `None` without a best form.
    pub target_error_p95: Option<f32>,
    /// How far each obstacle was grown (mm), one per obstacle in the scenario's order.
    pub margins: heapless::Vec<f32, MAX_OBSTACLES>,
    /// Plans made.
    pub rounds: u32,
    /// The best form's predicted collision probability is within the bound.
    pub within_bound: bool,
}

impl ChancePlan {
    /// The figures of this plan for a scenario of `obstacles` obstacles.
    pub fn figures(&self, obstacles: usize) -> ChanceFigures {
        let mut margins = heapless::Vec::new();
        for m in self.margins.iter().take(obstacles) {
            // Cannot fail: at most MAX_OBSTACLES.
            let _ = margins.push(*m);
        }
        ChanceFigures {
            collision_probability: self.risk.map(|r| r.collision_probability),
            target_error_p95: self.risk.map(|r| r.target_error_p95),
            margins,
            rounds: self.rounds,
            within_bound: self.within_bound,
        }
    }

    /// The plan a device reported, `planned` with its `figures` and `risk`, the host's own
    /// prediction of it (`None` without a best form).
    pub fn from_figures(
        planned: ScheduledPlan,
        figures: &ChanceFigures,
        risk: Option<ExecutionRisk>,
    ) -> ChancePlan {
        let mut margins = [0.0; MAX_OBSTACLES];
        for (m, f) in margins.iter_mut().zip(&figures.margins) {
            *m = *f;
        }
        ChancePlan {
            planned,
            risk,
            margins,
            rounds: figures.rounds,
            within_bound: figures.within_bound,
        }
    }
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
/// one the closed loop leaves. Runs a [`ChanceSearch`] to the end, as a device does one form per
/// poll.
pub fn plan_within_risk_as(
    scenario: &Scenario,
    model: &Perturbation,
    bound: f32,
    execution: Execution,
) -> Result<ChancePlan, PlanError> {
    let mut search = ChanceSearch::new(scenario.clone(), *model, bound, execution)?;
    while search.step()?.is_some() {}
    search.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Field;

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
