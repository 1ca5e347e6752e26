//! `plan()`: `needle plan` on a scenario, returning its JSON report (the command's, through the
//! same code) and the best path's points as an array.

use crate::errors::{guarded, plan_error, scenario_error, ScenarioError};
use crate::scenario::Scenario;
use needle_cli::report::local::plan_locally;
use needle_cli::scenario::restrict;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyList, PyString};
use serde_json::Value;

/// What `plan` hands the Python side: the JSON report as text and as Python objects (without
/// `best.points`, given apart as an `(n, 3)` array), and why the command would exit 1 after
/// printing the report (no feasible form, no plan within the collision bound), if it would.
type Planned<'py> = (
    String,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyArray2<f64>>>,
    Option<String>,
);

/// A JSON value as the Python object `json.loads` makes of its text (`int` for an integer,
/// `float` for a number written with a point or an exponent), without printing and parsing it.
fn python_value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let items = items
                .iter()
                .map(|i| python_value(py, i))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(map) => {
            let d = PyDict::new(py);
            for (k, item) in map {
                d.set_item(k, python_value(py, item)?)?;
            }
            d.into_any()
        }
    })
}

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
    let (text, mut value, points, verdict) = py
        .detach(|| {
            guarded(|| {
                let made = plan_locally(&core, &execution)?;
                let json = made.json(&core, &execution);
                let points = json.best.as_ref().and_then(|b| b.path.points.clone());
                let verdict = made.verdict().err().map(|e| crate::errors::message(&e));
                // The command prints this value: its keys sorted.
                let value = serde_json::to_value(&json)?;
                Ok((value.to_string(), value, points, verdict))
            })
        })
        .map_err(|f| f.into_py(plan_error))?;
    if let Some(best) = value.get_mut("best").and_then(Value::as_object_mut) {
        best.remove("points");
    }
    let report = python_value(py, &value)?;
    let points = points
        .map(|p| {
            let flat: Vec<f64> = p.iter().flatten().copied().collect();
            Array2::from_shape_vec((p.len(), 3), flat)
                .map(|a| a.into_pyarray(py))
                .map_err(|e| plan_error(&anyhow::anyhow!("{e}")))
        })
        .transpose()?;
    Ok((text, report, points, verdict))
}
