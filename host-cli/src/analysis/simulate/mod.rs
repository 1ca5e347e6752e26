//! `needle simulate`'s work: a plan's schedule executed open loop in many perturbed worlds (the
//! insertion simulator of `hil-sim`), in parallel, and the figures over the runs. Simulated
//! figures, always called so.

pub mod closed;
pub mod device;
pub mod json;
pub mod plot;
pub mod table;

use crate::analysis::parallel;
use anyhow::{anyhow, Context, Result};
use hil_sim::insertion::{open_loop, Perturbation, Planned, Run};
use planner_core::execute::schedule::{schedule, Schedule};
use planner_core::{FormOutcome, Scenario};

/// The plan being simulated: the best form's outcome (or the one form asked for) and its schedule.
pub struct Prepared {
    /// The planned form.
    pub outcome: FormOutcome,
    /// What the driver executes.
    pub schedule: Schedule,
}

/// Plans `scenario` (already restricted to the form asked for, if any) and schedules the best.
pub fn prepare(scenario: &Scenario) -> Result<Prepared> {
    let report = planner_core::plan(scenario).context("planning failed")?;
    let outcome = report
        .best()
        .cloned()
        .ok_or_else(|| anyhow!(planner_core::PlanError::Unreachable))?;
    let schedule = schedule(scenario, &outcome)
        .map_err(|e| anyhow!("cannot schedule the {} path: {e:?}", outcome.form))?;
    Ok(Prepared { outcome, schedule })
}

/// The seed of run `i` (runs are independent: a run's result depends on its seed alone).
pub fn run_seed(seed: u64, i: usize) -> u64 {
    seed.wrapping_add(i as u64)
}

/// `runs` open-loop insertions on `threads` threads; the result is the same on any thread count.
pub fn simulate(
    scenario: &Scenario,
    prepared: &Prepared,
    p: &Perturbation,
    runs: usize,
    seed: u64,
    threads: usize,
    done: impl Fn() + Sync,
) -> Result<Vec<Run>> {
    p.validate()?;
    let planned = Planned::of(scenario, &prepared.outcome);
    let seeds: Vec<u64> = (0..runs).map(|i| run_seed(seed, i)).collect();
    let results = parallel::map(
        &seeds,
        threads,
        |s| open_loop(scenario, &planned, &prepared.schedule, p, *s),
        done,
    );
    results
        .into_iter()
        .collect::<Result<Vec<_>, _>>()
        .map_err(Into::into)
}

/// Mean, RMS, 95th percentile (nearest rank) and maximum of some values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Root mean square.
    pub rms: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// The figures of `values` (zeros when empty).
    pub fn of(values: impl Iterator<Item = f32>) -> Spread {
        let mut v: Vec<f64> = values.map(f64::from).collect();
        if v.is_empty() {
            return Spread::default();
        }
        v.sort_by(f64::total_cmp);
        let n = v.len() as f64;
        let rank = ((0.95 * n).ceil() as usize).clamp(1, v.len());
        Spread {
            mean: v.iter().sum::<f64>() / n,
            rms: (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
            p95: v[rank - 1],
            max: v[v.len() - 1],
        }
    }
}

/// The figures over all runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Distance of each run's end to its true target (mm).
    pub target_error: Spread,
    /// Each run's RMS deviation from the planned path; its `rms` is the RMS over all runs.
    pub path_rms: Spread,
    /// Each run's largest deviation from the planned path.
    pub path_max: Spread,
    /// Plane scenarios: each run's RMS deviation in the plan's plane (the points projected onto
    /// it), what a view across a planar phantom measures.
    pub path_rms_in_plane: Option<Spread>,
    /// Plane scenarios: each run's largest in-plane deviation.
    pub path_max_in_plane: Option<Spread>,
    /// Runs whose true path entered an obstacle.
    pub collisions: usize,
    /// Smallest clearance over all runs (mm).
    pub min_clearance: f32,
}

/// The summary of `runs`.
pub fn summarise(runs: &[Run]) -> Summary {
    Summary {
        target_error: Spread::of(runs.iter().map(|r| r.target_error)),
        path_rms: Spread::of(runs.iter().map(|r| r.path_rms)),
        path_max: Spread::of(runs.iter().map(|r| r.path_max)),
        path_rms_in_plane: in_plane(runs, |r| r.path_rms_in_plane),
        path_max_in_plane: in_plane(runs, |r| r.path_max_in_plane),
        collisions: runs.iter().filter(|r| r.collided).count(),
        min_clearance: runs
            .iter()
            .map(|r| r.min_clearance)
            .fold(f32::INFINITY, f32::min),
    }
}

fn in_plane(runs: &[Run], f: impl Fn(&Run) -> Option<f32>) -> Option<Spread> {
    let values: Option<Vec<f32>> = runs.iter().map(f).collect();
    values
        .filter(|v| !v.is_empty())
        .map(|v| Spread::of(v.into_iter()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_figures() {
        let s = Spread::of([3.0f32, 1.0, 2.0, 4.0].into_iter());
        assert_eq!(s.mean, 2.5);
        assert_eq!(s.max, 4.0);
        assert_eq!(s.p95, 4.0);
        assert!((s.rms - 7.5f64.sqrt()).abs() < 1e-12);
        let many = Spread::of((1..=100).map(|k| k as f32));
        assert_eq!(many.p95, 95.0);
        assert_eq!(Spread::of(std::iter::empty()), Spread::default());
    }

    #[test]
    fn runs_repeat_on_any_thread_count() {
        let scenario = Scenario::paper();
        let prepared = prepare(&scenario).unwrap();
        let p = Perturbation::default();
        let one = simulate(&scenario, &prepared, &p, 6, 11, 1, || {}).unwrap();
        let three = simulate(&scenario, &prepared, &p, 6, 11, 3, || {}).unwrap();
        assert_eq!(one, three);
        assert_eq!(one[4].seed, 15);
        let mut bad = p;
        bad.tracker_heading_deg = -1.0;
        let e = simulate(&scenario, &prepared, &bad, 2, 0, 1, || {}).unwrap_err();
        assert!(e.to_string().contains("tracker_heading_deg"), "{e}");
    }
}
