//! The instructions of closed-loop steering on the device: one simulated insertion (seed 1, in
//! the default world or the clinical one) steered by the firmware in QEMU, each reading counted
//! on its own by the instruction-count plugin (the firmware brackets every poll that answers a
//! reading).

use crate::qemu::Qemu;
use anyhow::{anyhow, bail, Context, Result};
use needle_link::{Client, LinkError, Transport};
use needle_sim::{
    closed_loop_in, Conditions, Controller, Perturbation, Planned, TrackerFaults, WorldEffects,
};
use planner_core::steer::{NoiseModel, SteerConfig, SteerReply, SteerStats, TipMeasurement};
use planner_core::Scenario;

/// What a lab tells the steering of an insertion in soft, layered tissue: the `[steering]` of
/// examples/paper-clinical.toml and space-clinical.toml (a test holds them equal). Told that the
/// tissue's curvature changes along the way, the steering tries more turns per replan (the turn
/// made early, eased) than with [`SteerConfig::DEFAULT`].
pub const LAB_STEERING: SteerConfig = SteerConfig {
    noise: NoiseModel {
        registration_mm: 0.42,
        target_speed_walk: 0.02,
        curvature_walk: 0.02,
        ..NoiseModel::DEFAULT
    },
    ..SteerConfig::DEFAULT
};

/// The curvature reserve the clinical examples' plans keep (`planner.curvature_reserve`): layered
/// tissue takes curvature away where a plan needs it, so a lab keeps more in hand, and each
/// replan then eases the turn made early from the full curvature down to this share.
pub const LAB_RESERVE: f32 = 0.4;

/// How one insertion is steered, and in which world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Steered {
    /// What the steering is told.
    pub config: SteerConfig,
    /// The clinical world (`needle simulate --world clinical`: a 5-DOF tracker, layers and
    /// punctures, a pushed target, latency, dropouts) instead of the default one.
    pub clinical: bool,
}

impl Steered {
    /// The default configuration in the default world.
    pub const DEFAULT: Steered = Steered {
        config: SteerConfig::DEFAULT,
        clinical: false,
    };

    /// A lab's configuration ([`LAB_STEERING`]) in the clinical world.
    pub const LAB: Steered = Steered {
        config: LAB_STEERING,
        clinical: true,
    };
}

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

/// Steers one insertion of `scenario` on `device` as `how` says and returns the per-reading
/// figures.
pub fn measure<T: Transport>(
    device: &mut Client<T>,
    qemu: &Qemu,
    scenario: &Scenario,
    how: &Steered,
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
        .steer_start(&how.config)
        .context("starting to steer")?;
    let (effects, faults) = if how.clinical {
        (WorldEffects::clinical(), WorldEffects::clinical_faults())
    } else {
        (WorldEffects::default(), TrackerFaults::default())
    };
    let world = Conditions {
        perturbation: &Perturbation::default(),
        effects: &effects,
        faults: &faults,
    };
    let before = qemu.counts()?.len();
    let run = closed_loop_in(
        scenario,
        &Planned::of(scenario, &best),
        &schedule,
        &world,
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
