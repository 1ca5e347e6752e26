//! A plan with the motor schedule of its best form: what a device answers when a plan finishes,
//! and what the host computes from the same scenario to compare with it.

use super::schedule::{schedule, Schedule, ScheduleError};
use crate::model::scenario::Scenario;
use crate::report::PlanReport;
use serde::{Deserialize, Serialize};

/// The planner's report and the schedule of its best form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScheduledPlan {
    /// Every form tried and the best named.
    pub report: PlanReport,
    /// What the driver executes for the best form, or why it cannot; `None` when the report has
    /// no best form (the driver is validated with the scenario, so this is `Some(Ok(_))` for any
    /// report with a best form the planner makes).
    pub schedule: Option<Result<Schedule, ScheduleError>>,
}

impl ScheduledPlan {
    /// `report` with the schedule of its best form under the scenario's driver.
    ///
    /// ```
    /// use planner_core::execute::ScheduledPlan;
    /// use planner_core::{plan, Scenario};
    ///
    /// let scenario = Scenario::paper();
    /// let planned = ScheduledPlan::new(&scenario, plan(&scenario).unwrap());
    /// assert!(planned.schedule.unwrap().unwrap().duration_s > 0.0);
    /// ```
    pub fn new(scenario: &Scenario, report: PlanReport) -> ScheduledPlan {
        let schedule = report.best().map(|best| schedule(scenario, best));
        ScheduledPlan { report, schedule }
    }
}
