//! Path classification (the best path of each form) and player killing (the best form).
//!
//! [`PlanSession`] plans one form per [`PlanSession::step`], so a device can report progress and
//! honour a cancel request between forms; [`plan`] runs a session to the end.

use crate::error::PlanError;
use crate::execute::plan_with_schedule::ScheduledPlan;
use crate::model::form::FormSet;
use crate::model::scenario::{
    Driver, Entry, Needle, Obstacles, PlannerOptions, RiskMeasure, Scenario, Target, Weights,
    Workspace,
};
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
        let mut session = PlanSession::idle();
        session.scenario = scenario;
        session.restart()?;
        Ok(session)
    }

    /// A session with nothing to plan and a scenario of zeros. Every byte is zero, so a device
    /// whose session lives in a static keeps it in `.bss`, and fills it in place
    /// ([`PlanSession::scenario_mut`], [`PlanSession::restart`]): a scenario moved in by value
    /// would pass through the stack, 16 bytes a sphere, more than once.
    pub(crate) const fn idle() -> PlanSession {
        let zero = [0.0; 3];
        PlanSession {
            scenario: Scenario {
                needle: Needle {
                    curvature_radius: 0.0,
                    max_arc_deg: 0.0,
                    max_line_length: 0.0,
                    length: 0.0,
                },
                entry: Entry {
                    position: zero,
                    direction: zero,
                    max_tilt_deg: 0.0,
                },
                target: Target {
                    position: zero,
                    tolerance: 0.0,
                },
                obstacles: Obstacles::new(),
                weights: Weights {
                    length: 0.0,
                    risk: 0.0,
                    penalty: 0.0,
                    control: 0.0,
                },
                options: PlannerOptions {
                    max_control_degree: 0,
                    forms: FormSet(0),
                    workspace: Workspace::Space,
                    risk: RiskMeasure::Mean,
                    min_clearance: 0.0,
                    curvature_reserve: 0.0,
                    risk_within_mm: None,
                },
                driver: Driver {
                    insert_speed: 0.0,
                    rotate_speed: 0.0,
                    spin_rate: 0.0,
                    max_twist_deg: 0.0,
                },
            },
            remaining: FormSet(0),
            outcomes: FormOutcomes::new(),
        }
    }

    /// Validates the scenario as it now is and prepares to plan its selected forms, forgetting
    /// what was planned before. On an error nothing is left to plan.
    pub(crate) fn restart(&mut self) -> Result<(), PlanError> {
        self.remaining = FormSet(0);
        self.outcomes.clear();
        self.scenario.validate()?;
        self.remaining = self.scenario.options.selected_forms();
        Ok(())
    }

    /// The scenario being planned.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The scenario, to change in place before [`PlanSession::restart`].
    pub(crate) fn scenario_mut(&mut self) -> &mut Scenario {
        &mut self.scenario
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
        self.take_scheduled()
    }

    /// [`PlanSession::scheduled_so_far`] leaving the session (and its scenario) in place, with
    /// no form planned and none left.
    pub(crate) fn take_scheduled(&mut self) -> ScheduledPlan {
        self.remaining = FormSet(0);
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
