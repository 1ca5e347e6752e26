//! `cover()`: `needle cover` on a label map or a closed mesh, returning the command's JSON
//! report (the segments, their spheres and how tight they are) as Python objects.

use crate::convert::python_value;
use crate::errors::{guarded, scenario_error};
use needle_cli::anatomy::command::{cover_json, CoverArgs};
use pyo3::prelude::*;
use std::path::PathBuf;

/// Covers the segments of `image` as `needle cover` does, with its defaults.
#[pyfunction]
#[pyo3(signature = (image, labels=None, segments=None, margin=0.0, max_spheres=32, tightness=3.0, voxel=0.5))]
#[allow(clippy::too_many_arguments)]
pub fn cover<'py>(
    py: Python<'py>,
    image: PathBuf,
    labels: Option<Vec<i64>>,
    segments: Option<Vec<String>>,
    margin: f64,
    max_spheres: usize,
    tightness: f64,
    voxel: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let args = CoverArgs {
        image,
        voxel,
        labels: labels.unwrap_or_default(),
        segments: segments.unwrap_or_default(),
        margin,
        max_spheres,
        tightness,
        json: true,
        out: None,
        scenario: None,
    };
    let value = py
        .detach(|| guarded(|| cover_json(&args)))
        .map_err(|f| f.into_py(scenario_error))?;
    python_value(py, &value)
}
