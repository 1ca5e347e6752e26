//! `needle sweep`.

use super::args::ScenarioArgs;
use super::output::{progress, title_of, write};
use crate::sweep_plot::sweep_svg;
use crate::{parallel, sweep};
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;

/// `needle sweep`
#[derive(clap::Args, Clone, Debug)]
pub struct SweepArgs {
    /// The scenario and what to plan in it.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Weight to vary: length, risk, penalty or control.
    #[arg(long, ignore_case = true)]
    pub weight: sweep::Weight,
    /// First value.
    #[arg(long)]
    pub from: f64,
    /// Last value.
    #[arg(long)]
    pub to: f64,
    /// Number of values, both ends included.
    #[arg(long, default_value_t = 10)]
    pub steps: usize,
    /// Space the values evenly in log10.
    #[arg(long)]
    pub log: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also write the table as CSV.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Also draw F and L against the weight (SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Threads (default: every core).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs `needle sweep`.
pub fn run_sweep(a: &SweepArgs) -> Result<()> {
    let (scenario, _) = a.scenario.load()?;
    let range = sweep::Range {
        from: a.from,
        to: a.to,
        steps: a.steps,
        log: a.log,
    };
    let bar = progress(range.values()?.len(), &format!("sweep {}", a.weight));
    let threads = a.threads.unwrap_or_else(parallel::default_threads).max(1);
    let points = sweep::run(&scenario, a.weight, &range, threads, || bar.inc(1))?;
    bar.finish_and_clear();
    if a.json {
        writeln!(std::io::stdout(), "{}", sweep::to_json(a.weight, &points))?;
    } else {
        write!(std::io::stdout(), "{}", sweep::to_table(a.weight, &points))?;
    }
    if let Some(p) = &a.csv {
        write(p, &sweep::to_csv(a.weight, &points))?;
    }
    if let Some(p) = &a.plot {
        let title = format!(
            "{}: sweep of weight {} ({} values)",
            title_of(&a.scenario.source.file),
            a.weight,
            points.len()
        );
        write(p, &sweep_svg(a.weight, &points, a.log, &title))?;
    }
    Ok(())
}
