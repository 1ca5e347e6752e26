//! `needle plan` and `needle send`: a scenario planned here or on a device (`needle-report`,
//! `needle-device`), printed the same way.

use crate::link::LinkArgs;
use crate::values::MethodArg;
use anyhow::{anyhow, Result};
use needle_device::checked::{plan_checked, Sent};
use needle_report::local::{plan_locally, LocalPlan};
use needle_report::schedule_table;
use needle_scenario::{load_execution, load_scenario, load_scenario_shapes, restrict, Execution};
use planner_core::{PlanReport, Scenario};
use std::io::Write;
use std::path::PathBuf;

/// Options that restrict what is planned, shared by `plan` and `send`.
#[derive(clap::Args, Clone)]
pub struct PlanArgs {
    /// Scenario file (TOML, see examples/paper.toml).
    file: PathBuf,
    /// Print one JSON object instead of the table (it always carries `best.schedule`).
    #[arg(long)]
    json: bool,
    /// Also print the best path's motor schedule as a table after the plan.
    #[arg(long)]
    schedule: bool,
    /// Largest control degree N to try (overrides the file).
    #[arg(long)]
    max_degree: Option<u8>,
    /// Comma-separated forms to try, e.g. RL,LRL (overrides the file).
    #[arg(long, value_delimiter = ',')]
    forms: Option<Vec<String>>,
    /// Also draw every form's path (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Turn polygon obstacles into circles this way: circumscribed, segmented or bordered.
    #[arg(long, ignore_case = true)]
    approx: Option<MethodArg>,
    /// Also write files 3D Slicer opens into DIR: the path as a markups curve, the entry and
    /// target as markups points (RAS), the obstacles as a model (docs/anatomy.md).
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
}

/// `needle send`: the options of `plan` plus where the device is.
#[derive(clap::Args)]
pub struct SendArgs {
    #[command(flatten)]
    plan: PlanArgs,
    #[command(flatten)]
    link: LinkArgs,
}

fn load(args: &PlanArgs) -> Result<Scenario> {
    let mut scenario = match args.approx {
        None => load_scenario(&args.file)?,
        Some(m) => load_scenario_shapes(&args.file, Some(m.into()))?.0,
    };
    restrict(&mut scenario, args.max_degree, args.forms.as_deref())?;
    Ok(scenario)
}

/// Prints a plan as `plan` and `send` do: the table (and with `--schedule` the schedule's), or
/// the JSON report with `best.schedule` (`best` is `null` when no form is feasible, and there is
/// no schedule), with the predictions when there are any.
fn print_plan(args: &PlanArgs, made: &LocalPlan, execution: &Execution) -> Result<()> {
    let schedule = made.schedule()?;
    let clearance = label_map_clearance(args, made)?;
    let mut out = std::io::stdout();
    if args.json {
        let mut json = made.json(execution);
        if let Some(best) = json.best.as_mut() {
            best.label_map_clearance_mm = clearance;
        }
        writeln!(out, "{json}")?;
        return Ok(());
    }
    write!(out, "{}", made.table(execution))?;
    let file = needle_scenario::file::ScenarioFile::load(&args.file)?;
    for line in file.target_lines()? {
        writeln!(out, "{line}")?;
    }
    if let Some(c) = clearance {
        writeln!(
            out,
            "label-map clearance {c:.2} mm: the best path to the nearest voxel centre of the \
             covered segments, on the label map (the table's clearances are to the spheres)"
        )?;
    }
    if let Some(schedule) = schedule.filter(|_| args.schedule) {
        let driver = &made.scenario.driver;
        write!(out, "{}", schedule_table(schedule, driver))?;
    }
    Ok(())
}

/// Says on stderr which files `--export` wrote (stdout stays the report).
fn wrote(files: &[PathBuf]) {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    eprintln!("wrote {}", names.join(", "));
}

/// With `[[anatomy]]`: the best path's least distance (mm) to the covered segments' voxels,
/// measured on the label maps themselves.
fn label_map_clearance(args: &PlanArgs, made: &LocalPlan) -> Result<Option<f64>> {
    let Some(best) = made.report().best() else {
        return Ok(None);
    };
    let file = needle_scenario::file::ScenarioFile::load(&args.file)?;
    if file.anatomy.is_empty() {
        return Ok(None);
    }
    file.label_map_clearance(&made.scenario, best)
}

/// A printed report without a best form is still a failed plan: the command says why on stderr
/// and exits 1.
fn reachable(report: &PlanReport) -> Result<()> {
    match report.best() {
        Some(_) => Ok(()),
        None => Err(anyhow!(planner_core::PlanError::Unreachable)),
    }
}

/// Runs `needle plan`.
pub fn plan(args: &PlanArgs) -> Result<()> {
    if !args.json {
        needle_anatomy::progress::enable();
    }
    let scenario = load(args)?;
    let execution = load_execution(&args.file)?;
    let made = plan_locally(&scenario, &execution)?;
    print_plan(args, &made, &execution)?;
    // The scenario as planned: its reserve is the plan's.
    let (scenario, report) = (&made.scenario, made.report());
    if let Some(out) = &args.plot {
        needle_analysis::commands::write_plan_plot(
            &args.file,
            args.approx.map(Into::into),
            scenario,
            report,
            out,
        )?;
    }
    if let Some(dir) = &args.export {
        wrote(&needle_report::slicer::export(dir, scenario, report)?);
    }
    made.verdict()
}

/// Runs `needle send`.
pub fn send(args: &SendArgs) -> Result<()> {
    if !args.plan.json {
        needle_anatomy::progress::enable();
    }
    let scenario = load(&args.plan)?;
    let execution = load_execution(&args.plan.file)?;
    let made = match plan_checked(&scenario, &execution, &args.link.options())? {
        Sent::Planned(made) => *made,
        Sent::Refused(e) => return Err(e),
    };
    print_plan(&args.plan, &made, &execution)?;
    let report = made.report();
    if report.best().is_none() {
        return reachable(report);
    }
    if let Some(dir) = &args.plan.export {
        wrote(&needle_report::slicer::export(dir, &made.scenario, report)?);
    }
    made.verdict()
}
