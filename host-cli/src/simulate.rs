//! `needle simulate`: its flags, the runs made by `needle_simulate`. Flags that mean nothing
//! alone are refused by clap as usage errors (exit status 2, as for any other bad flag) rather
//! than silently ignored.

use crate::values::at_least_one;
use needle_device::LinkOptions;
use needle_simulate::SimulateOptions;
use std::path::PathBuf;

/// Default `--retries` of a closed loop on a device: at one request in five through, 400 tries
/// leave about one failed reading in 10^38.
const STEER_RETRIES: u32 = 400;

/// `needle simulate`
#[derive(clap::Args, Clone, Debug)]
pub struct SimulateArgs {
    /// Scenario file (TOML, see examples/paper.toml).
    file: PathBuf,
    /// Simulated insertions, 1 to 1 000 000 (checked with the scenario, so that the Python
    /// package's `simulate` gives the same message).
    #[arg(long, default_value_t = SimulateOptions::default().runs)]
    runs: usize,
    /// Seed of the first run (run i uses seed + i).
    #[arg(long, default_value_t = SimulateOptions::default().seed)]
    seed: u64,
    /// Plan and simulate only this form (e.g. RL) instead of the best.
    #[arg(long)]
    form: Option<String>,
    /// Change one perturbation or world effect, KEY=VALUE (repeatable; over `--world`; see
    /// docs/execution.md).
    #[arg(long = "perturb", value_name = "KEY=VALUE")]
    perturb: Vec<String>,
    /// The world the runs are made in: `default` (the perturbation alone) or `clinical` (a
    /// 5-DOF sensor, field bias, registration error, punctured layers, a pushed target, late
    /// imaging and tracker, dropouts; docs/execution.md, "The clinical world").
    #[arg(long, value_name = "NAME")]
    world: Option<String>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// With --json: every run's draws, figures, points and steps (as executed: a step broken off
    /// with the length, time and turns it took).
    #[arg(long, requires = "json")]
    detail: bool,
    /// Also draw the plan and the executed paths (SVG; the file is opened before simulating).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Also write files 3D Slicer opens into DIR: the plan as `needle plan --export` writes it,
    /// and every simulated path as a model (`paths-open-loop.vtk`, `paths-closed-loop.vtk`).
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
    /// Threads, at least 1 (default: every core).
    #[arg(long, value_parser = at_least_one)]
    threads: Option<usize>,
    /// Steer every run with the closed-loop controller (replanning from each tracker reading)
    /// instead of executing the schedule open loop.
    #[arg(long)]
    closed_loop: bool,
    /// With --closed-loop: a tracker fault, KEY=VALUE (repeatable): dropout_rate, dropout_mm,
    /// outlier_rate, outlier_mm, repeat_rate, stale_rate (dropouts per mm, the rest per reading).
    #[arg(long = "fault", value_name = "KEY=VALUE", requires = "closed_loop")]
    fault: Vec<String>,
    /// With --closed-loop: tell the controller one thing of the tracker or the insertion,
    /// KEY=VALUE (repeatable; a key of the scenario's `[steering]`, docs/scenario.md, over
    /// what the file says). The world stays as `--perturb` makes it.
    #[arg(long = "steer", value_name = "KEY=VALUE", requires = "closed_loop")]
    steer: Vec<String>,
    /// With --closed-loop: steer on the device at this TCP address (hil-sim --tcp, QEMU)
    /// instead of in-process; the host runs the simulated robot, tissue and tracker.
    #[arg(long, requires = "closed_loop", conflicts_with = "port")]
    tcp: Option<String>,
    /// With --closed-loop: steer on the device at this serial port instead of in-process.
    #[arg(long, requires = "closed_loop")]
    port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = LinkOptions::default().baud)]
    baud: u32,
    /// Seconds of silence allowed per exchange with the device.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
    /// Times one request to the device is sent again before giving up. More than a plan's
    /// default: a steering request (about 80 bytes) cannot be cut into parts, and a line that
    /// damages 2 % of its bytes lets one in five through; a silent device still ends the
    /// exchange after --timeout.
    #[arg(long, default_value_t = STEER_RETRIES)]
    retries: u32,
    /// With --closed-loop: also run the same worlds open loop and print both side by side.
    #[arg(long, requires = "closed_loop")]
    compare_open_loop: bool,
}

impl SimulateArgs {
    /// The device to steer on (`--tcp` or `--port`), if any.
    fn link(&self) -> Option<LinkOptions> {
        let mut link = LinkOptions::optional(&self.port, self.baud, &self.tcp, self.timeout)?;
        link.retries = self.retries;
        Some(link)
    }

    /// What the flags ask.
    fn options(&self) -> SimulateOptions {
        SimulateOptions {
            file: self.file.clone(),
            runs: self.runs,
            seed: self.seed,
            form: self.form.clone(),
            perturb: self.perturb.clone(),
            world: self.world.clone(),
            json: self.json,
            detail: self.detail,
            plot: self.plot.clone(),
            export: self.export.clone(),
            threads: self.threads,
            closed_loop: self.closed_loop,
            faults: self.fault.clone(),
            steer: self.steer.clone(),
            link: self.link(),
            compare_open_loop: self.compare_open_loop,
        }
    }
}

/// Runs `needle simulate`.
pub fn simulate(a: &SimulateArgs) -> anyhow::Result<()> {
    needle_simulate::run_simulate(&a.options())
}
