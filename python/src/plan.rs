//! `plan()`: `needle plan` on a scenario, returning its JSON report (the command's, through the
//! same code) and the best path's points as an array.

use crate::convert::{points_array, python_value};
use crate::errors::{guarded, plan_error, scenario_error, ScenarioError};
use crate::scenario::Scenario;
use needle_report::local::plan_locally;
use needle_report::PlanJson;
use needle_scenario::restrict;
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyString;
use serde_json::Value;

/// What `plan` hands the Python side: the JSON report as text and as Python objects (without
/// `best.points`, given apart as an `(n, 3)` array), and why the command would exit 1 after
/// printing the report (no feasible form, no plan within the collision bound), if it would.
pub type Planned<'py> = (
    String,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyArray2<f64>>>,
    Option<String>,
);

/// A report as `plan` hands it over, with `verdict`: why the command would fail after printing it.
pub fn planned<'py>(
    py: Python<'py>,
    json: &PlanJson,
    verdict: Option<String>,
) -> PyResult<Planned<'py>> {
    // The command prints this value: its keys sorted.
    let mut value = serde_json::to_value(json).map_err(|e| plan_error(&e.into()))?;
    let text = value.to_string();
    if let Some(best) = value.get_mut("best").and_then(Value::as_object_mut) {
        best.remove("points");
    }
    let report = python_value(py, &value)?;
    let points = json.best.as_ref().and_then(|b| b.path.points.as_deref());
    let points = points.map(|p| points_array(py, p)).transpose()?;
    Ok((text, report, points, verdict))
}

/// The forms asked for: a list of words or one comma-separated string, as `--forms` takes them.
pub fn form_words(forms: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if let Ok(s) = forms.cast::<PyString>() {
        return Ok(s.to_cow()?.split(',').map(str::to_string).collect());
    }
    forms.extract().map_err(|_| {
        ScenarioError::new_err(
            "forms: a list of form words such as [\"RL\", \"LRL\"], or \"RL,LRL\"",
        )
    })
}

/// `--max-degree`'s value, with clap's message for one out of range.
pub fn degree(max_degree: Option<i64>) -> PyResult<Option<u8>> {
    max_degree
        .map(|n| {
            u8::try_from(n).map_err(|e| {
                ScenarioError::new_err(format!(
                    "invalid value '{n}' for '--max-degree <MAX_DEGREE>': {e}"
                ))
            })
        })
        .transpose()
}

/// Plans `scenario` as `needle plan` does.
#[pyfunction]
#[pyo3(signature = (scenario, forms=None, max_degree=None))]
pub fn plan<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    forms: Option<&Bound<'py, PyAny>>,
    max_degree: Option<i64>,
) -> PyResult<Planned<'py>> {
    let words = forms.map(form_words).transpose()?;
    let mut core = scenario.core.clone();
    restrict(&mut core, degree(max_degree)?, words.as_deref()).map_err(|e| scenario_error(&e))?;
    let execution = scenario.execution;
    let (json, verdict) = py
        .detach(|| {
            guarded(|| {
                let made = plan_locally(&core, &execution)?;
                let verdict = made.verdict().err().map(|e| crate::errors::message(&e));
                Ok((made.json(&execution), verdict))
            })
        })
        .map_err(|f| f.into_py(plan_error))?;
    planned(py, &json, verdict)
}
