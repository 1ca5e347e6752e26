//! The typed JSON of `needle simulate --json`.

use super::{Spread, Summary};
use crate::report::schedule::StepJson;
use hil_sim::insertion::{Perturbation, Run};
use serde::Serialize;

/// The whole output.
#[derive(Serialize)]
pub struct SimulateJson<'a> {
    /// Number of runs.
    pub runs: usize,
    /// Always false: the schedule is executed open loop.
    pub closed_loop: bool,
    /// The perturbation every run drew from.
    pub perturbation: Perturbation,
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
    /// Smallest clearance over all runs (mm; null without obstacles).
    pub min_clearance: f32,
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

/// The JSON of a simulation.
pub fn to_json<'a>(
    p: &Perturbation,
    runs: &'a [Run],
    summary: &Summary,
    detail: bool,
) -> SimulateJson<'a> {
    SimulateJson {
        runs: runs.len(),
        closed_loop: false,
        perturbation: *p,
        summary: SummaryJson {
            target_error: error(&summary.target_error),
            path_deviation: DeviationJson {
                rms: summary.path_rms.rms,
                max: summary.path_max.max,
            },
            collisions: summary.collisions,
            min_clearance: summary.min_clearance,
        },
        runs_detail: detail.then(|| runs.iter().map(RunJson::of).collect()),
    }
}
