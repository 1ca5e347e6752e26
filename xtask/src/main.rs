//! `cargo xtask`: the repository's developer tasks, run from a checkout (the alias is in
//! `.cargo/config.toml`). They need the firmware's sources, its toolchain and QEMU, so they are
//! not part of the `needle` binary a user installs; the work is `needle-devtools`'.

use anyhow::Result;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "cargo xtask",
    bin_name = "cargo xtask",
    about = "Developer tasks of needle-planner (run from a checkout)"
)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Subcommand)]
enum Task {
    /// Measure the firmware in QEMU: flash, RAM, stack and instructions per plan.
    DeviceBench(needle_devtools::device_bench::Args),
}

fn run(task: &Task) -> Result<()> {
    match task {
        // The scenario files are read as `needle` reads them, collision bound included.
        Task::DeviceBench(a) => {
            needle_devtools::device_bench::run(a, &needle_scenario::load_plan_request)
        }
    }
}

fn main() -> ExitCode {
    match run(&Cli::parse().task) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
