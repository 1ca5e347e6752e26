//! The typed `needle sweep --json` report: per swept value, the best form's figures and every
//! form's F and L. Numbers follow the plan report's rules (see [`super::json`]).

use super::json::{finite, write_sorted};
use planner_core::{FormOutcome, PlanError, PlanReport};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The `needle sweep --json` object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepJson {
    /// The swept weight's name (`length`, `risk`, `penalty` or `control`).
    pub weight: String,
    /// One entry per value, in sweep order.
    pub points: Vec<SweepPointJson>,
}

/// One value of the sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPointJson {
    /// The weight's value.
    pub value: f64,
    /// The best form at this value, `null` without a plan.
    pub best: Option<SweepBestJson>,
    /// Every form tried (empty without a plan).
    pub forms: Vec<SweepFormJson>,
    /// Why there is no plan, when there is none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// `best` of a sweep point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepBestJson {
    /// The form word.
    pub form: String,
    /// N.
    pub control_degree: usize,
    /// L (mm).
    pub length: Option<f64>,
    /// D.
    pub risk: Option<f64>,
    /// F.
    pub objective: Option<f64>,
}

/// One form at a sweep point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepFormJson {
    /// F, `null` when infeasible.
    pub objective: Option<f64>,
    /// L (mm), `null` when infeasible.
    pub length: Option<f64>,
    /// The form word.
    pub form: String,
    /// Whether it has a path.
    pub feasible: bool,
}

impl SweepPointJson {
    /// The entry for `value` and what the planner made of it.
    pub fn new(value: f64, plan: &Result<PlanReport, PlanError>) -> SweepPointJson {
        let report = plan.as_ref().ok();
        SweepPointJson {
            value,
            best: report.and_then(PlanReport::best).map(SweepBestJson::of),
            forms: report
                .iter()
                .flat_map(|r| r.forms.iter())
                .map(SweepFormJson::of)
                .collect(),
            error: plan.as_ref().err().map(ToString::to_string),
        }
    }
}

impl SweepBestJson {
    fn of(b: &FormOutcome) -> SweepBestJson {
        SweepBestJson {
            form: b.form.to_string(),
            control_degree: b.form.len(),
            length: finite(b.length),
            risk: finite(b.risk),
            objective: finite(b.objective),
        }
    }
}

impl SweepFormJson {
    fn of(o: &FormOutcome) -> SweepFormJson {
        let number = |v: f32| finite(v).filter(|_| o.feasible);
        SweepFormJson {
            form: o.form.to_string(),
            feasible: o.feasible,
            objective: number(o.objective),
            length: number(o.length),
        }
    }
}

impl fmt::Display for SweepJson {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_sorted(self, f)
    }
}
