//! `needle approx`: its flags, polygon obstacles' circles printed by `needle_analysis::commands`.

use crate::values::MethodArg;
use needle_analysis::commands::ApproxOptions;
use std::path::PathBuf;

/// `needle approx`
#[derive(clap::Args, Clone, Debug)]
pub struct ApproxArgs {
    /// Scenario file with polygon obstacles.
    file: PathBuf,
    /// circumscribed, segmented or bordered (default: each obstacle's own `approx`).
    #[arg(long, ignore_case = true)]
    method: Option<MethodArg>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Draw the polygons and their circles (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// Runs `needle approx`.
pub fn approx(a: &ApproxArgs) -> anyhow::Result<()> {
    needle_analysis::commands::run_approx(&ApproxOptions {
        file: a.file.clone(),
        method: a.method.map(Into::into),
        json: a.json,
        plot: a.plot.clone(),
    })
}
