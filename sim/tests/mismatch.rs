//! The controller against a world it does not know: it is built from its `SteerConfig` alone and
//! answers the readings alone, and with each figure of the world it models at half or twice its
//! assumption it touches no obstacle and ends every run it cannot finish with a stop.

use needle_sim::{
    closed_loop_in, in_process, Conditions, Perturbation, Planned, TrackerFaults, WorldEffects,
};
use planner_core::execute::schedule::{schedule, Schedule};
use planner_core::model::scenario::Workspace;
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, Steering, TipMeasurement};
use planner_core::{plan, FormOutcome, Scenario};

fn best(s: &Scenario) -> (FormOutcome, Schedule) {
    let o = plan(s).unwrap().best().unwrap().clone();
    let sched = schedule(s, &o).unwrap();
    (o, sched)
}

/// The in-process controller, recording each reading and its answer.
struct Recorded(Steering, Vec<(TipMeasurement, SteerReply)>);

impl needle_sim::Controller for Recorded {
    type Error = std::convert::Infallible;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error> {
        let reply = self.0.update(m);
        self.1.push((*m, reply.clone()));
        Ok(reply)
    }
    fn stats(&mut self) -> Result<SteerStats, Self::Error> {
        Ok(self.0.stats())
    }
}

/// A clinical-world insertion steered in the simulator, then its readings replayed into a
/// controller started from the scenario, the schedule and the `SteerConfig` only (nothing of
/// the world in scope): the same answers, bit for bit. What the controller does is a function of
/// what a lab gives it and of the readings, never of the world's parameters.
#[test]
fn the_controller_answers_from_its_config_and_the_readings_alone() {
    let s = Scenario::paper();
    let (o, sched) = best(&s);
    let effects = WorldEffects::clinical();
    let faults = WorldEffects::clinical_faults();
    let world = Conditions {
        perturbation: &Perturbation::default(),
        effects: &effects,
        faults: &faults,
    };
    let config = SteerConfig::DEFAULT;
    for seed in [2, 5] {
        let started = in_process(&s, &sched, &config).unwrap();
        let mut recorded = Recorded(started, Vec::new());
        closed_loop_in(
            &s,
            &Planned::of(&s, &o),
            &sched,
            &world,
            &mut recorded,
            seed,
        )
        .unwrap();
        assert!(recorded.1.len() > 40, "{} readings", recorded.1.len());
        let mut replayed = Steering::start(&s, &sched, &config).unwrap();
        // Compared as printed: a reply's NaN (no prediction) is not equal to itself.
        for (reading, answered) in &recorded.1 {
            let again = replayed.update(reading);
            assert_eq!(format!("{again:?}"), format!("{answered:?}"), "seed {seed}");
        }
        assert_eq!(replayed.stats(), recorded.0.stats());
    }
}

/// The world's figures that the controller's noise model assumes, set to `factor` times the
/// assumption one at a time (the line drift, which the model states as a heading walk, to
/// `factor` times the world's default).
fn mismatched(factor: f32) -> Vec<(&'static str, Perturbation)> {
    let n = SteerConfig::DEFAULT.noise;
    let d = Perturbation::default();
    let set = |f: &dyn Fn(&mut Perturbation)| {
        let mut p = d;
        f(&mut p);
        p
    };
    vec![
        (
            "curvature",
            set(&|p| p.curvature_spread = factor * n.curvature_spread),
        ),
        (
            "arc curvature",
            set(&|p| p.segment_curvature_spread = factor * n.segment_curvature_spread),
        ),
        (
            "torsion",
            set(&|p| p.torsion_lag_deg_per_mm = factor * n.torsion_lag_deg_per_mm),
        ),
        (
            "line drift",
            set(&|p| p.line_drift_mm_per_mm = factor * d.line_drift_mm_per_mm),
        ),
        (
            "insertion",
            set(&|p| p.insertion_error_mm = factor * n.insertion_error_mm),
        ),
        (
            "entry point",
            set(&|p| p.entry_position_mm = factor * n.entry_position_mm),
        ),
        (
            "entry direction",
            set(&|p| p.entry_direction_deg = factor * n.entry_direction_deg),
        ),
        ("target", set(&|p| p.target_shift_mm = factor * n.target_mm)),
        (
            "tracker position",
            set(&|p| p.tracker_position_mm = factor * n.position_mm),
        ),
        (
            "tracker heading",
            set(&|p| p.tracker_heading_deg = factor * n.orientation_deg),
        ),
    ]
}

/// Runs `runs` insertions of `s` in each mismatched world; returns per world (collisions, runs
/// reached, the worst error of a run called reached).
fn campaign(s: &Scenario, factor: f32, runs: u64) -> Vec<(&'static str, usize, usize, f32)> {
    let (o, sched) = best(s);
    let planned = Planned::of(s, &o);
    let config = SteerConfig::DEFAULT;
    let (effects, faults) = (WorldEffects::default(), TrackerFaults::default());
    let mut out = Vec::new();
    for (name, p) in mismatched(factor) {
        let world = Conditions {
            perturbation: &p,
            effects: &effects,
            faults: &faults,
        };
        let (mut collisions, mut reached, mut worst) = (0, 0, 0.0f32);
        for seed in 1..=runs {
            let mut steering = in_process(s, &sched, &config).unwrap();
            let r = closed_loop_in(s, &planned, &sched, &world, &mut steering, seed).unwrap();
            collisions += usize::from(r.run.collided);
            if r.stop_reason.is_none() {
                reached += 1;
                worst = worst.max(r.run.target_error);
            }
        }
        out.push((name, collisions, reached, worst));
    }
    out
}

fn space() -> Scenario {
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    s.target.position = [4.0, 6.0, 88.0];
    s
}

/// Each modelled figure at half the controller's assumption: every run reaches the target
/// within the reach tolerance, none touches an obstacle.
#[test]
fn a_quieter_world_than_assumed_is_steered_to_the_target() {
    let tolerance = SteerConfig::DEFAULT.reach_tolerance_mm;
    for s in [Scenario::paper(), space()] {
        for (name, collisions, reached, worst) in campaign(&s, 0.5, 6) {
            assert_eq!(collisions, 0, "{name} at 0.5x");
            assert_eq!(reached, 6, "{name} at 0.5x");
            assert!(worst <= tolerance, "{name} at 0.5x: {worst} mm");
        }
    }
}

/// Each modelled figure at twice the controller's assumption: no run touches an obstacle, and
/// a run the controller calls reached is within the reach tolerance; the others end with a
/// reported stop (a noisier tracker than assumed leaves many `missed`, none silently off).
#[test]
fn a_world_twice_as_rough_as_assumed_collides_never_and_stops_when_it_must() {
    let tolerance = SteerConfig::DEFAULT.reach_tolerance_mm;
    for s in [Scenario::paper(), space()] {
        for (name, collisions, reached, worst) in campaign(&s, 2.0, 6) {
            println!(
                "{name} at 2x: {collisions} collisions, {reached} of 6 reached, worst {worst} mm"
            );
            assert_eq!(collisions, 0, "{name} at 2x");
            assert!(
                worst <= tolerance,
                "{name} at 2x: {worst} mm, {reached} reached"
            );
        }
    }
}
