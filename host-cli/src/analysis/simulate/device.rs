//! Closed-loop simulation with the controller on a device (hil-sim or the firmware): the host
//! runs the simulated robot, tissue and tracker and sends each reading over the link.

use super::{run_seed, Prepared};
use crate::device::commands::LinkArgs;
use anyhow::{anyhow, bail, Context, Result};
use hil_sim::insertion::{closed_loop, ClosedRun, Perturbation, Planned, TrackerFaults};
use planner_core::steer::SteerConfig;
use planner_core::Scenario;
use std::time::Duration;

/// `runs` closed-loop insertions, one after the other, each steered by the device at `link`
/// (which plans the scenario first: its plan must be the host's, bit for bit).
#[allow(clippy::too_many_arguments)]
pub fn simulate_on_device(
    scenario: &Scenario,
    prepared: &Prepared,
    p: &Perturbation,
    faults: &TrackerFaults,
    config: &SteerConfig,
    runs: usize,
    seed: u64,
    link: &LinkArgs,
    done: impl Fn(),
) -> Result<Vec<ClosedRun>> {
    p.validate()?;
    let (mut client, _info) = link.connect_within(link.config()?, Duration::MAX)?;
    let planned_there = client
        .plan(scenario, &mut |_| {})
        .context("planning on the device")?
        .map_err(|e| anyhow!("the device refused the scenario: {e}"))?;
    match &planned_there.schedule {
        Some(Ok(s)) if *s == prepared.schedule => {}
        _ => bail!("the device's plan differs from the host's: it cannot steer the same insertion"),
    }
    let planned = Planned::of(scenario, &prepared.outcome);
    let mut out = Vec::with_capacity(runs);
    for i in 0..runs {
        let steps = client.steer_start(config).context("starting to steer")?;
        if steps[..] != prepared.schedule.steps[..] {
            bail!("the device starts steering with other steps than the plan's");
        }
        let run = closed_loop(
            scenario,
            &planned,
            &prepared.schedule,
            p,
            faults,
            &mut client,
            run_seed(seed, i),
        )
        .map_err(|e| anyhow!("run {}: {e}", i + 1))?;
        out.push(run);
        done();
    }
    Ok(out)
}
