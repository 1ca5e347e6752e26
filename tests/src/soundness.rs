//! The soundness check shared by the planner's property test and its fuzz target: `plan`
//! refuses exactly what validation refuses, every form it reports feasible passes the reference's
//! f64 re-check (end point, every clearance, bounds; no code shared with the core), the best form
//! is feasible, its schedule passes the nominal check, and the work done stays under a bound.

use crate::reference::{evaluate_outcome, is_feasible};
use planner_core::execute::nominal;
use planner_core::{plan_scheduled, Scenario};

/// Path evaluations one plan may make at most (all forms, seeds and solves together). The
/// heaviest scenarios seen (32 spheres in 3-D, every form) stay an order of magnitude below.
pub const MAX_EVALUATIONS: u32 = 2_000_000;

/// Plans `s` and checks the plan against validation and the f64 reference; `Err` says what broke.
pub fn check_plan(s: &Scenario) -> Result<(), String> {
    let valid = s.validate();
    match plan_scheduled(s) {
        Err(e) => match valid {
            Err(v) if v != e => Err(format!("plan refused with {e:?}, validation with {v:?}")),
            _ => Ok(()),
        },
        Ok(planned) => {
            if let Err(v) = valid {
                return Err(format!("an invalid scenario was planned: {v:?}"));
            }
            let evaluations = planned.report.evaluations();
            if evaluations > MAX_EVALUATIONS {
                return Err(format!(
                    "{evaluations} evaluations (bound {MAX_EVALUATIONS})"
                ));
            }
            // The report gives the insertion angles as f32 degrees, rounded by up to 5e-7 degrees
            // each: a posture the optimiser put on the tilt bound may lie that far beyond it when
            // the reported numbers are measured in f64 (found by the property test: 10.0000005
            // degrees for a 10-degree bound), so the f64 check widens the cone by 1e-5 degrees.
            let mut rounded = s.clone();
            rounded.entry.max_tilt_deg += 1e-5;
            for o in planned.report.forms.iter().filter(|o| o.feasible) {
                let ev = evaluate_outcome(&rounded, o);
                if !is_feasible(&rounded, &ev) {
                    return Err(format!("{} fails the f64 check: {ev:?}", o.form));
                }
            }
            match planned.report.best() {
                Some(best) if best.feasible => {}
                None if planned.report.forms.iter().all(|o| !o.feasible) => {
                    // Unreachable: every form's outcome is reported, and there is nothing to
                    // execute.
                    return match planned.schedule {
                        None => Ok(()),
                        Some(s) => Err(format!("a plan with no best form has a schedule: {s:?}")),
                    };
                }
                other => return Err(format!("the best form is not feasible: {other:?}")),
            }
            let schedule = match planned.schedule.as_ref() {
                Some(Ok(schedule)) => schedule,
                other => return Err(format!("a plan without a schedule: {other:?}")),
            };
            let check = nominal::check(s, schedule);
            if !check.feasible {
                return Err(format!("the schedule fails the nominal check: {check:?}"));
            }
            Ok(())
        }
    }
}
