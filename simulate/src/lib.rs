//! `needle simulate`: a plan's schedule executed in many perturbed worlds (the insertion
//! simulator of `needle-sim`), open loop or steered, in parallel, and the figures over the runs.
//! Simulated figures, always called so. [`benchmark`] is `needle benchmark`: the same runs on
//! generated scenarios nobody tuned on.
//!
//! Executing the paper's plan in simulated worlds, open loop:
//!
//! ```
//! use needle_sim::{Perturbation, TrackerFaults};
//! use needle_simulate::setup::{Keep, Setup};
//! use needle_simulate::summarise;
//! use planner_core::Scenario;
//!
//! let setup = Setup::new(Scenario::paper(), Perturbation::default(), TrackerFaults::default(), 4, 7)?;
//! let runs = setup.open_loop(&Keep::default(), 2, || {})?;
//! assert_eq!(runs.len(), 4);
//! assert_eq!(runs[3].seed, 10); // run i is seeded seed + i: any thread count gives the same
//! let simulated = summarise(&runs);
//! assert!(simulated.target_error.max >= simulated.target_error.mean);
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod benchmark;
mod command;
pub mod device;
pub mod json;
mod options;
pub mod plot;
pub mod request;
pub mod setup;
pub mod steering;
pub mod table;

pub use command::{closed_loop_setup, run_simulate};
pub use options::{SimulateOptions, MAX_RUNS, MAX_SCENARIOS};

use anyhow::{anyhow, Context, Result};
use needle_scenario::reserve::{is_unreachable, keeping_reserve, Shortfall};
use needle_sim::Perturbation;
use needle_sim::Run;
use planner_core::chance::plan_within_risk_as;
use planner_core::execute::schedule::{schedule, Schedule};
use planner_core::{FormOutcome, Scenario};

/// The plan being simulated: the best form's outcome (or the one form asked for) and its schedule.
pub struct Prepared {
    /// The planned form.
    pub outcome: FormOutcome,
    /// What the driver executes.
    pub schedule: Schedule,
}

/// A bound on the predicted collision probability the plan must keep, under a perturbation
/// model (the scenario's `[execution]`, not the simulated world's: the planner is told what the
/// scenario says, never the world's draws).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanBound {
    /// The model the planner predicts with.
    pub model: Perturbation,
    /// The bound.
    pub max_collision_probability: f32,
    /// How the plan is executed, so how its spread is predicted.
    pub execution: planner_core::execute::risk::Execution,
}

/// No plan keeps the predicted collision probability within the bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundNotMet {
    /// The bound.
    pub bound: f32,
    /// The best plan's predicted probability.
    pub best: f32,
}

impl PlanBound {
    /// What a device is told to plan under this bound.
    pub fn request(&self) -> planner_core::wire::ChanceRequest {
        planner_core::wire::ChanceRequest {
            bound: self.max_collision_probability,
            model: self.model,
            execution: self.execution,
        }
    }
}

impl std::fmt::Display for BoundNotMet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "no plan keeps the predicted collision probability within {}: the best found has {:.4}",
            self.bound, self.best
        )
    }
}

impl std::error::Error for BoundNotMet {}

/// Plans `scenario` (already restricted to the form asked for, if any) and schedules the best;
/// with a bound, the best must keep it (else an error saying so).
pub fn prepare(scenario: &Scenario, bound: Option<&PlanBound>) -> Result<Prepared> {
    let report = match bound {
        None => planner_core::plan(scenario).context("planning failed")?,
        Some(b) => {
            let c =
                plan_within_risk_as(scenario, &b.model, b.max_collision_probability, b.execution)
                    .context("planning failed")?;
            if c.planned.report.best().is_none() {
                return Err(anyhow!(planner_core::PlanError::Unreachable));
            }
            if !c.within_bound {
                return Err(anyhow!(BoundNotMet {
                    bound: b.max_collision_probability,
                    best: c.risk.map_or(f32::NAN, |r| r.collision_probability),
                }));
            }
            c.planned.report
        }
    };
    let outcome = report
        .best()
        .cloned()
        .ok_or_else(|| anyhow!(planner_core::PlanError::Unreachable))?;
    let schedule = schedule(scenario, &outcome)
        .map_err(|e| anyhow!("cannot schedule the {} path: {e:?}", outcome.form))?;
    Ok(Prepared { outcome, schedule })
}

/// [`prepare`], keeping as much of the scenario's curvature reserve as a path allows (the rule
/// of [`needle_scenario::reserve`]); a scenario it gives up on is refused, saying why. Returns the scenario
/// with the reserve planned with, and the plan.
pub fn prepare_keeping_reserve(
    scenario: &Scenario,
    bound: Option<&PlanBound>,
) -> Result<(Scenario, Prepared)> {
    let (s, made) = keeping_reserve(
        scenario,
        |s| prepare(s, bound),
        |made| made.as_ref().err().and_then(shortfall),
    );
    let reserve = s.options.curvature_reserve;
    match made {
        Ok(p) => Ok((s, p)),
        Err(e) if reserve > 0.0 && is_unreachable(&e) => Err(e.context(format!(
            "no path keeps a curvature reserve of {reserve} or more for steering (planned at \
             the needle's full curvature, a tissue that bends a little less leaves the target \
             out of reach)"
        ))),
        Err(e) => Err(e),
    }
}

/// Why `e` refused a plan that a lower reserve might make.
fn shortfall(e: &anyhow::Error) -> Option<Shortfall> {
    if is_unreachable(e) {
        Some(Shortfall::Unreachable)
    } else if misses_bound(e) {
        Some(Shortfall::MissesBound)
    } else {
        None
    }
}

fn misses_bound(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<BoundNotMet>().is_some())
}

/// The seed of run `i` (runs are independent: a run's result depends on its seed alone).
pub fn run_seed(seed: u64, i: usize) -> u64 {
    seed.wrapping_add(i as u64)
}

/// Mean, RMS, 95th percentile (nearest rank) and maximum of some values.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
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
    /// Of them, the runs whose true path entered a voxel of an organ the spheres cover, judged
    /// against the label map (`None`: no label map).
    pub entered_voxels: Option<usize>,
    /// Smallest clearance over all runs (mm).
    pub min_clearance: f32,
    /// The bevel rotations per insertion.
    pub rotations: RotationFigures,
}

/// The bevel rotations over the runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RotationFigures {
    /// Median rotations per run (the upper middle of an even count).
    pub median_per_run: u32,
    /// Most rotations in one run.
    pub max_per_run: u32,
    /// Mean over the runs of their rotations' sizes summed (degrees).
    pub mean_total_deg: f64,
    /// The smallest rotation of any run (degrees; null without any).
    pub smallest_deg: Option<f32>,
}

impl RotationFigures {
    /// The figures of `runs`.
    pub fn of<'a>(runs: impl Iterator<Item = &'a Run>) -> RotationFigures {
        let mut counts = Vec::new();
        let (mut total, mut smallest) = (0.0f64, None::<f32>);
        for r in runs {
            counts.push(r.rotations.count);
            total += f64::from(r.rotations.total_deg);
            if let Some(s) = r.rotations.smallest_deg {
                smallest = Some(smallest.map_or(s, |m| m.min(s)));
            }
        }
        counts.sort_unstable();
        RotationFigures {
            median_per_run: counts.get(counts.len() / 2).copied().unwrap_or(0),
            max_per_run: counts.last().copied().unwrap_or(0),
            mean_total_deg: total / counts.len().max(1) as f64,
            smallest_deg: smallest,
        }
    }
}

/// The summary of `runs` (their figures: what is kept of every run).
pub fn summarise<'a, I>(runs: I) -> Summary
where
    I: IntoIterator<Item = &'a Run>,
    I::IntoIter: Clone,
{
    let runs = runs.into_iter();
    Summary {
        target_error: Spread::of(runs.clone().map(|r| r.target_error)),
        path_rms: Spread::of(runs.clone().map(|r| r.path_rms)),
        path_max: Spread::of(runs.clone().map(|r| r.path_max)),
        path_rms_in_plane: in_plane(runs.clone(), |r| r.path_rms_in_plane),
        path_max_in_plane: in_plane(runs.clone(), |r| r.path_max_in_plane),
        collisions: runs.clone().filter(|r| r.collided).count(),
        entered_voxels: runs.clone().any(|r| r.entered_voxels.is_some()).then(|| {
            runs.clone()
                .filter(|r| r.entered_voxels == Some(true))
                .count()
        }),
        rotations: RotationFigures::of(runs.clone()),
        min_clearance: runs.map(|r| r.min_clearance).fold(f32::INFINITY, f32::min),
    }
}

fn in_plane<'a>(
    runs: impl Iterator<Item = &'a Run>,
    f: impl Fn(&Run) -> Option<f32>,
) -> Option<Spread> {
    let values: Option<Vec<f32>> = runs.map(f).collect();
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
    fn runs_repeat_on_any_thread_count_and_keep_only_what_is_asked() {
        use needle_sim::{Perturbation, TrackerFaults};
        let p = Perturbation::default();
        let setup = |runs| {
            setup::Setup::new(Scenario::paper(), p, TrackerFaults::default(), runs, 11).unwrap()
        };
        let detail = setup::Keep {
            detail: true,
            ..setup::Keep::default()
        };
        let one = setup(6).open_loop(&detail, 1, || {}).unwrap();
        let three = setup(6).open_loop(&detail, 3, || {}).unwrap();
        assert_eq!(one, three);
        assert_eq!(one[4].seed, 15);
        assert!(one
            .iter()
            .all(|r| !r.points.is_empty() && !r.steps.is_empty()));
        // Without --detail, the figures alone (the same), and the paths of the first runs only.
        let drawn = setup::Keep {
            paths: 2,
            ..setup::Keep::default()
        };
        let lean = setup(6).open_loop(&drawn, 3, || {}).unwrap();
        assert_eq!(summarise(&lean), summarise(&one));
        let kept: Vec<bool> = lean.iter().map(|r| !r.points.is_empty()).collect();
        assert_eq!(kept, [true, true, false, false, false, false]);
        assert!(lean
            .iter()
            .all(|r| r.steps.is_empty() && r.drawn.steps.is_empty()));
        let mut bad = p;
        bad.tracker_heading_deg = -1.0;
        let e = setup::Setup::new(Scenario::paper(), bad, TrackerFaults::default(), 2, 0)
            .err()
            .unwrap();
        assert!(e.to_string().contains("tracker_heading_deg"), "{e}");
    }

    /// Runs stopped before the target keep their paths for the plot, the first so many of them
    /// wherever they are; the others keep their figures only.
    #[test]
    fn stopped_runs_keep_the_first_paths_only() {
        use needle_sim::{Perturbation, TrackerFaults};
        let mut faults = TrackerFaults::default();
        faults.apply("dropout_rate=1").unwrap();
        faults.apply("dropout_mm=50").unwrap();
        let setup =
            setup::Setup::new(Scenario::paper(), Perturbation::default(), faults, 5, 3).unwrap();
        let keep = setup::Keep {
            paths: 1,
            stopped_paths: 2,
            ..setup::Keep::default()
        };
        let runs = setup.closed_loop(&keep, 2, || {}).unwrap();
        assert!(runs.iter().all(|r| r.stop_reason.is_some()));
        let kept: Vec<bool> = runs.iter().map(|r| !r.run.points.is_empty()).collect();
        assert_eq!(kept, [true, true, false, false, false]);
        assert!(runs.iter().all(|r| r.replan_evaluations.is_empty()));
    }
}

#[cfg(test)]
mod reserve_tests {
    use super::*;
    use needle_scenario::unseen::unseen_scenario;
    use planner_core::execute::risk::{risk_by_obstacle, Execution, ObstacleRisk};
    use planner_core::steer::SteerConfig;

    fn steered(seed: u64) -> (Scenario, PlanBound) {
        let mut s = unseen_scenario(seed);
        s.options.curvature_reserve = 0.2;
        let bound = PlanBound {
            model: Perturbation::default(),
            max_collision_probability: 0.01,
            execution: Execution::Steered(SteerConfig::DEFAULT.noise),
        };
        (s, bound)
    }

    /// Where no plan keeps the steered bound with a fifth of the curvature in hand, a wider
    /// bend does (seed 223: 2 % at 0.2, within 1 % at 0.15); where none does down to 0.15, the
    /// scenario is refused with the bound's reason (seed 241: the best 58 %).
    #[test]
    fn the_reserve_gives_way_to_the_bound_down_to_its_floor() {
        let (s, bound) = steered(223);
        assert!(prepare(&s, Some(&bound)).is_err_and(|e| misses_bound(&e)));
        let (kept, prepared) = prepare_keeping_reserve(&s, Some(&bound)).unwrap();
        assert_eq!(kept.options.curvature_reserve, 0.15);
        let mut by = [ObstacleRisk::default(); planner_core::MAX_OBSTACLES];
        let r = risk_by_obstacle(
            &kept,
            &prepared.schedule,
            &bound.model,
            bound.execution,
            &mut by,
        );
        assert!(r.collision_probability <= 0.01, "{r:?}");
        let (s, bound) = steered(241);
        let Err(e) = prepare_keeping_reserve(&s, Some(&bound)) else {
            panic!("seed 241 planned within the bound");
        };
        assert!(misses_bound(&e), "{e:#}");
    }

    /// Where the form of lowest objective misses the bound but a longer one keeps it, the longer
    /// one is planned (seed 242 open loop under 5 %: no margins bring the best form within it).
    #[test]
    fn a_longer_form_within_the_bound_is_taken() {
        let s = unseen_scenario(242);
        let bound = PlanBound {
            model: Perturbation::default(),
            max_collision_probability: 0.05,
            execution: Execution::OpenLoop,
        };
        let (kept, prepared) = prepare_keeping_reserve(&s, Some(&bound)).unwrap();
        let c = plan_within_risk_as(&kept, &bound.model, 0.05, bound.execution).unwrap();
        assert!(c.within_bound);
        let report = &c.planned.report;
        let lowest = report
            .forms
            .iter()
            .filter(|o| o.feasible)
            .map(|o| o.objective)
            .fold(f32::INFINITY, f32::min);
        let best = report.best().unwrap();
        assert!(best.objective > lowest, "{} {lowest}", best.objective);
        assert_eq!(prepared.outcome.form, best.form);
    }
}
