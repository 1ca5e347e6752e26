//! `plan()`: `needle plan` on a scenario, returning its JSON report (the command's, through the
//! same code) and the best path's points as an array.

use crate::errors::{guarded, plan_error, scenario_error, ScenarioError};
use crate::scenario::Scenario;
use needle_cli::report::local::plan_locally;
use needle_cli::scenario::restrict;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyString;

/// What `plan` hands the Python side: the JSON report, the best path's points (`(n, 3)`), and
/// why the command would exit 1 after printing the report (no feasible form, no plan within the
/// collision bound), if it would.
type Planned<'py> = (String, Option<Bound<'py, PyArray2<f64>>>, Option<String>);

/// The forms asked for: a list of words or one comma-separated string, as `--forms` takes them.
fn form_words(forms: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
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
fn degree(max_degree: Option<i64>) -> PyResult<Option<u8>> {
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
    let (json, points, verdict) = py
        .detach(|| {
            guarded(|| {
                let made = plan_locally(&core, &execution)?;
                let json = made.json(&core, &execution);
                let points = json.best.as_ref().and_then(|b| b.path.points.clone());
                let verdict = made.verdict().err().map(|e| crate::errors::message(&e));
                Ok((json.to_string(), points, verdict))
            })
        })
        .map_err(|f| f.into_py(plan_error))?;
    let points = points
        .map(|p| {
            let flat: Vec<f64> = p.iter().flatten().copied().collect();
            Array2::from_shape_vec((p.len(), 3), flat)
                .map(|a| a.into_pyarray(py))
                .map_err(|e| plan_error(&anyhow::anyhow!("{e}")))
        })
        .transpose()?;
    Ok((json, points, verdict))
}
