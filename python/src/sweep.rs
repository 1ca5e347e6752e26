//! `sweep()`: `needle sweep` on a scenario, returning its `--json` report (each value's plan) as
//! Python objects.

use crate::convert::python_value;
use crate::errors::{guarded, plan_error, ScenarioError};
use crate::scenario::Scenario;
use needle_analysis::parallel;
use needle_analysis::sweep::{run, to_json, Range, Weight};
use pyo3::prelude::*;

/// Re-plans `scenario` for each value of one weight, as `needle sweep --json` does.
#[pyfunction]
#[pyo3(signature = (scenario, weight, start, stop, steps=10, log=false, threads=None))]
#[allow(clippy::too_many_arguments)]
pub fn sweep<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    weight: &str,
    start: f64,
    stop: f64,
    steps: i64,
    log: bool,
    threads: Option<i64>,
) -> PyResult<Bound<'py, PyAny>> {
    let weight = Weight::parse(weight).ok_or_else(|| {
        ScenarioError::new_err(format!(
            "invalid value '{weight}' for '--weight <WEIGHT>' [possible values: length, risk, \
             penalty, control]"
        ))
    })?;
    let range = Range {
        from: start,
        to: stop,
        // A negative count is refused below with the message of zero steps, not as an
        // OverflowError from the conversion.
        steps: usize::try_from(steps).unwrap_or(0),
        log,
    };
    // The range is the caller's input: refused as a ScenarioError before anything is planned.
    range
        .values()
        .map_err(|e| ScenarioError::new_err(crate::errors::message(&e)))?;
    let core = scenario.core.clone();
    let threads = match threads {
        None => parallel::default_threads(),
        Some(n) if n >= 1 => usize::try_from(n).unwrap_or(usize::MAX),
        Some(n) => {
            return Err(ScenarioError::new_err(format!(
                "invalid value '{n}' for '--threads <THREADS>': must be at least 1"
            )))
        }
    };
    let value = py
        .detach(|| {
            guarded(|| {
                let points = run(&core, weight, &range, threads, || {})?;
                Ok(serde_json::to_value(to_json(weight, &points))?)
            })
        })
        .map_err(|f| f.into_py(plan_error))?;
    python_value(py, &value)
}
