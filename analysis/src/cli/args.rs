//! Arguments shared by the analysis commands: the scenario and what to plan in it, and the RRT's
//! settings.

use crate::rrt;
use anyhow::Result;
use needle_scenario::approx::Method;
use needle_scenario::{load_scenario_shapes, restrict, ObstacleShape};
use planner_core::Scenario;
use std::path::PathBuf;

/// The scenario file alone: what a command that plans no path forms (the RRT) takes.
#[derive(clap::Args, Clone, Debug)]
pub struct ScenarioFileArgs {
    /// Scenario file (TOML, see examples/paper.toml).
    pub file: PathBuf,
    /// Turn every polygon obstacle into circles this way: circumscribed, segmented or bordered.
    #[arg(long, ignore_case = true)]
    pub approx: Option<Method>,
}

impl ScenarioFileArgs {
    /// Loads the file.
    pub fn load(&self) -> Result<(Scenario, Vec<ObstacleShape>)> {
        load_scenario_shapes(&self.file, self.approx)
    }
}

/// The scenario and what to plan in it.
#[derive(clap::Args, Clone, Debug)]
pub struct ScenarioArgs {
    /// The file.
    #[command(flatten)]
    pub source: ScenarioFileArgs,
    /// Largest control degree N to try (overrides the file).
    #[arg(long)]
    pub max_degree: Option<u8>,
    /// Comma-separated forms to try, e.g. RL,LRL (overrides the file).
    #[arg(long, value_delimiter = ',')]
    pub forms: Option<Vec<String>>,
}

impl ScenarioArgs {
    /// Loads the file and applies the overrides.
    pub fn load(&self) -> Result<(Scenario, Vec<ObstacleShape>)> {
        let (mut scenario, shapes) = self.source.load()?;
        restrict(&mut scenario, self.max_degree, self.forms.as_deref())?;
        Ok((scenario, shapes))
    }
}

/// RRT settings shared by `rrt` and `compare`.
#[derive(clap::Args, Clone, Debug)]
pub struct RrtArgs {
    /// Edge length (mm).
    #[arg(long, default_value_t = 10.0)]
    pub step: f32,
    /// Stop once the tip is this close to the target (mm).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f32,
    /// Most samples before giving up.
    #[arg(long, default_value_t = 20_000)]
    pub iterations: usize,
    /// Share of samples aimed at the target.
    #[arg(long, default_value_t = 0.2)]
    pub goal_bias: f64,
}

impl RrtArgs {
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
