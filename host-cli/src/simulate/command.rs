//! `needle simulate`.

use crate::analysis::cli::output::{progress, title_of, write};
use crate::analysis::parallel;
use crate::device::commands::LinkArgs;
use crate::scenario::{load_scenario_shapes, restrict};
use crate::simulate::closed::{simulate_closed, summarise_steering};
use crate::simulate::device::simulate_on_device;
use crate::simulate::json::closed_json;
use crate::simulate::json::to_json;
use crate::simulate::plot::simulate_svg;
use crate::simulate::table::closed_table;
use crate::simulate::table::{to_table, Header};
use crate::simulate::{prepare, simulate, summarise};
use anyhow::{Context, Result};
use needle_sim::{Perturbation, TrackerFaults};
use planner_core::steer::SteerConfig;
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
    /// Steer every run with the closed-loop controller (replanning from each tracker reading).
    #[arg(long)]
    pub closed_loop: bool,
    /// With --closed-loop: a tracker fault, KEY=VALUE (repeatable): dropout_rate, dropout_mm,
    /// outlier_rate, outlier_mm, repeat_rate, stale_rate (dropouts per mm, the rest per reading).
    #[arg(long = "fault", value_name = "KEY=VALUE", requires = "closed_loop")]
    pub fault: Vec<String>,
    /// With --closed-loop: steer on the device at this TCP address (hil-sim --tcp, QEMU)
    /// instead of in-process; the host runs the simulated robot, tissue and tracker.
    #[arg(long, requires = "closed_loop", conflicts_with = "port")]
    pub tcp: Option<String>,
    /// With --closed-loop: steer on the device at this serial port instead of in-process.
    #[arg(long, requires = "closed_loop")]
    pub port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Seconds of silence allowed per exchange with the device.
    #[arg(long, default_value_t = 5.0)]
    pub timeout: f64,
    /// With --closed-loop: also run the same worlds open loop and print both side by side.
    #[arg(long, requires = "closed_loop")]
    pub compare_open_loop: bool,
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
    let file = title_of(&a.file);
    let header = Header {
        file: &file,
        form: &form,
        runs: a.runs,
        seed: a.seed,
    };
    let open_needed = !a.closed_loop || a.compare_open_loop;
    let runs = if open_needed {
        simulate(&scenario, &prepared, &p, a.runs, a.seed, threads, || {
            bar.inc(1)
        })?
    } else {
        Vec::new()
    };
    let closed = if a.closed_loop {
        bar.reset();
        bar.set_message(format!("closed loop {form}"));
        let mut faults = TrackerFaults::default();
        for kv in &a.fault {
            faults
                .apply(kv)
                .map_err(|e| anyhow::anyhow!("--fault: {e}"))?;
        }
        let config = SteerConfig::DEFAULT;
        let c = if a.tcp.is_some() || a.port.is_some() {
            let link = LinkArgs {
                port: a.port.clone(),
                baud: a.baud,
                tcp: a.tcp.clone(),
                timeout: a.timeout,
                retries: needle_link::ClientConfig::DEFAULT.retries,
                deadline: 120.0,
            };
            simulate_on_device(
                &scenario,
                &prepared,
                &p,
                &faults,
                &config,
                a.runs,
                a.seed,
                &link,
                || bar.inc(1),
            )?
        } else {
            simulate_closed(
                &scenario,
                &prepared,
                &p,
                &faults,
                &config,
                a.runs,
                a.seed,
                threads,
                || bar.inc(1),
            )?
        };
        Some(c)
    } else {
        None
    };
    bar.finish_and_clear();
    let open_summary = (!runs.is_empty()).then(|| summarise(&runs));
    let mut out = std::io::stdout();
    match &closed {
        None => {
            let summary = open_summary.unwrap_or_else(|| summarise(&runs));
            if a.json {
                let j = to_json(&p, &runs, &summary, a.detail);
                writeln!(out, "{}", serde_json::to_string(&j)?)?;
            } else {
                write!(out, "{}", to_table(&header, &p, &summary))?;
            }
        }
        Some(c) => {
            let plain: Vec<_> = c.iter().map(|r| r.run.clone()).collect();
            let summary = summarise(&plain);
            let steering = summarise_steering(c);
            if a.json {
                let j = closed_json(&p, c, &summary, &steering, open_summary.as_ref(), a.detail);
                writeln!(out, "{}", serde_json::to_string(&j)?)?;
            } else {
                let t = closed_table(&header, &p, &summary, &steering, open_summary.as_ref());
                write!(out, "{t}")?;
            }
        }
    }
    if let Some(out) = &a.plot {
        let (shown, kind) = match &closed {
            Some(c) => (c.iter().map(|r| r.run.clone()).collect(), "closed-loop"),
            None => (runs.clone(), "open-loop"),
        };
        let title = format!(
            "{file}: {form}, {} simulated {kind} insertions",
            shown.len()
        );
        let svg = simulate_svg(&scenario, &shapes, &prepared.outcome, &shown, &title);
        write(out, &svg)?;
    }
    Ok(())
}
