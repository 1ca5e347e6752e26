//! `needle simulate`.

use super::output::{progress, title_of, write};
use crate::analysis::parallel;
use crate::analysis::simulate::json::to_json;
use crate::analysis::simulate::plot::simulate_svg;
use crate::analysis::simulate::table::{to_table, Header};
use crate::analysis::simulate::{prepare, simulate, summarise};
use crate::scenario::{load_scenario_shapes, restrict};
use anyhow::{Context, Result};
use hil_sim::insertion::Perturbation;
use std::io::Write;
use std::path::PathBuf;

/// `needle simulate`
#[derive(clap::Args, Clone, Debug)]
pub struct SimulateArgs {
    /// Scenario file (TOML, see examples/paper.toml).
    pub file: PathBuf,
    /// Simulated insertions.
    #[arg(long, default_value_t = 100)]
    pub runs: usize,
    /// Seed of the first run (run i uses seed + i).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Plan and simulate only this form (e.g. RL) instead of the best.
    #[arg(long)]
    pub form: Option<String>,
    /// Change one perturbation, KEY=VALUE (repeatable; see docs/execution.md).
    #[arg(long = "perturb", value_name = "KEY=VALUE")]
    pub perturb: Vec<String>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// With --json: every run's draws, figures, points and steps.
    #[arg(long)]
    pub detail: bool,
    /// Also draw the plan and the executed paths (SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Threads (default: every core).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Runs `needle simulate`.
pub fn run_simulate(a: &SimulateArgs) -> Result<()> {
    let mut p = Perturbation::default();
    for kv in &a.perturb {
        p.apply(kv).context("--perturb")?;
    }
    anyhow::ensure!(a.runs >= 1, "--runs must be at least 1");
    let (mut scenario, shapes) = load_scenario_shapes(&a.file, None)?;
    if let Some(f) = &a.form {
        restrict(&mut scenario, None, Some(std::slice::from_ref(f)))?;
    }
    let prepared = prepare(&scenario)?;
    let form = prepared.outcome.form.to_string();
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        progress(a.runs, &format!("simulate {form}"))
    };
    let threads = a.threads.unwrap_or_else(parallel::default_threads).max(1);
    let runs = simulate(&scenario, &prepared, &p, a.runs, a.seed, threads, || {
        bar.inc(1)
    })?;
    bar.finish_and_clear();
    let summary = summarise(&runs);
    let file = title_of(&a.file);
    if a.json {
        let out = to_json(&p, &runs, &summary, a.detail);
        writeln!(std::io::stdout(), "{}", serde_json::to_string(&out)?)?;
    } else {
        let header = Header {
            file: &file,
            form: &form,
            runs: runs.len(),
            seed: a.seed,
        };
        write!(std::io::stdout(), "{}", to_table(&header, &p, &summary))?;
    }
    if let Some(out) = &a.plot {
        let title = format!(
            "{file}: {form}, {} simulated open-loop insertions",
            runs.len()
        );
        let svg = simulate_svg(&scenario, &shapes, &prepared.outcome, &runs, &title);
        write(out, &svg)?;
    }
    Ok(())
}
