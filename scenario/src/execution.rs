//! The scenario's `[execution]` table and `planner.max_collision_probability`: the world the
//! plan will be executed in (the perturbation model `needle simulate` runs, same keys, same
//! defaults and floors: one definition, `planner_core::execute::perturbation`) and the bound on
//! the predicted probability of collision the plan must keep. The table also takes the
//! simulated world's effects (`world = "clinical"` and the keys of `needle_sim::WorldEffects`),
//! which only the simulator sees: the planner is never told them.

use super::file::ScenarioFile;
use anyhow::{anyhow, bail, Context, Result};
use needle_sim::{LayerDepths, TrackerFaults, WorldEffects, LAYER_DEPTHS_KEY};
use planner_core::execute::perturbation::Perturbation;
use planner_core::execute::risk;
use planner_core::steer::SteerConfig;
use std::path::Path;

/// The curvature reserve (`planner.curvature_reserve`) of a scenario whose `execution.mode` is
/// `"closed_loop"` and that says nothing of it, and of the plans `needle benchmark` steers: the
/// share of the needle's curvature kept for the controller. Measured on the unseen scenarios
/// (docs/execution.md, "Curvature in hand"): a tissue that bends less than the plan assumed
/// otherwise leaves a target no path reaches.
pub const CLOSED_LOOP_CURVATURE_RESERVE: f32 = 0.2;

/// `planner.max_collision_probability` where the scenario says nothing of it: a plan is made
/// to be executed, and one that enters an obstacle in more than 1 % of executions is refused
/// unless the file opts out with `"off"` (the bound the examples set up for a lab use).
pub const DEFAULT_MAX_COLLISION_PROBABILITY: f32 = 0.01;

/// The value of `planner.max_collision_probability` that opts out of the bound.
pub const UNBOUNDED: &str = "off";

/// How the plan will be executed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExecutionMode {
    /// The schedule as planned, no tracker in the loop.
    OpenLoop,
    /// Steered from the tracker's readings.
    ClosedLoop,
}

impl ExecutionMode {
    /// The name in the scenario file.
    pub fn name(self) -> &'static str {
        match self {
            ExecutionMode::OpenLoop => "open_loop",
            ExecutionMode::ClosedLoop => "closed_loop",
        }
    }
}

/// What a scenario says about its execution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Execution {
    /// The perturbation model (the simulator's defaults where the table is silent).
    pub model: Perturbation,
    /// `execution.mode`, default closed loop: what a lab executes.
    pub mode: ExecutionMode,
    /// `planner.max_collision_probability`: [`DEFAULT_MAX_COLLISION_PROBABILITY`] unless the
    /// file gives another, `None` when it says `"off"`.
    pub max_collision_probability: Option<f32>,
    /// What the closed-loop controller is told (`[steering]`; its defaults where silent): the
    /// steering's estimator noise model also predicts the closed loop's spread.
    pub steering: SteerConfig,
    /// The simulated world's effects (`execution.world` and the effects' keys; all off where
    /// silent). The simulator's only: the planner never sees them.
    pub world: WorldEffects,
    /// The tracker faults of `execution.world` (the clinical world's dropouts).
    pub faults: TrackerFaults,
}

impl Default for Execution {
    fn default() -> Self {
        Execution {
            model: Perturbation::default(),
            mode: ExecutionMode::ClosedLoop,
            max_collision_probability: Some(DEFAULT_MAX_COLLISION_PROBABILITY),
            steering: super::steering::ASSUMED_STEERING,
            world: WorldEffects::default(),
            faults: TrackerFaults::default(),
        }
    }
}

impl Execution {
    /// What a device is told to plan under the collision bound, if the scenario has one.
    pub fn chance_request(&self) -> Option<planner_core::wire::ChanceRequest> {
        self.max_collision_probability
            .map(|bound| planner_core::wire::ChanceRequest {
                bound,
                model: self.model,
                execution: self.predicted_as(),
            })
    }

    /// How the planner predicts the spread: open loop, or the closed loop's (the steering's own
    /// estimator noise model, as `[steering]` tells it, never the world's).
    pub fn predicted_as(&self) -> risk::Execution {
        match self.mode {
            ExecutionMode::OpenLoop => risk::Execution::OpenLoop,
            ExecutionMode::ClosedLoop => risk::Execution::Steered(self.steering.noise),
        }
    }
}

/// The execution of a parsed scenario file.
pub fn execution_of(file: &ScenarioFile) -> Result<Execution> {
    let mut out = Execution {
        steering: super::steering::steering_of(file)?,
        ..Execution::default()
    };
    if let Some(table) = &file.execution {
        // The named world first, wherever it stands: its keys are changed by the others.
        if let Some(name) = table.get("world") {
            let name = name.as_str().with_context(|| {
                format!("execution.world is `{name}`: allowed are \"default\" and \"clinical\"")
            })?;
            (out.world, out.faults) =
                WorldEffects::preset(name).map_err(|e| anyhow!("execution.world: {e}"))?;
        }
        for (key, value) in table {
            if key == "world" || key == LAYER_DEPTHS_KEY {
                continue;
            }
            if key == "mode" {
                out.mode = match value.as_str() {
                    Some("open_loop") => ExecutionMode::OpenLoop,
                    Some("closed_loop") => ExecutionMode::ClosedLoop,
                    _ => bail!("execution.mode is `{value}`: allowed are \"open_loop\" and \"closed_loop\""),
                };
                continue;
            }
            let number = value
                .as_float()
                .or_else(|| value.as_integer().map(|i| i as f64))
                .with_context(|| format!("execution.{key} is `{value}`, not a number"))?;
            if WorldEffects::knows(key) {
                out.world
                    .set(key, number as f32)
                    .map_err(|e| anyhow!("execution.{e}"))?;
                continue;
            }
            out.model
                .set(key, number as f32)
                .map_err(|e| anyhow!("execution.{e}"))?;
        }
        // Last: given boundaries set `layers` to their count, whatever it said.
        if let Some(value) = table.get(LAYER_DEPTHS_KEY) {
            out.world.set_depths(depths_of(value)?);
        }
    }
    out.max_collision_probability = bound_of(file)?;
    Ok(out)
}

/// `planner.max_collision_probability`: [`DEFAULT_MAX_COLLISION_PROBABILITY`] where the file is
/// silent, `None` for `"off"`.
fn bound_of(file: &ScenarioFile) -> Result<Option<f32>> {
    let value = file
        .planner
        .as_ref()
        .and_then(|p| p.max_collision_probability.as_ref());
    let Some(value) = value else {
        return Ok(Some(DEFAULT_MAX_COLLISION_PROBABILITY));
    };
    if value.as_str() == Some(UNBOUNDED) {
        return Ok(None);
    }
    let bound = value
        .as_float()
        .or_else(|| value.as_integer().map(|i| i as f64))
        .with_context(|| {
            format!(
                "planner.max_collision_probability is `{value}`: allowed is a probability \
                 (more than 0, less than 1) or \"off\""
            )
        })? as f32;
    if !(bound > 0.0 && bound < 1.0) {
        bail!(
            "planner.max_collision_probability = {bound}: allowed is more than 0 and less than 1, \
             or \"off\""
        );
    }
    Ok(Some(bound))
}

/// `execution.layer_depths_mm = [12, 30, 55]`.
fn depths_of(value: &toml::Value) -> Result<LayerDepths> {
    let not_a_list = || anyhow!("execution.{LAYER_DEPTHS_KEY} is `{value}`, not a list of numbers");
    let depths: Option<Vec<f32>> = value
        .as_array()
        .ok_or_else(not_a_list)?
        .iter()
        .map(|v| {
            v.as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .map(|d| d as f32)
        })
        .collect();
    LayerDepths::new(&depths.ok_or_else(not_a_list)?).map_err(|e| anyhow!("execution.{e}"))
}

/// The execution of the scenario file at `path`.
pub fn load_execution(path: &Path) -> Result<Execution> {
    let file = ScenarioFile::load(path)?;
    execution_of(&file).with_context(|| format!("in scenario {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(extra: &str) -> Result<Execution> {
        execution_of(&super::super::file::minimal_with(extra)?)
    }

    #[test]
    fn the_table_sets_the_simulators_keys_and_the_bound() {
        let e = parse("").unwrap();
        assert_eq!(e, Execution::default());
        let e = parse("[execution]\ncurvature_spread = 0.05\ninsertion_error_mm = 1\n").unwrap();
        assert_eq!(e.mode, ExecutionMode::ClosedLoop);
        assert_eq!(e.model.curvature_spread, 0.05);
        assert_eq!(e.model.insertion_error_mm, 1.0);
        assert_eq!(
            e.model.entry_position_mm,
            Perturbation::default().entry_position_mm
        );
        let e = parse("[planner]\nmax_collision_probability = 0.05\n").unwrap();
        assert_eq!(e.max_collision_probability, Some(0.05));
    }

    /// A file that says nothing is planned for what a lab does with it: steered closed loop,
    /// under a 1 % bound, told a real tracker and real tissue; opting out is explicit.
    #[test]
    fn a_silent_file_is_planned_safe_and_opting_out_is_explicit() {
        let e = parse("").unwrap();
        assert_eq!(e.mode, ExecutionMode::ClosedLoop);
        assert_eq!(e.max_collision_probability, Some(0.01));
        assert_eq!(e.steering, crate::steering::ASSUMED_STEERING);
        assert!(e.steering.noise.registration_mm > 0.0);
        let off = parse("[planner]\nmax_collision_probability = \"off\"\n").unwrap();
        assert_eq!(off.max_collision_probability, None);
        let open = parse("[execution]\nmode = \"open_loop\"\n").unwrap();
        assert_eq!(open.mode, ExecutionMode::OpenLoop);
        assert_eq!(
            open.max_collision_probability,
            Some(0.01),
            "the bound stays"
        );
        for (extra, says) in [
            (
                "\"none\"",
                "allowed is a probability (more than 0, less than 1) or \"off\"",
            ),
            ("0", "allowed is more than 0 and less than 1, or \"off\""),
            ("true", "is `true`"),
        ] {
            let text = format!("[planner]\nmax_collision_probability = {extra}\n");
            let e = format!("{:#}", parse(&text).unwrap_err());
            assert!(e.contains(says), "{extra}: {e}");
        }
    }

    #[test]
    fn bad_values_name_the_key() {
        for (extra, says) in [
            (
                "[execution]\ncurvature = 0.1\n",
                "unknown perturbation `curvature`",
            ),
            (
                "[execution]\ncurvature_spread = -1\n",
                "curvature_spread = -1 is outside",
            ),
            (
                "[execution]\ncurvature_spread = \"x\"\n",
                "execution.curvature_spread is `\"x\"`",
            ),
            (
                "[execution]\nmode = \"fast\"\n",
                "execution.mode is `\"fast\"`",
            ),
            (
                "[planner]\nmax_collision_probability = 1.5\n",
                "max_collision_probability = 1.5",
            ),
        ] {
            let e = format!("{:#}", parse(extra).unwrap_err());
            assert!(e.contains(says), "{extra}: {e}");
        }
    }

    /// The world's effects: a named world, its keys changed by the others; the planner's model
    /// untouched; bad names and values named.
    #[test]
    fn the_table_sets_the_worlds_effects_apart_from_the_model() {
        let e = parse("[execution]\nlayers = 3\nworld = \"clinical\"\ntracker_dof = 6\n").unwrap();
        assert_eq!(e.model, Perturbation::default());
        assert_eq!(e.world.layers, 3);
        assert_eq!(e.world.tracker_dof, 6);
        assert_eq!(e.world.tracker_latency_ms, 30.0, "the rest is clinical");
        assert_eq!(e.faults, WorldEffects::clinical_faults());
        assert_eq!(
            parse("[execution]\nlayers = 2\n").unwrap().faults,
            TrackerFaults::default()
        );
        let given = parse("[execution]\nlayers = 1\nlayer_depths_mm = [5, 40.5]\n").unwrap();
        assert_eq!(given.world.layers, 2);
        assert_eq!(given.world.layer_depths_mm.unwrap().as_slice(), [5.0, 40.5]);
        for (extra, says) in [
            (
                "[execution]\nlayers = 9\n",
                "execution.layers = 9 is outside [0, 8]",
            ),
            (
                "[execution]\nworld = \"lab\"\n",
                "execution.world: unknown world `lab`",
            ),
            ("[execution]\nworld = 3\n", "execution.world is `3`"),
            (
                "[execution]\nlayer_depths_mm = 3\n",
                "not a list of numbers",
            ),
            (
                "[execution]\nlayer_depths_mm = [9, 2]\n",
                "execution.layer_depths_mm: the depths must ascend",
            ),
        ] {
            let e = format!("{:#}", parse(extra).unwrap_err());
            assert!(e.contains(says), "{extra}: {e}");
        }
    }

    /// A bound with the closed loop is predicted with the steering's own noise model.
    #[test]
    fn a_closed_loop_bound_is_predicted_steered() {
        let e = parse(
            "[execution]\nmode = \"closed_loop\"\n[planner]\nmax_collision_probability = 0.01\n",
        )
        .unwrap();
        assert_eq!(e.max_collision_probability, Some(0.01));
        let assumed = crate::steering::ASSUMED_STEERING;
        assert_eq!(e.predicted_as(), risk::Execution::Steered(assumed.noise));
        let open = parse("[execution]\nmode = \"open_loop\"\n").unwrap();
        assert_eq!(open.predicted_as(), risk::Execution::OpenLoop);
        let told =
            parse("[execution]\nmode = \"closed_loop\"\n[steering]\ntracker_position_mm = 1.5\n")
                .unwrap();
        let mut noise = assumed.noise;
        noise.position_mm = 1.5;
        assert_eq!(told.predicted_as(), risk::Execution::Steered(noise));
        assert_eq!(told.steering.noise, noise);
    }

    /// A scenario steered closed loop (the default) keeps curvature in hand unless it says
    /// otherwise; one executed open loop plans at the full curvature; a reserve out of range
    /// names its key.
    #[test]
    fn the_closed_loop_keeps_curvature_in_hand_by_default() {
        let scenario = |extra: &str| super::super::file::minimal_with(extra)?.to_scenario();
        let reserve = |extra: &str| scenario(extra).unwrap().options.curvature_reserve;
        assert_eq!(reserve(""), CLOSED_LOOP_CURVATURE_RESERVE);
        assert_eq!(reserve("[execution]\nmode = \"open_loop\"\n"), 0.0);
        let closed = "[execution]\nmode = \"closed_loop\"\n";
        assert_eq!(reserve(closed), CLOSED_LOOP_CURVATURE_RESERVE);
        let given = format!("{closed}[planner]\ncurvature_reserve = 0.05\n");
        assert_eq!(reserve(&given), 0.05);
        let e = scenario("[planner]\ncurvature_reserve = 0.7\n").unwrap_err();
        assert!(
            format!("{e:#}").contains("planner.curvature_reserve"),
            "{e:#}"
        );
    }
}
