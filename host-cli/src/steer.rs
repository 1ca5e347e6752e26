//! `needle steer`: its flags, the insertion steered in a lab by `needle_lab::steer`.

use needle_device::LinkOptions;
use needle_lab::wire::{TARGET_DEVICE, TIP_DEVICE};
use needle_lab::SteerOptions;
use std::net::IpAddr;
use std::path::PathBuf;

/// `needle steer`
#[derive(clap::Args, Clone, Debug)]
pub struct SteerArgs {
    /// Scenario file (TOML): planned as `needle simulate --closed-loop` plans it.
    file: PathBuf,
    /// The tracker's OpenIGTLink server (PLUS, or `hil-sim --lab`), HOST:PORT.
    #[arg(long)]
    tracker: String,
    /// Device name of the tip's TRANSFORM.
    #[arg(long, default_value = TIP_DEVICE)]
    tip_name: String,
    /// Device name of the target's TRANSFORM.
    #[arg(long, default_value = TARGET_DEVICE)]
    target_name: String,
    /// The registration: a JSON file with `rotation` (row-major) and `translation_mm`, taking a
    /// point of the tracker's reference frame to the scenario's (default: the same frame).
    #[arg(long, conflicts_with = "registration_name")]
    registration: Option<PathBuf>,
    /// The registration from the tracker stream: the device name of a TRANSFORM taking a point
    /// of the tracker's reference frame to the scenario's (as the file's), e.g.
    /// ReferenceToScenario. Steering waits for the first one; a later different one is refused.
    #[arg(long, value_name = "NAME")]
    registration_name: Option<String>,
    /// With --registration-name: how long to wait for it before giving up ("no_registration").
    #[arg(long, requires = "registration_name", default_value_t = SteerOptions::default().registration_timeout_ms)]
    registration_timeout_ms: u64,
    /// The robot's OpenIGTLink server (the robot mapping of docs/lab.md), HOST:PORT. Without
    /// it, the driver board at --tcp or --port plans, steers and moves the needle itself
    /// (armed and homed first: `needle motion arm`, `home`; docs/motion.md).
    #[arg(long, required_unless_present_any = ["tcp", "port"])]
    robot: Option<String>,
    /// With a driver board and no --robot: the needle guide is set to the plan's tilt (the
    /// board only turns and inserts); a plan that tilts the needle is refused without it.
    #[arg(long, conflicts_with = "robot")]
    tilt_set: bool,
    /// Show the insertion in 3D Slicer: its OpenIGTLinkIF server (a client connection), HOST:PORT.
    #[arg(long, conflicts_with = "serve_slicer")]
    slicer: Option<String>,
    /// Show the insertion in 3D Slicer by serving OpenIGTLink on this port of 127.0.0.1 (or of
    /// --serve-slicer-bind): Slicer's OpenIGTLinkIF connector of type Client connects to it, as
    /// to PLUS; 0 picks a free port, printed on stderr. Viewers may join and leave during the
    /// insertion. Anyone who can connect sees the plan and the insertion (no authentication).
    #[arg(long, value_name = "PORT")]
    serve_slicer: Option<u16>,
    /// With --serve-slicer: the address to serve on (default 127.0.0.1, this machine only;
    /// 0.0.0.0 every interface, so any host that reaches this one can watch).
    #[arg(long, value_name = "ADDR", requires = "serve_slicer",
          default_value_t = SteerOptions::default().serve_slicer_bind)]
    serve_slicer_bind: IpAddr,
    /// With --serve-slicer: wait up to this many seconds for the first viewer before steering.
    #[arg(
        long,
        value_name = "SECONDS",
        requires = "serve_slicer",
        default_value_t = SteerOptions::default().wait_for_slicer
    )]
    wait_for_slicer: f64,
    /// Write the insertion log here (JSON lines: the plan, each reading, each command, the stop).
    #[arg(long)]
    log: Option<PathBuf>,
    /// Seed of the insertion's world, for the record (the world is the lab's, not this
    /// program's).
    #[arg(long)]
    seed: Option<u64>,
    /// Degrees of freedom of the tip sensor: 6 (the tip TRANSFORM's roll is the bevel's) or 5
    /// (a 5-DOF coil, as the ones that fit a needle: the TRANSFORM's roll means nothing and is
    /// left out; the controller infers the roll from how the path bends).
    #[arg(long, value_name = "N", default_value_t = SteerOptions::default().tracker_dof,
          value_parser = clap::value_parser!(u8).range(5..=6))]
    tracker_dof: u8,
    /// Tell the controller one thing, KEY=VALUE (as `needle simulate --steer`).
    #[arg(long = "steer", value_name = "KEY=VALUE")]
    steer: Vec<String>,
    /// No tip pose for this long: the robot is told hold, then stop ("tracking_lost").
    #[arg(long, default_value_t = SteerOptions::default().tracking_timeout_ms)]
    tracking_timeout_ms: u64,
    /// No robot report this long after a command: the robot is told stop
    /// ("robot_not_answering").
    #[arg(long, default_value_t = SteerOptions::default().robot_timeout_ms)]
    robot_timeout_ms: u64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    /// Steer on the device at this TCP address (hil-sim --tcp, QEMU) instead of in-process.
    #[arg(long, conflicts_with = "port")]
    tcp: Option<String>,
    /// Steer on the device at this serial port instead of in-process.
    #[arg(long)]
    port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = LinkOptions::default().baud)]
    baud: u32,
    /// Seconds of silence allowed per exchange with the device.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
}

impl SteerArgs {
    /// What the flags ask; the device to steer on is `--tcp` or `--port`, if any.
    fn options(&self) -> SteerOptions {
        SteerOptions {
            file: self.file.clone(),
            tracker: self.tracker.clone(),
            tip_name: self.tip_name.clone(),
            target_name: self.target_name.clone(),
            registration: self.registration.clone(),
            registration_name: self.registration_name.clone(),
            registration_timeout_ms: self.registration_timeout_ms,
            robot: self.robot.clone(),
            tilt_set: self.tilt_set,
            slicer: self.slicer.clone(),
            serve_slicer: self.serve_slicer,
            serve_slicer_bind: self.serve_slicer_bind,
            wait_for_slicer: self.wait_for_slicer,
            log: self.log.clone(),
            seed: self.seed,
            tracker_dof: self.tracker_dof,
            steer: self.steer.clone(),
            tracking_timeout_ms: self.tracking_timeout_ms,
            robot_timeout_ms: self.robot_timeout_ms,
            json: self.json,
            link: LinkOptions::optional(&self.port, self.baud, &self.tcp, self.timeout),
        }
    }
}

/// Runs `needle steer`; how the insertion ended is the error's exit status
/// (`needle_lab::exit_code`).
pub fn steer(a: &SteerArgs) -> anyhow::Result<()> {
    needle_lab::run_steer(&a.options())
}
