//! The TOML scenario format (see `examples/paper.toml`) and its translation to the core's
//! [`Scenario`]. Missing optional keys take the documented defaults.

use anyhow::{bail, Context, Result};
use planner_core::form::{Form, FormSet};
use planner_core::scenario::{
    Entry, Needle, Obstacle, PlannerOptions, RiskMeasure, Target, Weights, Workspace,
};
use planner_core::{PlanError, Scenario, MAX_OBSTACLES};
use serde::Deserialize;
use std::path::Path;

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

/// `[[obstacles]]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleFile {
    /// Centre (mm).
    pub center: [f32; 3],
    /// Radius (mm).
    pub radius: f32,
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
        Self::parse(&text).with_context(|| format!("in scenario {}", path.display()))
    }

    /// Parses scenario text.
    pub fn parse(text: &str) -> Result<ScenarioFile> {
        Ok(toml::from_str(text)?)
    }

    /// Builds the core scenario, checking what the core checks (so errors name the file's keys).
    pub fn to_scenario(&self) -> Result<Scenario> {
        let mut obstacles = heapless::Vec::<Obstacle, MAX_OBSTACLES>::new();
        if self.obstacles.len() > MAX_OBSTACLES {
            bail!(PlanError::TooManyObstacles {
                given: self.obstacles.len().min(u16::MAX as usize) as u16,
                capacity: MAX_OBSTACLES as u16,
            });
        }
        for o in &self.obstacles {
            // Cannot fail: the count was checked above.
            let _ = obstacles.push(Obstacle {
                center: o.center,
                radius: o.radius,
            });
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

/// Loads a scenario file straight into the core's type.
pub fn load_scenario(path: &Path) -> Result<Scenario> {
    ScenarioFile::load(path)?
        .to_scenario()
        .with_context(|| format!("in scenario {}", path.display()))
}
