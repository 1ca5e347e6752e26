//! `cover()`: `needle cover` on a label map or a closed mesh, returning the command's JSON
//! report (the segments, their spheres and how tight they are) as Python objects.

use crate::convert::python_value;
use crate::errors::{guarded, scenario_error, ScenarioError};
use needle_anatomy::command::{cover_json, CoverRequest};
use needle_anatomy::cover::DEFAULT_TIGHTNESS;
use needle_anatomy::mesh::DEFAULT_VOXEL_MM;
use planner_core::MAX_OBSTACLES;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Covers the segments of `image` as `needle cover` does, with its defaults. `labels` and
/// `segments` together, an empty list, or a label given twice are refused, as the command and a
/// scenario's `[[anatomy]]` refuse them.
#[pyfunction]
#[pyo3(signature = (image, labels=None, segments=None, margin=0.0, max_spheres=None, tightness=None, voxel=None, unit=None))]
#[allow(clippy::too_many_arguments)]
pub fn cover<'py>(
    py: Python<'py>,
    image: PathBuf,
    labels: Option<Vec<i64>>,
    segments: Option<Vec<String>>,
    margin: f64,
    max_spheres: Option<i64>,
    tightness: Option<f64>,
    voxel: Option<f64>,
    unit: Option<String>,
) -> PyResult<Bound<'py, PyAny>> {
    // A negative count is refused with the command's wording, not as an OverflowError.
    let max_spheres = match max_spheres {
        None => MAX_OBSTACLES,
        Some(n) => usize::try_from(n).map_err(|_| {
            ScenarioError::new_err(format!(
                "the most spheres a segment may take must be at least 1, not {n}"
            ))
        })?,
    };
    let args = CoverRequest {
        image,
        voxel: voxel.unwrap_or(DEFAULT_VOXEL_MM),
        unit,
        labels,
        segments,
        margin,
        max_spheres,
        tightness: tightness.unwrap_or(DEFAULT_TIGHTNESS),
        json: true,
    };
    let value = py
        .detach(|| guarded(|| cover_json(&args)))
        .map_err(|f| f.into_py(scenario_error))?;
    python_value(py, &value)
}
