//! `needle`: plan bevel-tip needle paths locally or on a device, and analyse them.

//!
//! Each command's flags are here and only here, one module per command where `main.rs` does not
//! say them in a line, turned into the plain options of a library crate (`needle-scenario`,
//! `needle-report`, `needle-device`, `needle-analysis`, `needle-simulate`, `needle-lab`,
//! `needle-anatomy`), whose functions do the work and print; none of those depends on clap, so
//! the Python package calls them with the same options.

use clap::{Parser, Subcommand};
use link::LinkArgs;
use needle_device::commands as device;
use std::process::ExitCode;

mod approx;
mod bench;
mod benchmark;
mod compare;
mod cover;
mod link;
mod motion;
mod plan;
mod plot;
mod rrt;
mod scenario_args;
mod simulate;
mod steer;
mod sweep;
mod values;

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

#[derive(Subcommand)]
enum Command {
    /// Plan a scenario on this machine.
    Plan(plan::PlanArgs),
    /// Re-plan for each value of one weight (robustness analysis).
    Sweep(sweep::SweepArgs),
    /// Plan with the RRT baseline.
    Rrt(rrt::RrtCmd),
    /// The optimiser against the RRT over several seeds.
    Compare(compare::CompareArgs),
    /// Turn polygon obstacles into covering circles.
    Approx(approx::ApproxArgs),
    /// Cover a label map's segments (NRRD, Slicer .seg.nrrd, NIfTI) with spheres to avoid.
    Cover(cover::CoverArgs),
    /// Draw a scenario and its plan (SVG).
    Plot(plot::PlotArgs),
    /// Execute the plan in simulated perturbed insertions, open loop or steered (closed loop).
    Simulate(simulate::SimulateArgs),
    /// Steer an insertion in a lab: OpenIGTLink tracker poses in, robot commands out
    /// (docs/lab.md; `hil-sim --lab` is a simulated lab).
    Steer(steer::SteerArgs),
    /// Plan and simulate (open and closed loop) seeded 3-D scenarios nobody tuned on.
    Benchmark(benchmark::BenchmarkArgs),
    /// Plan a scenario on a device (serial port or TCP); prints what `plan` prints.
    Send(plan::SendArgs),
    /// Drive a board's two axes: arm, home, move a scenario's plan, hold, stop, e-stop
    /// (docs/motion.md; `hil-sim --axes` and the QEMU firmware drive simulated ones).
    Motion(motion::MotionArgs),
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
    Bench(bench::BenchArgs),
    /// Moved to `cargo xtask device-bench`: the firmware's measurement needs a checkout (its
    /// sources, toolchain and QEMU), so the installed command does not carry it.
    #[command(hide = true, disable_help_flag = true)]
    DeviceBench {
        #[arg(num_args = 0.., allow_hyphen_values = true, trailing_var_arg = true)]
        args: Vec<String>,
    },
}

/// The error of a subcommand that became a `cargo xtask` task: where it went, with the arguments
/// given.
fn moved_to_xtask(task: &str, args: &[String]) -> anyhow::Error {
    let given: String = args.iter().map(|a| format!(" {a}")).collect();
    anyhow::anyhow!(
        "`needle {task}` moved out of needle: run `cargo xtask {task}{given}` in a needle-planner \
         checkout (docs/firmware.md)"
    )
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
        Command::Plan(a) => plan::plan(a),
        Command::Sweep(a) => sweep::sweep(a),
        Command::Rrt(a) => rrt::rrt(a),
        Command::Compare(a) => compare::compare(a),
        Command::Approx(a) => approx::approx(a),
        Command::Cover(a) => cover::run_cover(a),
        Command::Plot(a) => plot::plot(a),
        Command::Simulate(a) => simulate::simulate(a),
        Command::Steer(a) => steer::steer(a),
        Command::Benchmark(a) => benchmark::benchmark(a),
        Command::Send(a) => plan::send(a),
        Command::Motion(a) => motion::motion(a),
        Command::Ping { link, count } => device::ping(&link.options(), *count),
        Command::Info { link, json } => device::info(&link.options(), *json),
        Command::Ports => device::ports(),
        Command::Bench(a) => bench::bench(a),
        Command::DeviceBench { args } => Err(moved_to_xtask("device-bench", args)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader closed the pipe (`needle plan ... | head`): it has what it wanted.
        Err(e) if closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // `needle steer` says how an insertion ended by its exit status; anything else is 1.
            ExitCode::from(needle_lab::exit_code(&e))
        }
    }
}
