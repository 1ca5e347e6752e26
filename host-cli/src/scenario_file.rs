//! The TOML scenario format (see `examples/paper.toml`) and its translation to the core's
//! [`Scenario`]. Missing optional keys take the documented defaults.

use crate::analysis::approx::{approximate, Approximation, Method, Polygon};
use anyhow::{bail, Context, Result};
use planner_core::model::form::{Form, FormSet};
use planner_core::model::scenario::{
    Entry, Needle, Obstacle, PlannerOptions, RiskMeasure, Target, Weights, Workspace,
};
use planner_core::{PlanError, Scenario, MAX_OBSTACLES};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A scenario file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Free-form name.
    #[serde(default)]
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
    /// Weights (defaults 1, 1, 1000, 2).
    #[serde(default)]
    pub weights: Option<WeightsFile>,
    /// Planner options.
    #[serde(default)]
    pub planner: Option<PlannerFile>,
    /// Directory of the file, for `polygon_file` paths (set by [`ScenarioFile::load`]).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

/// One `[[obstacles]]` entry as the planner sees it: its circles, and the polygon they replace.
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleShape {
    /// Index in the file's `[[obstacles]]` list.
    pub index: usize,
    /// The polygon and its covering circles, for polygon obstacles.
    pub polygon: Option<(Polygon, Approximation)>,
    /// Circles (spheres) handed to the planner.
    pub circles: Vec<Obstacle>,
}

/// `[needle]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NeedleFile {
    /// Arc radius (mm).
    pub curvature_radius: f32,
    /// Longest arc as a turning angle (degrees), default 180.
    #[serde(default = "default_max_arc")]
    pub max_arc_deg: f32,
    /// Longest line (mm); default: twice the entry-target distance plus a half turn.
    #[serde(default)]
    pub max_line_length: Option<f32>,
}

fn default_max_arc() -> f32 {
    180.0
}

/// `[entry]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EntryFile {
    /// Entry point (mm).
    pub position: [f32; 3],
    /// Nominal insertion axis.
    pub direction: [f32; 3],
    /// Tilt bound (degrees), default 60.
    #[serde(default = "default_tilt")]
    pub max_tilt_deg: f32,
}

fn default_tilt() -> f32 {
    60.0
}

/// `[target]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetFile {
    /// Target point (mm).
    pub position: [f32; 3],
    /// Allowed end-point error (mm), default 0.1.
    #[serde(default = "default_tolerance")]
    pub tolerance: f32,
}

fn default_tolerance() -> f32 {
    0.1
}

/// `[[obstacles]]`: a circle (sphere in 3-D) by `center` and `radius`, or, in plane mode, a polygon
/// in the y-z plane by `polygon = [[y, z], ...]` or `polygon_file`, turned into covering circles by
/// `approx` (see [`crate::analysis::approx`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleFile {
    /// Centre (mm).
    #[serde(default)]
    pub center: Option<[f32; 3]>,
    /// Radius (mm).
    #[serde(default)]
    pub radius: Option<f32>,
    /// Outline in the y-z plane (mm), vertices in order.
    #[serde(default)]
    pub polygon: Option<Vec<[f64; 2]>>,
    /// A text file with one `y z` vertex per line, relative to the scenario file.
    #[serde(default)]
    pub polygon_file: Option<PathBuf>,
    /// `"circumscribed"`, `"segmented"` (default) or `"bordered"`.
    #[serde(default)]
    pub approx: Option<String>,
}

/// `[weights]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeightsFile {
    /// a1
    #[serde(default)]
    pub length: Option<f32>,
    /// a2
    #[serde(default)]
    pub risk: Option<f32>,
    /// a3
    #[serde(default)]
    pub penalty: Option<f32>,
    /// a4
    #[serde(default)]
    pub control: Option<f32>,
}

/// `[planner]`
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct PlannerFile {
    /// Largest control degree, default 3.
    #[serde(default)]
    pub max_control_degree: Option<u8>,
    /// `"yz"` for the paper's plane mode; absent for 3-D.
    #[serde(default)]
    pub plane: Option<String>,
    /// Forms to try, e.g. `["RL", "LRL"]`.
    #[serde(default)]
    pub forms: Option<Vec<String>>,
    /// `"mean"` (default) or `"sum"`.
    #[serde(default)]
    pub risk: Option<String>,
    /// Smallest clearance a plan must keep (mm), default 0.
    #[serde(default)]
    pub min_clearance: Option<f32>,
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

    /// The obstacles as circles; polygons are approximated by `approx` when given, else by
    /// their own `approx` key (default segmented). Radii are rounded up by 0.001 mm so the
    /// planner's `f32` circles still cover the polygon.
    pub fn obstacle_shapes(&self, approx: Option<Method>) -> Result<Vec<ObstacleShape>> {
        let plane = self
            .planner
            .as_ref()
            .and_then(|p| p.plane.as_deref())
            .is_some_and(|s| s.eq_ignore_ascii_case("yz"));
        let x = self.entry.position[0];
        let mut shapes = Vec::with_capacity(self.obstacles.len());
        for (index, o) in self.obstacles.iter().enumerate() {
            let shape = self
                .obstacle_shape(index, o, approx, plane, x)
                .with_context(|| format!("in obstacles[{index}]"))?;
            shapes.push(shape);
        }
        Ok(shapes)
    }

    fn obstacle_shape(
        &self,
        index: usize,
        o: &ObstacleFile,
        approx: Option<Method>,
        plane: bool,
        x: f32,
    ) -> Result<ObstacleShape> {
        let outline = match (&o.polygon, &o.polygon_file) {
            (Some(_), Some(_)) => bail!("give either polygon or polygon_file, not both"),
            (Some(v), None) => Some(Polygon::new(v.clone())?),
            (None, Some(f)) => {
                let path = self
                    .base_dir
                    .as_deref()
                    .map(|d| d.join(f))
                    .unwrap_or_else(|| f.clone());
                let text = std::fs::read_to_string(&path)
                    .with_context(|| format!("cannot read polygon file {}", path.display()))?;
                Some(
                    Polygon::parse_text(&text)
                        .with_context(|| format!("in polygon file {}", path.display()))?,
                )
            }
            (None, None) => None,
        };
        let Some(poly) = outline else {
            if o.approx.is_some() {
                bail!("approx applies to polygon obstacles only");
            }
            let (Some(center), Some(radius)) = (o.center, o.radius) else {
                bail!("give center and radius, or a polygon (polygon = [[y, z], ...] or polygon_file)");
            };
            return Ok(ObstacleShape {
                index,
                polygon: None,
                circles: vec![Obstacle { center, radius }],
            });
        };
        if o.center.is_some() || o.radius.is_some() {
            bail!("a polygon obstacle takes no center or radius");
        }
        if !plane {
            bail!("polygon obstacles lie in the y-z plane: they need planner.plane = \"yz\"");
        }
        let method = match (approx, o.approx.as_deref()) {
            (Some(m), _) => m,
            (None, Some(name)) => name.parse()?,
            (None, None) => Method::default(),
        };
        let approximation = approximate(&poly, method);
        let inside_msg = |what: &str, p: [f32; 3]| -> Result<()> {
            let q = [f64::from(p[1]), f64::from(p[2])];
            if poly.contains(q) {
                bail!("the {what} lies inside the polygon");
            }
            if approximation.circles.iter().any(|c| c.contains(q, 1e-3)) {
                bail!(
                    "the {what} lies outside the polygon but inside its {method} circles: \
                     try a tighter approximation (approx = \"bordered\" or \"segmented\")"
                );
            }
            Ok(())
        };
        inside_msg("entry point", self.entry.position)?;
        inside_msg("target", self.target.position)?;
        let circles = approximation
            .circles
            .iter()
            .map(|c| Obstacle {
                center: [x, c.center[0] as f32, c.center[1] as f32],
                radius: (c.radius + 1e-3) as f32,
            })
            .collect();
        Ok(ObstacleShape {
            index,
            polygon: Some((poly, approximation)),
            circles,
        })
    }

    /// Parses scenario text.
    pub fn parse(text: &str) -> Result<ScenarioFile> {
        Ok(toml::from_str(text)?)
    }

    /// Builds the core scenario, checking what the core checks (so errors name the file's keys).
    pub fn to_scenario(&self) -> Result<Scenario> {
        self.to_scenario_with(&self.obstacle_shapes(None)?)
    }

    /// Builds the core scenario with the obstacles' circles from [`Self::obstacle_shapes`].
    pub fn to_scenario_with(&self, shapes: &[ObstacleShape]) -> Result<Scenario> {
        let mut obstacles = heapless::Vec::<Obstacle, MAX_OBSTACLES>::new();
        let count: usize = shapes.iter().map(|s| s.circles.len()).sum();
        if count > MAX_OBSTACLES {
            let polygons = shapes.iter().filter(|s| s.polygon.is_some()).count();
            let err = PlanError::TooManyObstacles {
                given: count.min(u16::MAX as usize) as u16,
                capacity: MAX_OBSTACLES as u16,
            };
            if polygons > 0 {
                bail!("{err}; {polygons} polygon obstacle(s) became circles: a coarser approximation (circumscribed or segmented) needs fewer");
            }
            bail!(err);
        }
        for c in shapes.iter().flat_map(|s| &s.circles) {
            // Cannot fail: the count was checked above.
            let _ = obstacles.push(*c);
        }
        let p = self.planner.clone().unwrap_or_default();
        let workspace = match p.plane.as_deref() {
            None => Workspace::Space,
            Some(s) if s.eq_ignore_ascii_case("yz") => Workspace::PlaneYz,
            Some(other) => bail!(
                "planner.plane = {other:?}: only \"yz\" is supported (or leave it out for 3-D)"
            ),
        };
        let risk = match p.risk.as_deref() {
            None | Some("mean") => RiskMeasure::Mean,
            Some("sum") => RiskMeasure::Sum,
            Some(other) => bail!("planner.risk = {other:?}: use \"mean\" or \"sum\""),
        };
        let mut forms = FormSet::default();
        for word in p.forms.iter().flatten() {
            let f = parse_form(word)?;
            forms.insert(f);
        }
        let defaults = Weights::default();
        let w = self.weights.clone();
        let weights = Weights {
            length: w.as_ref().and_then(|w| w.length).unwrap_or(defaults.length),
            risk: w.as_ref().and_then(|w| w.risk).unwrap_or(defaults.risk),
            penalty: w
                .as_ref()
                .and_then(|w| w.penalty)
                .unwrap_or(defaults.penalty),
            control: w
                .as_ref()
                .and_then(|w| w.control)
                .unwrap_or(defaults.control),
        };
        let scenario = Scenario {
            needle: Needle {
                curvature_radius: self.needle.curvature_radius,
                max_arc_deg: self.needle.max_arc_deg,
                max_line_length: self.needle.max_line_length.unwrap_or(0.0),
            },
            entry: Entry {
                position: self.entry.position,
                direction: self.entry.direction,
                max_tilt_deg: self.entry.max_tilt_deg,
            },
            target: Target {
                position: self.target.position,
                tolerance: self.target.tolerance,
            },
            obstacles,
            weights,
            options: PlannerOptions {
                max_control_degree: p.max_control_degree.unwrap_or(3),
                forms,
                workspace,
                risk,
                min_clearance: p.min_clearance.unwrap_or(0.0),
            },
        };
        scenario.validate()?;
        Ok(scenario)
    }
}

/// Parses one form word, with a clear message.
pub fn parse_form(word: &str) -> Result<Form> {
    match Form::parse(word) {
        Some(f) => Ok(f),
        None => bail!(
            "{word:?} is not a path form: use R and L, no LL, at most {} letters",
            planner_core::MAX_CONTROL_DEGREE
        ),
    }
}

/// Loads a scenario file into the core's type, approximating polygons by `approx` (or each
/// obstacle's own method), and returns the obstacle shapes alongside for plotting.
pub fn load_scenario_shapes(
    path: &Path,
    approx: Option<Method>,
) -> Result<(Scenario, Vec<ObstacleShape>)> {
    let file = ScenarioFile::load(path)?;
    let shapes = file
        .obstacle_shapes(approx)
        .with_context(|| format!("in scenario {}", path.display()))?;
    let scenario = file
        .to_scenario_with(&shapes)
        .with_context(|| format!("in scenario {}", path.display()))?;
    Ok((scenario, shapes))
}

/// Loads a scenario file straight into the core's type.
pub fn load_scenario(path: &Path) -> Result<Scenario> {
    ScenarioFile::load(path)?
        .to_scenario()
        .with_context(|| format!("in scenario {}", path.display()))
}
