//! `simulate()`: `needle simulate` on a scenario, returning its JSON (the command's, through the
//! same code) and every run's figures as arrays, built here in one pass over the runs.

use crate::convert::points_array;
use crate::errors::{guarded, plan_error, scenario_error, ScenarioError};
use crate::scenario::Scenario;
use needle_analysis::parallel::default_threads;
use needle_sim::Run;
use needle_simulate::request::{asked, results_json, Request, Results};
use needle_simulate::setup::Keep;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// Every run's figures, one entry per run in seed order.
#[derive(Default)]
struct PerRun {
    seeds: Vec<u64>,
    target_errors: Vec<f64>,
    path_rms: Vec<f64>,
    path_max: Vec<f64>,
    collided: Vec<bool>,
    min_clearances: Vec<f64>,
    paths: Vec<Vec<[f32; 3]>>,
    /// Closed loop: why the controller stopped the run before the target (`None`: it did not).
    stop_reasons: Vec<Option<&'static str>>,
    /// Closed loop: how the run ended, judged on the true tip and path (`reached`, `missed`,
    /// `collided`, `stopped`).
    outcomes: Vec<&'static str>,
}

impl PerRun {
    fn push(&mut self, r: &Run) {
        self.seeds.push(r.seed);
        self.target_errors.push(f64::from(r.target_error));
        self.path_rms.push(f64::from(r.path_rms));
        self.path_max.push(f64::from(r.path_max));
        self.collided.push(r.collided);
        self.min_clearances.push(f64::from(r.min_clearance));
        self.paths.push(r.points.clone());
    }

    /// The runs of `results`, a steered run's true tip within `tolerance_mm` counted as at the
    /// target.
    fn of(results: &Results, tolerance_mm: f32) -> PerRun {
        let mut out = PerRun::default();
        match (&results.closed, &results.open) {
            (Some(closed), _) => {
                for c in closed {
                    out.push(&c.run);
                    out.stop_reasons.push(c.stop_reason.map(|s| s.name()));
                    out.outcomes
                        .push(needle_sim::Outcome::of(c, tolerance_mm).name());
                }
            }
            (None, Some(open)) => open.iter().for_each(|r| out.push(r)),
            (None, None) => {}
        }
        out
    }
}

/// `KEY=VALUE` assignments from a dict, each value as Python prints it: the command's parser
/// then reads them, with its messages.
fn assignments(what: &str, d: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
    let Some(d) = d else { return Ok(Vec::new()) };
    d.iter()
        .map(|(k, v)| {
            let key: String = k
                .extract()
                .map_err(|_| ScenarioError::new_err(format!("{what}: keys are str")))?;
            Ok(format!("{key}={}", v.str()?.to_cow()?))
        })
        .collect()
}

/// Runs `needle simulate --json` on `scenario`; returns the JSON and a dict of per-run arrays.
#[pyfunction]
#[pyo3(signature = (scenario, runs=100, seed=1, closed_loop=false, perturb=None, faults=None,
    steer=None, form=None, threads=None, compare_open_loop=false, world=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    runs: i64,
    seed: u64,
    closed_loop: bool,
    perturb: Option<&Bound<'py, PyDict>>,
    faults: Option<&Bound<'py, PyDict>>,
    steer: Option<&Bound<'py, PyDict>>,
    form: Option<String>,
    threads: Option<i64>,
    compare_open_loop: bool,
    world: Option<String>,
) -> PyResult<(String, Bound<'py, PyDict>)> {
    let request = Request {
        runs: usize::try_from(runs).unwrap_or(0),
        seed,
        form,
        perturb: assignments("perturb", perturb)?,
        world,
        faults: assignments("faults", faults)?,
        steer: assignments("steer", steer)?,
        closed_loop,
        on_device: false,
    };
    let steered_only = !(request.faults.is_empty() && request.steer.is_empty());
    if steered_only && !closed_loop {
        return Err(ScenarioError::new_err(
            "faults and steer are for the closed loop: pass closed_loop=True",
        ));
    }
    let threads = match threads {
        None => default_threads(),
        Some(n) if n >= 1 => usize::try_from(n).unwrap_or(usize::MAX),
        Some(n) => {
            return Err(ScenarioError::new_err(format!(
                "invalid value '{n}' for '--threads <THREADS>': must be at least 1"
            )))
        }
    };
    let asked = asked(&scenario.file, scenario.path.as_deref(), &request)
        .map_err(|e| scenario_error(&e))?;
    let (json, per_run) = py
        .detach(|| {
            guarded(|| {
                let (setup, _) = asked.set_up()?;
                let keep = Keep {
                    detail: false,
                    paths: setup.runs,
                    stopped_paths: setup.runs,
                };
                let open = (!closed_loop || compare_open_loop)
                    .then(|| setup.open_loop(&keep, threads, || {}))
                    .transpose()?;
                let closed = closed_loop
                    .then(|| setup.closed_loop(&keep, threads, || {}))
                    .transpose()?;
                let results = Results { open, closed };
                Ok((
                    results_json(&setup, &results, false)?,
                    PerRun::of(&results, setup.config.reach_tolerance_mm),
                ))
            })
        })
        .map_err(|f| f.into_py(plan_error))?;
    let out = PyDict::new(py);
    out.set_item("seeds", PyArray1::from_vec(py, per_run.seeds))?;
    out.set_item(
        "target_errors",
        PyArray1::from_vec(py, per_run.target_errors),
    )?;
    out.set_item("path_rms", PyArray1::from_vec(py, per_run.path_rms))?;
    out.set_item("path_max", PyArray1::from_vec(py, per_run.path_max))?;
    out.set_item("collided", PyArray1::from_vec(py, per_run.collided))?;
    out.set_item(
        "min_clearances",
        PyArray1::from_vec(py, per_run.min_clearances),
    )?;
    let paths = per_run
        .paths
        .iter()
        .map(|p| points_array(py, p))
        .collect::<PyResult<Vec<_>>>()?;
    out.set_item("paths", PyList::new(py, paths)?)?;
    if closed_loop {
        out.set_item("stop_reasons", PyList::new(py, per_run.stop_reasons)?)?;
        out.set_item("outcomes", PyList::new(py, per_run.outcomes)?)?;
    }
    Ok((json, out))
}
