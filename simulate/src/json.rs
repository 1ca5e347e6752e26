//! The typed JSON of `needle simulate --json`.

use super::setup::Setup;
use super::steering::SteeringSummary;
use super::{Spread, Summary};
use needle_report::schedule::StepJson;
use needle_sim::{ClosedRun, Perturbation, Run, WorldEffects};
use serde::Serialize;
use std::collections::BTreeMap;

/// The insertion every run executes.
#[derive(Clone, Serialize)]
pub struct PlanJson {
    /// The plan's form (`RL`).
    pub form: String,
    /// Its length (mm).
    pub length_mm: f32,
    /// The share of the needle's curvature it leaves for steering.
    pub curvature_reserve: f32,
    /// The share the scenario asked for: more than `curvature_reserve` where no path kept it
    /// (within the collision bound, or at all).
    pub curvature_reserve_asked: f32,
    /// The bound on the predicted collision probability the plan was made under; null when the
    /// scenario opted out (`"off"`: unbounded).
    pub max_collision_probability: Option<f32>,
}

impl PlanJson {
    /// What `setup` executes.
    pub fn of(setup: &Setup) -> PlanJson {
        let outcome = &setup.prepared.outcome;
        PlanJson {
            form: outcome.form.to_string(),
            length_mm: outcome.length,
            curvature_reserve: setup.scenario.options.curvature_reserve,
            curvature_reserve_asked: setup.reserve_asked,
            max_collision_probability: setup.bound.map(|b| b.max_collision_probability),
        }
    }
}

/// The whole output.
#[derive(Serialize)]
pub struct SimulateJson<'a> {
    /// Number of runs.
    pub runs: usize,
    /// False: the schedule is executed open loop (see [`ClosedJson`] for the closed loop).
    pub closed_loop: bool,
    /// The plan executed.
    pub plan: PlanJson,
    /// The perturbation every run drew from.
    pub perturbation: Perturbation,
    /// The world's effects beyond it (every key; all off in the default world).
    pub world: WorldEffects,
    /// Figures over the runs.
    pub summary: SummaryJson,
    /// Per run, with `--detail`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_detail: Option<Vec<RunJson<'a>>>,
}

/// Mean, RMS, 95th percentile and maximum (mm).
#[derive(Serialize)]
pub struct ErrorJson {
    /// Mean.
    pub mean: f64,
    /// Root mean square.
    pub rms: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

/// Deviation from the planned path (mm).
#[derive(Serialize)]
pub struct DeviationJson {
    /// RMS over the runs of each run's RMS over its points (runs have nearly equal point counts).
    pub rms: f64,
    /// Largest over all runs' points.
    pub max: f64,
}

/// The summary.
#[derive(Serialize)]
pub struct SummaryJson {
    /// Distance of the true end to the true target.
    pub target_error: ErrorJson,
    /// Distance of the true path to the planned one.
    pub path_deviation: DeviationJson,
    /// Runs whose true path entered an obstacle.
    pub collisions: usize,
    /// With `[[anatomy]]`: of the collisions, the runs whose true path entered a voxel of a
    /// covered segment, judged against the label map.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entered_voxels: Option<usize>,
    /// Smallest clearance over all runs (mm; null without obstacles).
    pub min_clearance: f32,
    /// Bevel rotations per insertion: `median_per_run`, `max_per_run`, `mean_total_deg`,
    /// `smallest_deg` (each run's own under `rotations` in `runs_detail`).
    pub rotations: super::RotationFigures,
}

/// One run: its figures, draws and points, and the steps as executed.
#[derive(Serialize)]
pub struct RunJson<'a> {
    /// `seed`, `drawn`, `target_error`, `path_rms`, `path_max`, `collided`, `min_clearance`,
    /// `points`.
    #[serde(flatten)]
    pub run: &'a Run,
    /// What the driver executed.
    pub steps: Vec<StepJson>,
}

impl<'a> RunJson<'a> {
    /// One run's record.
    pub fn of(run: &'a Run) -> RunJson<'a> {
        RunJson {
            run,
            steps: run
                .steps
                .iter()
                .map(|st| StepJson::of(&st.op, st.duration_s))
                .collect(),
        }
    }
}

fn error(s: &Spread) -> ErrorJson {
    ErrorJson {
        mean: s.mean,
        rms: s.rms,
        p95: s.p95,
        max: s.max,
    }
}

/// The JSON of the open-loop simulation of `setup`.
pub fn to_json<'a>(
    setup: &Setup,
    runs: &'a [Run],
    summary: &Summary,
    detail: bool,
) -> SimulateJson<'a> {
    SimulateJson {
        runs: runs.len(),
        closed_loop: false,
        plan: PlanJson::of(setup),
        perturbation: setup.perturbation,
        world: setup.effects,
        summary: summary_json(summary),
        runs_detail: detail.then(|| runs.iter().map(RunJson::of).collect()),
    }
}

/// The closed loop's summary: the open-loop figures of the steered runs and the steering's own.
#[derive(Serialize)]
pub struct ClosedSummaryJson {
    /// Target error, path deviation, collisions and clearance of the steered runs.
    #[serde(flatten)]
    pub figures: SummaryJson,
    /// `replans`, `replan_failures`, `stops` (every reason listed), `outliers`, `no_fix`,
    /// `target_outliers`, `target_jumps`, `stale`, `repeated`.
    #[serde(flatten)]
    pub steering: SteeringSummary,
}

/// `needle simulate --closed-loop --json`.
#[derive(Serialize)]
pub struct ClosedJson<'a> {
    /// Number of runs.
    pub runs: usize,
    /// True.
    pub closed_loop: bool,
    /// The plan steered.
    pub plan: PlanJson,
    /// The perturbation every run drew from.
    pub perturbation: Perturbation,
    /// The world's effects beyond it.
    pub world: WorldEffects,
    /// What the controller was told (the `[steering]` keys, from the file, `--steer` and the
    /// defaults): beside `perturbation`, what the world was.
    pub controller: BTreeMap<&'static str, f32>,
    /// Figures over the steered runs.
    pub summary: ClosedSummaryJson,
    /// With --compare-open-loop: the same worlds executed open loop.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub open_loop_summary: Option<SummaryJson>,
    /// Per run, with `--detail`: as open loop, plus `stop_reason` (null when the target was
    /// reached) and the controller's counters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_detail: Option<Vec<ClosedRunJson<'a>>>,
}

/// One steered run.
#[derive(Serialize)]
pub struct ClosedRunJson<'a> {
    /// The open-loop record's keys.
    #[serde(flatten)]
    pub run: RunJson<'a>,
    /// How the run ended, judged on the true tip and path: `reached`, `missed`, `collided` or
    /// `stopped` (`needle_sim::Outcome`). A run whose true path entered an obstacle is
    /// `collided`, whatever the controller concluded.
    pub outcome: &'static str,
    /// The controller's own verdict: `reached` (it let the insertion end at the target as it
    /// estimated it) or its stop reason.
    pub controller_verdict: &'static str,
    /// Why the controller stopped before the target (`no_safe_continuation`, `tracking_lost`,
    /// `bad_measurement`), or `missed` (the steps ran out with the estimate farther than the reach
    /// tolerance from the target), or null: reached.
    pub stop_reason: Option<&'static str>,
    /// The controller's estimate of the miss when it stopped (mm; null without a verdict);
    /// `target_error` is the true miss.
    pub predicted_miss_mm: Option<f32>,
    /// The controller's counters.
    pub steering: planner_core::steer::SteerStats,
}

fn summary_json(summary: &Summary) -> SummaryJson {
    SummaryJson {
        target_error: error(&summary.target_error),
        path_deviation: DeviationJson {
            rms: summary.path_rms.rms,
            max: summary.path_max.max,
        },
        collisions: summary.collisions,
        entered_voxels: summary.entered_voxels,
        min_clearance: summary.min_clearance,
        rotations: summary.rotations,
    }
}

/// The JSON of the closed-loop simulation of `setup`.
pub fn closed_json<'a>(
    setup: &Setup,
    runs: &'a [ClosedRun],
    summary: &Summary,
    steering: &SteeringSummary,
    open: Option<&Summary>,
    detail: bool,
) -> ClosedJson<'a> {
    ClosedJson {
        runs: runs.len(),
        closed_loop: true,
        plan: PlanJson::of(setup),
        perturbation: setup.perturbation,
        world: setup.effects,
        controller: needle_scenario::steering::steering_keys(&setup.config),
        summary: ClosedSummaryJson {
            figures: summary_json(summary),
            steering: steering.clone(),
        },
        open_loop_summary: open.map(summary_json),
        runs_detail: detail.then(|| {
            runs.iter()
                .map(|r| ClosedRunJson {
                    run: RunJson::of(&r.run),
                    outcome: needle_sim::Outcome::of(r, setup.config.reach_tolerance_mm).name(),
                    controller_verdict: needle_sim::controller_verdict(r),
                    stop_reason: r.stop_reason.map(|s| s.name()),
                    predicted_miss_mm: r.predicted_miss_mm,
                    steering: r.stats,
                })
                .collect()
        }),
    }
}
