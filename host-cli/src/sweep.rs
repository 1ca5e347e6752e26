//! `needle sweep`: its flags, the weight sweep of `needle_analysis::commands`.

use crate::scenario_args::ScenarioArgs;
use needle_analysis::commands::SweepOptions;
use needle_analysis::sweep::Weight;
use std::path::PathBuf;

/// Which weight of F = a1 L + a2 D + a3 H + a4 N is swept (by its name or by a1..a4).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeightArg {
    /// a1
    #[value(alias = "a1")]
    Length,
    /// a2
    #[value(alias = "a2")]
    Risk,
    /// a3
    #[value(alias = "a3")]
    Penalty,
    /// a4
    #[value(alias = "a4")]
    Control,
}

impl From<WeightArg> for Weight {
    fn from(w: WeightArg) -> Weight {
        match w {
            WeightArg::Length => Weight::Length,
            WeightArg::Risk => Weight::Risk,
            WeightArg::Penalty => Weight::Penalty,
            WeightArg::Control => Weight::Control,
        }
    }
}

/// `needle sweep`
#[derive(clap::Args, Clone, Debug)]
pub struct SweepArgs {
    /// The scenario and what to plan in it.
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Weight to vary: length, risk, penalty or control.
    #[arg(long, ignore_case = true)]
    weight: WeightArg,
    /// First value.
    #[arg(long)]
    from: f64,
    /// Last value.
    #[arg(long)]
    to: f64,
    /// Number of values, both ends included.
    #[arg(long, default_value_t = 10)]
    steps: usize,
    /// Space the values evenly in log10.
    #[arg(long)]
    log: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Also write the table as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Also draw F and L against the weight (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Threads (default: every core).
    #[arg(long)]
    threads: Option<usize>,
}

/// Runs `needle sweep`.
pub fn sweep(a: &SweepArgs) -> anyhow::Result<()> {
    needle_analysis::commands::run_sweep(&SweepOptions {
        scenario: a.scenario.options(),
        weight: a.weight.into(),
        from: a.from,
        to: a.to,
        steps: a.steps,
        log: a.log,
        json: a.json,
        csv: a.csv.clone(),
        plot: a.plot.clone(),
        threads: a.threads,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// The command line reads every name and alias of a weight as the library does.
    #[test]
    fn the_flags_name_every_weight_as_the_library() {
        let flags: Vec<Weight> = WeightArg::value_variants()
            .iter()
            .map(|&w| w.into())
            .collect();
        assert_eq!(flags, Weight::ALL);
        for w in Weight::ALL {
            for name in [w.name(), w.alias()] {
                let arg = WeightArg::from_str(&name.to_uppercase(), true).unwrap();
                assert_eq!(Weight::from(arg), w, "{name}");
                assert_eq!(Weight::parse(&name.to_uppercase()), Some(w), "{name}");
            }
        }
    }
}
