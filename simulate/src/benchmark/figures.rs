//! The benchmark's figures, per scenario and in total, and its JSON (the keys are these
//! structures' fields). A total is computed from the runs themselves, pooled over the scenarios
//! (its mean and p95 are those of every run, not an average of the rows').

use crate::steering::summarise_steering;
use crate::Prepared;
use crate::Spread;
use needle_sim::{ClosedRun, Perturbation, Run};
use planner_core::execute::risk::{risk_by_obstacle, Execution, ObstacleRisk};
use planner_core::steer::NoiseModel;
use planner_core::{FormOutcome, Scenario};
use serde::Serialize;
use std::collections::BTreeMap;

/// Runs a scenario may have before its worlds' seeds would meet the next scenario's.
pub const WORLD_SEED_STRIDE: u64 = 1 << 20;

/// What is kept of a set of runs, open and closed loop, to compute the figures (and to pool
/// them over scenarios).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pool {
    /// Runs (each executed open and closed loop).
    pub runs: usize,
    /// Open loop: each run's target error (mm).
    pub open_errors: Vec<f32>,
    /// Open loop: runs whose true path entered an obstacle.
    pub open_hits: usize,
    /// Closed loop: the target error of each run that arrived (was not stopped; mm).
    pub arrived_errors: Vec<f32>,
    /// Closed loop: runs stopped before the target, by reason.
    pub stops: BTreeMap<&'static str, usize>,
    /// Closed loop: how the runs ended, judged on the true tip and path
    /// (`needle_sim::Outcome`), by name.
    pub outcomes: BTreeMap<&'static str, usize>,
    /// Closed loop: runs whose true path entered an obstacle.
    pub closed_hits: usize,
    /// Closed loop: runs made (0 with `--open-loop-only`).
    pub closed_runs: usize,
    /// Closed loop: runs whose target was within reach of any steering
    /// ([`crate::steering::SteeringSummary::within_reach`]).
    pub within_reach: usize,
    /// Closed loop: of those, the runs that reached.
    pub reached_within_reach: usize,
}

impl Pool {
    /// The pool of the same worlds run `open` and `closed` loop, a target within
    /// `reach_tolerance_mm` counted as reached.
    pub fn of(open: &[Run], closed: &[ClosedRun], reach_tolerance_mm: f32) -> Pool {
        let steering = summarise_steering(closed, reach_tolerance_mm);
        Pool {
            runs: open.len(),
            open_errors: open.iter().map(|r| r.target_error).collect(),
            open_hits: open.iter().filter(|r| r.collided).count(),
            closed_runs: closed.len(),
            arrived_errors: closed
                .iter()
                .filter(|r| r.stop_reason.is_none())
                .map(|r| r.run.target_error)
                .collect(),
            stops: steering.stops,
            outcomes: steering.outcomes,
            closed_hits: closed.iter().filter(|r| r.run.collided).count(),
            within_reach: steering.within_reach,
            reached_within_reach: steering.reached_within_reach,
        }
    }

    /// Adds `other`'s runs.
    pub fn merge(&mut self, other: &Pool) {
        self.runs += other.runs;
        self.open_errors.extend_from_slice(&other.open_errors);
        self.open_hits += other.open_hits;
        self.arrived_errors.extend_from_slice(&other.arrived_errors);
        for (reason, n) in &other.stops {
            *self.stops.entry(reason).or_default() += n;
        }
        for (outcome, n) in &other.outcomes {
            *self.outcomes.entry(outcome).or_default() += n;
        }
        self.closed_hits += other.closed_hits;
        self.closed_runs += other.closed_runs;
        self.within_reach += other.within_reach;
        self.reached_within_reach += other.reached_within_reach;
    }

    /// Only the open-loop runs.
    pub fn open_part(&self) -> Pool {
        Pool {
            runs: self.runs,
            open_errors: self.open_errors.clone(),
            open_hits: self.open_hits,
            ..Pool::default()
        }
    }

    /// Only the closed-loop runs.
    pub fn closed_part(&self) -> Pool {
        Pool {
            arrived_errors: self.arrived_errors.clone(),
            stops: self.stops.clone(),
            outcomes: self.outcomes.clone(),
            closed_hits: self.closed_hits,
            closed_runs: self.closed_runs,
            within_reach: self.within_reach,
            reached_within_reach: self.reached_within_reach,
            ..Pool::default()
        }
    }

    fn percent(&self, count: usize) -> f64 {
        if self.runs == 0 {
            0.0
        } else {
            100.0 * count as f64 / self.runs as f64
        }
    }

    /// The open-loop figures.
    pub fn open(&self) -> OpenFigures {
        let errors = Spread::of(self.open_errors.iter().copied());
        OpenFigures {
            hits: self.open_hits,
            hit_percent: self.percent(self.open_hits),
            mean_target_error: errors.mean,
            p95_target_error: errors.p95,
        }
    }

    /// The closed-loop figures (`None` when no run was steered).
    pub fn closed(&self) -> Option<ClosedFigures> {
        if self.closed_runs == 0 {
            return None;
        }
        let arrived = self.arrived_errors.len();
        let errors = (arrived > 0).then(|| Spread::of(self.arrived_errors.iter().copied()));
        let outcome = |name: &str| self.outcomes.get(name).copied().unwrap_or(0);
        let reached = outcome("reached");
        Some(ClosedFigures {
            reached,
            reached_percent: 100.0 * reached as f64 / self.closed_runs as f64,
            missed: outcome("missed"),
            collided: outcome("collided"),
            stopped: outcome("stopped"),
            arrived,
            stops: self.stops.values().sum(),
            stop_reasons: self.stops.clone(),
            hits: self.closed_hits,
            mean_target_error: errors.map(|s| s.mean),
            p95_target_error: errors.map(|s| s.p95),
            within_reach: self.within_reach,
            reached_within_reach: self.reached_within_reach,
        })
    }
}

/// Open loop: the schedule executed as planned.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OpenFigures {
    /// Runs whose true path entered an obstacle.
    pub hits: usize,
    /// The same, in percent of the runs.
    pub hit_percent: f64,
    /// Mean distance of the true end to the true target (mm).
    pub mean_target_error: f64,
    /// 95th percentile (nearest rank) of the same (mm).
    pub p95_target_error: f64,
}

/// What the planner predicted for the plan's open-loop execution, under its model (first order;
/// `planner_core::execute::risk`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PredictedFigures {
    /// Probability that the executed path enters a sphere.
    pub collision_probability: f64,
    /// 95th percentile of the miss (mm).
    pub target_error_p95: f64,
    /// The length of the plan made without the bound (mm; null without a bound): the safe
    /// plan's cost is `plan_length` minus this.
    pub unbounded_length: Option<f64>,
}

/// Closed loop: the same worlds, steered from the tracker's readings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ClosedFigures {
    /// Runs that reached the target: the true path clear and the true tip within the reach
    /// tolerance of the true target (`needle_sim::Outcome::Reached`).
    pub reached: usize,
    /// The same, in percent of the runs.
    pub reached_percent: f64,
    /// Runs the controller let go through whose true tip ended farther than the tolerance.
    pub missed: usize,
    /// Runs whose true path entered an obstacle (never counted as reached or missed).
    pub collided: usize,
    /// Runs the controller stopped before the target (for a reason other than its own
    /// `missed`) whose true path kept clear.
    pub stopped: usize,
    /// Runs the controller did not stop (they end where the steering ends them): reached,
    /// missed, or collided on the way.
    pub arrived: usize,
    /// Runs the controller stopped before the target.
    pub stops: usize,
    /// `stops` by reason (`no_safe_continuation`, `tracking_lost`, `bad_measurement`).
    pub stop_reasons: BTreeMap<&'static str, usize>,
    /// Runs whose true path entered an obstacle (stopped or not).
    pub hits: usize,
    /// Mean target error of the runs that arrived (mm; null when none did).
    pub mean_target_error: Option<f64>,
    /// 95th percentile (nearest rank) of the same (mm; null when none did).
    pub p95_target_error: Option<f64>,
    /// Runs whose target was within reach of any steering, and of those the runs that reached
    /// ([`crate::steering::SteeringSummary::within_reach`]).
    pub within_reach: usize,
    /// Of the runs within reach, those that reached.
    pub reached_within_reach: usize,
}

/// The plan a scenario is steered along: made keeping curvature in hand.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SteeredPlan {
    /// Its form.
    pub form: String,
    /// Its length (mm).
    pub plan_length: f32,
    /// Its smallest clearance to a sphere (mm).
    pub plan_clearance: f32,
    /// The curvature reserve it keeps (the one asked for, or less where no path keeps that).
    pub curvature_reserve: f32,
    /// The collision probability the closed loop's spread predicts for it (first order).
    pub predicted_collision_probability: f64,
}

impl SteeredPlan {
    /// The plan `prepared` of `scenario`, its risk predicted steered (by a controller told
    /// `noise`) under `model`.
    pub fn of(
        scenario: &Scenario,
        prepared: &Prepared,
        model: &Perturbation,
        noise: NoiseModel,
    ) -> SteeredPlan {
        let outcome = &prepared.outcome;
        let mut by_obstacle = [ObstacleRisk::default(); planner_core::MAX_OBSTACLES];
        let steered = Execution::Steered(noise);
        let risk = risk_by_obstacle(
            scenario,
            &prepared.schedule,
            model,
            steered,
            &mut by_obstacle,
        );
        SteeredPlan {
            form: outcome.form.to_string(),
            plan_length: outcome.length,
            plan_clearance: outcome.min_clearance,
            curvature_reserve: scenario.options.curvature_reserve,
            predicted_collision_probability: f64::from(risk.collision_probability),
        }
    }
}

/// One generated scenario, planned and executed.
#[derive(Clone, Debug, Serialize)]
pub struct ScenarioRow {
    /// The generator's seed: `unseen_scenario(seed)`.
    pub seed: u64,
    /// Spheres in the scenario.
    pub spheres: usize,
    /// Distance of the target from the entry (mm).
    pub target_distance: f32,
    /// The planned (best) form, e.g. `RL`.
    pub form: String,
    /// The plan's length (mm).
    pub plan_length: f32,
    /// The plan's smallest clearance to a sphere (mm).
    pub plan_clearance: f32,
    /// Runs, each executed open and closed loop.
    pub runs: usize,
    /// The first world's seed (run k uses it plus k).
    pub world_seed: u64,
    /// What the planner predicted for the open loop.
    pub predicted: PredictedFigures,
    /// Open-loop figures.
    pub open_loop: OpenFigures,
    /// The plan steered closed loop (null with `--open-loop-only` or when refused).
    pub closed_loop_plan: Option<SteeredPlan>,
    /// Why the scenario was not steered (no steered plan keeps the curvature reserve or the
    /// bound); null when it was, or with `--open-loop-only`.
    pub closed_loop_refused: Option<String>,
    /// Closed-loop figures (null with `--open-loop-only`).
    pub closed_loop: Option<ClosedFigures>,
    /// The runs behind the figures (for the totals).
    #[serde(skip)]
    pub pool: Pool,
}

impl ScenarioRow {
    /// The row of scenario `seed` planned as `outcome` and executed as `pool` holds.
    pub fn new(
        seed: u64,
        spheres: usize,
        target_distance: f32,
        outcome: &FormOutcome,
        predicted: PredictedFigures,
        closed_loop_plan: Result<Option<SteeredPlan>, String>,
        pool: Pool,
    ) -> ScenarioRow {
        let (closed_loop_plan, closed_loop_refused) = match closed_loop_plan {
            Ok(plan) => (plan, None),
            Err(reason) => (None, Some(reason)),
        };
        ScenarioRow {
            seed,
            spheres,
            target_distance,
            form: outcome.form.to_string(),
            plan_length: outcome.length,
            plan_clearance: outcome.min_clearance,
            runs: pool.runs,
            world_seed: super::world_seed(seed),
            predicted,
            open_loop: pool.open(),
            closed_loop_plan,
            closed_loop_refused,
            closed_loop: pool.closed(),
            pool,
        }
    }

    /// The row in a few words, for the progress line.
    pub fn progress(&self) -> String {
        let o = &self.open_loop;
        let refused = self.closed_loop_refused.as_ref();
        let closed = self.closed_loop.as_ref().map_or(String::new(), |c| {
            format!(
                "; closed loop {} reached, {} missed, {} stopped, {} hit",
                c.reached, c.missed, c.stops, c.hits
            )
        });
        format!(
            "{} spheres, {} {:.1} mm; open loop {} of {} hit (predicted {:.1} %){closed}{}",
            self.spheres,
            self.form,
            self.plan_length,
            o.hits,
            self.runs,
            100.0 * self.predicted.collision_probability,
            refused.map_or(String::new(), |r| format!("; not steered: {r}"))
        )
    }
}

/// A generated scenario that could not be planned (or its plan not executed).
#[derive(Clone, Debug, Serialize)]
pub struct Unplanned {
    /// The generator's seed.
    pub seed: u64,
    /// Spheres in the scenario.
    pub spheres: usize,
    /// Why, as the planner or the simulator said it.
    pub reason: String,
}

/// The figures over every run of every benchmarked scenario.
#[derive(Clone, Debug, Serialize)]
pub struct Totals {
    /// Scenarios generated.
    pub scenarios: usize,
    /// Scenarios planned and executed (the rows).
    pub planned: usize,
    /// Scenarios that could not be (listed in `unplanned`).
    pub unplanned: usize,
    /// Runs over the rows (each open and closed loop).
    pub runs: usize,
    /// Open-loop figures over every run.
    pub open_loop: OpenFigures,
    /// The predicted open-loop collision rate over every run (the mean of the rows'
    /// predictions, weighted by their runs).
    pub predicted_collision_probability: f64,
    /// Closed-loop figures over every run (null with `--open-loop-only`).
    /// Scenarios planned but refused for steering (their rows say why; their open-loop runs
    /// count).
    pub closed_loop_refused: usize,
    pub closed_loop: Option<ClosedFigures>,
}

/// The figures over the runs of the scenarios planned with one form: open loop by the open-loop
/// plan's form, closed loop by the steered plan's.
#[derive(Clone, Debug, Serialize)]
pub struct FormTotals {
    /// Scenarios whose open-loop plan has the form.
    pub scenarios: usize,
    /// Runs over them.
    pub runs: usize,
    /// Open-loop figures over those runs (null when no open-loop plan has the form).
    pub open_loop: Option<OpenFigures>,
    /// Scenarios whose steered plan has the form.
    pub closed_loop_scenarios: usize,
    /// Closed-loop figures over their runs (null when none).
    pub closed_loop: Option<ClosedFigures>,
}

/// `needle benchmark --json`: `scenarios` (one row per benchmarked scenario), `totals`,
/// `by_form` (the totals of the scenarios planned with each form), `unplanned` and the
/// `perturbation` every world drew from.
#[derive(Clone, Debug, Serialize)]
pub struct BenchmarkReport {
    /// One row per scenario planned and executed, in seed order.
    pub scenarios: Vec<ScenarioRow>,
    /// Over every run of the rows.
    pub totals: Totals,
    /// Over the runs of the rows planned with each form, by form word.
    pub by_form: BTreeMap<String, FormTotals>,
    /// The scenarios that could not be planned or executed, with the reason.
    pub unplanned: Vec<Unplanned>,
    /// The perturbation every world drew from.
    pub perturbation: Perturbation,
    /// The world's effects beyond it (all off: today's world).
    pub world: needle_sim::WorldEffects,
    /// The tracker's faults of the closed loop.
    pub faults: needle_sim::TrackerFaults,
    /// What the closed loop was told.
    pub controller: planner_core::steer::SteerConfig,
    /// The generator of the scenarios.
    pub generator: super::Generator,
}

impl BenchmarkReport {
    /// The report of `generated` scenarios: `rows` benchmarked, `unplanned` not.
    pub fn new(
        generated: usize,
        generator: super::Generator,
        world: &super::BenchWorld,
        rows: Vec<ScenarioRow>,
        unplanned: Vec<Unplanned>,
    ) -> BenchmarkReport {
        let mut all = Pool::default();
        let mut expected_hits = 0.0;
        let mut forms: BTreeMap<String, (usize, usize, Pool)> = BTreeMap::new();
        for row in &rows {
            all.merge(&row.pool);
            expected_hits += row.predicted.collision_probability * row.runs as f64;
            let (open, _, pool) = forms.entry(row.form.clone()).or_default();
            *open += 1;
            pool.merge(&row.pool.open_part());
            if let Some(steered) = &row.closed_loop_plan {
                let (_, closed, pool) = forms.entry(steered.form.clone()).or_default();
                *closed += 1;
                pool.merge(&row.pool.closed_part());
            }
        }
        let by_form = forms
            .into_iter()
            .map(|(form, (scenarios, closed_loop_scenarios, pool))| {
                let totals = FormTotals {
                    scenarios,
                    runs: pool.runs,
                    open_loop: (scenarios > 0).then(|| pool.open()),
                    closed_loop_scenarios,
                    closed_loop: pool.closed(),
                };
                (form, totals)
            })
            .collect();
        BenchmarkReport {
            generator,
            totals: Totals {
                scenarios: generated,
                planned: rows.len(),
                unplanned: unplanned.len(),
                runs: all.runs,
                open_loop: all.open(),
                predicted_collision_probability: expected_hits / all.runs.max(1) as f64,
                closed_loop_refused: rows
                    .iter()
                    .filter(|r| r.closed_loop_refused.is_some())
                    .count(),
                closed_loop: all.closed(),
            },
            by_form,
            scenarios: rows,
            unplanned,
            perturbation: world.perturbation,
            world: world.effects,
            faults: world.faults,
            controller: world.config,
        }
    }
}

#[cfg(test)]
mod tests;
