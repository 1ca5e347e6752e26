//! Twice the clinical world (every spread and effect at twice the controller's assumption, the
//! flags of scripts/clinical-campaign.py's "clinical x2, lab-told"): the controller, told only
//! the defaults and the target's speed walk, must touch no obstacle; a run it cannot finish
//! safely ends in a reported stop (docs/journal/2026-12-05.md, "Twice the world").

use needle_sim::{
    closed_loop_in, in_process, Conditions, Perturbation, Planned, TrackerFaults, WorldEffects,
    TWICE_CLINICAL_FAULT_KEYS, TWICE_CLINICAL_KEYS,
};
use planner_core::execute::schedule::schedule;
use planner_core::steer::{SteerConfig, StopReason};
use planner_core::{plan, Scenario};

fn twice_the_world() -> (Perturbation, WorldEffects, TrackerFaults) {
    let (mut effects, mut faults) = WorldEffects::preset("clinical").unwrap();
    let mut p = Perturbation::default();
    for kv in TWICE_CLINICAL_KEYS {
        if p.apply(kv).is_err() {
            effects.apply(kv).unwrap();
        }
    }
    for kv in TWICE_CLINICAL_FAULT_KEYS {
        faults.apply(kv).unwrap();
    }
    (p, effects, faults)
}

/// The paper's insertion at twice the world, seeds 1 to [`SEEDS`]: before the estimate that has
/// lost the tip stopped the run near an obstacle (`planner-core/src/steer/lost.rs`), the seeds
/// of [`COLLIDED`] touched a sphere (three of them ended `tracking_lost` only after it, two
/// `missed`, one reached); now none does, and each of those ends in a reported stop.
#[test]
fn twice_the_world_touches_nothing_and_stops_what_it_cannot_finish() {
    let s = Scenario::paper();
    let best = plan(&s).unwrap().best().unwrap().clone();
    let sched = schedule(&s, &best).unwrap();
    let planned = Planned::of(&s, &best);
    let (p, effects, faults) = twice_the_world();
    let world = Conditions {
        perturbation: &p,
        effects: &effects,
        faults: &faults,
    };
    let mut config = SteerConfig::DEFAULT;
    config.noise.target_speed_walk = 0.02;
    let mut collided = Vec::new();
    let mut stops = Vec::new();
    for seed in 1..=SEEDS {
        let mut controller = in_process(&s, &sched, &config).unwrap();
        let r = closed_loop_in(&s, &planned, &sched, &world, &mut controller, seed).unwrap();
        if r.run.collided {
            collided.push(seed);
        }
        if COLLIDED.contains(&seed) {
            stops.push(r.stop_reason);
        }
    }
    println!("collided: {collided:?}; the seeds that collided before end {stops:?}");
    assert!(collided.is_empty(), "collided: {collided:?}");
    for reason in stops {
        assert!(
            matches!(
                reason,
                Some(StopReason::TrackingLost | StopReason::NoSafeContinuation)
            ),
            "{reason:?}"
        );
    }
}

/// The seeds run, and those that collided before the change (the same as `needle simulate
/// examples/paper.toml --closed-loop --runs 60 --seed 1` with the campaign's x2 flags).
const SEEDS: u64 = 60;
const COLLIDED: [u64; 7] = [17, 20, 25, 33, 37, 43, 54];
