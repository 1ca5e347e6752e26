//! Closed-loop simulation: every run steered by the controller of `planner-core` (in-process
//! here; on a device with `--tcp`/`--port`), in the same worlds the open-loop runs see.

use super::{run_seed, Prepared};
use crate::analysis::parallel;
use anyhow::{anyhow, Result};
use needle_sim::{closed_loop, in_process, ClosedRun, Perturbation, Planned, TrackerFaults};
use planner_core::steer::{SteerConfig, StopReason};
use planner_core::Scenario;
use std::collections::BTreeMap;

/// `runs` closed-loop insertions with the in-process controller on `threads` threads; the
/// result is the same on any thread count.
#[allow(clippy::too_many_arguments)]
pub fn simulate_closed(
    scenario: &Scenario,
    prepared: &Prepared,
    p: &Perturbation,
    faults: &TrackerFaults,
    config: &SteerConfig,
    runs: usize,
    seed: u64,
    threads: usize,
    done: impl Fn() + Sync,
) -> Result<Vec<ClosedRun>> {
    p.validate()?;
    let planned = Planned::of(scenario, &prepared.outcome);
    let seeds: Vec<u64> = (0..runs).map(|i| run_seed(seed, i)).collect();
    let results = parallel::map(
        &seeds,
        threads,
        |s| -> Result<ClosedRun> {
            let mut ctl = in_process(scenario, &prepared.schedule, config)
                .map_err(|e| anyhow!("steering cannot start: {e}"))?;
            closed_loop(
                scenario,
                &planned,
                &prepared.schedule,
                p,
                faults,
                &mut ctl,
                *s,
            )
            .map_err(|e| anyhow!("{e}"))
        },
        done,
    );
    results.into_iter().collect()
}

/// The closed loop's own figures over the runs (their keys in `--json`'s `summary`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SteeringSummary {
    /// New continuations commanded, over all runs.
    pub replans: u64,
    /// Replans that found nothing passing the check.
    pub replan_failures: u64,
    /// Runs stopped before the target, by reason.
    pub stops: BTreeMap<&'static str, usize>,
    /// Fixes rejected as outliers.
    pub outliers: u64,
    /// Readings without a fix.
    pub no_fix: u64,
    /// Readings older than the last (ignored).
    pub stale: u64,
    /// Readings answered again: a tracker's duplicate, or (on a device) the link sending a
    /// reading again; the one count that depends on the transport.
    pub repeated: u64,
}

/// The steering figures of `runs`.
pub fn summarise_steering(runs: &[ClosedRun]) -> SteeringSummary {
    let mut s = SteeringSummary::default();
    for reason in [
        StopReason::NoSafeContinuation,
        StopReason::TrackingLost,
        StopReason::BadMeasurement,
    ] {
        s.stops.insert(reason.name(), 0);
    }
    for r in runs {
        s.replans += u64::from(r.stats.replans);
        s.replan_failures += u64::from(r.stats.replan_failures);
        s.outliers += u64::from(r.stats.outliers);
        s.no_fix += u64::from(r.stats.no_fix);
        s.stale += u64::from(r.stats.stale);
        s.repeated += u64::from(r.stats.repeated);
        if let Some(reason) = r.stop_reason {
            *s.stops.entry(reason.name()).or_default() += 1;
        }
    }
    s
}
