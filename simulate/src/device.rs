//! Closed-loop simulation with the controller on a device (hil-sim or the firmware): the host
//! runs the simulated robot, tissue and tracker and sends each reading over the link.

use super::setup::{Keep, Setup};
use anyhow::{anyhow, bail, Context, Result};
use needle_device::LinkOptions;
use needle_link::{Client, LinkError, Transport};
use needle_sim::{ClosedRun, Controller};
use planner_core::steer::{SteerReply, SteerStats, TipMeasurement};
use std::time::Duration;

/// A device's controller behind the link, answering the simulated tracker's readings: the
/// simulator knows no transport, so the host adapts the client to it.
pub struct LinkController<'a, T: Transport>(pub &'a mut Client<T>);

impl<T: Transport> Controller for LinkController<'_, T> {
    type Error = LinkError;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, LinkError> {
        self.0.steer(m)
    }
    fn stats(&mut self) -> Result<SteerStats, LinkError> {
        self.0.steer_status().map(|(stats, _)| stats)
    }
}

/// Connects to the device at `link` and has it plan `setup`'s scenario (under its collision
/// bound, if any): its plan must be the host's, bit for bit, for it to steer the insertion the
/// host plans.
pub fn device_planning(setup: &Setup, link: &LinkOptions) -> Result<Client<Box<dyn Transport>>> {
    let (mut client, _info) = link.connect_within(link.config()?, Duration::MAX)?;
    let chance = setup.bound.as_ref().map(|b| b.request());
    let planned_there = client
        .plan_bounded(&setup.scenario, chance, &mut |_| {})
        .context("planning on the device")?
        .map_err(|e| anyhow!("the device refused the scenario: {e}"))?;
    match &planned_there.planned.schedule {
        Some(Ok(s)) if *s == setup.prepared.schedule => Ok(client),
        _ => bail!("the device's plan differs from the host's: it cannot steer the same insertion"),
    }
}

/// Starts the device's controller on its plan, with `setup`'s `[steering]`.
pub fn start_steering<T: Transport>(client: &mut Client<T>, setup: &Setup) -> Result<()> {
    let steps = client
        .steer_start(&setup.config)
        .context("starting to steer")?;
    if steps[..] != setup.prepared.schedule.steps[..] {
        bail!("the device starts steering with other steps than the plan's");
    }
    Ok(())
}

/// Every run of `setup`, one after the other, each steered by the device at `link` (which plans
/// the scenario first: its plan must be the host's, bit for bit).
pub fn on_device(
    setup: &Setup,
    keep: &Keep,
    link: &LinkOptions,
    done: impl Fn(),
) -> Result<Vec<ClosedRun>> {
    let mut client = device_planning(setup, link)?;
    setup.collect(keep, |items| {
        let mut out = Vec::with_capacity(items.len());
        for &(i, seed) in items {
            start_steering(&mut client, setup)?;
            let mut run = setup
                .steer(&mut LinkController(&mut client), seed)
                .map_err(|e| anyhow!("run {}: {e}", i + 1))?;
            setup.judge(&mut run.run);
            out.push(keep.trim_closed(i, run));
            done();
        }
        Ok(out)
    })
}
