//! `needle compare`: its flags, the optimiser against the RRT by `needle_analysis::commands`.

use crate::scenario_args::{RrtArgs, ScenarioArgs};
use needle_analysis::commands::CompareOptions;
use std::path::PathBuf;

/// `needle compare`
#[derive(clap::Args, Clone, Debug)]
pub struct CompareArgs {
    /// The scenario and what to plan in it.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// The RRT's settings.
    #[command(flatten)]
    rrt: RrtArgs,
    /// Number of RRT runs (seeds first, first + 1, ...).
    #[arg(long, default_value_t = 11)]
    runs: usize,
    /// First RRT seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Threads for the RRT runs (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Draw the optimiser's best path and the median RRT run's path (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// Runs `needle compare`.
pub fn compare(a: &CompareArgs) -> anyhow::Result<()> {
    needle_analysis::commands::run_compare(&CompareOptions {
        scenario: a.scenario.options(),
        rrt: a.rrt.settings(),
        runs: a.runs,
        seed: a.seed,
        threads: a.threads,
        json: a.json,
        plot: a.plot.clone(),
    })
}
