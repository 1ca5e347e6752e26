//! From the library's values to Python's: JSON values as the objects `json.loads` makes of their
//! text, point lists as `(n, 3)` arrays.

use crate::errors::NeedleError;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyList, PyString};
use serde_json::Value;

/// A JSON value as the Python object `json.loads` makes of its text (`int` for an integer,
/// `float` for a number written with a point or an exponent), without printing and parsing it.
pub fn python_value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
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

/// Points as an `(n, 3)` float64 array (`f32` widened exactly).
pub fn points_array<'py, T: Copy + Into<f64>>(
    py: Python<'py>,
    points: &[[T; 3]],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = points.iter().flatten().map(|v| (*v).into()).collect();
    Array2::from_shape_vec((points.len(), 3), flat)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| NeedleError::new_err(e.to_string()))
}
