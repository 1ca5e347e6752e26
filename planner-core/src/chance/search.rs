//! The search for margins as a job that can be paused between forms: a device plans one form
//! per poll (answering pings and cancels in between), the host runs it to the end, and both get
//! the same plan bit for bit because it is the same code.

use super::margins::{grown, raise_margins};
use super::{ChancePlan, MAX_ROUNDS};
use crate::execute::perturbation::Perturbation;
use crate::execute::risk::{risk_by_obstacle, Execution, ObstacleRisk};
use crate::execute::schedule::schedule;
use crate::model::form::{Form, FORM_COUNT};
use crate::model::scenario::Scenario;
use crate::session::PlanSession;
use crate::{Field, PlanError, MAX_OBSTACLES};

/// What one [`ChanceSearch::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChanceStep {
    /// Planned `form` in round `round` (counted from 1).
    Form {
        /// The round (one plan of every form, obstacles grown by that round's margins).
        round: u32,
        /// The form planned.
        form: Form,
        /// Whether it gave a feasible path.
        feasible: bool,
    },
    /// Judged round `round`'s plan against the bound, and started the next round or ended.
    RoundEnded {
        /// The round judged.
        round: u32,
    },
}

/// A plan under a collision bound, made one unit of work at a time.
///
/// ```
/// use planner_core::chance::{plan_within_risk, ChanceSearch, ChanceStep};
/// use planner_core::execute::perturbation::Perturbation;
/// use planner_core::execute::risk::Execution;
/// use planner_core::Scenario;
///
/// let scenario = Scenario::paper();
/// let model = Perturbation::default();
/// let mut search = ChanceSearch::new(scenario.clone(), model, 0.01, Execution::OpenLoop).unwrap();
/// let mut rounds = 0;
/// while let Some(step) = search.step().unwrap() {
///     if let ChanceStep::RoundEnded { .. } = step {
///         rounds += 1;
///     }
/// }
/// let planned = search.finish().unwrap();
/// assert_eq!(planned.rounds, rounds);
/// // The same plan as the one-call form, bit for bit (NaN figures of infeasible forms included).
/// let whole = plan_within_risk(&scenario, &model, 0.01).unwrap();
/// assert_eq!(format!("{planned:?}"), format!("{whole:?}"));
/// ```
pub struct ChanceSearch {
    /// The scenario with its true obstacles.
    scenario: Scenario,
    model: Perturbation,
    bound: f32,
    execution: Execution,
    /// This round's margins.
    margins: [f32; MAX_OBSTACLES],
    /// The margins of the last round that found a path: a round whose grown obstacles leave none
    /// backs off half way towards them.
    found: [f32; MAX_OBSTACLES],
    round: u32,
    /// The round being planned; `None` once the search has ended.
    session: Option<PlanSession>,
    /// The last round that found a path, and once the search has ended, its result.
    last: Option<ChancePlan>,
    /// Why the search could not go on (a grown scenario the planner refused).
    failed: Option<PlanError>,
}

impl ChanceSearch {
    /// Checks the bound (in (0, 1)) and the scenario, and prepares the first round: the
    /// scenario as it is.
    pub fn new(
        scenario: Scenario,
        model: Perturbation,
        bound: f32,
        execution: Execution,
    ) -> Result<Self, PlanError> {
        if !bound.is_finite() {
            return Err(PlanError::NotFinite(Field::MaxCollisionProbability));
        }
        if !(bound > 0.0 && bound < 1.0) {
            return Err(PlanError::OutOfRange(Field::MaxCollisionProbability));
        }
        let session = PlanSession::new(scenario.clone())?;
        Ok(ChanceSearch {
            scenario,
            model,
            bound,
            execution,
            margins: [0.0; MAX_OBSTACLES],
            found: [0.0; MAX_OBSTACLES],
            round: 1,
            session: Some(session),
            last: None,
            failed: None,
        })
    }

    /// The scenario, with its true obstacles.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Forms planned in each round.
    pub fn forms_per_round(&self) -> usize {
        self.session.as_ref().map_or(0, PlanSession::form_count)
    }

    /// Plans one form, or judges a finished round; `Ok(None)` once the search has ended. `Err`
    /// when a round's grown scenario cannot be planned; the search is then over.
    pub fn step(&mut self) -> Result<Option<ChanceStep>, PlanError> {
        if let Some(e) = self.failed {
            return Err(e);
        }
        let round = self.round;
        let Some(session) = self.session.as_mut() else {
            return Ok(None);
        };
        if let Some(o) = session.step() {
            let (form, feasible) = (o.form, o.feasible);
            return Ok(Some(ChanceStep::Form {
                round,
                form,
                feasible,
            }));
        }
        match self.end_round() {
            Ok(()) => Ok(Some(ChanceStep::RoundEnded { round })),
            Err(e) => {
                self.failed = Some(e);
                Err(e)
            }
        }
    }

    /// Runs what is left and returns the plan the search settled on.
    pub fn finish(mut self) -> Result<ChancePlan, PlanError> {
        while self.step()?.is_some() {}
        // Every ending sets `last`.
        self.last.ok_or(PlanError::Unreachable)
    }

    /// Judges the finished round's plan: done when it keeps the bound (or no path exists even
    /// without margins); otherwise the margins grow (or back off after a round without a path)
    /// and the next round starts. Never inlined, so its locals are not on the stack while a
    /// form is planned.
    #[inline(never)]
    fn end_round(&mut self) -> Result<(), PlanError> {
        let Some(session) = self.session.take() else {
            return Ok(());
        };
        let planned = session.scheduled_so_far();
        let mut by_obstacle = [ObstacleRisk::default(); MAX_OBSTACLES];
        let risk = match &planned.schedule {
            Some(Ok(s)) => Some(risk_by_obstacle(
                &self.scenario,
                s,
                &self.model,
                self.execution,
                &mut by_obstacle,
            )),
            _ => None,
        };
        let within_bound = risk.is_some_and(|r| r.collision_probability <= self.bound);
        let outcome = ChancePlan {
            planned,
            risk,
            margins: self.margins,
            rounds: self.round,
            within_bound,
        };
        if within_bound {
            self.last = Some(outcome);
            return Ok(());
        }
        if risk.is_none() {
            let Some(last) = self.last.as_mut() else {
                self.last = Some(outcome); // no path even without margins
                return Ok(());
            };
            last.rounds = self.round;
            if self.margins == self.found {
                return self.conclude();
            }
            for (m, f) in self.margins.iter_mut().zip(&self.found) {
                *m = 0.5 * (*m + f);
            }
            return self.next_round();
        }
        self.found = self.margins;
        self.last = Some(outcome);
        if !raise_margins(&self.scenario, self.bound, &by_obstacle, &mut self.margins) {
            return self.conclude();
        }
        self.next_round()
    }

    fn next_round(&mut self) -> Result<(), PlanError> {
        if self.round >= MAX_ROUNDS {
            return self.conclude();
        }
        self.round += 1;
        self.session = Some(PlanSession::new(grown(&self.scenario, &self.margins))?);
        Ok(())
    }

    /// Ends the search on the last round that found a path.
    fn conclude(&mut self) -> Result<(), PlanError> {
        let last = self.last.as_mut().ok_or(PlanError::Unreachable)?;
        within_bound_by_another_form(
            &self.scenario,
            &self.model,
            self.bound,
            self.execution,
            last,
        );
        Ok(())
    }
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
