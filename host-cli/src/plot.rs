//! `needle plot`: its flags, the scenario and its plan drawn by `needle_analysis::commands`.

use crate::scenario_args::ScenarioArgs;
use needle_analysis::commands::PlotOptions;
use needle_analysis::slice_maps::SliceAt;
use std::path::PathBuf;

/// `needle plot`
#[derive(clap::Args, Clone, Debug)]
pub struct PlotArgs {
    /// The scenario and what to plan in it.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// A `needle plan --json` output to draw instead of planning again.
    #[arg(long)]
    plan: Option<PathBuf>,
    /// Output SVG file.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// With `[[anatomy]]`: where the axial, coronal and sagittal slices of the label maps cross:
    /// `closest` (the best path's point nearest an obstacle), `target`, `entry`, or `X,Y,Z`
    /// (RAS, mm); it must lie inside a label map.
    #[arg(long, value_name = "WHERE")]
    slice_at: Option<SliceAt>,
    /// With `[[anatomy]]`: draw the two projections of a scenario without anatomy instead of
    /// the slices.
    #[arg(long, conflicts_with = "slice_at")]
    projections: bool,
}

/// Runs `needle plot`.
pub fn plot(a: &PlotArgs) -> anyhow::Result<()> {
    needle_analysis::commands::run_plot(&PlotOptions {
        scenario: a.scenario.options(),
        plan: a.plan.clone(),
        output: a.output.clone(),
        slice_at: a.slice_at.clone(),
        projections: a.projections,
    })
}
