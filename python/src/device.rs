//! `Device`: a planner device (the firmware on a board, in QEMU, or `hil-sim`) over TCP or a
//! serial port, as `needle info` and `needle send` reach it: its identity, and a plan made there
//! and re-checked here.

use crate::convert::python_value;
use crate::errors::{guarded, message, Failed, PlanError};
use crate::plan::{degree, form_words, planned, Planned};
use crate::scenario::Scenario;
use needle_device::checked::{plan_checked, Sent};
use needle_device::commands::info_json;
use needle_device::LinkOptions;
use needle_scenario::restrict;
use pyo3::prelude::*;

/// How `Device.plan` went wrong: the device (link, answer) or the planning it reported.
enum Wrong {
    Device(anyhow::Error),
    Plan(anyhow::Error),
}

/// A planner device.
#[pyclass(frozen, module = "needle_planner")]
pub struct Device {
    link: LinkOptions,
}

fn device_error(f: Failed) -> PyErr {
    f.into_py(crate::errors::device_error)
}

#[pymethods]
impl Device {
    /// The device at TCP address `tcp` ("host:port") or serial port `port`, with `needle send`'s
    /// link settings.
    #[new]
    #[pyo3(signature = (tcp=None, port=None, baud=115_200, timeout=None, retries=None, deadline=120.0))]
    fn new(
        tcp: Option<String>,
        port: Option<String>,
        baud: u32,
        timeout: Option<f64>,
        retries: Option<u32>,
        deadline: f64,
    ) -> PyResult<Device> {
        if tcp.is_some() == port.is_some() {
            return Err(crate::errors::DeviceError::new_err(
                "a device is reached by tcp=\"host:port\" or port=\"/dev/...\" (one of the two)",
            ));
        }
        let defaults = needle_link::ClientConfig::DEFAULT;
        let link = LinkOptions {
            port,
            baud,
            tcp,
            timeout: timeout.unwrap_or(defaults.timeout.as_secs_f64()),
            retries: retries.unwrap_or(defaults.retries),
            deadline,
        };
        link.config().map_err(|e| crate::errors::device_error(&e))?;
        Ok(Device { link })
    }

    /// What `needle info --json` prints: protocol, name, firmware, capacities.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let link = self.link.clone();
        let info = py
            .detach(|| guarded(|| Ok(info_json(&link.connect()?.1))))
            .map_err(device_error)?;
        python_value(py, &info)
    }

    /// Plans `scenario` on the device as `needle send` does (the device's plan re-checked here),
    /// returning what `plan` returns.
    #[pyo3(signature = (scenario, forms=None, max_degree=None))]
    fn plan<'py>(
        &self,
        py: Python<'py>,
        scenario: &Scenario,
        forms: Option<&Bound<'py, PyAny>>,
        max_degree: Option<i64>,
    ) -> PyResult<Planned<'py>> {
        let words = forms.map(form_words).transpose()?;
        let mut core = scenario.core.clone();
        restrict(&mut core, degree(max_degree)?, words.as_deref())
            .map_err(|e| crate::errors::scenario_error(&e))?;
        let link = self.link.clone();
        let execution = scenario.execution;
        let made = py.detach(|| {
            guarded(|| {
                Ok(match plan_checked(&core, &execution, &link) {
                    Err(e) => Err(Wrong::Device(e)),
                    Ok(Sent::Refused(e)) => Err(Wrong::Plan(e)),
                    Ok(Sent::Planned(made)) => {
                        let verdict = made.verdict().err().map(|e| message(&e));
                        Ok((made.json(&execution), verdict))
                    }
                })
            })
        });
        match made.map_err(device_error)? {
            Ok((json, verdict)) => planned(py, &json, verdict),
            Err(Wrong::Device(e)) => Err(crate::errors::device_error(&e)),
            Err(Wrong::Plan(e)) => Err(PlanError::new_err(message(&e))),
        }
    }
}
