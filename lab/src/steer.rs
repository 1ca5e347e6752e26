//! `needle steer`: plan a scenario as `needle simulate --closed-loop` does, then steer the
//! insertion in a lab: tracker poses over OpenIGTLink in, robot commands out, the in-process
//! controller in between, the interlocks of [`super::session`], an insertion log. Without a
//! robot, a driver board moves the needle itself ([`super::board`]).

use super::report::{self, Printing};
use super::session::INTERRUPTED;
use super::session::{Event, Inputs, LabController, Session, SessionOutcome};
use super::steer_setup::{
    check_name, connect, forward_tracker, report_viewers, session_config, set_up, tracker_names,
    viewers, SteerOptions, EVENTS_WAITING,
};
use super::wire::read_frames_counting;
use anyhow::{anyhow, Result};
use needle_sim::in_process;
use needle_simulate::device::{device_planning, start_steering, LinkController};
use std::net::TcpStream;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Arc;

/// Reads the robot's frames into `tx`.
fn forward_robot(stream: &TcpStream, tx: &SyncSender<Event>) -> Result<Arc<AtomicU64>> {
    let (frames, ended) = (tx.clone(), tx.clone());
    let bytes = Arc::new(AtomicU64::new(0));
    read_frames_counting(
        stream.try_clone()?,
        bytes.clone(),
        move |a| frames.send(Event::Robot(Box::new(a))).is_ok(),
        move || {
            let _ = ended.send(Event::RobotClosed);
        },
    );
    Ok(bytes)
}

/// Runs `needle steer`: an insertion that does not reach the target is an error carrying its
/// exit status ([`super::outcome::exit_code`]); with `--json` every ending prints one object.
pub fn run_steer(a: &SteerOptions) -> Result<()> {
    let mut form = None;
    match steer(a, &mut form) {
        Ok(outcome) => report::print(printing(a), form.unwrap_or_default(), outcome),
        Err(e) => report::failed(printing(a), form, e),
    }
}

/// Plans, connects and steers; `form` is the form steered once it is known.
fn steer(a: &SteerOptions, form_steered: &mut Option<String>) -> Result<SessionOutcome> {
    check_name("--tip-name", &a.tip_name)?;
    check_name("--target-name", &a.target_name)?;
    if let Some(name) = &a.registration_name {
        check_name("--registration-name", name)?;
    }
    let robot_address = match (&a.robot, &a.link) {
        (Some(robot), _) => robot,
        (None, Some(_)) => return super::board::steer_on_board(a, form_steered),
        (None, None) => anyhow::bail!(
            "needle steer needs a robot that moves the needle (--robot HOST:PORT) or a driver \
             board that moves it itself (--tcp ADDRESS or --port PORT, no --robot)"
        ),
    };
    let setup = set_up(a)?;
    let config = session_config(a, &setup)?;
    let schedule = &setup.prepared.schedule;
    let mut in_process_controller;
    let mut device;
    let mut on_device;
    let controller: &mut dyn LabController = match &a.link {
        None => {
            in_process_controller = in_process(&setup.scenario, schedule, &setup.config)
                .map_err(|e| anyhow!("steering cannot start: {e}"))?;
            &mut in_process_controller
        }
        Some(link) => {
            device = device_planning(&setup, link)?;
            start_steering(&mut device, &setup)?;
            on_device = LinkController(&mut device);
            &mut on_device
        }
    };
    let (mut log, mut slicer) = viewers(a, &setup, form_steered)?;
    let tracker = connect("tracker", &a.tracker)?;
    let robot = connect("robot", robot_address)?;
    let (tx, rx) = sync_channel(EVENTS_WAITING);
    let (tracker_state, tracker_bytes) = forward_tracker(&tracker, &tx, tracker_names(a))?;
    let robot_bytes = forward_robot(&robot, &tx)?;
    drop(tx);
    // A second handler cannot be set (a test calling twice): the first one still flags.
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    let inputs = Inputs {
        events: rx,
        tracker: tracker_state,
        tracker_bytes,
        robot_bytes,
    };
    let outcome =
        Session::new(config, controller, robot, &mut log, &mut slicer, inputs).run(&schedule.steps);
    let _ = tracker.shutdown(std::net::Shutdown::Both);
    report_viewers(&slicer, &log);
    Ok(outcome)
}

/// What the end's printing needs of the flags.
fn printing(a: &SteerOptions) -> Printing<'_> {
    Printing {
        json: a.json,
        seed: a.seed,
        registration: a
            .registration_name
            .as_deref()
            .map(|n| (n, a.registration_timeout_ms)),
    }
}
