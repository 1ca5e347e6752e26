//! The native half of the Python package `needle_planner`: scenarios, plans and simulations
//! through the library crates the `needle` command calls (`needle-scenario`, `needle-report`,
//! `needle-simulate`, ...), so Python gets the command's numbers and messages. The Python half (`needle_planner/__init__.py`) wraps what this module
//! returns in typed objects.
//!
//! Nothing panics across the boundary: the planner and the simulator run inside
//! [`errors::guarded`], which turns a panic into a `NeedleError`, with the GIL released.

mod convert;
mod cover;
mod device;
mod errors;
mod plan;
mod scenario;
mod simulate;
mod sweep;

use pyo3::prelude::*;

/// `needle_planner._native`
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("NeedleError", py.get_type::<errors::NeedleError>())?;
    m.add("ScenarioError", py.get_type::<errors::ScenarioError>())?;
    m.add("PlanError", py.get_type::<errors::PlanError>())?;
    m.add("DeviceError", py.get_type::<errors::DeviceError>())?;
    m.add_class::<scenario::Scenario>()?;
    m.add_class::<device::Device>()?;
    m.add_function(wrap_pyfunction!(plan::plan, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(cover::cover, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    Ok(())
}
