//! Path classification (the best path of each form) and player killing (the best form).
//!
//! [`PlanSession`] plans one form per [`PlanSession::step`], so a device can report progress and
//! honour a cancel request between forms; [`plan`] runs a session to the end.

use crate::error::PlanError;
use crate::execute::plan_with_schedule::ScheduledPlan;
use crate::model::form::FormSet;
use crate::model::scenario::Scenario;
use crate::report::{FormOutcome, FormOutcomes, PlanReport};
use crate::search::solve::solve_form;

/// A planning run in progress.
pub struct PlanSession {
    scenario: Scenario,
    remaining: FormSet,
    outcomes: FormOutcomes,
}

impl PlanSession {
    /// Validates the scenario and prepares to plan its selected forms.
    pub fn new(scenario: Scenario) -> Result<Self, PlanError> {
        scenario.validate()?;
        Ok(PlanSession {
            remaining: scenario.options.selected_forms(),
            scenario,
            outcomes: FormOutcomes::new(),
        })
    }

    /// The scenario being planned.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Number of forms this session plans.
    pub fn form_count(&self) -> usize {
        self.outcomes.len() + self.remaining.iter().count()
    }

    /// Plans the next form and returns its outcome; `None` once every form is done.
    ///
    /// ```
    /// use planner_core::{PlanSession, Scenario};
    ///
    /// let mut session = PlanSession::new(Scenario::paper()).unwrap();
    /// let forms = session.form_count();
    /// let mut words = Vec::new();
    /// // One form per step: a device reports progress, or honours a cancel, in between.
    /// while let Some(outcome) = session.step() {
    ///     words.push(outcome.form.word());
    /// }
    /// assert_eq!(words.len(), forms);
    /// assert_eq!((words[0].as_str(), words[1].as_str()), ("R", "L"));
    /// let report = session.finish();
    /// assert_eq!(report.best().unwrap().form.word().as_str(), "RL");
    /// ```
    pub fn step(&mut self) -> Option<&FormOutcome> {
        let form = self.remaining.iter().next()?;
        self.remaining.0 &= !(1 << form.index());
        let outcome = solve_form(&self.scenario, form, &self.outcomes);
        // Capacity is the catalogue size and each form is planned once.
        self.outcomes.push(outcome).ok()?;
        self.outcomes.last()
    }

    /// Plans what is left and picks the best feasible form (none when no form is feasible: the
    /// report still tells how every form ended).
    pub fn finish(mut self) -> PlanReport {
        self.conclude()
    }

    /// Plans what is left, picks the best feasible form and builds its motor schedule (what a
    /// device answers).
    pub fn finish_scheduled(mut self) -> ScheduledPlan {
        let report = self.conclude();
        ScheduledPlan::new(&self.scenario, report)
    }

    /// Builds the best planned form's motor schedule from the forms planned so far, planning
    /// none: what a device answers once [`PlanSession::step`] has returned `None`. Leaving the
    /// solver out keeps its frames off the stack under the device's result encoding.
    pub fn scheduled_so_far(mut self) -> ScheduledPlan {
        let report = self.report_so_far();
        ScheduledPlan::new(&self.scenario, report)
    }

    /// Plans what is left and moves the outcomes into the report of the best feasible form.
    fn conclude(&mut self) -> PlanReport {
        while self.step().is_some() {}
        self.report_so_far()
    }

    /// Moves the outcomes planned so far into the report of the best feasible one.
    fn report_so_far(&mut self) -> PlanReport {
        let mut best: Option<usize> = None;
        for (i, o) in self.outcomes.iter().enumerate() {
            let better = match best {
                None => true,
                Some(b) => o.objective < self.outcomes[b].objective,
            };
            if o.feasible && better {
                best = Some(i);
            }
        }
        PlanReport {
            forms: core::mem::take(&mut self.outcomes),
            best: best.map(|b| b as u8),
        }
    }
}

/// Plans every selected form of `scenario` and returns the per-form table and the best plan (if
/// any form is feasible). `Err` only for a scenario that cannot be planned (invalid input).
pub fn plan(scenario: &Scenario) -> Result<PlanReport, PlanError> {
    Ok(PlanSession::new(scenario.clone())?.finish())
}

/// Plans `scenario` and builds the best form's motor schedule: exactly what a device answers.
pub fn plan_scheduled(scenario: &Scenario) -> Result<ScheduledPlan, PlanError> {
    Ok(PlanSession::new(scenario.clone())?.finish_scheduled())
}
