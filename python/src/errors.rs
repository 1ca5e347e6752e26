//! The package's exceptions, carrying the `needle` command's messages (what it prints after
//! `error: `), and the guard that keeps a panic from crossing into the interpreter.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::PyErr;
use std::panic::{catch_unwind, AssertUnwindSafe};

create_exception!(
    needle_planner,
    NeedleError,
    PyException,
    "Any error of needle_planner."
);
create_exception!(
    needle_planner,
    ScenarioError,
    NeedleError,
    "A scenario, or an option given with it, that cannot be planned or simulated as given."
);
create_exception!(
    needle_planner,
    PlanError,
    NeedleError,
    "Planning failed: no feasible form, no plan within the collision bound, no schedule."
);
create_exception!(
    needle_planner,
    DeviceError,
    NeedleError,
    "A device did not answer, or answered wrong."
);

/// The command's message of `e`: every cause, outermost first, as `needle` prints it (without
/// the line break a TOML error ends with).
pub fn message(e: &anyhow::Error) -> String {
    format!("{e:#}").trim_end().to_string()
}

/// `e` as a `ScenarioError`.
pub fn scenario_error(e: &anyhow::Error) -> PyErr {
    ScenarioError::new_err(message(e))
}

/// `e` as a `PlanError`.
pub fn plan_error(e: &anyhow::Error) -> PyErr {
    PlanError::new_err(message(e))
}

/// `e` as a `DeviceError`.
pub fn device_error(e: &anyhow::Error) -> PyErr {
    DeviceError::new_err(message(e))
}

/// What failed inside [`guarded`] work.
pub enum Failed {
    /// The work's own error.
    Error(anyhow::Error),
    /// The work panicked: a bug, reported as a `NeedleError` rather than tearing down the
    /// interpreter.
    Panic(String),
}

impl Failed {
    /// As a Python exception: the work's errors through `typed`, a panic as a `NeedleError`.
    pub fn into_py(self, typed: fn(&anyhow::Error) -> PyErr) -> PyErr {
        match self {
            Failed::Error(e) => typed(&e),
            Failed::Panic(why) => {
                NeedleError::new_err(format!("internal error (please report it): {why}"))
            }
        }
    }
}

/// Runs `work`, catching a panic.
pub fn guarded<T>(work: impl FnOnce() -> anyhow::Result<T>) -> Result<T, Failed> {
    match catch_unwind(AssertUnwindSafe(work)) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(Failed::Error(e)),
        Err(payload) => {
            let why = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".to_string());
            Err(Failed::Panic(why))
        }
    }
}
