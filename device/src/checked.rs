//! A plan made on the device and re-checked here, whole: its schedule (against the nominal model
//! and the host's own, bit for bit) and, under a collision bound, its predicted figures. What
//! `needle send` prints and the Python `Device.plan` returns.

use super::commands::LinkOptions;
use super::send::plan_on_device;
use super::verify::{verified_chance, verified_schedule};
use anyhow::{anyhow, Result};
use needle_report::local::LocalPlan;
use needle_report::Stats;
use needle_scenario::reserve::{is_unreachable, keeping_reserve, Shortfall};
use needle_scenario::Execution;
use planner_core::Scenario;

/// How a plan on the device ended, once its answer passed every check.
pub enum Sent {
    /// The plan, printed and judged as `needle plan` prints and judges its own (boxed: it holds
    /// the whole report).
    Planned(Box<LocalPlan>),
    /// The device's planner refused the scenario (its typed error, as `needle plan` gives it).
    Refused(anyhow::Error),
}

/// Plans `scenario` on the device at `link`, under `execution`'s collision bound if it has one,
/// keeping as much of the curvature reserve as a path allows (`needle_scenario::reserve`: the
/// scenario is sent again with less where the device's plan falls short), and checks each
/// answer. `Err` when the link fails or an answer fails a check.
pub fn plan_checked(
    scenario: &Scenario,
    execution: &Execution,
    link: &LinkOptions,
) -> Result<Sent> {
    let start = std::time::Instant::now();
    let (_, sent) = keeping_reserve(
        scenario,
        |s| plan_checked_once(s, execution, link),
        |sent| match sent {
            Ok(Sent::Planned(made)) => made.shortfall(),
            Ok(Sent::Refused(e)) => is_unreachable(e).then_some(Shortfall::Unreachable),
            Err(_) => None,
        },
    );
    let mut sent = sent?;
    if let Sent::Planned(made) = &mut sent {
        made.reserve_asked = scenario.options.curvature_reserve;
        made.judge(execution);
        // Every plan sent to keep the reserve counts in the time.
        made.stats.time_us = start.elapsed().as_micros() as u64;
    }
    Ok(sent)
}

/// One plan of `scenario` as it is on the device, checked.
fn plan_checked_once(
    scenario: &Scenario,
    execution: &Execution,
    link: &LinkOptions,
) -> Result<Sent> {
    let (result, device) = plan_on_device(scenario, execution.chance_request(), link)?;
    let answer = match result {
        Ok(a) => a,
        Err(e) => return Ok(Sent::Refused(anyhow!(e).context("planning failed"))),
    };
    let stats = Stats {
        time_us: device.time_us,
    };
    let checked = verified_chance(scenario, execution, &answer)?;
    let made = LocalPlan::new(scenario, execution, answer.planned, checked, stats);
    if made.report().best().is_some() {
        verified_schedule(scenario, &made.planned)?;
    }
    Ok(Sent::Planned(Box::new(made)))
}
