//! Weight robustness sweeps (the paper's Figures 6-8 and Table 2): re-plan the scenario for each
//! value of one weight, the others fixed, and report the best form, L, D, N and F per value.

use super::parallel;
use anyhow::{bail, Result};
use needle_report::sweep::{SweepJson, SweepPointJson};
use planner_core::model::form::FormSet;
use planner_core::{Form, PlanError, PlanReport, Scenario};
use std::fmt;

/// Which weight of F = a1 L + a2 D + a3 H + a4 N is swept (by its name or by a1..a4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weight {
    /// a1
    Length,
    /// a2
    Risk,
    /// a3
    Penalty,
    /// a4
    Control,
}

impl Weight {
    /// Every weight, in the order of F's terms.
    pub const ALL: [Weight; 4] = [
        Weight::Length,
        Weight::Risk,
        Weight::Penalty,
        Weight::Control,
    ];

    /// The weight `name` names (`length` or `a1`, ..., any case), as `--weight` reads it.
    pub fn parse(name: &str) -> Option<Weight> {
        Weight::ALL
            .into_iter()
            .find(|w| w.name().eq_ignore_ascii_case(name) || w.alias().eq_ignore_ascii_case(name))
    }

    /// The coefficient's name in F: a1 to a4.
    pub fn alias(self) -> &'static str {
        match self {
            Weight::Length => "a1",
            Weight::Risk => "a2",
            Weight::Penalty => "a3",
            Weight::Control => "a4",
        }
    }

    /// Name as in the scenario file's `[weights]`.
    pub fn name(self) -> &'static str {
        match self {
            Weight::Length => "length",
            Weight::Risk => "risk",
            Weight::Penalty => "penalty",
            Weight::Control => "control",
        }
    }

    /// The scenario with this weight set to `value`.
    pub fn apply(self, scenario: &Scenario, value: f64) -> Scenario {
        let mut s = scenario.clone();
        let w = &mut s.weights;
        let slot = match self {
            Weight::Length => &mut w.length,
            Weight::Risk => &mut w.risk,
            Weight::Penalty => &mut w.penalty,
            Weight::Control => &mut w.control,
        };
        *slot = value as f32;
        s
    }
}

impl fmt::Display for Weight {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The most values one sweep visits: each is a whole plan, so more is a typing slip, not a study.
pub const MAX_SWEEP_STEPS: usize = 10_000;

/// The values a sweep visits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// First value.
    pub from: f64,
    /// Last value.
    pub to: f64,
    /// Number of values (both ends included).
    pub steps: usize,
    /// Spaced evenly in log10 rather than linearly.
    pub log: bool,
}

impl Range {
    /// The values, checked: finite, not negative, positive for a log range, at least one step.
    pub fn values(&self) -> Result<Vec<f64>> {
        let Range {
            from,
            to,
            steps,
            log,
        } = *self;
        if !from.is_finite() || !to.is_finite() {
            bail!("--from and --to must be finite numbers");
        }
        if from < 0.0 || to < 0.0 {
            bail!("weights cannot be negative (--from {from}, --to {to})");
        }
        if log && (from <= 0.0 || to <= 0.0) {
            bail!("a --log sweep needs --from and --to above zero");
        }
        if steps == 0 || steps > MAX_SWEEP_STEPS {
            bail!("--steps is {steps}: it must be 1 to {MAX_SWEEP_STEPS}");
        }
        if steps == 1 {
            return Ok(vec![from]);
        }
        let at = |k: usize| {
            let t = k as f64 / (steps - 1) as f64;
            if k + 1 == steps {
                to
            } else if log {
                10f64.powf(from.log10() + t * (to.log10() - from.log10()))
            } else {
                from + t * (to - from)
            }
        };
        Ok((0..steps).map(at).collect())
    }
}

/// One value of a sweep and what the planner made of it.
#[derive(Clone, Debug)]
pub struct Point {
    /// The weight's value.
    pub value: f64,
    /// The plan, or why there is none.
    pub plan: Result<PlanReport, PlanError>,
}

impl Point {
    /// The best form's outcome, when there is a plan.
    pub fn best(&self) -> Option<&planner_core::FormOutcome> {
        self.plan.as_ref().ok().and_then(|r| r.best())
    }
}

/// Plans `scenario` with `weight` at each value of `range`, on `threads` threads; `done` is
/// called after each value (for a progress bar).
pub fn run(
    scenario: &Scenario,
    weight: Weight,
    range: &Range,
    threads: usize,
    done: impl Fn() + Sync,
) -> Result<Vec<Point>> {
    let values = range.values()?;
    // Fail early and clearly if the scenario itself is wrong, rather than once per point.
    weight.apply(scenario, values[0]).validate()?;
    Ok(parallel::map(
        &values,
        threads,
        |&value| Point {
            value,
            plan: planner_core::plan(&weight.apply(scenario, value)),
        },
        done,
    ))
}

/// The `needle sweep --json` report.
pub fn to_json(weight: Weight, points: &[Point]) -> SweepJson {
    SweepJson {
        weight: weight.name().to_string(),
        points: points
            .iter()
            .map(|p| SweepPointJson::new(p.value, &p.plan))
            .collect(),
    }
}

/// Every form that appears in any point, in catalogue order.
pub fn forms_seen(points: &[Point]) -> Vec<Form> {
    let mut set = FormSet::default();
    for r in points.iter().filter_map(|p| p.plan.as_ref().ok()) {
        for o in &r.forms {
            set.insert(o.form);
        }
    }
    set.iter().collect()
}

fn objective_of(p: &Point, form: Form) -> Option<f32> {
    let r = p.plan.as_ref().ok()?;
    let o = r.forms.iter().find(|o| o.form == form)?;
    (o.feasible && o.objective.is_finite()).then_some(o.objective)
}

/// CSV: one row per value with the best form's figures, then each form's F (empty if infeasible).
pub fn to_csv(weight: Weight, points: &[Point]) -> String {
    let forms = forms_seen(points);
    let mut s = format!(
        "{},best_form,control_degree,length,risk,objective",
        weight.name()
    );
    for f in &forms {
        s.push_str(&format!(",F_{f}"));
    }
    s.push('\n');
    for p in points {
        s.push_str(&format!("{}", p.value));
        match p.best() {
            Some(b) => s.push_str(&format!(
                ",{},{},{},{},{}",
                b.form,
                b.form.len(),
                b.length,
                b.risk,
                b.objective
            )),
            None => s.push_str(",,,,,"),
        }
        for f in &forms {
            s.push(',');
            if let Some(v) = objective_of(p, *f) {
                s.push_str(&v.to_string());
            }
        }
        s.push('\n');
    }
    s
}

/// The table printed by `needle sweep`.
pub fn to_table(weight: Weight, points: &[Point]) -> String {
    let forms = forms_seen(points);
    let mut s = format!(
        "{:>12} {:<5} {:>2} {:>9} {:>8} {:>10}",
        weight.name(),
        "best",
        "N",
        "L (mm)",
        "D",
        "F"
    );
    for f in &forms {
        s.push_str(&format!(" {:>9}", format!("F({f})")));
    }
    s.push('\n');
    for p in points {
        s.push_str(&format!(
            "{:>12}",
            format!("{:.6}", p.value)
                .trim_end_matches('0')
                .trim_end_matches('.')
        ));
        match (p.best(), &p.plan) {
            (Some(b), _) => s.push_str(&format!(
                " {:<5} {:>2} {:>9.2} {:>8.4} {:>10.3}",
                b.form.to_string(),
                b.form.len(),
                b.length,
                b.risk,
                b.objective
            )),
            (None, Err(e)) => s.push_str(&format!("  no plan: {e}")),
            (None, Ok(_)) => s.push_str("  no plan"),
        }
        if p.plan.is_ok() {
            for f in &forms {
                match objective_of(p, *f) {
                    Some(v) => s.push_str(&format!(" {v:>9.3}")),
                    None => s.push_str(&format!(" {:>9}", "-")),
                }
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_include_both_ends() {
        let lin = Range {
            from: 0.0,
            to: 10.0,
            steps: 11,
            log: false,
        }
        .values()
        .unwrap();
        assert_eq!(lin.len(), 11);
        assert_eq!(lin[0], 0.0);
        assert_eq!(lin[10], 10.0);
        assert!((lin[3] - 3.0).abs() < 1e-12);
        let log = Range {
            from: 1.0,
            to: 1e9,
            steps: 10,
            log: true,
        }
        .values()
        .unwrap();
        assert_eq!(log[9], 1e9);
        assert!((log[3] - 1e3).abs() < 1e-6);
        assert!(Range {
            from: 0.0,
            to: 1.0,
            steps: 3,
            log: true
        }
        .values()
        .is_err());
        assert!(Range {
            from: -1.0,
            to: 1.0,
            steps: 3,
            log: false
        }
        .values()
        .is_err());
        assert!(Range {
            from: 1.0,
            to: 2.0,
            steps: 0,
            log: false
        }
        .values()
        .is_err());
        assert_eq!(
            Range {
                from: 2.0,
                to: 5.0,
                steps: 1,
                log: false
            }
            .values()
            .unwrap(),
            vec![2.0]
        );
    }

    #[test]
    fn weight_names_round_trip_and_apply_only_their_slot() {
        let s = Scenario::paper();
        for w in Weight::ALL {
            assert_eq!(Weight::parse(w.name()), Some(w));
            let t = w.apply(&s, 7.5);
            let changed = [
                t.weights.length != s.weights.length,
                t.weights.risk != s.weights.risk,
                t.weights.penalty != s.weights.penalty,
                t.weights.control != s.weights.control,
            ];
            assert_eq!(changed.iter().filter(|c| **c).count(), 1, "{w}");
        }
        assert_eq!(Weight::parse("A3"), Some(Weight::Penalty));
        assert_eq!(Weight::parse("RISK"), Some(Weight::Risk));
        assert_eq!(Weight::parse("alpha"), None);
    }
}
