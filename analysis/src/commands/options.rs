//! What the analysis commands share: the scenario and what to plan in it, and the RRT's
//! settings.

use crate::rrt;
use anyhow::Result;
use needle_scenario::approx::Method;
use needle_scenario::{load_scenario_shapes, restrict, ObstacleShape};
use planner_core::Scenario;
use std::path::PathBuf;

/// The scenario file alone: what a command that plans no path forms (the RRT) takes.
#[derive(Clone, Debug, Default)]
pub struct ScenarioSource {
    /// Scenario file (TOML, see examples/paper.toml).
    pub file: PathBuf,
    /// Turn every polygon obstacle into circles this way (`None`: each obstacle's own).
    pub approx: Option<Method>,
}

impl ScenarioSource {
    /// Loads the file.
    pub fn load(&self) -> Result<(Scenario, Vec<ObstacleShape>)> {
        load_scenario_shapes(&self.file, self.approx)
    }
}

/// The scenario and what to plan in it.
#[derive(Clone, Debug, Default)]
pub struct ScenarioOptions {
    /// The file.
    pub source: ScenarioSource,
    /// Largest control degree N to try (overrides the file).
    pub max_degree: Option<u8>,
    /// The forms to try, e.g. RL and LRL (overrides the file).
    pub forms: Option<Vec<String>>,
}

impl ScenarioOptions {
    /// Loads the file and applies the overrides.
    pub fn load(&self) -> Result<(Scenario, Vec<ObstacleShape>)> {
        let (mut scenario, shapes) = self.source.load()?;
        restrict(&mut scenario, self.max_degree, self.forms.as_deref())?;
        Ok((scenario, shapes))
    }
}

/// RRT settings shared by `rrt` and `compare`.
#[derive(Clone, Copy, Debug)]
pub struct RrtSettings {
    /// Edge length (mm).
    pub step: f32,
    /// Stop once the tip is this close to the target (mm).
    pub tolerance: f32,
    /// Most samples before giving up.
    pub iterations: usize,
    /// Share of samples aimed at the target.
    pub goal_bias: f64,
}

impl Default for RrtSettings {
    /// The commands' defaults.
    fn default() -> Self {
        RrtSettings {
            step: 10.0,
            tolerance: 1.0,
            iterations: 20_000,
            goal_bias: 0.2,
        }
    }
}

impl RrtSettings {
    /// The RRT's options for one seed.
    pub fn options(&self, seed: u64) -> rrt::Options {
        rrt::Options {
            step: self.step,
            tolerance: self.tolerance,
            seed,
            iterations: self.iterations,
            goal_bias: self.goal_bias,
            ..rrt::Options::default()
        }
    }
}
