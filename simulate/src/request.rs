//! A simulation as a library call: a parsed scenario file and what `needle simulate`'s flags
//! say (runs, seed, form, perturbation, tracker faults, what the controller is told) become one
//! [`Setup`], and the runs made become the command's JSON. The command and the Python package
//! both go through here, so they give the same numbers and the same messages.

use super::json::{closed_json, to_json};
use super::setup::Setup;
use super::steering::summarise_steering;
use super::{summarise, PlanBound};
use anyhow::{anyhow, Context, Result};
use needle_scenario::execution::execution_of;
use needle_scenario::{restrict, ObstacleShape, ScenarioFile};
use needle_sim::{ClosedRun, Run, TrackerFaults, WorldEffects, WORLD_KEYS};
use std::path::Path;

/// What a simulation is asked beside the scenario (the flags of `needle simulate`).
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// Simulated insertions, at least 1.
    pub runs: usize,
    /// Seed of the first run (run i uses seed + i).
    pub seed: u64,
    /// Plan and simulate only this form instead of the best.
    pub form: Option<String>,
    /// Changes to the world's perturbation or effects, `KEY=VALUE`.
    pub perturb: Vec<String>,
    /// The named world (`default`, `clinical`) the changes apply over.
    pub world: Option<String>,
    /// Tracker faults, `KEY=VALUE` (closed loop).
    pub faults: Vec<String>,
    /// What the controller is told over the file's `[steering]`, `KEY=VALUE` (closed loop).
    pub steer: Vec<String>,
    /// Steer every run instead of executing the schedule open loop.
    pub closed_loop: bool,
    /// The runs are steered on a device, not in-process.
    pub on_device: bool,
}

/// The runs made: open loop, closed loop, or both (`--compare-open-loop`).
pub struct Results {
    /// The open-loop runs.
    pub open: Option<Vec<Run>>,
    /// The steered runs.
    pub closed: Option<Vec<ClosedRun>>,
}

/// `result` with the message naming the scenario file, when it came from one.
fn in_scenario<T>(result: Result<T>, path: Option<&Path>) -> Result<T> {
    match path {
        Some(p) => result.with_context(|| format!("in scenario {}", p.display())),
        None => result,
    }
}

/// Everything a simulation was asked, checked, before anything is planned.
pub struct Asked {
    /// The scenario (restricted to the form asked for).
    pub scenario: planner_core::Scenario,
    /// Its obstacles as written (for plots).
    pub shapes: Vec<ObstacleShape>,
    /// The world's perturbation.
    pub perturbation: needle_sim::Perturbation,
    /// The world's effects beyond it.
    pub effects: WorldEffects,
    /// The tracker's faults.
    pub faults: TrackerFaults,
    /// What the controller is told.
    pub config: planner_core::steer::SteerConfig,
    /// The collision bound the plan keeps, if the scenario has one.
    pub bound: Option<PlanBound>,
    /// Simulated insertions.
    pub runs: usize,
    /// Seed of the first run.
    pub seed: u64,
}

/// Checks what a simulation is asked, from the parsed scenario `file` (read from `path`, if it
/// was): the errors of its input, none of its planning.
pub fn asked(file: &ScenarioFile, path: Option<&Path>, r: &Request) -> Result<Asked> {
    // The scenario's `[execution]` is the world (the simulator's defaults where it is
    // silent); `--perturb` changes the world, not what the planner was told.
    let execution = in_scenario(execution_of(file), path)?;
    let mut perturbation = execution.model;
    // `--world` replaces the file's world (`[execution]`'s effects and their faults).
    let (mut effects, mut faults) = match &r.world {
        Some(name) => WorldEffects::preset(name).context("--world")?,
        None => (execution.world, execution.faults),
    };
    for kv in &r.perturb {
        change_world(&mut perturbation, &mut effects, kv).context("--perturb")?;
    }
    let bound = execution
        .max_collision_probability
        .map(|max_collision_probability| PlanBound {
            model: execution.model,
            max_collision_probability,
            execution: execution.predicted_as(),
        });
    for kv in &r.faults {
        faults.apply(kv).map_err(|e| anyhow!("--fault: {e}"))?;
    }
    anyhow::ensure!(r.runs >= 1, "--runs must be at least 1");
    anyhow::ensure!(
        r.runs <= super::options::MAX_RUNS,
        "--runs is {}: at most {} runs are simulated at once",
        r.runs,
        super::options::MAX_RUNS
    );
    let shapes = in_scenario(file.obstacle_shapes(None), path)?;
    let mut scenario = in_scenario(file.to_scenario_with(&shapes), path)?;
    if let Some(f) = &r.form {
        restrict(&mut scenario, None, Some(std::slice::from_ref(f)))?;
    }
    perturbation.validate()?;
    // The controller is told what `[steering]` and `--steer` say, whatever the world
    // (`--perturb`) is.
    let mut config = execution.steering;
    for kv in &r.steer {
        needle_scenario::steering::apply(&mut config, kv).context("--steer")?;
    }
    Ok(Asked {
        scenario,
        shapes,
        perturbation,
        effects,
        faults,
        config,
        bound,
        runs: r.runs,
        seed: r.seed,
    })
}

impl Asked {
    /// Plans the scenario (under the bound, keeping what curvature reserve it can) and sets up
    /// the worlds.
    pub fn set_up(self) -> Result<(Setup, Vec<ObstacleShape>)> {
        let bound = self.bound.as_ref();
        let (p, faults) = (self.perturbation, self.faults);
        let mut setup = Setup::bounded(self.scenario, p, faults, self.runs, self.seed, bound)?;
        setup.config = self.config;
        setup.effects = self.effects;
        Ok((setup, self.shapes))
    }
}

/// Applies one `KEY=VALUE` of `--perturb`: a world effect's key to the effects, any other to
/// the perturbation (an unknown key is refused naming both lists).
pub(crate) fn change_world(
    perturbation: &mut needle_sim::Perturbation,
    effects: &mut WorldEffects,
    kv: &str,
) -> Result<()> {
    let key = kv.split_once('=').map(|(k, _)| k.trim());
    if key.is_some_and(WorldEffects::knows) {
        return Ok(effects.apply(kv)?);
    }
    perturbation.apply(kv).map_err(|e| match e {
        needle_sim::PerturbError::UnknownKey(_) => {
            let keys = WORLD_KEYS.join(", ");
            anyhow!(
                "{e}; or a world effect: {keys}, {}",
                needle_sim::LAYER_DEPTHS_KEY
            )
        }
        e => anyhow!(e),
    })
}

/// [`asked`], then [`Asked::set_up`].
pub fn set_up(
    file: &ScenarioFile,
    path: Option<&Path>,
    r: &Request,
) -> Result<(Setup, Vec<ObstacleShape>)> {
    let (mut setup, shapes) = asked(file, path, r)?.set_up()?;
    setup.voxels = in_scenario(file.voxel_judge(), path)?.map(std::sync::Arc::new);
    Ok((setup, shapes))
}

/// The `needle simulate --json` object of the runs made (`detail`: every run's record).
pub fn results_json(setup: &Setup, results: &Results, detail: bool) -> Result<String> {
    Ok(match (&results.closed, &results.open) {
        (Some(closed), open) => {
            let open = open.as_deref().map(summarise);
            let summary = summarise(closed.iter().map(|c| &c.run));
            let steering = summarise_steering(closed, setup.config.reach_tolerance_mm);
            let j = closed_json(setup, closed, &summary, &steering, open.as_ref(), detail);
            serde_json::to_string(&j)?
        }
        (None, Some(runs)) => {
            let summary = summarise(runs);
            serde_json::to_string(&to_json(setup, runs, &summary, detail))?
        }
        (None, None) => return Err(anyhow!("no run was made")),
    })
}
