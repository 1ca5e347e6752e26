//! `needle rrt`: its flags, the RRT baseline run by `needle_analysis::commands`.

use crate::scenario_args::{RrtArgs, ScenarioFileArgs};
use needle_analysis::commands::RrtOptions;
use std::path::PathBuf;

/// `needle rrt`
#[derive(clap::Args, Clone, Debug)]
pub struct RrtCmd {
    /// The scenario (the RRT plans no path forms, so it takes no --forms or --max-degree).
    #[command(flatten)]
    scenario: ScenarioFileArgs,
    /// The RRT's settings.
    #[command(flatten)]
    rrt: RrtArgs,
    /// Seed of the random samples.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
    /// Draw the tree and the path (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// Runs `needle rrt`.
pub fn rrt(a: &RrtCmd) -> anyhow::Result<()> {
    needle_analysis::commands::run_rrt(&RrtOptions {
        scenario: a.scenario.source(),
        rrt: a.rrt.settings(),
        seed: a.seed,
        json: a.json,
        plot: a.plot.clone(),
    })
}
