//! `hil-sim`: a simulated needle-planner device on a pseudo-terminal or a TCP port.
//!
//! Prints the device's address (the /dev/pts path, or the TCP address) as the first line on
//! stdout, then serves until killed.
//!
//! `hil-sim --lab SCENARIO --tracker-port P --robot-port Q` is the simulated lab instead
//! (`hil_sim::lab`): its first line is `tracker ADDRESS robot ADDRESS` (`board ADDRESS` with
//! `--board-port`: a driver board instead of a robot), then one JSON line of true figures per
//! insertion.

use anyhow::{Context, Result};
use clap::Parser;
use hil_sim::lab::{Lab, LabConfig, TrackerClients, TrackerConfig};
use hil_sim::serve::{serve_with_axes, ServeConfig};
use hil_sim::{DeviceService, LineConfig, SimulatedAxes, IDENTITY};
use needle_simulate::request::Request;
use std::io::Write;
use std::net::TcpListener;

#[derive(Parser)]
#[command(name = "hil-sim", version, about = "Simulated needle-planner device")]
struct Args {
    /// Serve on this TCP address (e.g. 127.0.0.1:7878; port 0 picks a free one) instead of a pty.
    #[arg(long)]
    tcp: Option<String>,
    /// Fraction of bytes corrupted on the line, in each direction.
    #[arg(long, default_value_t = 0.0)]
    flip_rate: f64,
    /// Fraction of bytes lost on the line, in each direction.
    #[arg(long, default_value_t = 0.0)]
    drop_rate: f64,
    /// Fraction of bytes that start a burst of corrupted bytes, in each direction.
    #[arg(long, default_value_t = 0.0)]
    burst_rate: f64,
    /// Bytes corrupted by one burst.
    #[arg(long, default_value_t = 20)]
    burst_len: u32,
    /// Seed of the fault pattern; with --lab, of the first insertion's world (the k-th
    /// insertion from 0 runs in the world of seed + k, as `needle simulate` numbers runs).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Pace bytes as a UART at this baud rate would (8N1); 0 for no pacing.
    #[arg(long, default_value_t = 0)]
    baud: u32,
    /// Drive simulated motors: the device's motion core (protocol 10's motion requests) steps
    /// two simulated stages in real time (the bench axes of docs/motion.md).
    #[arg(long, conflicts_with = "lab")]
    axes: bool,
    #[command(flatten)]
    lab: LabArgs,
}

/// The simulated lab's flags.
#[derive(clap::Args)]
struct LabArgs {
    /// Serve the simulated lab of this scenario file: an OpenIGTLink tracker and robot over the
    /// world of `needle simulate` (docs/lab.md).
    #[arg(long, value_name = "SCENARIO", conflicts_with = "tcp")]
    lab: Option<std::path::PathBuf>,
    /// With --lab: the tracker's TCP port on 127.0.0.1 (0 picks a free one).
    #[arg(long, requires = "lab", default_value_t = 18944)]
    tracker_port: u16,
    /// With --lab: the robot's TCP port on 127.0.0.1 (0 picks a free one).
    #[arg(long, requires = "lab", default_value_t = 18945)]
    robot_port: u16,
    /// With --lab --real-time: play a driver board instead of a robot: the simulated device with
    /// the bench's simulated stages serves `needle`'s protocol on this TCP port of 127.0.0.1 (0
    /// picks a free one), and the world takes each piece the board moves itself (`needle motion
    /// arm`, `home`, then `needle steer --tcp` with no --robot; docs/motion.md).
    #[arg(long, requires = "real_time", value_name = "PORT")]
    board_port: Option<u16>,
    /// With --lab: pieces per second at most (0: lock-step, as fast as the host answers).
    #[arg(long, requires = "lab", default_value_t = 0.0)]
    rate: f64,
    /// With --lab: delay of each pose after its piece (ms).
    #[arg(long, requires = "lab", default_value_t = 0)]
    latency_ms: u64,
    /// With --lab: delay of each piece's report after its pose (ms), as a robot whose word
    /// travels slower than the tracker's stream.
    #[arg(long, requires = "lab", default_value_t = 0)]
    report_delay_ms: u64,
    /// With --lab, a fault for tests: the tracker goes quiet after this many poses.
    #[arg(long, requires = "lab")]
    tracker_silent_after: Option<u32>,
    /// With --lab, a fault for tests: the robot stops reporting after this many pieces.
    #[arg(long, requires = "lab")]
    robot_silent_after: Option<u32>,
    /// With --lab, a fault for tests: every this many poses one is flagged invalid
    /// (alternately by v3 metadata and by a tip STATUS that is not OK).
    #[arg(long, requires = "lab")]
    invalid_every: Option<u32>,
    /// With --lab, a fault for tests: after this many pieces the robot reports 5 mm more depth
    /// than it did.
    #[arg(long, requires = "lab")]
    robot_misreport_after: Option<u32>,
    /// With --lab, a fault for tests: after this many pieces the robot's contact sensor fires
    /// (it reports `collided` and stops), wherever the tip is. Without it the sensor fires when
    /// the true tip ends a piece inside an obstacle.
    #[arg(long, requires = "lab")]
    robot_collides_after: Option<u32>,
    /// With --lab: the robot's clock runs this far ahead of the machine's (ms; negative:
    /// behind), and its reports are stamped by it.
    #[arg(
        long,
        requires = "lab",
        value_name = "MS",
        default_value_t = 0,
        allow_negative_numbers = true
    )]
    robot_clock_offset_ms: i64,
    /// With --lab: run in real time, as a lab does: a free-running tracker sampling the tip at
    /// --tracker-rate (each sample stamped when taken, a piece's pose seen once it ended) and a
    /// robot whose pieces take their share of their step's duration times --time-scale.
    #[arg(long, requires = "lab", conflicts_with = "stream_rate")]
    real_time: bool,
    /// With --real-time: the tracker's samples a second.
    #[arg(
        long,
        requires = "real_time",
        value_name = "HZ",
        default_value_t = 40.0
    )]
    tracker_rate: f64,
    /// With --real-time: the factor on the pieces' durations (1: the plan's real durations;
    /// 0.05: twenty times faster).
    #[arg(long, requires = "real_time", value_name = "F", default_value_t = 1.0)]
    time_scale: f64,
    /// With --real-time, a fault for tests: each sample goes out this long after it was taken
    /// (a tracker lagging the robot).
    #[arg(long, requires = "real_time", value_name = "MS", default_value_t = 0)]
    tracker_lag_ms: u64,
    /// With --lab: the robot's absolute base roll when an insertion begins (degrees); it turns
    /// to the posture's roll the shorter way and reports absolute rolls.
    #[arg(
        long,
        requires = "lab",
        value_name = "DEG",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    robot_start_roll: f64,
    /// With --lab: the robot holds the needle in a fixed guide along the entry axis and
    /// refuses a posture that tilts it (`posture-refused max_tilt_deg=0`).
    #[arg(long, requires = "lab")]
    robot_fixed_guide: bool,
    /// With --lab: the registration `needle steer --registration` is given (JSON, tracker to
    /// scenario frame); the tracker then reports in the tracker's frame.
    #[arg(long, requires = "lab")]
    registration: Option<std::path::PathBuf>,
    /// With --lab and --registration: the tracker also sends the registration as a TRANSFORM of
    /// this name (to each client on connecting, and with each pose), as `needle steer
    /// --registration-name` takes it.
    #[arg(long, requires = "registration", value_name = "NAME")]
    registration_name: Option<String>,
    /// With --registration-name, a fault for tests: after this many pieces the registration sent
    /// is moved 5 mm along x (the poses stay in the first one's frame).
    #[arg(long, requires = "registration_name")]
    registration_change_after: Option<u32>,
    /// With --lab: the tracker also streams the newest pose free-running at this rate (Hz), as
    /// PLUS streams a tool, besides sending each piece's pose when it is measured.
    #[arg(long, requires = "lab", value_name = "HZ")]
    stream_rate: Option<f64>,
    /// With --stream-rate: every 50 periods this many poses go out back to back in one write.
    #[arg(long, requires = "stream_rate", default_value_t = 1)]
    stream_burst: u32,
    /// With --lab, a fault for tests: before every this many pieces' pose (with --real-time,
    /// every this many samples) one bad frame (in turn: a bad CRC, a wrong body size, a 20-byte
    /// name not UTF-8, a non-rigid matrix, a 20-byte name one letter off the tip's).
    #[arg(long, requires = "lab")]
    bad_frames_every: Option<u32>,
    /// With --lab: the world the insertions are made in, as `needle simulate --world` names it
    /// (`default`, `clinical`; docs/execution.md, "The clinical world"); without it, the
    /// scenario's `[execution]` world.
    #[arg(long, requires = "lab", value_name = "NAME")]
    world: Option<String>,
    /// With --lab: change one perturbation or world effect, KEY=VALUE (repeatable; over
    /// --world), as `needle simulate --perturb`.
    #[arg(long = "perturb", requires = "lab", value_name = "KEY=VALUE")]
    perturb: Vec<String>,
    /// With --lab: a tracker fault, KEY=VALUE (repeatable; over --world), as `needle simulate
    /// --fault`: dropout_rate, dropout_mm, outlier_rate, outlier_mm (repeat_rate and stale_rate
    /// are refused: `needle steer` uses a sample once).
    #[arg(long = "fault", requires = "lab", value_name = "KEY=VALUE")]
    fault: Vec<String>,
}

impl LabArgs {
    /// What `needle simulate` is asked that makes the lab's world.
    fn world(&self) -> Request {
        Request {
            world: self.world.clone(),
            perturb: self.perturb.clone(),
            faults: self.fault.clone(),
            ..Request::default()
        }
    }
}

/// Serves the simulated lab until killed.
fn serve_lab(file: &std::path::Path, a: &Args) -> Result<()> {
    let l = &a.lab;
    anyhow::ensure!(
        l.rate.is_finite() && l.rate >= 0.0,
        "--rate must be 0 or more"
    );
    anyhow::ensure!(
        l.tracker_rate.is_finite() && (1.0..=10_000.0).contains(&l.tracker_rate),
        "--tracker-rate must be within 1 and 10000 Hz"
    );
    anyhow::ensure!(
        l.time_scale.is_finite() && (0.0..=100.0).contains(&l.time_scale),
        "--time-scale must be within 0 and 100"
    );
    anyhow::ensure!(
        l.robot_start_roll.is_finite() && l.robot_start_roll.abs() <= 1e6,
        "--robot-start-roll must be a finite angle within 1e6 degrees"
    );
    if let Some(hz) = l.stream_rate {
        anyhow::ensure!(
            hz.is_finite() && (1.0..=100_000.0).contains(&hz),
            "--stream-rate must be within 1 and 100000 Hz"
        );
    }
    let setup = needle_simulate::closed_loop_setup(file, a.seed, &l.world())?;
    hil_sim::lab::check_faults(&setup.faults)?;
    let tracker = TcpListener::bind(("127.0.0.1", l.tracker_port))
        .with_context(|| format!("cannot listen on tracker port {}", l.tracker_port))?;
    let (peer, port) = match l.board_port {
        Some(port) => ("board", port),
        None => ("robot", l.robot_port),
    };
    let listener = TcpListener::bind(("127.0.0.1", port))
        .with_context(|| format!("cannot listen on {peer} port {port}"))?;
    let mut out = std::io::stdout();
    writeln!(
        out,
        "tracker {} {peer} {}",
        tracker.local_addr()?,
        listener.local_addr()?
    )?;
    out.flush()?;
    let lab = Lab {
        setup,
        config: LabConfig {
            seed: a.seed,
            rate_hz: l.rate,
            latency_ms: l.latency_ms,
            report_delay_ms: l.report_delay_ms,
            tracker_silent_after: l.tracker_silent_after,
            robot_silent_after: l.robot_silent_after,
            invalid_every: l.invalid_every,
            robot_misreport_after: l.robot_misreport_after,
            robot_collides_after: l.robot_collides_after,
            robot_clock_offset_ms: l.robot_clock_offset_ms,
            robot_start_roll_deg: l.robot_start_roll,
            robot_fixed_guide: l.robot_fixed_guide,
            time_scale: l.real_time.then_some(l.time_scale),
        },
        tracker: TrackerClients::new(TrackerConfig {
            registration: l
                .registration
                .as_deref()
                .map(needle_lab::wire::load_registration)
                .transpose()?,
            registration_name: l.registration_name.clone(),
            registration_change_after: l.registration_change_after,
            bad_frames_every: l.bad_frames_every,
            sampling: l.real_time,
        }),
    };
    lab.tracker.accept(tracker);
    if let Some(hz) = l.stream_rate {
        lab.tracker.stream(hz, l.stream_burst);
    }
    if l.real_time {
        let lag = std::time::Duration::from_millis(l.tracker_lag_ms);
        lab.tracker.sample(l.tracker_rate, lag);
    }
    let print = |run: &hil_sim::lab::LabRun| {
        if let Ok(line) = serde_json::to_string(run) {
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        }
    };
    if l.board_port.is_some() {
        lab.serve_board(listener, print)
    } else {
        lab.serve(listener, print)
    }
}

fn main() -> Result<()> {
    let a = Args::parse();
    if let Some(file) = &a.lab.lab {
        if let Err(e) = serve_lab(file, &a) {
            // One line, as `needle simulate` says it (`--perturb: layers = 9 is outside ...`).
            eprintln!("hil-sim: {e:#}");
            std::process::exit(1);
        }
        return Ok(());
    }
    for (name, rate) in [
        ("--flip-rate", a.flip_rate),
        ("--drop-rate", a.drop_rate),
        ("--burst-rate", a.burst_rate),
    ] {
        anyhow::ensure!((0.0..=1.0).contains(&rate), "{name} must be within 0 and 1");
    }
    let line = |seed| LineConfig {
        flip_rate: a.flip_rate,
        drop_rate: a.drop_rate,
        burst_rate: a.burst_rate,
        burst_len: a.burst_len,
        seed,
    };
    let config = ServeConfig {
        to_device: line(a.seed),
        to_host: line(a.seed.wrapping_add(1)),
        baud: (a.baud > 0).then_some(a.baud),
    };
    let mut device = Box::new(DeviceService::with_identity(IDENTITY));
    let mut axes = if a.axes {
        let attached = SimulatedAxes::attach(&mut device);
        Some(attached.map_err(|e| anyhow::anyhow!("cannot set up the simulated axes: {e}"))?)
    } else {
        None
    };
    let mut out = std::io::stdout();
    if let Some(addr) = &a.tcp {
        let listener =
            TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))?;
        writeln!(out, "{}", listener.local_addr()?)?;
        out.flush()?;
        for (k, conn) in (0u64..).zip(listener.incoming()) {
            let mut conn = conn?;
            conn.set_nodelay(true)?;
            // Each connection its own fault pattern (a pty's line goes on from client to
            // client): the same seeds every time would give every session the same faults.
            let config = ServeConfig {
                to_device: line(a.seed.wrapping_add(2 * k)),
                to_host: line(a.seed.wrapping_add(2 * k + 1)),
                ..config
            };
            if let Err(e) = serve_with_axes(&mut conn, &mut device, &config, axes.as_mut()) {
                eprintln!("hil-sim: connection ended: {e}");
            }
        }
        return Ok(());
    }
    let (mut master, slave) =
        serialport::TTYPort::pair().context("cannot open a pseudo-terminal")?;
    let path = serialport::SerialPort::name(&slave).context("the pseudo-terminal has no name")?;
    writeln!(out, "{path}")?;
    out.flush()?;
    // `slave` stays open for the life of the process: without an open slave, reads on the master
    // fail (EIO) between two clients.
    loop {
        if let Err(e) = serve_with_axes(&mut master, &mut device, &config, axes.as_mut()) {
            eprintln!("hil-sim: {e}");
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
}
