//! `needle benchmark`: its flags, the generated scenarios planned and simulated by
//! `needle_simulate::benchmark`.

use crate::values::{at_least_one, run_count, scenario_count};
use needle_simulate::benchmark::{BenchmarkOptions, Generator};
use std::path::PathBuf;

/// `needle benchmark`
#[derive(clap::Args, Clone, Debug)]
pub struct BenchmarkArgs {
    /// Generated scenarios, 1 to 100 000 (seeds S, S+1, ...).
    #[arg(long, default_value_t = BenchmarkOptions::default().scenarios, value_parser = scenario_count)]
    scenarios: usize,
    /// Seed of the first scenario.
    #[arg(long, default_value_t = BenchmarkOptions::default().seed)]
    seed: u64,
    /// Simulated insertions per scenario, 1 to 1 000 000: each open loop, and the same worlds
    /// closed loop.
    #[arg(long, default_value_t = BenchmarkOptions::default().runs, value_parser = run_count)]
    runs: usize,
    /// Threads, at least 1 (default: every core).
    #[arg(long, value_parser = at_least_one)]
    threads: Option<usize>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Change one perturbation or world effect, KEY=VALUE (repeatable; over `--world`; see
    /// docs/execution.md).
    #[arg(long = "perturb", value_name = "KEY=VALUE")]
    perturb: Vec<String>,
    /// The world every run is made in: `default` (today's) or `clinical` (docs/execution.md,
    /// "The clinical world"), as `needle simulate --world`.
    #[arg(long, value_name = "NAME")]
    world: Option<String>,
    /// A tracker fault of the closed loop, KEY=VALUE (repeatable; over `--world`'s), as
    /// `needle simulate --fault`.
    #[arg(long = "fault", value_name = "KEY=VALUE")]
    faults: Vec<String>,
    /// Tell the closed-loop controller one `[steering]` key, KEY=VALUE (repeatable): it steers
    /// with it, and a steered bound predicts its spread with it.
    #[arg(long = "steer", value_name = "KEY=VALUE")]
    steer: Vec<String>,
    /// Also write each generated scenario to DIR/unseen-SEED.toml (a file `needle plan` reads).
    #[arg(long, value_name = "DIR")]
    write_scenarios: Option<PathBuf>,
    /// Plan every scenario under this bound on the predicted collision probability (default
    /// model: the simulator's defaults, not `--perturb`); a scenario no plan meets it for is
    /// counted with that reason.
    #[arg(long, value_name = "P", value_parser = probability)]
    max_collision_probability: Option<f32>,
    /// Plan the scenarios steered closed loop under this bound on the collision probability
    /// the closed loop's spread predicts (`execution.mode = "closed_loop"` with
    /// `planner.max_collision_probability`); a scenario no steered plan meets it for is counted
    /// with that reason (its open-loop runs stay).
    #[arg(long, value_name = "P", value_parser = probability)]
    closed_loop_max_collision_probability: Option<f32>,
    /// Execute open loop only (no closed-loop runs; their figures are null).
    #[arg(long)]
    open_loop_only: bool,
    /// The curvature reserve of the plans steered closed loop (`planner.curvature_reserve`:
    /// halved where no path keeps it, down to none; the row says what was kept).
    #[arg(long, value_name = "R", default_value_t = BenchmarkOptions::default().curvature_reserve, value_parser = reserve)]
    curvature_reserve: f32,
    /// Which generator draws the scenarios: `unseen` (the spheres drawn with no regard for
    /// whether a path is left) or `planted` (a needle path drawn first, every sphere kept 2 mm
    /// from it: every scenario has a path).
    #[arg(long, value_enum, default_value_t = GeneratorArg::Unseen)]
    generator: GeneratorArg,
}

/// The seeded families `needle benchmark` draws from (docs/execution.md, "Unseen scenarios").
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeneratorArg {
    // Each family's help is the library function that draws it, as the help has always said.
    #[value(help = "[`unseen_scenario`]")]
    Unseen,
    #[value(help = "[`planted_scenario`]")]
    Planted,
}

impl From<GeneratorArg> for Generator {
    fn from(g: GeneratorArg) -> Generator {
        match g {
            GeneratorArg::Unseen => Generator::Unseen,
            GeneratorArg::Planted => Generator::Planted,
        }
    }
}

/// A probability strictly between 0 and 1.
fn probability(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(p) if p > 0.0 && p < 1.0 => Ok(p),
        _ => Err("must be a number more than 0 and less than 1".into()),
    }
}

/// A curvature reserve the scenario accepts.
fn reserve(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(r) if (0.0..=planner_core::MAX_CURVATURE_RESERVE).contains(&r) => Ok(r),
        _ => Err(format!(
            "must be a number from 0 to {}",
            planner_core::MAX_CURVATURE_RESERVE
        )),
    }
}

impl BenchmarkArgs {
    /// What the flags ask.
    fn options(&self) -> BenchmarkOptions {
        BenchmarkOptions {
            scenarios: self.scenarios,
            seed: self.seed,
            runs: self.runs,
            threads: self.threads,
            json: self.json,
            perturb: self.perturb.clone(),
            world: self.world.clone(),
            faults: self.faults.clone(),
            steer: self.steer.clone(),
            write_scenarios: self.write_scenarios.clone(),
            max_collision_probability: self.max_collision_probability,
            closed_loop_max_collision_probability: self.closed_loop_max_collision_probability,
            open_loop_only: self.open_loop_only,
            curvature_reserve: self.curvature_reserve,
            generator: self.generator.into(),
        }
    }
}

/// Runs `needle benchmark`.
pub fn benchmark(a: &BenchmarkArgs) -> anyhow::Result<()> {
    needle_simulate::benchmark::run_benchmark(&a.options())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// The command line names each family as the library does, in the same order.
    #[test]
    fn the_flags_name_every_generator_as_the_library() {
        let flags: Vec<(String, Generator)> = GeneratorArg::value_variants()
            .iter()
            .map(|&g| (g.to_possible_value().unwrap().get_name().into(), g.into()))
            .collect();
        let library: Vec<(String, Generator)> = Generator::ALL
            .iter()
            .map(|&g| (g.name().into(), g))
            .collect();
        assert_eq!(flags, library);
        for (name, g) in library {
            assert_eq!(name.to_uppercase().parse::<Generator>().unwrap(), g);
        }
    }
}
