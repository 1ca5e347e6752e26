//! `needle steer`: plan a scenario as `needle simulate --closed-loop` does, then steer the
//! insertion in a lab: tracker poses over OpenIGTLink in, robot commands out, the in-process
//! controller in between, the interlocks of [`super::session`], an insertion log.

use super::log::InsertionLog;
use super::robot::step_list;
use super::session::{Event, LabController, Session, SessionConfig, SessionOutcome, INTERRUPTED};
use super::slicer::Slicer;
use super::wire::{load_registration, read_frames, TARGET_DEVICE, TIP_DEVICE};
use crate::device::commands::LinkArgs;
use crate::simulate::closed_loop_setup;
use crate::simulate::device::{device_planning, start_steering, LinkController};
use anyhow::{anyhow, Context, Result};
use needle_sim::in_process;
use serde::Serialize;
use serde_json::json;
use std::net::{TcpStream, ToSocketAddrs};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{channel, Sender};
use std::time::Duration;

/// `needle steer`
#[derive(clap::Args, Clone, Debug)]
pub struct SteerArgs {
    /// Scenario file (TOML): planned as `needle simulate --closed-loop` plans it.
    pub file: PathBuf,
    /// The tracker's OpenIGTLink server (PLUS, or `hil-sim --lab`), HOST:PORT.
    #[arg(long)]
    pub tracker: String,
    /// Device name of the tip's TRANSFORM.
    #[arg(long, default_value = TIP_DEVICE)]
    pub tip_name: String,
    /// Device name of the target's TRANSFORM.
    #[arg(long, default_value = TARGET_DEVICE)]
    pub target_name: String,
    /// The registration: a JSON file with `rotation` (row-major) and `translation_mm`, taking a
    /// point of the tracker's reference frame to the scenario's (default: the same frame).
    #[arg(long)]
    pub registration: Option<PathBuf>,
    /// The robot's OpenIGTLink server (the robot mapping of docs/lab.md), HOST:PORT.
    #[arg(long)]
    pub robot: String,
    /// Show the insertion in 3D Slicer: its OpenIGTLinkIF server (a client connection), HOST:PORT.
    #[arg(long, conflicts_with = "serve_slicer")]
    pub slicer: Option<String>,
    /// Show the insertion in 3D Slicer by serving OpenIGTLink on this port of every interface
    /// (Slicer's OpenIGTLinkIF connector of type Client connects to it, as to PLUS; 0 picks a
    /// free port, printed on stderr). Viewers may join and leave during the insertion.
    #[arg(long, value_name = "PORT")]
    pub serve_slicer: Option<u16>,
    /// With --serve-slicer: wait up to this many seconds for the first viewer before steering.
    #[arg(
        long,
        value_name = "SECONDS",
        requires = "serve_slicer",
        default_value_t = 0.0
    )]
    pub wait_for_slicer: f64,
    /// Write the insertion log here (JSON lines: the plan, each reading, each command, the stop).
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Seed of the insertion's world, for the record (the world is the lab's, not this
    /// program's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Tell the controller one thing, KEY=VALUE (as `needle simulate --steer`).
    #[arg(long = "steer", value_name = "KEY=VALUE")]
    pub steer: Vec<String>,
    /// No tip pose for this long: the robot is told hold, then stop ("tracking_lost").
    #[arg(long, default_value_t = 500)]
    pub tracking_timeout_ms: u64,
    /// No robot report this long after a command: the robot is told stop
    /// ("robot_not_answering").
    #[arg(long, default_value_t = 2000)]
    pub robot_timeout_ms: u64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Steer on the device at this TCP address (hil-sim --tcp, QEMU) instead of in-process.
    #[arg(long, conflicts_with = "port")]
    pub tcp: Option<String>,
    /// Steer on the device at this serial port instead of in-process.
    #[arg(long)]
    pub port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Seconds of silence allowed per exchange with the device.
    #[arg(long, default_value_t = 5.0)]
    pub timeout: f64,
}

impl SteerArgs {
    /// The device to steer on (`--tcp` or `--port`), if any.
    pub fn link(&self) -> Option<LinkArgs> {
        LinkArgs::optional(&self.port, self.baud, &self.tcp, self.timeout)
    }
}

/// Median and largest latency (ms) over the readings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Latency {
    /// Readings measured.
    pub readings: usize,
    /// Median (ms).
    pub median: f64,
    /// Largest (ms).
    pub max: f64,
}

impl Latency {
    /// Of the latencies given (`None` without any).
    pub fn of(values: &[f64]) -> Option<Latency> {
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let max = *v.last()?;
        Some(Latency {
            readings: v.len(),
            median: v[v.len() / 2],
            max,
        })
    }
}

/// `needle steer --json`.
#[derive(Serialize)]
pub struct SteerJson {
    /// The seed given, if any.
    pub seed: Option<u64>,
    /// The form steered.
    pub form: String,
    /// Why it stopped, as `needle simulate --closed-loop --json --detail` names it per run, plus
    /// the lab's own: `tracking_lost`, `robot_not_answering`, `interrupted`,
    /// `robot_disconnected`, `tracker_disconnected`, `robot_stopped`. Null: reached.
    #[serde(flatten)]
    pub outcome: SessionOutcome,
    /// Tip pose received to robot command sent.
    pub latency_ms: Option<Latency>,
}

fn connect(what: &str, address: &str) -> Result<TcpStream> {
    let addr = address
        .to_socket_addrs()
        .with_context(|| format!("{what} address {address}"))?
        .next()
        .ok_or_else(|| anyhow!("{what} address {address} resolves to nothing"))?;
    let s = TcpStream::connect_timeout(&addr, Duration::from_secs(5))
        .with_context(|| format!("cannot reach the {what} at {address}"))?;
    s.set_nodelay(true)?;
    Ok(s)
}

fn forward(
    stream: &TcpStream,
    tx: &Sender<Event>,
    wrap: fn(super::wire::Arrival) -> Event,
    end: Event,
) -> Result<()> {
    let (frames, ended) = (tx.clone(), tx.clone());
    read_frames(
        stream.try_clone()?,
        move |a| frames.send(wrap(a)).is_ok(),
        move || {
            let _ = ended.send(end);
        },
    );
    Ok(())
}

/// The insertion without a usable pose after which a lab insertion stops (mm), unless the
/// scenario's `[steering]` or `--steer` says otherwise: a robot pushing a needle blind is the
/// lab's interlock, tighter than the simulator's controller default (which bridges tracker
/// dropouts of up to 10 mm).
pub const LAB_TRACKING_LOST_AFTER_MM: f32 = 2.0;

/// Runs `needle steer`.
pub fn run_steer(a: &SteerArgs) -> Result<()> {
    let mut flags: Vec<String> = a.steer.iter().map(|kv| format!("--steer={kv}")).collect();
    let key = "tracking_lost_after_mm";
    let told_here = a.steer.iter().any(|kv| kv.trim_start().starts_with(key));
    let told_in_file = crate::scenario::ScenarioFile::load(&a.file)?
        .steering
        .is_some_and(|t| t.contains_key(key));
    if !told_here && !told_in_file {
        flags.insert(0, format!("--steer={key}={LAB_TRACKING_LOST_AFTER_MM}"));
    }
    // The same refusal as `needle simulate` (a plan bound the device cannot plan).
    if let Some(t) = &a.tcp {
        flags.push(format!("--tcp={t}"));
    }
    if let Some(p) = &a.port {
        flags.push(format!("--port={p}"));
    }
    let setup = closed_loop_setup(&a.file, a.seed.unwrap_or(1), &flags)?;
    let registration = a
        .registration
        .as_deref()
        .map(load_registration)
        .transpose()?;
    let schedule = &setup.prepared.schedule;
    let mut in_process_controller;
    let mut device;
    let mut on_device;
    let controller: &mut dyn LabController = match a.link() {
        None => {
            in_process_controller = in_process(&setup.scenario, schedule, &setup.config)
                .map_err(|e| anyhow!("steering cannot start: {e}"))?;
            &mut in_process_controller
        }
        Some(link) => {
            device = device_planning(&setup, &link)?;
            start_steering(&mut device, &setup)?;
            on_device = LinkController(&mut device);
            &mut on_device
        }
    };
    let mut log = InsertionLog::create(a.log.as_deref())?;
    let form = setup.prepared.outcome.form.to_string();
    let steps: Vec<String> = step_list(&schedule.steps)
        .iter()
        .map(ToString::to_string)
        .collect();
    log.write(
        "plan",
        json!({ "file": a.file, "form": form, "posture": schedule.posture, "steps": steps }),
    );
    let mut slicer = match a.serve_slicer {
        Some(port) => {
            let wait = Duration::try_from_secs_f64(a.wait_for_slicer)
                .map_err(|_| anyhow::anyhow!("--wait-for-slicer must be 0 or more seconds"))?;
            Slicer::serve(port, wait)?
        }
        None => Slicer::connect(a.slicer.as_deref())?,
    };
    slicer.plan(&setup.scenario, schedule);
    let tracker = connect("tracker", &a.tracker)?;
    let robot = connect("robot", &a.robot)?;
    let (tx, rx) = channel();
    forward(&tracker, &tx, Event::Tracker, Event::TrackerClosed)?;
    forward(&robot, &tx, Event::Robot, Event::RobotClosed)?;
    drop(tx);
    // A second handler cannot be set (a test calling twice): the first one still flags.
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    let config = SessionConfig {
        tip_name: a.tip_name.clone(),
        target_name: a.target_name.clone(),
        tracking_timeout: Duration::from_millis(a.tracking_timeout_ms),
        robot_timeout: Duration::from_millis(a.robot_timeout_ms),
        arc_radius_mm: setup.scenario.needle.curvature_radius,
        registration,
    };
    let outcome =
        Session::new(config, controller, robot, &mut log, &mut slicer, rx).run(&schedule.steps);
    let _ = tracker.shutdown(std::net::Shutdown::Both);
    if let Some(e) = &slicer.failure {
        eprintln!("needle steer: Slicer was not shown everything: {e}");
    }
    print(a, form, outcome, &log)
}

fn print(a: &SteerArgs, form: String, outcome: SessionOutcome, log: &InsertionLog) -> Result<()> {
    let latency = Latency::of(&outcome.latencies_ms);
    let interrupted = outcome.stop_reason == Some("interrupted");
    if a.json {
        let j = SteerJson {
            seed: a.seed,
            form,
            outcome,
            latency_ms: latency,
        };
        println!("{}", serde_json::to_string(&j)?);
    } else {
        match outcome.stop_reason {
            None => println!("{form}: reached the target"),
            Some(r) => println!("{form}: stopped: {r}"),
        }
        if let Some(m) = outcome.predicted_miss_mm {
            println!("predicted miss {m:.2} mm");
        }
        let s = outcome.steering;
        println!(
            "{} readings, {} replans, robot {}",
            s.readings,
            s.replans,
            if outcome.robot_stopped {
                "stopped"
            } else {
                "did not confirm the stop"
            }
        );
        if let Some(l) = latency {
            println!(
                "latency pose to command: median {:.2} ms, max {:.2} ms over {} readings",
                l.median, l.max, l.readings
            );
        }
    }
    if let Some(e) = &log.failure {
        eprintln!("needle steer: the insertion log is incomplete: {e}");
    }
    anyhow::ensure!(!interrupted, "interrupted: the robot was told to stop");
    Ok(())
}
