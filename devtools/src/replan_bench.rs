//! The instructions of closed-loop steering on the device: one simulated insertion (default
//! perturbation, seed 1) steered by the firmware in QEMU, each reading counted on its own by the
//! instruction-count plugin (the firmware brackets every poll that answers a reading).

use crate::qemu::Qemu;
use anyhow::{anyhow, bail, Context, Result};
use needle_link::{Client, LinkError, Transport};
use needle_sim::{closed_loop, Controller, Perturbation, Planned, TrackerFaults};
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, TipMeasurement};
use planner_core::Scenario;

/// Instructions per reading over one closed-loop insertion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplanFigures {
    /// Readings answered (link resends included).
    pub readings: usize,
    /// Readings that replanned.
    pub replans: u32,
    /// Most instructions of one reading.
    pub max: u64,
    /// Median instructions of a reading.
    pub median: u64,
}

/// The firmware's controller behind the link, answering the simulated tracker's readings.
struct Firmware<'a, T: Transport>(&'a mut Client<T>);

impl<T: Transport> Controller for Firmware<'_, T> {
    type Error = LinkError;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.0.steer(m)
    }
    fn stats(&mut self) -> Result<SteerStats, LinkError> {
        self.0.steer_status().map(|(stats, _)| stats)
    }
}

/// Steers one insertion of `scenario` on `device` and returns the per-reading figures.
pub fn measure<T: Transport>(
    device: &mut Client<T>,
    qemu: &Qemu,
    scenario: &Scenario,
) -> Result<ReplanFigures> {
    let planned = planner_core::plan_scheduled(scenario)
        .map_err(|e| anyhow!("the host cannot plan the scenario: {e}"))?;
    let schedule = planned
        .schedule
        .clone()
        .context("the plan has no feasible form to schedule")?
        .map_err(|e| anyhow!("no schedule: {e}"))?;
    let best = planned
        .report
        .best()
        .context("the plan names no best form")?
        .clone();
    device
        .plan(scenario, &mut |_| {})
        .context("planning")?
        .map_err(|e| anyhow!("the device refused the scenario: {e}"))?;
    device
        .steer_start(&SteerConfig::DEFAULT)
        .context("starting to steer")?;
    let before = qemu.counts()?.len();
    let run = closed_loop(
        scenario,
        &Planned::of(scenario, &best),
        &schedule,
        &Perturbation::default(),
        &TrackerFaults::default(),
        &mut Firmware(device),
        1,
    )
    .map_err(|e| anyhow!("{e}"))?;
    let mut counts: Vec<u64> = qemu.counts()?.split_off(before);
    if counts.is_empty() {
        bail!("the plugin counted no steering reading");
    }
    counts.sort_unstable();
    Ok(ReplanFigures {
        readings: counts.len(),
        replans: run.stats.replans,
        max: counts[counts.len() - 1],
        median: counts[counts.len() / 2],
    })
}
