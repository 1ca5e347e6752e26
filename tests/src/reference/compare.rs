//! Compares one form's planner outcome with the reference optimum and says what disagrees.

use super::problem::Problem;
use super::{evaluate_outcome, is_feasible, RefSolution};
use planner_core::{FormOutcome, Scenario};

/// The tolerance on F: 1e-3 |F| + 0.01.
pub fn tolerance(f: f64) -> f64 {
    1e-3 * f.abs() + 0.01
}

/// A disagreement between the planner and the reference on one form.
#[derive(Clone, Debug)]
pub enum Mismatch {
    /// The reference found a feasible path; the planner reports none.
    PlannerMissedFeasible,
    /// The planner's optimum is worse than the reference's beyond the tolerance.
    PlannerSuboptimal,
    /// A path the planner reports feasible fails the reference's f64 check.
    PlannerPathInfeasible,
    /// The planner's reported F differs from the f64 F of its own path.
    PlannerObjectiveWrong,
    /// The planner found a valid path better than the reference's: the reference missed it.
    ReferenceMissed,
}

/// One form's comparison, with both sides written out for a report.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The disagreement, if any.
    pub mismatch: Option<Mismatch>,
    /// What both sides found, for the report.
    pub detail: String,
}

fn describe(outcome: &FormOutcome) -> String {
    let mut s = format!(
        "{} F={:.4} L={:.4} D={:.5} minclr={:.3} err={:.2e} theta=({:.4},{:.4})deg segs=[",
        outcome.form,
        outcome.objective,
        outcome.length,
        outcome.risk,
        outcome.min_clearance,
        outcome.target_error,
        outcome.insertion.theta1_deg,
        outcome.insertion.theta2_deg
    );
    for seg in &outcome.segments {
        s += &format!(
            " {}:{:.4}@{:.2}",
            seg.kind.letter(),
            seg.length,
            seg.bevel_deg
        );
    }
    s + " ]"
}

/// Compares the planner's outcome for a form with the reference's optimum (`None`: infeasible).
pub fn compare(
    scenario: &Scenario,
    outcome: &FormOutcome,
    reference: Option<&RefSolution>,
) -> Comparison {
    let planner_text = if outcome.feasible {
        describe(outcome)
    } else {
        format!("{} infeasible ({:?})", outcome.form, outcome.status)
    };
    let ref_text = reference.map_or("infeasible".to_string(), |r| r.to_string());
    let mut detail = format!("planner:   {planner_text}\nreference: {ref_text}");
    let mut mismatch = None;
    let ev = evaluate_outcome(scenario, outcome);
    if outcome.feasible {
        detail += &format!(
            "\nplanner path in f64: F={:.4} err={:.2e} minclr={:.4} bounds={}",
            ev.objective, ev.target_error, ev.min_clearance, ev.within_bounds
        );
        if !is_feasible(scenario, &ev) {
            mismatch = Some(Mismatch::PlannerPathInfeasible);
        } else if (ev.objective - f64::from(outcome.objective)).abs() > tolerance(ev.objective) {
            mismatch = Some(Mismatch::PlannerObjectiveWrong);
        }
    }
    if mismatch.is_none() {
        mismatch = match (outcome.feasible, reference) {
            (false, Some(_)) => Some(Mismatch::PlannerMissedFeasible),
            (true, None) => Some(Mismatch::ReferenceMissed),
            (true, Some(r)) => {
                let f = f64::from(outcome.objective);
                // The planner may end up to its tolerance short of the target: allow that length.
                let slack =
                    tolerance(r.objective) + f64::from(scenario.weights.length) * ev.target_error;
                if f > r.objective + tolerance(r.objective) {
                    Some(Mismatch::PlannerSuboptimal)
                } else if f < r.objective - slack {
                    // Ill-conditioned optima (a clearance of hundredths of a mm) can gain more
                    // than the slack from the planner's end error alone: solve again for the
                    // planner's actual end point before blaming the reference.
                    let mut moved = Problem::new(scenario);
                    moved.target = ev.end;
                    let again = super::solve_problem(&moved, outcome.form, super::Effort(1.0));
                    detail += &format!(
                        "\nreference for the planner's end point: {}",
                        again
                            .as_ref()
                            .map_or("infeasible".into(), |a| a.to_string())
                    );
                    match again {
                        Some(a) if f >= a.objective - tolerance(a.objective) => None,
                        _ => Some(Mismatch::ReferenceMissed),
                    }
                } else {
                    None
                }
            }
            (false, None) => None,
        };
    }
    Comparison { mismatch, detail }
}

/// One scenario's comparison over every form the scenario selects.
#[derive(Clone, Debug)]
pub struct ScenarioReport {
    /// Per form: the planner's outcome, the reference's optimum and their comparison.
    pub forms: Vec<(FormOutcome, Option<RefSolution>, Comparison)>,
    /// `plan` refused the scenario (a plan with no feasible form is not an error: its forms are
    /// compared like any others).
    pub plan_error: Option<planner_core::PlanError>,
}

impl ScenarioReport {
    /// The forms that disagree.
    pub fn mismatches(
        &self,
    ) -> impl Iterator<Item = &(FormOutcome, Option<RefSolution>, Comparison)> {
        self.forms.iter().filter(|f| f.2.mismatch.is_some())
    }
}

/// How the planner is asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ask {
    /// One `plan` call for every selected form (the default use).
    AllForms,
    /// One `plan` call per form, restricted to it (`--forms RL`).
    EachForm,
}

/// Plans `scenario` with the planner and with the reference, and compares every selected form.
pub fn compare_scenario(scenario: &Scenario, effort: super::Effort, ask: Ask) -> ScenarioReport {
    let selected: Vec<planner_core::Form> = scenario.options.selected_forms().iter().collect();
    compare_forms(scenario, &selected, effort, ask)
}

/// Like [`compare_scenario`] for the listed forms only (the planner still plans every selected
/// form when asked [`Ask::AllForms`]).
pub fn compare_forms(
    scenario: &Scenario,
    selected: &[planner_core::Form],
    effort: super::Effort,
    ask: Ask,
) -> ScenarioReport {
    let mut plan_error = None;
    let mut outcomes: Vec<Option<FormOutcome>> = Vec::new();
    match ask {
        Ask::AllForms => match planner_core::plan(scenario) {
            Ok(report) => {
                for f in selected {
                    outcomes.push(report.forms.iter().find(|o| o.form == *f).cloned());
                }
            }
            Err(e) => {
                plan_error = Some(e);
                outcomes = vec![None; selected.len()];
            }
        },
        Ask::EachForm => {
            for f in selected {
                let mut one = scenario.clone();
                one.options.forms = planner_core::FormSet::default();
                one.options.forms.insert(*f);
                match planner_core::plan(&one) {
                    Ok(report) => {
                        outcomes.push(report.forms.iter().find(|o| o.form == *f).cloned())
                    }
                    Err(e) => {
                        plan_error = Some(e);
                        outcomes.push(None);
                    }
                }
            }
        }
    }
    let mut forms = Vec::new();
    for (&form, outcome) in selected.iter().zip(outcomes) {
        let reference = super::solve_form(scenario, form, effort);
        let outcome = outcome.unwrap_or_else(|| FormOutcome::infeasible(form));
        let cmp = compare(scenario, &outcome, reference.as_ref());
        forms.push((outcome, reference, cmp));
    }
    ScenarioReport { forms, plan_error }
}

/// The scenario's numbers on a few lines, enough to rebuild it in a report.
pub fn describe_scenario(s: &Scenario) -> String {
    let mut t = format!(
        "{:?} rho={} max_arc={}deg max_line={} tilt<={}deg entry={:?} dir={:?} target={:?} tol={}\n\
         weights L={} D={} N={} risk={:?} min_clearance={}\nobstacles:",
        s.options.workspace,
        s.needle.curvature_radius,
        s.needle.max_arc_deg,
        s.needle.max_line_length,
        s.entry.max_tilt_deg,
        s.entry.position,
        s.entry.direction,
        s.target.position,
        s.target.tolerance,
        s.weights.length,
        s.weights.risk,
        s.weights.control,
        s.options.risk,
        s.options.min_clearance
    );
    for o in &s.obstacles {
        t += &format!(" ({:?} r={})", o.center, o.radius);
    }
    t
}

/// Totals over many scenarios.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Scenarios compared.
    pub scenarios: usize,
    /// Forms compared.
    pub forms: usize,
    /// Forms the reference found feasible.
    pub feasible: usize,
    /// Forms where the planner is worse than the reference by more than 0.01 (within tolerance).
    pub near_misses: usize,
    /// Largest F(planner) - F(reference) over forms both solved without a mismatch.
    pub worst_gap: f64,
    /// Full text of every disagreement.
    pub mismatches: Vec<String>,
    /// Scenarios whose overall best ("player killing") is worse than the reference's best.
    pub best_worse: usize,
}

impl core::fmt::Display for Summary {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} scenarios, {} forms ({} feasible): {} mismatches, {} near misses (gap > 0.01), \
             worst tolerated gap {:.4}; overall best worse than the reference's in {} scenarios",
            self.scenarios,
            self.forms,
            self.feasible,
            self.mismatches.len(),
            self.near_misses,
            self.worst_gap,
            self.best_worse
        )
    }
}

/// Compares every named scenario, printing each disagreement and near miss as it goes.
pub fn run_suite(
    scenarios: impl IntoIterator<Item = (String, Scenario)>,
    effort: super::Effort,
    ask: Ask,
) -> Summary {
    let mut sum = Summary::default();
    for (name, s) in scenarios {
        let rep = compare_scenario(&s, effort, ask);
        sum.scenarios += 1;
        let planner_best = rep
            .forms
            .iter()
            .filter(|f| f.0.feasible)
            .map(|f| f64::from(f.0.objective))
            .fold(f64::INFINITY, f64::min);
        let ref_best = rep
            .forms
            .iter()
            .filter_map(|f| f.1.as_ref().map(|r| r.objective))
            .fold(f64::INFINITY, f64::min);
        if ref_best.is_finite() && planner_best > ref_best + tolerance(ref_best) {
            sum.best_worse += 1;
            println!("*** {name}: overall best F {planner_best:.4} (planner) vs {ref_best:.4} (reference)");
        }
        for (o, r, c) in &rep.forms {
            sum.forms += 1;
            sum.feasible += usize::from(r.is_some());
            let gap = r
                .as_ref()
                .filter(|_| o.feasible)
                .map(|r| f64::from(o.objective) - r.objective);
            let text = format!(
                "--- {name}, form {}, {ask:?}: {}\n{}\n{}",
                o.form,
                c.mismatch
                    .as_ref()
                    .map_or("near miss".to_string(), |m| format!("{m:?}")),
                describe_scenario(&s),
                c.detail
            );
            if c.mismatch.is_some() {
                println!("{text}");
                sum.mismatches.push(text);
            } else if let Some(g) = gap {
                sum.worst_gap = sum.worst_gap.max(g);
                if g > 0.01 {
                    sum.near_misses += 1;
                    println!("{text}");
                }
            }
        }
    }
    println!("{sum}");
    sum
}
