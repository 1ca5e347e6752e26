//! `needle motion`: the board's two axes from the host (docs/motion.md). One request per call;
//! `home`, `move` and `resume` then keep the link alive, which is the board's watchdog, and show
//! the axes until they are at rest. Ctrl-C while they move asks the board to stop (decelerate,
//! the moves dropped), a second Ctrl-C sends the e-stop. A command that ends otherwise while they
//! move (killed, a lost link) leaves the board without its heartbeat: it holds after 200 ms and
//! stops with `LinkLost` after 1 s, by its own safety rules.

use crate::commands::LinkOptions;
use crate::posture::{board_steps, tilt_deg, turn_to_roll};
use anyhow::{anyhow, bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use needle_link::{Client, LinkError, Transport};
use needle_motion::State;
use needle_report::local::plan_locally;
use needle_scenario::{load_execution, load_scenario};
use planner_core::execute::schedule::Schedule;
use planner_core::model::scenario::Driver;
use planner_core::wire::{Fault, MotionFault, MotionRequest, MotionStatus};
use serde_json::{json, Value};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

/// Ctrl-C presses while the axes move.
static INTERRUPTS: AtomicU32 = AtomicU32::new(0);

/// What to ask the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// The axes' status (also a heartbeat).
    Status,
    /// Allow motion (from disarmed).
    Arm,
    /// Forbid motion: both axes stop at once.
    Disarm,
    /// Seek the insertion stage's home switch, and wait until homed.
    Home,
    /// Plan the scenario here and execute its motor schedule, and wait until it is done.
    Move,
    /// Decelerate to rest, keeping the rest of the moves.
    Hold,
    /// Continue after a hold, and wait until done.
    Resume,
    /// Decelerate to rest and drop the moves.
    Stop,
    /// The e-stop: both axes stop at once; latched until cleared.
    Estop,
    /// End a latched fault whose cause is gone (disarmed, and unhomed unless the link was lost).
    ClearFault,
    /// Back to the power-up state (a latched fault stays).
    Reset,
}

impl Action {
    /// Every action, in the order `needle motion --help` lists them.
    pub const ALL: [Action; 11] = [
        Action::Status,
        Action::Arm,
        Action::Disarm,
        Action::Home,
        Action::Move,
        Action::Hold,
        Action::Resume,
        Action::Stop,
        Action::Estop,
        Action::ClearFault,
        Action::Reset,
    ];

    /// The action's name, as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Action::Status => "status",
            Action::Arm => "arm",
            Action::Disarm => "disarm",
            Action::Home => "home",
            Action::Move => "move",
            Action::Hold => "hold",
            Action::Resume => "resume",
            Action::Stop => "stop",
            Action::Estop => "estop",
            Action::ClearFault => "clear-fault",
            Action::Reset => "reset",
        }
    }
}

/// What `needle motion ACTION [SCENARIO]` asks (the `needle` binary reads it from its flags).
#[derive(Clone, Debug)]
pub struct MotionOptions {
    /// What to ask the board.
    pub action: Action,
    /// The scenario whose plan `move` executes (planned here as `needle plan` plans it).
    pub scenario: Option<PathBuf>,
    /// With `move`: the needle guide is set at the plan's tilt (a tilted plan is refused
    /// without it).
    pub tilt_set: bool,
    /// Print the final status as one JSON object.
    pub json: bool,
    /// How to reach the board.
    pub link: LinkOptions,
}

/// How often the axes are asked for their status while they move (the heartbeat: the board
/// holds after 200 ms of silence).
const POLL: Duration = Duration::from_millis(50);

/// `needle motion`.
pub fn motion(args: &MotionOptions) -> Result<()> {
    if args.scenario.is_some() && args.action != Action::Move {
        bail!("only `needle motion move` takes a scenario");
    }
    let waits = matches!(args.action, Action::Home | Action::Move | Action::Resume);
    if waits {
        // A second handler cannot be set (a library caller running twice): the first one counts.
        let _ = ctrlc::set_handler(|| {
            INTERRUPTS.fetch_add(1, Ordering::SeqCst);
        });
    }
    if args.tilt_set && args.action != Action::Move {
        bail!("only `needle motion move` takes --tilt-set");
    }
    // Planned before connecting: a scenario that does not plan never reaches the board.
    let planned = match args.action {
        Action::Move => Some(plan_move(args)?),
        _ => None,
    };
    let mut config = args.link.config()?;
    // A move lasts as long as it lasts: each exchange is bounded by --timeout, not the whole.
    config.deadline = None;
    let (mut client, _) = args.link.connect_within(config, Duration::MAX)?;
    if INTERRUPTS.load(Ordering::SeqCst) > 0 {
        bail!(
            "interrupted (Ctrl-C) before `{}` was sent",
            args.action.name()
        );
    }
    let request = match planned {
        Some(plan) => {
            let now = ask(&mut client, MotionRequest::Status, Action::Status)?;
            plan.request(now.position[1], args.tilt_set)?
        }
        None => request(args)?,
    };
    let mut status = ask(&mut client, request, args.action)?;
    let mut interrupted = false;
    if waits {
        (status, interrupted) = wait_at_rest(&mut client, status)?;
    }
    print_status(&status, args.json)?;
    match (status.state, status.last_fault) {
        _ if interrupted && status.state != State::Faulted => {
            bail!("interrupted: the board stopped and dropped the moves (Ctrl-C)")
        }
        (State::Faulted, Some(f)) if args.action != Action::Estop => {
            bail!("the board stopped with a fault: {}", fault_line(&f))
        }
        (State::Holding, _) if args.action != Action::Hold => bail!(
            "the board holds (the link was silent for 200 ms, or another host asked): \
             `needle motion resume` continues; silent for 1 s, it stops with LinkLost"
        ),
        _ => Ok(()),
    }
}

/// The request for `args`, with the plan made here for `move`.
fn request(args: &MotionOptions) -> Result<MotionRequest> {
    Ok(match args.action {
        Action::Status => MotionRequest::Status,
        Action::Arm => MotionRequest::Arm,
        Action::Disarm => MotionRequest::Disarm,
        Action::Home => MotionRequest::Home,
        Action::Hold => MotionRequest::Hold,
        Action::Resume => MotionRequest::Resume,
        Action::Stop => MotionRequest::Stop,
        Action::Estop => MotionRequest::EStop,
        Action::ClearFault => MotionRequest::ClearFault,
        Action::Reset => MotionRequest::Reset,
        Action::Move => bail!("`move` is planned first (plan_move)"),
    })
}

/// A plan for `move`, made here as `needle plan` makes it.
struct PlannedMove {
    driver: Driver,
    needle_mm: f32,
    schedule: Schedule,
}

fn plan_move(args: &MotionOptions) -> Result<PlannedMove> {
    let file = args.scenario.as_ref().context("`move` needs a scenario")?;
    let scenario = load_scenario(file)?;
    let execution = load_execution(file)?;
    let made = plan_locally(&scenario, &execution)?;
    let schedule = made
        .schedule()?
        .ok_or_else(|| anyhow!("{}: no feasible path, nothing to move", file.display()))?;
    Ok(PlannedMove {
        driver: made.scenario.driver,
        needle_mm: made.scenario.needle.length,
        schedule: schedule.clone(),
    })
}

impl PlannedMove {
    /// The move for a shaft now at `rotation_deg`: the turn to the plan's roll, then its steps;
    /// said on stderr.
    fn request(&self, rotation_deg: f32, tilt_set: bool) -> Result<MotionRequest> {
        let p = &self.schedule.posture;
        let steps = board_steps(
            p,
            &self.schedule.steps,
            &self.driver,
            rotation_deg,
            tilt_set,
        )?;
        let turn = turn_to_roll(rotation_deg, p.roll_deg);
        eprintln!(
            "posture: tilt {:.2} deg (the guide's), bevel roll {} deg: the shaft turns {turn} deg \
             first",
            tilt_deg(p.theta1_deg, p.theta2_deg),
            p.roll_deg
        );
        Ok(MotionRequest::Move {
            driver: self.driver,
            needle_mm: self.needle_mm,
            steps,
        })
    }
}

/// One request; a refusal as an error that says why.
fn ask(
    client: &mut Client<Box<dyn Transport>>,
    request: MotionRequest,
    action: Action,
) -> Result<MotionStatus> {
    client.motion(request).map_err(|e| match e {
        LinkError::Device(Fault::Motion(why)) => {
            anyhow!("the board refused `{}`: {why}", action.name())
        }
        LinkError::Device(Fault::NoMotion) => anyhow!(
            "the device drives no axes (hil-sim drives simulated ones with --axes; the QEMU \
             firmware drives simulated ones; the STM32F4 firmware none yet)"
        ),
        other => anyhow!(other),
    })
}

/// Asks for the status every `POLL` (the heartbeat) until the axes neither home nor move; a
/// spinner with the positions on a terminal. Whether Ctrl-C stopped them.
fn wait_at_rest(
    client: &mut Client<Box<dyn Transport>>,
    mut status: MotionStatus,
) -> Result<(MotionStatus, bool)> {
    let bar = ProgressBar::new_spinner();
    bar.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}")?);
    let mut sent = 0;
    while matches!(status.state, State::Homing | State::Moving) {
        let pressed = INTERRUPTS.load(Ordering::SeqCst);
        if pressed > sent {
            sent = pressed;
            let (request, action) = match pressed {
                1 => (MotionRequest::Stop, Action::Stop),
                _ => (MotionRequest::EStop, Action::Estop),
            };
            bar.suspend(|| eprintln!("Ctrl-C: {}", action.name()));
            status = ask(client, request, action)?;
            continue;
        }
        bar.set_message(format!(
            "{}: insertion {:.3} mm, rotation {:.1}°, {} moves left",
            status.state, status.position[0], status.position[1], status.moves_left
        ));
        bar.tick();
        std::thread::sleep(POLL);
        status = ask(client, MotionRequest::Status, Action::Status)?;
    }
    bar.finish_and_clear();
    Ok((status, sent > 0))
}

fn fault_line(f: &MotionFault) -> String {
    format!(
        "{} at insertion {:.3} mm, rotation {:.1}° (board time {} ms)",
        f.cause, f.position[0], f.position[1], f.at_ms
    )
}

/// The object `needle motion --json` prints.
pub fn status_json(s: &MotionStatus) -> Value {
    json!({
        "state": s.state.to_string(),
        "homed": s.homed,
        "insertion_mm": s.position[0],
        "rotation_deg": s.position[1],
        "insertion_speed_mm_s": s.speed[0],
        "rotation_speed_deg_s": s.speed[1],
        "moves_left": s.moves_left,
        "last_fault": s.last_fault.map(|f| json!({
            "cause": f.cause.to_string(),
            "insertion_mm": f.position[0],
            "rotation_deg": f.position[1],
            "encoder_steps": f.encoder,
            "at_ms": f.at_ms,
        })),
    })
}

fn print_status(s: &MotionStatus, json: bool) -> Result<()> {
    let mut out = std::io::stdout();
    if json {
        writeln!(out, "{}", status_json(s))?;
        return Ok(());
    }
    let homed = if s.homed { "homed" } else { "not homed" };
    writeln!(out, "state:      {} ({homed})", s.state)?;
    writeln!(out, "insertion:  {:.3} mm", s.position[0])?;
    writeln!(out, "rotation:   {:.1}°", s.position[1])?;
    writeln!(
        out,
        "speed:      {:.3} mm/s, {:.1}°/s",
        s.speed[0], s.speed[1]
    )?;
    writeln!(out, "moves left: {}", s.moves_left)?;
    let fault = s
        .last_fault
        .map_or_else(|| "none".to_string(), |f| fault_line(&f));
    writeln!(out, "last fault: {fault}")?;
    Ok(())
}
