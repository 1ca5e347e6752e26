//! The unseen family's scenarios the planner finds no path for (`needle benchmark --generator
//! unseen`: spheres drawn with no regard for whether a path is left), looked at with the
//! independent sampler (`needle_e2e::sampling`, an RRT over tip frames in f64): where it finds no
//! path either, the scenario is refused rightly, whatever the safe defaults ask of a plan. The
//! seeds are those of scripts/default-campaign.py (batches of 50 from 7001, 7101, ...); a few in
//! the default suite, the campaign behind `--ignored`, its figures in docs/execution.md:
//!
//! ```text
//! cargo test -p needle-e2e --profile ci --test unseen_refusals -- --ignored --nocapture
//! ```

use needle_e2e::sampling::{sample, Budget};
use needle_scenario::unseen::unseen_scenario;

/// What the planner and the sampler found on some seeds.
#[derive(Default)]
struct Tally {
    scenarios: usize,
    planner_none: Vec<u64>,
    sampled_where_planner_none: Vec<u64>,
}

fn tally(seeds: impl IntoIterator<Item = u64>) -> Tally {
    let mut t = Tally::default();
    for seed in seeds {
        let s = unseen_scenario(seed);
        t.scenarios += 1;
        let report = planner_core::plan(&s).expect("the family's scenarios are valid");
        if report.best().is_some() {
            continue;
        }
        t.planner_none.push(seed);
        if let Some(p) = sample(&s, Budget::DEFAULT, seed) {
            println!("seed {seed}: the planner found none, the sampler {p}");
            t.sampled_where_planner_none.push(seed);
        }
    }
    println!(
        "{} scenarios: no path planned for {} ({:?}); of them the sampler found a path for {}",
        t.scenarios,
        t.planner_none.len(),
        t.planner_none,
        t.sampled_where_planner_none.len()
    );
    t
}

/// The first 12 seeds of the campaign's first batch: each scenario the planner refuses, the
/// sampler finds no path for either.
#[test]
fn unplanned_unseen_scenarios_have_no_sampled_path_either() {
    let t = tally(7001..7013);
    assert!(
        !t.planner_none.is_empty(),
        "the seeds were meant to hold a blocked scenario"
    );
    assert!(t.sampled_where_planner_none.is_empty());
}

/// The campaign's 250 scenarios.
#[test]
#[ignore]
fn the_campaigns_unplanned_scenarios() {
    let seeds = (0..5u64).flat_map(|b| (7001 + 100 * b)..(7051 + 100 * b));
    let t = tally(seeds);
    assert!(t.sampled_where_planner_none.is_empty());
}
