//! `needle benchmark`: the planner and its execution on scenarios nobody tuned on. Scenario `i`
//! is [`unseen_scenario`]`(seed + i)`; its best plan is executed in `--runs` simulated worlds
//! open loop, and the same worlds closed loop, exactly as `needle simulate --closed-loop
//! --compare-open-loop` does (the same [`Setup`]); one row per scenario, the totals over every
//! run, and the scenarios that could not be planned or executed, each with its reason.
//! Simulated figures, always called so.

mod figures;
mod table;
mod world;

pub use world::BenchWorld;

pub use figures::{
    BenchmarkReport, ClosedFigures, OpenFigures, Pool, PredictedFigures, ScenarioRow, Totals,
};
pub use figures::{FormTotals, SteeredPlan, Unplanned, WORLD_SEED_STRIDE};

use crate::setup::{Keep, Setup};
use crate::PlanBound;
use anyhow::{Context, Result};
use needle_analysis::commands::output::progress;
use needle_analysis::parallel;
use needle_scenario::execution::CLOSED_LOOP_CURVATURE_RESERVE;
use needle_scenario::planted::planted_scenario;
use needle_scenario::unseen::unseen_scenario;
use needle_scenario::write::scenario_toml;
use needle_sim::Perturbation;
use planner_core::execute::risk::{execution_risk, Execution};
use planner_core::Scenario;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `needle benchmark` is asked (the `needle` binary reads it from its flags).
#[derive(Clone, Debug)]
pub struct BenchmarkOptions {
    /// Generated scenarios, 1 to [`crate::MAX_SCENARIOS`] (seeds `seed`, `seed` + 1, ...).
    pub scenarios: usize,
    /// Seed of the first scenario.
    pub seed: u64,
    /// Simulated insertions per scenario: each open loop, and the same worlds closed loop.
    pub runs: usize,
    /// Threads, at least 1 (`None`: every core).
    pub threads: Option<usize>,
    /// Print one JSON object instead of the table.
    pub json: bool,
    /// Changes to the world's perturbation or effects, `KEY=VALUE`, over `world`.
    pub perturb: Vec<String>,
    /// The named world every run is made in (`default`, `clinical`).
    pub world: Option<String>,
    /// Tracker faults of the closed loop, `KEY=VALUE`, over `world`'s.
    pub faults: Vec<String>,
    /// What the closed-loop controller is told, `KEY=VALUE` of `[steering]`: it steers with it,
    /// and a steered bound predicts its spread with it.
    pub steer: Vec<String>,
    /// Also write each generated scenario into this folder.
    pub write_scenarios: Option<PathBuf>,
    /// Plan every scenario under this bound on the predicted collision probability (the
    /// simulator's default model); a scenario no plan meets it for is counted with that reason.
    pub max_collision_probability: Option<f32>,
    /// Plan the scenarios steered closed loop under this bound on the collision probability the
    /// closed loop's spread predicts; a scenario no steered plan meets it for is counted with
    /// that reason (its open-loop runs stay).
    pub closed_loop_max_collision_probability: Option<f32>,
    /// Execute open loop only (no closed-loop runs; their figures are null).
    pub open_loop_only: bool,
    /// The curvature reserve of the plans steered closed loop (halved where no path keeps it,
    /// down to none).
    pub curvature_reserve: f32,
    /// Which generator draws the scenarios.
    pub generator: Generator,
}

impl Default for BenchmarkOptions {
    /// The command's defaults.
    fn default() -> Self {
        BenchmarkOptions {
            scenarios: 20,
            seed: 101,
            runs: 40,
            threads: None,
            json: false,
            perturb: Vec::new(),
            world: None,
            faults: Vec::new(),
            steer: Vec::new(),
            write_scenarios: None,
            max_collision_probability: None,
            closed_loop_max_collision_probability: None,
            open_loop_only: false,
            curvature_reserve: CLOSED_LOOP_CURVATURE_RESERVE,
            generator: Generator::Unseen,
        }
    }
}

/// The seeded families `needle benchmark` draws from (docs/execution.md, "Unseen scenarios").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Generator {
    /// [`unseen_scenario`].
    Unseen,
    /// [`planted_scenario`].
    Planted,
}

impl Generator {
    /// Every family, in the order `needle benchmark --help` lists them.
    pub const ALL: [Generator; 2] = [Generator::Unseen, Generator::Planted];

    /// The scenario of `seed`.
    pub fn scenario(self, seed: u64) -> Scenario {
        match self {
            Generator::Unseen => unseen_scenario(seed),
            Generator::Planted => planted_scenario(seed),
        }
    }

    /// The family's name, as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Generator::Unseen => "unseen",
            Generator::Planted => "planted",
        }
    }
}

/// A family by its name (any case).
impl std::str::FromStr for Generator {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Generator> {
        Generator::ALL
            .into_iter()
            .find(|g| g.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| anyhow::anyhow!("generator {s:?}: use unseen or planted"))
    }
}

/// The seed of the first world of scenario `seed`: worlds of different scenarios never share a
/// seed (up to [`WORLD_SEED_STRIDE`] runs a scenario), so no two scenarios draw the same
/// perturbations.
pub fn world_seed(scenario_seed: u64) -> u64 {
    scenario_seed.wrapping_mul(WORLD_SEED_STRIDE)
}

/// Runs `needle benchmark`.
pub fn run_benchmark(a: &BenchmarkOptions) -> Result<()> {
    let world = BenchWorld::of(a.world.as_deref(), &a.perturb, &a.faults, &a.steer)?;
    if let Some(dir) = &a.write_scenarios {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let threads = a.threads.unwrap_or_else(parallel::default_threads);
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        progress(a.scenarios, "benchmark")
    };
    let mut rows = Vec::new();
    let mut unplanned = Vec::new();
    for i in 0..a.scenarios {
        let seed = a.seed.wrapping_add(i as u64);
        let scenario = a.generator.scenario(seed);
        if let Some(dir) = &a.write_scenarios {
            write_scenario(dir, a.generator, seed, &scenario)?;
        }
        let started = Instant::now();
        let spheres = scenario.obstacles.len();
        let head = format!("scenario {}/{} (seed {seed})", i + 1, a.scenarios);
        match measure(scenario, &world, a, seed, threads) {
            Ok(row) => {
                let secs = started.elapsed().as_secs_f64();
                bar.println(format!("{head}: {}, {secs:.1} s", row.progress()));
                rows.push(row);
            }
            Err(e) => {
                let reason = format!("{e:#}");
                bar.println(format!("{head}: not benchmarked: {reason}"));
                unplanned.push(Unplanned {
                    seed,
                    spheres,
                    reason,
                });
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let report = BenchmarkReport::new(a.scenarios, a.generator, &world, rows, unplanned);
    let text = if a.json {
        serde_json::to_string(&report)? + "\n"
    } else {
        table::to_table(a, &report)
    };
    write!(std::io::stdout(), "{text}")?;
    Ok(())
}

/// Writes `scenario` to `dir/GENERATOR-SEED.toml`.
fn write_scenario(dir: &Path, generator: Generator, seed: u64, scenario: &Scenario) -> Result<()> {
    let name = format!("{}-{seed}", generator.name());
    let path = dir.join(format!("{name}.toml"));
    let header = format!(
        "A generated 3-D scenario: needle_scenario::{0}::{0}_scenario({seed}),\n\
         written by `needle benchmark` (see docs/simulation.md, \"Unseen scenarios\").",
        generator.name()
    );
    std::fs::write(&path, scenario_toml(scenario, &name, &header))
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Plans `scenario` (its best form), executes it in `runs` worlds open loop and the same worlds
/// closed loop, and keeps the figures of each run (not their paths).
fn measure(
    scenario: Scenario,
    world: &BenchWorld,
    a: &BenchmarkOptions,
    seed: u64,
    threads: usize,
) -> Result<ScenarioRow> {
    let model = Perturbation::default();
    let bound = a
        .max_collision_probability
        .map(|max_collision_probability| PlanBound {
            model,
            max_collision_probability,
            execution: Execution::OpenLoop,
        });
    let spheres = scenario.obstacles.len();
    let (entry, target) = (scenario.entry.position, scenario.target.position);
    let target_distance = (0..3)
        .map(|k| (target[k] - entry[k]).powi(2))
        .sum::<f32>()
        .sqrt();
    let unbounded_length = bound.map(|_| {
        planner_core::plan(&scenario)
            .ok()
            .and_then(|r| r.best().map(|b| f64::from(b.length)))
            .unwrap_or(f64::NAN)
    });
    let mut steered = scenario.clone();
    let p = world.perturbation;
    let mut setup = Setup::bounded(
        scenario,
        p,
        world.faults,
        a.runs,
        world_seed(seed),
        bound.as_ref(),
    )?;
    setup.effects = world.effects;
    let risk = execution_risk(&setup.scenario, &setup.prepared.schedule, &model);
    let predicted = PredictedFigures {
        collision_probability: f64::from(risk.collision_probability),
        target_error_p95: f64::from(risk.target_error_p95),
        unbounded_length,
    };
    let keep = Keep::default();
    let open = setup.open_loop(&keep, threads, || {})?;
    let (closed, closed_plan) = if a.open_loop_only {
        (Vec::new(), Ok(None))
    } else {
        steered.options.curvature_reserve = a.curvature_reserve;
        let bound = a
            .closed_loop_max_collision_probability
            .map(|max_collision_probability| PlanBound {
                model,
                max_collision_probability,
                execution: Execution::Steered(world.config.noise),
            });
        let seed = world_seed(seed);
        // A scenario refused for steering keeps its open-loop runs.
        match Setup::bounded(steered, p, world.faults, a.runs, seed, bound.as_ref()) {
            Ok(mut setup) => {
                setup.effects = world.effects;
                setup.config = world.config;
                let plan =
                    SteeredPlan::of(&setup.scenario, &setup.prepared, &model, world.config.noise);
                (setup.closed_loop(&keep, threads, || {})?, Ok(Some(plan)))
            }
            Err(e) => (Vec::new(), Err(format!("{e:#}"))),
        }
    };
    let outcome = &setup.prepared.outcome;
    Ok(ScenarioRow::new(
        seed,
        spheres,
        target_distance,
        outcome,
        predicted,
        closed_plan,
        Pool::of(&open, &closed, world.config.reach_tolerance_mm),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use needle_scenario::parse_form;

    /// A scenario with no feasible plan is reported with its reason, not a panic; the table
    /// lists it and the totals count it.
    /// The command's defaults for `scenarios` scenarios from `seed`, `runs` worlds each.
    fn args(scenarios: usize, seed: u64, runs: usize) -> BenchmarkOptions {
        BenchmarkOptions {
            scenarios,
            seed,
            runs,
            ..BenchmarkOptions::default()
        }
    }

    /// Keeping curvature in hand is what lets the controller reach the target when the tissue
    /// bends less than the plan assumed: on a scenario planned as one arc, steering the plan
    /// made at the needle's full curvature ends most runs `missed`, the reserved one reaches
    /// the target in every run (both over the same worlds).
    #[test]
    fn the_curvature_reserve_gives_the_closed_loop_its_reach() {
        let p = BenchWorld::of(None, &[], &[], &[]).unwrap();
        let args = |curvature_reserve| BenchmarkOptions {
            curvature_reserve,
            ..args(1, 111, 20)
        };
        let reached = |reserve| {
            let row = measure(unseen_scenario(111), &p, &args(reserve), 111, 2).unwrap();
            let plan = row.closed_loop_plan.clone().unwrap();
            assert_eq!((plan.form.as_str(), plan.curvature_reserve), ("R", reserve));
            row.closed_loop.unwrap().reached
        };
        let (full, reserved) = (reached(0.0), reached(0.2));
        assert!(full <= 10 && reserved == 20, "{full} {reserved}");
        // A target only the needle's full bend reaches is refused for steering, with why; its
        // open-loop runs stay.
        let row = measure(unseen_scenario(229), &p, &args(0.2), 229, 2).unwrap();
        let why = row.closed_loop_refused.clone().unwrap_or_default();
        assert!(
            why.contains("no path keeps a curvature reserve of 0.1"),
            "{why}"
        );
        assert!(row.closed_loop.is_none() && row.closed_loop_plan.is_none());
        assert_eq!((row.runs, row.pool.open_errors.len()), (20, 20));
    }

    /// The closed loop's spread moves the steered plan where the unbounded one would have it
    /// graze a sphere (seed 201: an RL plan 0.37 mm from one, predicted 30 % steered); under a
    /// 1 % bound the plan keeps it, and the same worlds steered along it hit nothing.
    #[test]
    fn a_steered_bound_keeps_the_closed_loop_off_the_spheres() {
        let p = BenchWorld::of(None, &[], &[], &[]).unwrap();
        let free = measure(unseen_scenario(201), &p, &args(1, 201, 10), 201, 2).unwrap();
        let bounded_args = BenchmarkOptions {
            closed_loop_max_collision_probability: Some(0.01),
            ..args(1, 201, 10)
        };
        let bounded = measure(unseen_scenario(201), &p, &bounded_args, 201, 2).unwrap();
        let predicted = |r: &ScenarioRow| {
            r.closed_loop_plan
                .as_ref()
                .unwrap()
                .predicted_collision_probability
        };
        assert!(predicted(&free) > 0.05, "{}", predicted(&free));
        assert!(predicted(&bounded) <= 0.01, "{}", predicted(&bounded));
        let closed = bounded.closed_loop.unwrap();
        assert_eq!((closed.hits, closed.reached), (0, 10), "{closed:?}");
        // The open loop is planned as before: the steered bound is the closed loop's alone.
        assert_eq!(free.form, bounded.form);
        assert_eq!(free.open_loop.hits, bounded.open_loop.hits);
    }

    /// `--world`, `--fault` and `--steer` reach every run: the clinical world's layers and
    /// pushed target move the open loop's ends; the steered bound is predicted with what the
    /// controller is told (a registration error it keeps clear of moves the plan), and
    /// the report says the world, the faults and the told controller.
    #[test]
    fn the_world_and_the_told_controller_reach_every_run() {
        let bounded = BenchmarkOptions {
            closed_loop_max_collision_probability: Some(0.01),
            ..args(1, 204, 4)
        };
        let today = BenchWorld::of(None, &[], &[], &[]).unwrap();
        let told = ["registration_mm=0.6".to_string()];
        let clinical = BenchWorld::of(Some("clinical"), &[], &[], &told).unwrap();
        let a = measure(planted_scenario(204), &today, &bounded, 204, 2).unwrap();
        let b = measure(planted_scenario(204), &clinical, &bounded, 204, 2).unwrap();
        assert_ne!(a.open_loop.mean_target_error, b.open_loop.mean_target_error);
        let plan = |r: &ScenarioRow| {
            let p = r.closed_loop_plan.clone().unwrap();
            (p.plan_length, p.plan_clearance)
        };
        assert_ne!(
            plan(&a),
            plan(&b),
            "the told registration moves the steered plan"
        );
        let report = BenchmarkReport::new(1, Generator::Planted, &clinical, vec![b], vec![]);
        let json: serde_json::Value = serde_json::to_value(&report).unwrap();
        assert_eq!(json["world"]["tracker_dof"], 5);
        assert_eq!(json["faults"]["dropout_mm"], 2.0);
        let told = json["controller"]["noise"]["registration_mm"]
            .as_f64()
            .unwrap();
        assert!((told - 0.6).abs() < 1e-6);
    }

    #[test]
    fn a_scenario_that_cannot_be_planned_is_counted_with_its_reason() {
        let mut s = unseen_scenario(101);
        // The first sphere blocks the straight line, the one path a single line can take.
        s.options.forms.insert(parse_form("L").unwrap());
        let p = BenchWorld::of(None, &[], &[], &[]).unwrap();
        let args = args(2, 101, 2);
        let reason = format!("{:#}", measure(s.clone(), &p, &args, 101, 1).unwrap_err());
        assert!(
            reason.contains("planning") || reason.contains("reach"),
            "{reason}"
        );
        let planned = measure(unseen_scenario(102), &p, &args, 102, 1).unwrap();
        assert_eq!(planned.runs, 2);
        let lost = Unplanned {
            seed: 101,
            spheres: s.obstacles.len(),
            reason: reason.clone(),
        };
        let report = BenchmarkReport::new(2, Generator::Unseen, &p, vec![planned], vec![lost]);
        assert_eq!((report.totals.planned, report.totals.unplanned), (1, 1));
        assert_eq!(report.totals.runs, 2);
        let table = table::to_table(&args, &report);
        assert!(
            table.contains("not benchmarked: 1 of 2 scenarios"),
            "{table}"
        );
        assert!(table.contains(&format!(
            "seed 101 ({} spheres): {reason}",
            s.obstacles.len()
        )));
    }
}
