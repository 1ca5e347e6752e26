//! The step interrupt's instructions on a board that drives axes: the QEMU board homes its
//! simulated stage and moves the paper's schedule, and the firmware brackets each step it takes
//! (`Controller::next_step`, the work of the step timer's interrupt) as a region of the
//! instruction-count plugin, one report per homing or move.

use crate::qemu::{Qemu, Report};
use anyhow::{anyhow, bail, Context, Result};
use needle_link::{Client, LinkError, Transport};
use needle_motion::{FaultCause, State};
use planner_core::execute::schedule::schedule;
use planner_core::wire::{Fault, MotionRequest, MotionStatus};
use planner_core::{plan, Scenario};
use std::time::{Duration, Instant};

/// The instructions of each step of a homing and of the paper's schedule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepFigures {
    /// Steps taken (both axes; the homing's and the move's).
    pub steps: u64,
    /// Instructions of the costliest step.
    pub max: u64,
    /// Instructions of all the steps.
    pub sum: u64,
    /// Instructions of the costliest move request of the paper's schedule (decoded, every move
    /// checked against the soft limits and queued, the first segment set up, answered).
    pub move_request: u64,
}

impl StepFigures {
    /// Instructions of a step on average.
    pub fn mean(&self) -> f64 {
        self.sum as f64 / self.steps.max(1) as f64
    }
}

/// How often the host asks for the status while the axes move (the board's heartbeat).
const POLL: Duration = Duration::from_millis(20);

/// Homes the board's stage and moves the paper's schedule; the steps' figures, or `None` if
/// the board drives no axes.
pub fn measure<T: Transport>(device: &mut Client<T>, qemu: &Qemu) -> Result<Option<StepFigures>> {
    match device.motion(MotionRequest::Status) {
        Err(LinkError::Device(Fault::NoMotion)) => return Ok(None),
        other => other.context("the board's motion status")?,
    };
    let scenario = Scenario::paper();
    let report = plan(&scenario).map_err(|e| anyhow!("planning the paper's scenario: {e:?}"))?;
    let best = report.best().context("the paper's scenario has no plan")?;
    let sched = schedule(&scenario, best).map_err(|e| anyhow!("its schedule: {e:?}"))?;
    let before = qemu.reports()?.len();
    let move_request = MotionRequest::Move {
        driver: scenario.driver,
        needle_mm: scenario.needle.length,
        steps: sched.steps.clone(),
    };
    for tries in 1.. {
        device.motion(MotionRequest::Arm)?;
        home(device)?;
        device.motion(move_request.clone())?;
        let end = wait_at_rest(device)?;
        let lost = end
            .last_fault
            .is_some_and(|f| f.cause == FaultCause::LinkLost);
        // A loaded machine may keep the host from the board past the watchdog's second: the
        // move is made again (its steps so far are still steps the interrupt took).
        if lost && tries < 3 {
            device.motion(MotionRequest::ClearFault)?;
            continue;
        }
        if end.state != State::Armed || end.last_fault.is_some() {
            bail!("the board's move of the paper's schedule ended {end:?}");
        }
        break;
    }
    step_runs(qemu, before)
}

/// The figures of the step runs the firmware reported since the `before`th (each homing and
/// move, as its axes come to rest): at least a homing and a move, once no more come.
fn step_runs(qemu: &Qemu, before: usize) -> Result<Option<StepFigures>> {
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut seen = 0;
    loop {
        let reports = qemu.reports()?;
        let since = &reports[before.min(reports.len())..];
        // A move request is one region; a homing or a move's steps are thousands.
        let (requests, runs): (Vec<&Report>, Vec<&Report>) =
            since.iter().partition(|r| r.regions == 1);
        if runs.len() >= 2 && !requests.is_empty() && since.len() == seen {
            return Ok(Some(StepFigures {
                steps: runs.iter().map(|r| r.regions).sum(),
                max: runs.iter().map(|r| r.largest).max().unwrap_or(0),
                sum: runs.iter().map(|r| r.sum).sum(),
                move_request: requests.iter().map(|r| r.sum).max().unwrap_or(0),
            }));
        }
        seen = since.len();
        if Instant::now() > deadline {
            bail!(
                "the plugin reported {} step runs, not 2 or more (homing, move)",
                runs.len()
            );
        }
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// Homes the stage. A loaded machine may keep the host from the board long enough for the link
/// watchdog to hold, which ends a homing unhomed: then it homes again (three tries).
fn home<T: Transport>(device: &mut Client<T>) -> Result<()> {
    for _ in 0..3 {
        device.motion(MotionRequest::Home)?;
        let s = wait_at_rest(device)?;
        if s.homed && s.state == State::Armed {
            return Ok(());
        }
        if s.last_fault.is_some() {
            bail!("homing ended {s:?}");
        }
    }
    bail!("the stage did not home in three tries (the link watchdog held each)")
}

/// Asks for the status until the axes neither home nor move (10 minutes at most), resuming
/// after a hold of the link watchdog (a loaded machine may delay the host).
fn wait_at_rest<T: Transport>(device: &mut Client<T>) -> Result<MotionStatus> {
    let deadline = Instant::now() + Duration::from_secs(600);
    loop {
        std::thread::sleep(POLL);
        let s = device.motion(MotionRequest::Status)?;
        match s.state {
            State::Holding if s.last_fault.is_none() => {
                device.motion(MotionRequest::Resume)?;
            }
            State::Homing | State::Moving | State::Holding => {}
            _ => return Ok(s),
        }
        if Instant::now() > deadline {
            bail!("the axes still move after 10 minutes: {s:?}");
        }
    }
}
