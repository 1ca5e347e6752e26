//! `needle sweep`.

use super::options::ScenarioOptions;
use super::output::{progress, title_of, write};
use crate::sweep_plot::sweep_svg;
use crate::{parallel, sweep};
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;

/// What `needle sweep` is asked.
#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// The scenario and what to plan in it.
    pub scenario: ScenarioOptions,
    /// The weight to vary.
    pub weight: sweep::Weight,
    /// First value.
    pub from: f64,
    /// Last value.
    pub to: f64,
    /// Number of values, both ends included.
    pub steps: usize,
    /// Space the values evenly in log10.
    pub log: bool,
    /// Print one JSON object instead of the table.
    pub json: bool,
    /// Also write the table as CSV.
    pub csv: Option<PathBuf>,
    /// Also draw F and L against the weight (SVG).
    pub plot: Option<PathBuf>,
    /// Threads (`None`: every core).
    pub threads: Option<usize>,
}

/// Runs `needle sweep`.
pub fn run_sweep(a: &SweepOptions) -> Result<()> {
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
