//! The last millimetres of an insertion are trimmed, not re-planned: within 2 mm of the end a
//! reading tries no form (no solve), since the needle can bend there less than the tracker
//! resolves, and each form tried costs a solve (on the device, at the end of a 256-sphere
//! insertion steered with a reserve, one reading once tried ten, over the budget of a reading:
//! docs/journal/2026-12-07.md, "Measurements once in code comments"). The runs still end on
//! the target.

use needle_sim::WorldEffects;
use needle_sim::{closed_loop_in, in_process, Conditions, Perturbation, Planned, TrackerFaults};
use planner_core::execute::schedule::schedule;
use planner_core::steer::{SteerConfig, SteerReply, SteerStats, Steering, TipMeasurement};
use planner_core::{plan, Scenario};

/// The in-process controller, recording before each reading the insertion its continuation has
/// left, and the evaluations its answer spent.
struct Recorded(Steering, Vec<(f32, u32)>);

impl needle_sim::Controller for Recorded {
    type Error = std::convert::Infallible;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error> {
        let left: f32 = self.0.steps().iter().map(|s| s.op.inserted_mm()).sum();
        let reply = self.0.update(m);
        self.1.push((left, reply.evaluations));
        Ok(reply)
    }
    fn stats(&mut self) -> Result<SteerStats, Self::Error> {
        Ok(self.0.stats())
    }
}

#[test]
fn the_last_two_millimetres_are_trimmed_not_replanned() {
    let mut s = Scenario::paper();
    s.options.curvature_reserve = 0.2;
    let best = plan(&s).unwrap().best().unwrap().clone();
    let sched = schedule(&s, &best).unwrap();
    let planned = Planned::of(&s, &best);
    let (p, faults, effects) = (
        Perturbation::default(),
        TrackerFaults::default(),
        WorldEffects::default(),
    );
    let world = Conditions {
        perturbation: &p,
        effects: &effects,
        faults: &faults,
    };
    let (mut near_the_end, mut solved_before) = (0, 0);
    for seed in 1..=20 {
        let ctl = in_process(&s, &sched, &SteerConfig::DEFAULT).unwrap();
        let mut recorded = Recorded(ctl, Vec::new());
        let run = closed_loop_in(&s, &planned, &sched, &world, &mut recorded, seed).unwrap();
        assert_eq!(run.stop_reason, None, "seed {seed}");
        assert!(
            run.run.target_error < 0.5,
            "seed {seed}: {}",
            run.run.target_error
        );
        for &(left, evaluations) in &recorded.1 {
            if left <= 2.0 {
                near_the_end += 1;
                assert_eq!(evaluations, 0, "seed {seed}: {left} mm left");
            } else {
                solved_before += usize::from(evaluations > 0);
            }
        }
    }
    assert!(
        near_the_end >= 10 && solved_before > 0,
        "{near_the_end} {solved_before}"
    );
}
