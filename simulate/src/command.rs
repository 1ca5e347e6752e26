//! `needle simulate`: from what it is asked to one [`Setup`], the runs of the mode asked for (open
//! loop, closed loop in-process or on a device, or both), then the table or the JSON, and the
//! plot (its file opened before the runs).

use super::device::on_device;
use super::options::SimulateOptions;
use super::plot::{simulate_slices_svg, simulate_svg, Executed, MAX_DRAWN};
use super::request::{self, results_json, Request, Results};
use super::setup::{Keep, Setup};
use super::steering::summarise_steering;
use super::summarise;
use super::table::{closed_table, to_table, Header};
use anyhow::{anyhow, Result};
use needle_analysis::commands::output::{progress, title_of, OutputFile};
use needle_analysis::parallel;
use needle_scenario::{ObstacleShape, ScenarioFile};
use std::io::Write;

/// Runs `needle simulate`.
pub fn run_simulate(a: &SimulateOptions) -> Result<()> {
    if !a.json {
        // Covering a scenario's anatomy can take seconds before the runs' bar starts.
        needle_anatomy::progress::enable();
    }
    let (setup, shapes) = set_up(a)?;
    let plot = a.plot.as_deref().map(OutputFile::open).transpose()?;
    // The export keeps every path; the plot the first few.
    let drawn = match (&a.export, &plot) {
        (Some(_), _) => a.runs,
        (None, Some(_)) => MAX_DRAWN,
        (None, None) => 0,
    };
    let keep = Keep {
        detail: a.detail,
        paths: drawn,
        stopped_paths: drawn,
    };
    let results = execute(a, &setup, &keep)?;
    print(a, &setup, &results)?;
    if let Some(dir) = &a.export {
        export_runs(dir, &setup, &results)?;
    }
    if let Some(file) = plot {
        let executed = Executed {
            open: results.open.as_deref(),
            closed: results.closed.as_deref(),
        };
        let title = plot_title(a, &setup, &executed);
        let outcome = &setup.prepared.outcome;
        let loaded = ScenarioFile::load(&a.file)?;
        let svg = if loaded.anatomy.is_empty() {
            simulate_svg(&setup.scenario, &shapes, outcome, &executed, &title)
        } else {
            simulate_slices_svg(&setup.scenario, &loaded, outcome, &executed, &title)?
        };
        file.write(&svg)?;
    }
    Ok(())
}

/// `--export DIR`: the plan as `needle plan --export` writes it, and the simulated paths.
fn export_runs(dir: &std::path::Path, setup: &Setup, results: &Results) -> Result<()> {
    use needle_report::slicer::{export_best, polylines_vtk};
    export_best(dir, &setup.scenario, Some(&setup.prepared.outcome))?;
    let write = |name: &str, lines: Vec<&[[f32; 3]]>| -> Result<()> {
        let path = dir.join(name);
        let text = polylines_vtk("needle-planner simulated paths", &lines);
        std::fs::write(&path, text).map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
    };
    if let Some(runs) = &results.open {
        write(
            "paths-open-loop.vtk",
            runs.iter().map(|r| r.points.as_slice()).collect(),
        )?;
    }
    if let Some(runs) = &results.closed {
        write(
            "paths-closed-loop.vtk",
            runs.iter().map(|r| r.run.points.as_slice()).collect(),
        )?;
    }
    Ok(())
}

/// The setup of one closed-loop run of `file` as `needle simulate FILE --closed-loop --runs 1
/// --seed SEED` makes it, with `asked`'s world, faults, steering and form (its runs, seed and
/// `closed_loop` are those): the simulated lab and `needle steer` plan and steer the very
/// insertion the simulation does.
pub fn closed_loop_setup(file: &std::path::Path, seed: u64, asked: &Request) -> Result<Setup> {
    let request = Request {
        runs: 1,
        seed,
        closed_loop: true,
        ..asked.clone()
    };
    let loaded = ScenarioFile::load(file)?;
    Ok(request::set_up(&loaded, Some(file), &request)?.0)
}

/// The perturbation, the tracker's faults, the scenario (restricted to `--form`) and its plan.
fn set_up(a: &SimulateOptions) -> Result<(Setup, Vec<ObstacleShape>)> {
    let file = ScenarioFile::load(&a.file)?;
    let request = Request {
        runs: a.runs,
        seed: a.seed,
        form: a.form.clone(),
        perturb: a.perturb.clone(),
        world: a.world.clone(),
        faults: a.faults.clone(),
        steer: a.steer.clone(),
        closed_loop: a.closed_loop,
        on_device: a.link.is_some(),
    };
    request::set_up(&file, Some(&a.file), &request)
}

/// The runs of the mode asked for, with a progress bar on a terminal (not with `--json`).
fn execute(a: &SimulateOptions, setup: &Setup, keep: &Keep) -> Result<Results> {
    let form = setup.prepared.outcome.form;
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        progress(a.runs, &format!("simulate {form}"))
    };
    let threads = a.threads.unwrap_or_else(parallel::default_threads);
    let open = if !a.closed_loop || a.compare_open_loop {
        Some(setup.open_loop(keep, threads, || bar.inc(1))?)
    } else {
        None
    };
    let closed = if a.closed_loop {
        bar.reset();
        bar.set_message(format!("closed loop {form}"));
        Some(match &a.link {
            Some(link) => on_device(setup, keep, link, || bar.inc(1))?,
            None => setup.closed_loop(keep, threads, || bar.inc(1))?,
        })
    } else {
        None
    };
    bar.finish_and_clear();
    Ok(Results { open, closed })
}

/// The table, or the JSON object, on stdout.
fn print(a: &SimulateOptions, setup: &Setup, r: &Results) -> Result<()> {
    let file = title_of(&a.file);
    let form = setup.prepared.outcome.form.to_string();
    let header = Header {
        file: &file,
        form: &form,
        runs: a.runs,
        seed: a.seed,
    };
    if a.json {
        let json = results_json(setup, r, a.detail)?;
        writeln!(std::io::stdout(), "{json}")?;
        return Ok(());
    }
    let p = &setup.perturbation;
    let mut text = match (&r.closed, &r.open) {
        (Some(closed), open) => {
            let open = open.as_deref().map(summarise);
            let summary = summarise(closed.iter().map(|c| &c.run));
            let steering = summarise_steering(closed, setup.config.reach_tolerance_mm);
            closed_table(&header, p, &summary, &steering, open.as_ref())
        }
        (None, Some(runs)) => to_table(&header, p, &summarise(runs)),
        (None, None) => return Err(anyhow!("no run was made")),
    };
    text.push_str(&super::table::world_line(&setup.effects));
    let planned = setup.scenario.options.curvature_reserve;
    text.push_str(&super::table::reserve_line(planned, setup.reserve_asked));
    text.push_str(&match &setup.bound {
        Some(b) => format!(
            "plan: made under a bound of {} on the predicted collision probability\n",
            b.max_collision_probability
        ),
        None => "plan: unbounded (planner.max_collision_probability = \"off\")\n".into(),
    });
    write!(std::io::stdout(), "{text}")?;
    Ok(())
}

/// "paper.toml: RL, 100 simulated closed-loop insertions", and what else the plot shows.
fn plot_title(a: &SimulateOptions, setup: &Setup, executed: &Executed<'_>) -> String {
    let kind = match (executed.closed, executed.open) {
        (Some(_), Some(_)) => "closed-loop insertions (and the same worlds open loop)",
        (Some(_), None) => "closed-loop insertions",
        _ => "open-loop insertions",
    };
    format!(
        "{}: {}, {} simulated {kind}",
        title_of(&a.file),
        setup.prepared.outcome.form,
        a.runs
    )
}
