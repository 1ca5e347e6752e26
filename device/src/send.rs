//! `needle send`: a whole plan on the device within `--deadline`, starting over on a fresh
//! connection when the device restarts mid-plan (its connection closed, or it no longer knows
//! the request).

use super::commands::LinkOptions;
use anyhow::{anyhow, bail, Result};
use indicatif::{ProgressBar, ProgressStyle};
use needle_link::{Client, LinkError, LinkStats, Progress, Transport};
use planner_core::wire::{ChanceRequest, DeviceInfo, Fault, PlanResult};
use planner_core::Scenario;
use std::time::{Duration, Instant};

/// Times a plan starts over after the device restarted, within the deadline.
const RESTARTS: u32 = 3;

/// Pause between connection attempts while a restarted device comes back.
const RECONNECT_PAUSE: Duration = Duration::from_millis(100);

/// What a plan on the device took.
#[derive(Clone, Copy, Debug)]
pub struct DevicePlanStats {
    /// Wall-clock time from upload to the fetched result (µs).
    pub time_us: u64,
    /// Link counters (of the last connection).
    pub link: LinkStats,
    /// Times the plan started over on a new connection.
    pub restarts: u32,
}

/// Whether `e` says the device went away or restarted (worth a fresh connection).
fn restarted(e: &LinkError) -> bool {
    matches!(
        e,
        LinkError::Lost { .. } | LinkError::Device(Fault::UnknownRequest)
    )
}

/// Plans `scenario` on the device (under the collision bound `chance`, if any), with a
/// progress bar on a terminal.
pub fn plan_on_device(
    scenario: &Scenario,
    chance: Option<ChanceRequest>,
    link: &LinkOptions,
) -> Result<(PlanResult, DevicePlanStats)> {
    let config = link.config()?;
    let limit = config.deadline.unwrap_or(Duration::MAX);
    let start = Instant::now();
    let (mut client, mut info) = link.connect_within(config, limit)?;
    let mut restarts = 0;
    loop {
        let result = plan_once(scenario, chance, &mut client, &info)?;
        let e = match result {
            Ok(r) => {
                let stats = DevicePlanStats {
                    time_us: start.elapsed().as_micros() as u64,
                    link: client.stats(),
                    restarts,
                };
                return Ok((r, stats));
            }
            Err(e) => e,
        };
        let why = format!("{e} ({:.2} s into the send)", start.elapsed().as_secs_f64());
        if !restarted(&e) || restarts >= RESTARTS {
            let again = match restarts {
                0 => String::new(),
                n => format!(" (after starting over {n} times)"),
            };
            return Err(anyhow!("planning on the device failed{again}: {why}"));
        }
        restarts += 1;
        drop(client);
        (client, info) = reconnect(link, start, limit, config.timeout, &why)?;
    }
}

/// A fresh connection after the device went away: attempts every [`RECONNECT_PAUSE`] for up
/// to `patience` (the silence allowed), within the deadline.
fn reconnect(
    link: &LinkOptions,
    start: Instant,
    limit: Duration,
    patience: Duration,
    why: &str,
) -> Result<(Client<Box<dyn Transport>>, DeviceInfo)> {
    let config = link.config()?;
    let from = Instant::now();
    loop {
        let left = limit.saturating_sub(start.elapsed());
        if left.is_zero() {
            bail!(
                "planning on the device failed: {why}; the {:.2} s deadline (--deadline) \
                 passed while reconnecting",
                limit.as_secs_f64()
            );
        }
        match link.connect_within(config, left) {
            Ok(c) => return Ok(c),
            Err(e) if from.elapsed() >= patience => bail!(
                "planning on the device failed: {why}; it did not come back on {} within \
                 {:.2} s: {e:#}",
                link.target(),
                from.elapsed().as_secs_f64()
            ),
            Err(_) => std::thread::sleep(RECONNECT_PAUSE.min(left)),
        }
    }
}

/// One attempt at the plan on `client`; the outer error is not worth starting over for.
fn plan_once(
    scenario: &Scenario,
    chance: Option<ChanceRequest>,
    client: &mut Client<Box<dyn Transport>>,
    info: &DeviceInfo,
) -> Result<Result<PlanResult, LinkError>> {
    if scenario.obstacles.len() > usize::from(info.max_obstacles) {
        bail!(
            "the scenario has {} obstacles but the device holds at most {}",
            scenario.obstacles.len(),
            info.max_obstacles
        );
    }
    // Hidden when stderr is not a terminal, so piped output stays exactly `needle plan`'s.
    let bar = ProgressBar::new(scenario.options.selected_forms().iter().count() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} planning on the device [{bar:30}] {pos}/{len} forms {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let mut on_progress = |p: Progress| {
        bar.set_length(u64::from(p.total));
        bar.set_position(u64::from(p.done));
        if let Some(f) = p.form {
            // Under a collision bound every round plans the forms again, obstacles grown.
            let round = match chance {
                Some(_) => format!("round {}, ", p.round),
                None => String::new(),
            };
            bar.set_message(format!(
                "{round}{f}: {}",
                if p.feasible { "feasible" } else { "infeasible" }
            ));
        }
    };
    let result = client.plan_bounded(scenario, chance, &mut on_progress);
    bar.finish_and_clear();
    Ok(result)
}
