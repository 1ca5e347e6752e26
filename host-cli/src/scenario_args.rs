//! Flags the analysis commands share: the scenario and what to plan in it, and the RRT's
//! settings (`needle_analysis::commands`' `ScenarioSource`, `ScenarioOptions`, `RrtSettings`).

use crate::values::MethodArg;
use needle_analysis::commands::{RrtSettings, ScenarioOptions, ScenarioSource};
use std::path::PathBuf;

/// The scenario file alone: what a command that plans no path forms (the RRT) takes.
#[derive(clap::Args, Clone, Debug)]
pub struct ScenarioFileArgs {
    /// Scenario file (TOML, see examples/paper.toml).
    file: PathBuf,
    /// Turn every polygon obstacle into circles this way: circumscribed, segmented or bordered.
    #[arg(long, ignore_case = true)]
    approx: Option<MethodArg>,
}

impl ScenarioFileArgs {
    /// The file the flags name, and how its polygons become circles.
    pub fn source(&self) -> ScenarioSource {
        ScenarioSource {
            file: self.file.clone(),
            approx: self.approx.map(Into::into),
        }
    }
}

/// The scenario and what to plan in it.
#[derive(clap::Args, Clone, Debug)]
pub struct ScenarioArgs {
    /// The file.
    #[command(flatten)]
    source: ScenarioFileArgs,
    /// Largest control degree N to try (overrides the file).
    #[arg(long)]
    max_degree: Option<u8>,
    /// Comma-separated forms to try, e.g. RL,LRL (overrides the file).
    #[arg(long, value_delimiter = ',')]
    forms: Option<Vec<String>>,
}

impl ScenarioArgs {
    /// The scenario and the overrides the flags give.
    pub fn options(&self) -> ScenarioOptions {
        ScenarioOptions {
            source: self.source.source(),
            max_degree: self.max_degree,
            forms: self.forms.clone(),
        }
    }
}

/// RRT settings shared by `rrt` and `compare`.
#[derive(clap::Args, Clone, Debug)]
pub struct RrtArgs {
    /// Edge length (mm).
    #[arg(long, default_value_t = RrtSettings::default().step)]
    step: f32,
    /// Stop once the tip is this close to the target (mm).
    #[arg(long, default_value_t = RrtSettings::default().tolerance)]
    tolerance: f32,
    /// Most samples before giving up.
    #[arg(long, default_value_t = RrtSettings::default().iterations)]
    iterations: usize,
    /// Share of samples aimed at the target.
    #[arg(long, default_value_t = RrtSettings::default().goal_bias)]
    goal_bias: f64,
}

impl RrtArgs {
    /// The settings the flags give.
    pub fn settings(&self) -> RrtSettings {
        RrtSettings {
            step: self.step,
            tolerance: self.tolerance,
            iterations: self.iterations,
            goal_bias: self.goal_bias,
        }
    }
}
