//! The closed loop's own figures over the runs: replans, stops by reason, the tracker's faults
//! as the controller saw them.

use needle_sim::{ClosedRun, Outcome};
use planner_core::steer::StopReason;
use std::collections::BTreeMap;

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
    /// Imaged targets rejected as outliers.
    pub target_outliers: u64,
    /// Times the imaged target moved and the controller followed it.
    pub target_jumps: u64,
    /// Readings older than the last (ignored).
    pub stale: u64,
    /// Readings answered again: a tracker's duplicate, or (on a device) the link sending a
    /// reading again; the one count that depends on the transport.
    pub repeated: u64,
    /// How the runs ended, judged on the world's truth (`needle_sim::Outcome`): `reached`,
    /// `missed`, `collided`, `stopped`; every name listed.
    pub outcomes: BTreeMap<&'static str, usize>,
    /// Runs that reached the target: the true path clear of every obstacle and the true tip
    /// within the reach tolerance of the true target (`outcomes.reached`). A run whose true path
    /// entered an obstacle is never counted here, whatever the controller concluded.
    pub reached: usize,
    /// Runs the controller itself let end at the target as it estimated it (no stop): its own
    /// verdict, beside `reached`, which is the world's.
    pub controller_reached: usize,
    /// Target error over the runs that reached (mm; zeros when none): the accuracy of the
    /// insertions that went through, beside `target_error` over every run, which counts a
    /// stopped run's distance from where it stopped.
    pub reached_target_error: super::Spread,
    /// Runs within the tissue's reach: the world's full curvature, turned at the target from
    /// the true entry, comes within the reach tolerance of where the target ended
    /// (`needle_sim::nearest_reach`): what a controller that knew the world could reach.
    pub within_reach: usize,
    /// Of the runs within the tissue's reach, those that reached.
    pub reached_within_reach: usize,
}

/// The steering figures of `runs`, a target within `reach_tolerance_mm` counted as reached.
pub fn summarise_steering(runs: &[ClosedRun], reach_tolerance_mm: f32) -> SteeringSummary {
    let mut s = SteeringSummary::default();
    for reason in [
        StopReason::NoSafeContinuation,
        StopReason::TrackingLost,
        StopReason::BadMeasurement,
        StopReason::Missed,
    ] {
        s.stops.insert(reason.name(), 0);
    }
    for r in runs {
        s.replans += u64::from(r.stats.replans);
        s.replan_failures += u64::from(r.stats.replan_failures);
        s.outliers += u64::from(r.stats.outliers);
        s.no_fix += u64::from(r.stats.no_fix);
        s.target_outliers += u64::from(r.stats.target_outliers);
        s.target_jumps += u64::from(r.stats.target_jumps);
        s.stale += u64::from(r.stats.stale);
        s.repeated += u64::from(r.stats.repeated);
        if let Some(reason) = r.stop_reason {
            *s.stops.entry(reason.name()).or_default() += 1;
        }
    }
    for name in Outcome::NAMES {
        s.outcomes.insert(name, 0);
    }
    let reached = |r: &&ClosedRun| Outcome::of(r, reach_tolerance_mm) == Outcome::Reached;
    for r in runs {
        *s.outcomes
            .entry(Outcome::of(r, reach_tolerance_mm).name())
            .or_default() += 1;
    }
    s.reached = runs.iter().filter(reached).count();
    s.controller_reached = runs.iter().filter(|r| r.stop_reason.is_none()).count();
    s.reached_target_error =
        super::Spread::of(runs.iter().filter(reached).map(|r| r.run.target_error));
    let within = runs
        .iter()
        .filter(|r| r.run.nearest_reach_mm <= reach_tolerance_mm);
    s.within_reach = within.clone().count();
    s.reached_within_reach = within.filter(reached).count();
    s
}
