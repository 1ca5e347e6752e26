//! `needle`: plan bevel-tip needle paths locally or on a device, and analyse them.

use anyhow::{anyhow, Result};
use clap::{Parser, Subcommand};
use needle_cli::analysis::cli as analysis;
use needle_cli::device::{self, commands::LinkArgs};
use needle_cli::report::local::{plan_locally, LocalPlan};
use needle_cli::report::schedule_table;
use needle_cli::scenario::{
    load_execution, load_scenario, load_scenario_shapes, restrict, Execution,
};
use planner_core::{PlanReport, Scenario};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "needle",
    version,
    about = "Path planner for bevel-tip steerable needles"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Options that restrict what is planned, shared by `plan` and `send`.
#[derive(clap::Args, Clone)]
struct PlanArgs {
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
    approx: Option<needle_cli::scenario::approx::Method>,
    /// Also write files 3D Slicer opens into DIR: the path as a markups curve, the entry and
    /// target as markups points (RAS), the obstacles as a model (docs/anatomy.md).
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Plan a scenario on this machine.
    Plan(PlanArgs),
    /// Re-plan for each value of one weight (robustness analysis).
    Sweep(analysis::SweepArgs),
    /// Plan with the RRT baseline.
    Rrt(analysis::RrtCmd),
    /// The optimiser against the RRT over several seeds.
    Compare(analysis::CompareArgs),
    /// Turn polygon obstacles into covering circles.
    Approx(analysis::ApproxArgs),
    /// Cover a label map's segments (NRRD, Slicer .seg.nrrd, NIfTI) with spheres to avoid.
    Cover(needle_cli::anatomy::command::CoverArgs),
    /// Draw a scenario and its plan (SVG).
    Plot(analysis::PlotArgs),
    /// Execute the plan in simulated perturbed insertions, open loop or steered (closed loop).
    Simulate(needle_cli::simulate::SimulateArgs),
    /// Steer an insertion in a lab: OpenIGTLink tracker poses in, robot commands out
    /// (docs/lab.md; `hil-sim --lab` is a simulated lab).
    Steer(needle_cli::lab::SteerArgs),
    /// Plan and simulate (open and closed loop) seeded 3-D scenarios nobody tuned on.
    Benchmark(needle_cli::benchmark::BenchmarkArgs),
    /// Plan a scenario on a device (serial port or TCP); prints what `plan` prints.
    Send(SendArgs),
    /// Check that a device answers, and how fast.
    Ping {
        #[command(flatten)]
        link: LinkArgs,
        /// Pings to send.
        #[arg(long, default_value_t = 4)]
        count: u32,
    },
    /// Show a device's firmware, protocol version and capacities.
    Info {
        #[command(flatten)]
        link: LinkArgs,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// List serial ports with their USB vendor and product ids.
    Ports,
    /// Time planning a scenario (release build: `cargo run --release -p needle-cli -- bench`).
    Bench(BenchArgs),
    /// Measure the firmware in QEMU: flash, RAM, stack and instructions per plan.
    DeviceBench(needle_devtools::device_bench::Args),
}

/// `needle send`: the options of `plan` plus where the device is.
#[derive(clap::Args)]
struct SendArgs {
    #[command(flatten)]
    plan: PlanArgs,
    #[command(flatten)]
    link: LinkArgs,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scenario files (default: examples/paper.toml).
    files: Vec<PathBuf>,
    /// Measured runs per scenario.
    #[arg(long, default_value_t = 200)]
    runs: usize,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Instead of files: TOTAL generated spheres of which NEAR lie within 20 mm of the
    /// entry-target segment (D summed over the spheres within 20 mm), planned side by side with
    /// the NEAR alone; the two plans must be the same (docs/anatomy.md, "Hundreds of spheres").
    #[arg(long, value_name = "TOTAL,NEAR", conflicts_with = "files")]
    near_and_far: Option<String>,
    /// The seed of `--near-and-far`'s scenario.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

fn load(args: &PlanArgs) -> Result<Scenario> {
    let mut scenario = match args.approx {
        None => load_scenario(&args.file)?,
        Some(m) => load_scenario_shapes(&args.file, Some(m))?.0,
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
    let file = needle_cli::scenario::file::ScenarioFile::load(&args.file)?;
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
    let file = needle_cli::scenario::file::ScenarioFile::load(&args.file)?;
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

fn plan(args: &PlanArgs) -> Result<()> {
    if !args.json {
        needle_cli::progress::enable();
    }
    let scenario = load(args)?;
    let execution = load_execution(&args.file)?;
    let made = plan_locally(&scenario, &execution)?;
    print_plan(args, &made, &execution)?;
    // The scenario as planned: its reserve is the plan's.
    let (scenario, report) = (&made.scenario, made.report());
    if let Some(out) = &args.plot {
        analysis::write_plan_plot(&args.file, args.approx, scenario, report, out)?;
    }
    if let Some(dir) = &args.export {
        wrote(&needle_cli::report::slicer::export(dir, scenario, report)?);
    }
    made.verdict()
}

fn send(args: &SendArgs) -> Result<()> {
    if !args.plan.json {
        needle_cli::progress::enable();
    }
    let scenario = load(&args.plan)?;
    let execution = load_execution(&args.plan.file)?;
    let made = match device::checked::plan_checked(&scenario, &execution, &args.link)? {
        device::checked::Sent::Planned(made) => *made,
        device::checked::Sent::Refused(e) => return Err(e),
    };
    print_plan(&args.plan, &made, &execution)?;
    let report = made.report();
    if report.best().is_none() {
        return reachable(report);
    }
    if let Some(dir) = &args.plan.export {
        wrote(&needle_cli::report::slicer::export(
            dir,
            &made.scenario,
            report,
        )?);
    }
    made.verdict()
}

fn bench(args: &BenchArgs) -> Result<()> {
    if let Some(spec) = &args.near_and_far {
        return bench_near_and_far(args, spec);
    }
    let files = if args.files.is_empty() {
        vec![PathBuf::from("examples/paper.toml")]
    } else {
        args.files.clone()
    };
    let mut out = Vec::new();
    for f in &files {
        let scenario = load_scenario(f)?;
        let name = f
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let r = needle_cli::bench::run(&scenario, 3, args.runs)?;
        if args.json {
            out.push(needle_cli::bench::to_json(&name, &r));
        } else {
            write!(std::io::stdout(), "{}", needle_cli::bench::table(&name, &r))?;
        }
    }
    if args.json {
        writeln!(std::io::stdout(), "{}", serde_json::Value::Array(out))?;
    }
    Ok(())
}

/// `needle bench --near-and-far TOTAL,NEAR`.
fn bench_near_and_far(args: &BenchArgs, spec: &str) -> Result<()> {
    let parsed = spec
        .split_once(',')
        .and_then(|(t, n)| Some((t.trim().parse().ok()?, n.trim().parse().ok()?)));
    let Some((total, near)) = parsed else {
        anyhow::bail!("--near-and-far {spec}: expected TOTAL,NEAR (two whole numbers)");
    };
    let r = needle_cli::bench::near_and_far(args.seed, total, near, args.runs)?;
    let m = needle_cli::bench::measures(args.seed, total, near, args.runs)?;
    let ratio = r.all_ms / r.near_ms;
    let rows = [("check", m.check), ("risk", m.risk), ("predict", m.predict)];
    let text = if args.json {
        let mut v = serde_json::json!({
            "seed": args.seed, "spheres": total, "near": near, "runs": args.runs.max(1),
            "best": r.best, "all_ms": r.all_ms, "near_ms": r.near_ms, "ratio": ratio,
            "measured_forms": m.forms,
        });
        for (name, x) in rows {
            v[format!("{name}_us")] = serde_json::json!({
                "culled": x.culled_us, "every": x.every_us, "near": x.near_us,
            });
        }
        format!("{v}\n")
    } else {
        let mut t = format!(
            "seed {}: {total} spheres, {near} within 20 mm; the same plan (best {})\n\
             {total} spheres: median {:.2} ms over {} runs\n\
             {near} alone: median {:.2} ms\nratio {ratio:.3}\n\
             every feasible form ({}) measured, median us: {total} culled, {total} every sphere, \
             {near} alone\n",
            args.seed,
            r.best,
            r.all_ms,
            args.runs.max(1),
            r.near_ms,
            m.forms
        );
        for (name, x) in rows {
            t.push_str(&format!(
                "{name:<8} {:>9.1} {:>9.1} {:>9.1}\n",
                x.culled_us, x.every_us, x.near_us
            ));
        }
        t
    };
    write!(std::io::stdout(), "{text}")?;
    Ok(())
}

/// Whether writing the output failed because its reader went away.
fn closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Plan(a) => plan(a),
        Command::Sweep(a) => analysis::run_sweep(a),
        Command::Rrt(a) => analysis::run_rrt(a),
        Command::Compare(a) => analysis::run_compare(a),
        Command::Approx(a) => analysis::run_approx(a),
        Command::Cover(a) => needle_cli::anatomy::command::run_cover(a),
        Command::Plot(a) => analysis::run_plot(a),
        Command::Simulate(a) => needle_cli::simulate::run_simulate(a),
        Command::Steer(a) => needle_cli::lab::run_steer(a),
        Command::Benchmark(a) => needle_cli::benchmark::run_benchmark(a),
        Command::Send(a) => send(a),
        Command::Ping { link, count } => device::commands::ping(link, *count),
        Command::Info { link, json } => device::commands::info(link, *json),
        Command::Ports => device::commands::ports(),
        Command::Bench(a) => bench(a),
        Command::DeviceBench(a) => {
            needle_devtools::device_bench::run(a, &needle_cli::scenario::load_plan_request)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader closed the pipe (`needle plan ... | head`): it has what it wanted.
        Err(e) if closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // `needle steer` says how an insertion ended by its exit status; anything else is 1.
            ExitCode::from(needle_cli::lab::exit_code(&e))
        }
    }
}
