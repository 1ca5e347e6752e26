//! The TOML scenario format as written (see `examples/paper.toml`): the file's tables and keys, a
//! missing optional key left as `None`. Turning it into the core's scenario, with the documented
//! defaults, is in `build.rs`; its polygon obstacles become circles in `shapes.rs`.

use anyhow::{Context, Result};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A scenario file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Free-form name.
    pub name: Option<String>,
    /// Needle mechanics.
    pub needle: NeedleFile,
    /// Entry.
    pub entry: EntryFile,
    /// Target.
    pub target: TargetFile,
    /// Obstacles.
    #[serde(default)]
    pub obstacles: Vec<ObstacleFile>,
    /// Obstacles from label maps: each entry's segments covered by spheres (docs/anatomy.md).
    #[serde(default)]
    pub anatomy: Vec<AnatomyFile>,
    /// Weights (defaults 1, 1, 1000, 2).
    pub weights: Option<WeightsFile>,
    /// Planner options.
    pub planner: Option<PlannerFile>,
    /// The needle driver (defaults 2.5 mm/s, 360 deg/s, 4 rev/s, 360 degrees).
    pub driver: Option<DriverFile>,
    /// The world the plan is executed in: `mode` and the perturbation keys of
    /// `needle simulate --perturb` (read by `execution::execution_of`).
    pub execution: Option<toml::Table>,
    /// What the closed-loop controller is told of the tracker and the insertion (read by
    /// `steering::steering_of`).
    pub steering: Option<toml::Table>,
    /// Directory of the file, for `polygon_file` paths (set by [`ScenarioFile::load`]).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

/// `[needle]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NeedleFile {
    /// Arc radius (mm).
    pub curvature_radius: f32,
    /// Longest arc as a turning angle (degrees), default 180.
    pub max_arc_deg: Option<f32>,
    /// Longest line (mm); default: twice the entry-target distance plus a half turn.
    pub max_line_length: Option<f32>,
    /// Insertable length (mm), default 200: no plan or continuation inserts more.
    pub length: Option<f32>,
}

/// `[entry]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EntryFile {
    /// Entry point (mm); or `markups`.
    #[serde(default, deserialize_with = "super::exact::optional_array")]
    pub position: Option<[f32; 3]>,
    /// A 3D Slicer markups file (`.mrk.json`) holding the entry point, relative to the
    /// scenario's folder.
    pub markups: Option<PathBuf>,
    /// The label of the markups' control point to take (default: the first).
    pub point: Option<String>,
    /// Nominal insertion axis.
    #[serde(deserialize_with = "super::exact::array")]
    pub direction: [f32; 3],
    /// Tilt bound (degrees), default 60.
    pub max_tilt_deg: Option<f32>,
}

/// `[target]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetFile {
    /// Target point (mm); or `markups`.
    #[serde(default, deserialize_with = "super::exact::optional_array")]
    pub position: Option<[f32; 3]>,
    /// A 3D Slicer markups file (`.mrk.json`) holding the target, relative to the scenario's
    /// folder.
    pub markups: Option<PathBuf>,
    /// The label of the markups' control point to take (default: the first).
    pub point: Option<String>,
    /// Or a segment of a label map: the target is its deepest point (farthest from its outside).
    pub label: Option<i64>,
    /// The label map holding `label` (default: the first `[[anatomy]]` file that holds it).
    pub label_file: Option<PathBuf>,
    /// Allowed end-point error (mm), default 0.1.
    pub tolerance: Option<f32>,
}

/// `[[obstacles]]`: a circle (sphere in 3-D) by `center` and `radius`, or, in plane mode, a polygon
/// in the y-z plane by `polygon = [[y, z], ...]` or `polygon_file`, turned into covering circles by
/// `approx` (see `approx.rs`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleFile {
    /// Centre (mm).
    #[serde(default, deserialize_with = "super::exact::optional_array")]
    pub center: Option<[f32; 3]>,
    /// Radius (mm).
    pub radius: Option<f32>,
    /// Outline in the y-z plane (mm), vertices in order.
    #[serde(default, deserialize_with = "super::exact::optional_vertices")]
    pub polygon: Option<Vec<[f64; 2]>>,
    /// A text file with one `y z` vertex per line, relative to the scenario file.
    pub polygon_file: Option<PathBuf>,
    /// `"circumscribed"`, `"segmented"` (default) or `"bordered"`.
    pub approx: Option<String>,
}

/// `[[anatomy]]`: a label map whose segments become spheres (as `needle cover` makes them).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AnatomyFile {
    /// The label map (`.nrrd`, `.seg.nrrd`, `.nii`, `.nii.gz`), relative to the scenario's folder.
    pub file: PathBuf,
    /// Cover these label values only (default: every label but 0).
    pub labels: Option<Vec<i64>>,
    /// Cover these segments only, by name (a `.seg.nrrd`).
    pub segments: Option<Vec<String>>,
    /// Grow every sphere by this much (mm), default 0.
    pub margin_mm: Option<f64>,
    /// The most spheres one segment may take (default: the planner's capacity).
    pub max_spheres: Option<usize>,
    /// The cover's tightness (default 3, as `needle cover --tightness`).
    pub tightness: Option<f64>,
    /// The voxel edge a mesh (`.stl`) is voxelised at (mm), default 0.5.
    pub voxel_mm: Option<f64>,
    /// The unit of a mesh's coordinates: "mm" (default), "cm", "m" or "um".
    pub unit: Option<String>,
}

/// `[weights]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeightsFile {
    /// a1
    pub length: Option<f32>,
    /// a2
    pub risk: Option<f32>,
    /// a3
    pub penalty: Option<f32>,
    /// a4
    pub control: Option<f32>,
}

/// `[driver]`
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct DriverFile {
    /// Insertion speed (mm/s).
    pub insert_speed: Option<f32>,
    /// Bevel rotation speed (deg/s).
    pub rotate_speed: Option<f32>,
    /// Spin rate while inserting a line (rev/s).
    pub spin_rate: Option<f32>,
    /// Largest accumulated shaft twist (degrees, at least 360).
    pub max_twist_deg: Option<f32>,
}

/// `[planner]`
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct PlannerFile {
    /// Largest control degree, default 3.
    pub max_control_degree: Option<u8>,
    /// `"yz"` for the paper's plane mode; absent for 3-D.
    pub plane: Option<String>,
    /// Forms to try, e.g. `["RL", "LRL"]`.
    pub forms: Option<Vec<String>>,
    /// `"mean"` (default) or `"sum"`.
    pub risk: Option<String>,
    /// Smallest clearance a plan must keep (mm), default 0.
    pub min_clearance: Option<f32>,
    /// Share of the needle's curvature the plan leaves unused for steering, 0 to 0.5.
    pub curvature_reserve: Option<f32>,
    /// Reach of the risk term (mm): farther obstacles add nothing to D (off by default).
    pub risk_within_mm: Option<f32>,
    /// Bound on the predicted probability that the executed plan enters an obstacle: a number,
    /// or `"off"` (unbounded); 0.01 where the file is silent (read by
    /// `execution::execution_of`).
    pub max_collision_probability: Option<toml::Value>,
    /// Spheres the `[[anatomy]]` covers may take together, at most the host's obstacles less
    /// the `[[obstacles]]`; where silent, what keeps the scenario within the device's capacity.
    pub max_anatomy_spheres: Option<usize>,
}

impl ScenarioFile {
    /// Reads and parses a scenario file.
    pub fn load(path: &Path) -> Result<ScenarioFile> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read scenario {}", path.display()))?;
        let mut file =
            Self::parse(&text).with_context(|| format!("in scenario {}", path.display()))?;
        file.base_dir = path.parent().map(Path::to_path_buf);
        Ok(file)
    }

    /// `execution.mode = "open_loop"`: the file asks for a plan executed as planned, so neither
    /// the closed loop's curvature reserve nor its assumptions about the tracker and tissue are
    /// its defaults.
    pub fn planned_open_loop(&self) -> bool {
        let mode = self.execution.as_ref().and_then(|t| t.get("mode"));
        mode.and_then(|m| m.as_str()) == Some("open_loop")
    }

    /// Parses scenario text.
    pub fn parse(text: &str) -> Result<ScenarioFile> {
        Ok(toml::from_str(text)?)
    }
}

/// A scenario file of the least a scenario needs (a needle, an entry and a target 90 mm ahead)
/// with `extra` appended: the tables' own tests add theirs to it.
#[cfg(test)]
pub(crate) fn minimal_with(extra: &str) -> Result<ScenarioFile> {
    ScenarioFile::parse(&format!(
        "[needle]\ncurvature_radius = 63.7\n[entry]\nposition = [0, 0, 0]\n\
         direction = [0, 0, 1]\n[target]\nposition = [0, 10, 90]\n{extra}"
    ))
}
