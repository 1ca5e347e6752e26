//! `Scenario`: a scenario file (TOML, docs/scenario.md) read from a path or text, or written from
//! keyword arguments with the same tables and keys; checked when made, with the command's
//! messages, so a bad scenario fails where it is written.

use crate::errors::{scenario_error, ScenarioError};
use needle_scenario::execution::execution_of;
use needle_scenario::{Execution, ScenarioFile};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::{Path, PathBuf};

/// A needle-planner scenario.
#[pyclass(frozen, module = "needle_planner")]
pub struct Scenario {
    /// The file as parsed.
    pub file: ScenarioFile,
    /// Where it was read from, if it was: messages name it, as the command's do.
    pub path: Option<PathBuf>,
    /// The TOML text.
    pub text: String,
    /// The core's scenario, with the file's defaults.
    pub core: planner_core::Scenario,
    /// The `[execution]` table and the collision bound.
    pub execution: Execution,
}

/// `result` with the message naming the scenario file, when it came from one.
fn in_file<T>(result: anyhow::Result<T>, path: Option<&Path>) -> anyhow::Result<T> {
    use anyhow::Context;
    match path {
        Some(p) => result.with_context(|| format!("in scenario {}", p.display())),
        None => result,
    }
}

impl Scenario {
    /// Parses and checks `text` (read from `path`, if it was).
    fn parse(text: String, path: Option<PathBuf>) -> anyhow::Result<Scenario> {
        let base_dir = path
            .as_deref()
            .and_then(Path::parent)
            .map(Path::to_path_buf);
        Scenario::parse_in(text, path, base_dir)
    }

    /// [`Scenario::parse`], with `polygon_file` paths relative to `base_dir`.
    fn parse_in(
        text: String,
        path: Option<PathBuf>,
        base_dir: Option<PathBuf>,
    ) -> anyhow::Result<Scenario> {
        let mut file = in_file(ScenarioFile::parse(&text), path.as_deref())?;
        file.base_dir = base_dir;
        let core = in_file(file.to_scenario(), path.as_deref())?;
        let execution = in_file(execution_of(&file), path.as_deref())?;
        Ok(Scenario {
            file,
            path,
            text,
            core,
            execution,
        })
    }

    /// Reads the file at `path` as `needle` does.
    fn load(path: PathBuf) -> PyResult<Scenario> {
        let text = std::fs::read_to_string(&path).map_err(|e| {
            ScenarioError::new_err(format!("cannot read scenario {}: {e}", path.display()))
        })?;
        Scenario::parse(text, Some(path)).map_err(|e| scenario_error(&e))
    }
}

#[pymethods]
impl Scenario {
    /// A scenario from keyword arguments: the tables of a scenario file as dicts (`needle`,
    /// `entry`, `target`, `obstacles` as a list of dicts, `weights`, `planner`, `driver`,
    /// `execution`, `steering`) and `name`. A key left `None` is left out.
    #[new]
    #[pyo3(signature = (**tables))]
    fn new(tables: Option<&Bound<'_, PyDict>>) -> PyResult<Scenario> {
        let mut table = toml::Table::new();
        if let Some(tables) = tables {
            for (key, value) in tables.iter() {
                let key: String = key.extract()?;
                if let Some(v) = toml_value(&value, &key)? {
                    table.insert(key, v);
                }
            }
        }
        let text = toml::to_string(&table).map_err(|e| ScenarioError::new_err(e.to_string()))?;
        Scenario::parse(text, None).map_err(|e| scenario_error(&e))
    }

    /// A copy with some tables or keys changed: each keyword is a table (`weights={"control":
    /// 0.5}` changes that key and keeps the others; a key given `None` is removed) or a
    /// top-level key (`name`, `obstacles`, replaced whole). Checked as a new file would be.
    #[pyo3(signature = (**tables))]
    fn replace(&self, tables: Option<&Bound<'_, PyDict>>) -> PyResult<Scenario> {
        let mut table: toml::Table =
            toml::from_str(&self.text).map_err(|e| ScenarioError::new_err(e.to_string()))?;
        for (key, value) in tables.into_iter().flat_map(|t| t.iter()) {
            let key: String = key.extract()?;
            match (toml_value(&value, &key)?, table.get_mut(&key)) {
                (Some(toml::Value::Table(new)), Some(toml::Value::Table(old))) => {
                    let removed = value.cast::<PyDict>().map(|d| {
                        d.iter()
                            .filter(|(_, v)| v.is_none())
                            .filter_map(|(k, _)| k.extract::<String>().ok())
                            .collect::<Vec<_>>()
                    });
                    old.extend(new);
                    for k in removed.into_iter().flatten() {
                        old.remove(&k);
                    }
                }
                (Some(new), _) => {
                    table.insert(key, new);
                }
                (None, _) => {
                    table.remove(&key);
                }
            }
        }
        let text = toml::to_string(&table).map_err(|e| ScenarioError::new_err(e.to_string()))?;
        Scenario::parse_in(text, None, self.file.base_dir.clone()).map_err(|e| scenario_error(&e))
    }

    /// A scenario from a file's path (a `str` or `os.PathLike`) or from TOML text (a `str` with
    /// a newline or an `=` in it).
    #[staticmethod]
    fn from_toml(source: &Bound<'_, PyAny>) -> PyResult<Scenario> {
        if let Ok(text) = source.cast::<PyString>() {
            let text = text.to_cow()?;
            if text.contains('\n') || text.contains('=') {
                return Scenario::parse(text.to_string(), None).map_err(|e| scenario_error(&e));
            }
            return Scenario::load(PathBuf::from(text.into_owned()));
        }
        let path: PathBuf = source.extract().map_err(|_| {
            ScenarioError::new_err(format!(
                "a scenario is read from a path or TOML text, not from {}",
                type_name(source)
            ))
        })?;
        Scenario::load(path)
    }

    /// The scenario as TOML: the file's text as read, or as written from the keywords.
    fn to_toml(&self) -> String {
        self.text.clone()
    }

    /// The file it was read from, if it was.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.path.clone()
    }

    /// The scenario's `name`, if it has one.
    #[getter]
    fn name(&self) -> Option<String> {
        self.file.name.clone()
    }

    fn __repr__(&self) -> String {
        match (&self.path, &self.file.name) {
            (Some(p), _) => format!("Scenario.from_toml({:?})", p.display().to_string()),
            (None, Some(n)) => format!("<Scenario {n:?}>"),
            (None, None) => "<Scenario>".to_string(),
        }
    }
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

/// A Python value as the TOML value a file would hold (`None`: leave the key out). Sequences
/// and numpy arrays become arrays, dicts tables.
fn toml_value(v: &Bound<'_, PyAny>, key: &str) -> PyResult<Option<toml::Value>> {
    use toml::Value;
    if v.is_none() {
        return Ok(None);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Some(Value::Boolean(v.extract()?)));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(Some(Value::Integer(i))),
            Err(_) => Ok(Some(Value::Float(v.extract()?))),
        };
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(Some(Value::Float(v.extract()?)));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Some(Value::String(s.to_cow()?.into_owned())));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, item) in d.iter() {
            let k: String = k.extract().map_err(|_| {
                ScenarioError::new_err(format!("{key}: a key is {}, not a str", type_name(&k)))
            })?;
            if let Some(value) = toml_value(&item, &format!("{key}.{k}"))? {
                table.insert(k, value);
            }
        }
        return Ok(Some(Value::Table(table)));
    }
    // numpy scalars and arrays: their Python values (a float, a nested list).
    if v.hasattr("tolist")? {
        let plain = v.call_method0("tolist")?;
        if !plain.is(v) {
            return toml_value(&plain, key);
        }
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, item) in v.try_iter()?.enumerate() {
            let item = item?;
            match toml_value(&item, &format!("{key}[{i}]"))? {
                Some(value) => items.push(value),
                None => {
                    return Err(ScenarioError::new_err(format!(
                        "{key}[{i}] is None: an array holds values only"
                    )))
                }
            }
        }
        return Ok(Some(Value::Array(items)));
    }
    Err(ScenarioError::new_err(format!(
        "{key}: a {} is not a value of a scenario file (numbers, strings, lists, dicts)",
        type_name(v)
    )))
}
