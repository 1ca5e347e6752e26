//! What a steered insertion needs before it starts, with a robot or a driver board: what
//! `needle steer` is asked, the plan (as `needle simulate --closed-loop` makes it), the insertion
//! log and 3D Slicer, the tracker's connection and the session's limits.

use super::log::InsertionLog;
use super::report::Unreachable;
use super::robot::step_list;
use super::session::{Event, SessionConfig};
use super::slicer::Slicer;
use super::tracker::{TrackerNames, TrackerState};
use super::wire::{load_registration, read_frames_counting, Arrival, TARGET_DEVICE, TIP_DEVICE};
use anyhow::Result;
use needle_device::LinkOptions;
use needle_simulate::closed_loop_setup;
use needle_simulate::request::Request;
use serde_json::json;
use std::net::{IpAddr, Ipv4Addr, TcpStream, ToSocketAddrs};
use std::path::PathBuf;
use std::sync::atomic::AtomicU64;
use std::sync::mpsc::{SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// What `needle steer` is asked (the `needle` binary reads it from its flags).
#[derive(Clone, Debug)]
pub struct SteerOptions {
    /// Scenario file (TOML): planned as `needle simulate --closed-loop` plans it.
    pub file: PathBuf,
    /// The tracker's OpenIGTLink server (PLUS, or `hil-sim --lab`), HOST:PORT.
    pub tracker: String,
    /// Device name of the tip's TRANSFORM.
    pub tip_name: String,
    /// Device name of the target's TRANSFORM.
    pub target_name: String,
    /// The registration from a JSON file with `rotation` (row-major) and `translation_mm`,
    /// taking a point of the tracker's reference frame to the scenario's (`None`: the same
    /// frame, or `registration_name`'s).
    pub registration: Option<PathBuf>,
    /// The registration from the tracker stream: the device name of its TRANSFORM. Steering
    /// waits for the first one; a later different one is refused.
    pub registration_name: Option<String>,
    /// With `registration_name`: how long to wait for it before giving up.
    pub registration_timeout_ms: u64,
    /// The robot's OpenIGTLink server (the robot mapping of docs/lab.md), HOST:PORT; `None`:
    /// the driver board at `link` moves the needle itself.
    pub robot: Option<String>,
    /// With a board and no robot: the needle guide is set to the plan's tilt (a board only
    /// turns and inserts).
    pub tilt_set: bool,
    /// Show the insertion in 3D Slicer: its OpenIGTLinkIF server (a client connection).
    pub slicer: Option<String>,
    /// Show the insertion in 3D Slicer by serving OpenIGTLink on this port of
    /// `serve_slicer_bind` (0: a free port, printed on stderr).
    pub serve_slicer: Option<u16>,
    /// With `serve_slicer`: the address to serve on.
    pub serve_slicer_bind: IpAddr,
    /// With `serve_slicer`: wait up to this many seconds for the first viewer before steering.
    pub wait_for_slicer: f64,
    /// Write the insertion log here (JSON lines: the plan, each reading, each command, the stop).
    pub log: Option<PathBuf>,
    /// Seed of the insertion's world, for the record (`None`: 1, and none recorded).
    pub seed: Option<u64>,
    /// Degrees of freedom of the tip sensor: 6 (the tip TRANSFORM's roll is the bevel's) or 5
    /// (the roll means nothing; the controller infers it from how the path bends).
    pub tracker_dof: u8,
    /// What the controller is told, `KEY=VALUE` (as `needle simulate --steer`).
    pub steer: Vec<String>,
    /// No tip pose for this long: the robot is told hold, then stop ("tracking_lost").
    pub tracking_timeout_ms: u64,
    /// No robot report this long after a command: the robot is told stop
    /// ("robot_not_answering").
    pub robot_timeout_ms: u64,
    /// Print one JSON object.
    pub json: bool,
    /// Steer on this device instead of in-process.
    pub link: Option<LinkOptions>,
}

impl Default for SteerOptions {
    /// The command's defaults, for no scenario, tracker or robot yet.
    fn default() -> Self {
        SteerOptions {
            file: PathBuf::new(),
            tracker: String::new(),
            tip_name: TIP_DEVICE.into(),
            target_name: TARGET_DEVICE.into(),
            registration: None,
            registration_name: None,
            registration_timeout_ms: 5000,
            robot: None,
            tilt_set: false,
            slicer: None,
            serve_slicer: None,
            serve_slicer_bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            wait_for_slicer: 0.0,
            log: None,
            seed: None,
            tracker_dof: 6,
            steer: Vec::new(),
            tracking_timeout_ms: 500,
            robot_timeout_ms: 2000,
            json: false,
            link: None,
        }
    }
}

/// Connects to the tracker or the robot; failing, the link is broken before anything moved.
pub(crate) fn connect(what: &'static str, address: &str) -> Result<TcpStream> {
    let unreachable = |message: String| Unreachable {
        reason: if what == "tracker" {
            "tracker_unreachable"
        } else {
            "robot_unreachable"
        },
        message,
    };
    let addr = address
        .to_socket_addrs()
        .map_err(|e| unreachable(format!("{what} address {address}: {e}")))?
        .next()
        .ok_or_else(|| unreachable(format!("{what} address {address} resolves to nothing")))?;
    let s = TcpStream::connect_timeout(&addr, Duration::from_secs(5))
        .map_err(|e| unreachable(format!("cannot reach the {what} at {address}: {e}")))?;
    s.set_nodelay(true)?;
    Ok(s)
}

/// Events waiting for the session at most: the robot's reader waits when they are this many
/// (the robot is lock-step: a few frames a piece), the tracker's sends at most one notice.
pub(crate) const EVENTS_WAITING: usize = 64;

/// Reads the tracker's frames into a shared [`TrackerState`] (bounded whatever the rate), and
/// tells the session with a notice when none is waiting already.
pub(crate) fn forward_tracker(
    stream: &TcpStream,
    tx: &SyncSender<Event>,
    names: TrackerNames,
) -> Result<(Arc<Mutex<TrackerState>>, Arc<AtomicU64>)> {
    let state = Arc::new(Mutex::new(TrackerState::default()));
    let (shared, notices, ended) = (state.clone(), tx.clone(), tx.clone());
    let bytes = Arc::new(AtomicU64::new(0));
    read_frames_counting(
        stream.try_clone()?,
        bytes.clone(),
        move |a: Arrival| {
            let notify = {
                let mut s = shared.lock().unwrap_or_else(|p| p.into_inner());
                s.on_frame(&names, a);
                !std::mem::replace(&mut s.notice_pending, true)
            };
            // Full: the session has news waiting anyway; it reads the state, not the notice.
            !notify
                || !matches!(
                    notices.try_send(Event::Tracker),
                    Err(TrySendError::Disconnected(_))
                )
        },
        move || {
            let _ = ended.send(Event::TrackerClosed);
        },
    );
    Ok((state, bytes))
}

/// A device name must fit the header's 20 bytes, or no frame can ever carry it.
pub(crate) fn check_name(flag: &str, name: &str) -> Result<()> {
    anyhow::ensure!(
        !name.is_empty() && name.len() <= needle_igtl::header::DEVICE_NAME_SIZE,
        "{flag} `{name}`: an OpenIGTLink device name has 1 to 20 bytes, this one {}",
        name.len()
    );
    Ok(())
}

/// The insertion without a usable pose after which a lab insertion stops (mm), unless the
/// scenario's `[steering]` or `--steer` says otherwise: a robot pushing a needle blind is the
/// lab's interlock, tighter than the simulator's controller default (which bridges tracker
/// dropouts of up to 10 mm).
pub const LAB_TRACKING_LOST_AFTER_MM: f32 = 2.0;

/// What `needle simulate --closed-loop` is asked to plan and set up the insertion as
/// `needle steer` is told: the `--steer` keys (the lab's tracking interlock unless the scenario
/// or a key sets it), and the device, for the same refusal (a plan bound the device cannot
/// plan).
fn simulate_request(a: &SteerOptions) -> Result<Request> {
    let mut steer = a.steer.clone();
    let key = "tracking_lost_after_mm";
    let told_here = a.steer.iter().any(|kv| kv.trim_start().starts_with(key));
    let told_in_file = needle_scenario::ScenarioFile::load(&a.file)?
        .steering
        .is_some_and(|t| t.contains_key(key));
    if !told_here && !told_in_file {
        steer.insert(0, format!("{key}={LAB_TRACKING_LOST_AFTER_MM}"));
    }
    Ok(Request {
        steer,
        on_device: a.link.is_some(),
        ..Request::default()
    })
}

/// The set-up of a steered insertion: planned as `needle simulate --closed-loop` plans it.
pub(crate) fn set_up(a: &SteerOptions) -> Result<needle_simulate::setup::Setup> {
    closed_loop_setup(&a.file, a.seed.unwrap_or(1), &simulate_request(a)?)
}

/// The insertion log (its first line the plan) and 3D Slicer (shown the plan); `form` is the
/// form steered.
pub(crate) fn viewers(
    a: &SteerOptions,
    setup: &needle_simulate::setup::Setup,
    form_steered: &mut Option<String>,
) -> Result<(InsertionLog, Slicer)> {
    let schedule = &setup.prepared.schedule;
    let mut log = InsertionLog::create(a.log.as_deref())?;
    let form = setup.prepared.outcome.form.to_string();
    *form_steered = Some(form.clone());
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
            Slicer::serve((a.serve_slicer_bind, port), wait)?
        }
        None => Slicer::connect(a.slicer.as_deref())?,
    };
    slicer.plan(&setup.scenario, schedule);
    Ok((log, slicer))
}

/// The names the tracker's frames are read by.
pub(crate) fn tracker_names(a: &SteerOptions) -> TrackerNames {
    TrackerNames {
        tip: a.tip_name.clone(),
        target: a.target_name.clone(),
        registration: a.registration_name.clone(),
    }
}

/// The session's limits and names.
pub(crate) fn session_config(
    a: &SteerOptions,
    setup: &needle_simulate::setup::Setup,
) -> Result<SessionConfig> {
    let registration = a
        .registration
        .as_deref()
        .map(load_registration)
        .transpose()?;
    Ok(SessionConfig {
        tracking_timeout: Duration::from_millis(a.tracking_timeout_ms),
        robot_timeout: Duration::from_millis(a.robot_timeout_ms),
        arc_radius_mm: setup.scenario.needle.curvature_radius,
        registration,
        registration_name: a.registration_name.clone(),
        registration_timeout: Duration::from_millis(a.registration_timeout_ms),
        roll_measured: a.tracker_dof == 6,
        posture: setup.prepared.schedule.posture,
    })
}

/// Says on stderr what Slicer or the log missed.
pub(crate) fn report_viewers(slicer: &Slicer, log: &InsertionLog) {
    if let Some(e) = &slicer.failure {
        eprintln!("needle steer: Slicer was not shown everything: {e}");
    }
    if let Some(e) = &log.failure {
        eprintln!("needle steer: the insertion log is incomplete: {e}");
    }
}
