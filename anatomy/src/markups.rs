//! 3D Slicer markups files (`.mrk.json`, Slicer's markups schema v1.0.3): points read from
//! them, and plans written as them.
//!
//! Read: the control points of every markup in the file, in RAS (a markup whose
//! `coordinateSystem` is LPS, the schema's default, has x and y negated), in millimetres (`um`
//! is scaled). Written: a `Curve` for a path and a `Fiducial` list for points, in RAS.

use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The schema a written file declares.
pub const SCHEMA: &str =
    "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/markups-schema-v1.0.3.json#";

#[derive(Deserialize)]
struct FileIn {
    markups: Vec<MarkupIn>,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct MarkupIn {
    coordinate_system: Option<String>,
    coordinate_units: Option<serde_json::Value>,
    #[serde(default)]
    control_points: Vec<PointIn>,
}

#[derive(Deserialize)]
struct PointIn {
    label: Option<String>,
    position: Option<Vec<f64>>,
}

/// The point labelled `label` (or the first point) of the markups file `path`, in RAS mm.
pub fn read_point(path: &Path, label: Option<&str>) -> Result<[f32; 3]> {
    let at = |e: anyhow::Error| anyhow!("{}: {e:#}", path.display());
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read markups {}", path.display()))?;
    let file: FileIn = serde_json::from_str(&text)
        .map_err(|e| at(anyhow!("not a Slicer markups file (.mrk.json): {e}")))?;
    let mut labels = Vec::new();
    for m in &file.markups {
        let flip = match m.coordinate_system.as_deref().unwrap_or("LPS") {
            "LPS" => [-1.0, -1.0, 1.0],
            "RAS" => [1.0, 1.0, 1.0],
            other => {
                return Err(at(anyhow!(
                    "coordinateSystem {other:?} is neither LPS nor RAS"
                )))
            }
        };
        let scale = match m.coordinate_units.as_ref().map(units) {
            None => 1.0,
            Some(Some(s)) => s,
            Some(None) => return Err(at(anyhow!("coordinateUnits are neither mm nor um"))),
        };
        for p in &m.control_points {
            labels.push(p.label.clone().unwrap_or_default());
            if label.is_some_and(|l| p.label.as_deref() != Some(l)) {
                continue;
            }
            let v = match p.position.as_deref() {
                Some(&[x, y, z]) if [x, y, z].iter().all(|c| c.is_finite()) => [x, y, z],
                _ => {
                    return Err(at(anyhow!(
                        "control point {} has no position of 3 finite numbers",
                        p.label
                            .as_deref()
                            .map_or("without a label".to_string(), |l| format!("{l:?}"))
                    )))
                }
            };
            return Ok([0, 1, 2].map(|k| (flip[k] * v[k] * scale) as f32));
        }
    }
    match label {
        Some(l) => bail!(
            "{}: no control point labelled {l:?} (labels: {})",
            path.display(),
            labels
                .iter()
                .map(|l| format!("{l:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => bail!("{}: the markups hold no control point", path.display()),
    }
}

/// Millimetres per unit of a markup's `coordinateUnits` (a string or a DICOM code triple).
fn units(v: &serde_json::Value) -> Option<f64> {
    let code = match v {
        serde_json::Value::String(s) => s.as_str(),
        serde_json::Value::Array(a) => a.first()?.as_str()?,
        _ => return None,
    };
    match code {
        "mm" => Some(1.0),
        "um" => Some(0.001),
        _ => None,
    }
}

/// A markups file to write.
#[derive(Serialize)]
pub struct FileOut {
    #[serde(rename = "@schema")]
    schema: &'static str,
    markups: Vec<MarkupOut>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct MarkupOut {
    #[serde(rename = "type")]
    kind: &'static str,
    name: String,
    coordinate_system: &'static str,
    coordinate_units: &'static str,
    locked: bool,
    control_points: Vec<PointOut>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct PointOut {
    id: String,
    label: String,
    position: [f64; 3],
    position_status: &'static str,
}

impl FileOut {
    /// One markup of `kind` (`Curve`, `Fiducial`) named `name`, its points labelled.
    pub fn one(kind: &'static str, name: &str, points: &[(String, [f32; 3])]) -> FileOut {
        FileOut {
            schema: SCHEMA,
            markups: vec![MarkupOut {
                kind,
                name: name.to_string(),
                coordinate_system: "RAS",
                coordinate_units: "mm",
                locked: true,
                control_points: points
                    .iter()
                    .enumerate()
                    .map(|(n, (label, p))| PointOut {
                        id: (n + 1).to_string(),
                        label: label.clone(),
                        position: p.map(f64::from),
                        position_status: "defined",
                    })
                    .collect(),
            }],
        }
    }
}
