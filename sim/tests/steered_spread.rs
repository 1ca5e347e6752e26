//! The closed loop's spread predicted before the insertion (`planner_core::steer::apriori`)
//! against the steered simulation: how far the steered needle strays from the plan, RMS over
//! the path and the runs, predicted and simulated, on the paper's plan and a 3-D one.

use needle_sim::{closed_loop, in_process, Perturbation, Planned, TrackerFaults};
use planner_core::execute::schedule::schedule;
use planner_core::model::kinematics::V3;
use planner_core::model::scenario::Workspace;
use planner_core::steer::apriori::propagate_steered;
use planner_core::steer::SteerConfig;
use planner_core::{plan, Scenario};

const RUNS: u64 = 200;

/// Predicted and simulated RMS distance of the steered path from the plan (mm).
fn predicted_and_simulated(s: &Scenario) -> (f32, f32) {
    let best = plan(s).unwrap().best().unwrap().clone();
    let sched = schedule(s, &best).unwrap();
    let p = Perturbation::default();
    let config = SteerConfig::DEFAULT;
    // Across the path only: the distance to the planned path does not see the along-path part.
    let (mut sum, mut n, mut last): (f32, u32, Option<V3>) = (0.0, 0, None);
    propagate_steered(s, &sched, &p, &config.noise, 1.0, |t| {
        if let Some(prev) = last {
            let d = t.planned - prev;
            if d.norm() > 1e-6 {
                let along = d / d.norm();
                sum += t.covariance.trace() - (along.transpose() * t.covariance * along)[0];
                n += 1;
            }
        }
        last = Some(t.planned);
    });
    let predicted = (sum / n.max(1) as f32).sqrt();
    let planned = Planned::of(s, &best);
    let mut squares = 0.0f32;
    for seed in 0..RUNS {
        let mut ctl = in_process(s, &sched, &config).unwrap();
        let f = TrackerFaults::default();
        let r = closed_loop(s, &planned, &sched, &p, &f, &mut ctl, 5000 + seed).unwrap();
        squares += r.run.path_rms * r.run.path_rms;
    }
    (predicted, (squares / RUNS as f32).sqrt())
}

#[test]
fn the_predicted_closed_loop_spread_matches_the_steered_needle() {
    let mut space = Scenario::paper();
    space.options.workspace = Workspace::Space;
    space.target.position = [9.0, 6.0, 86.0];
    for (name, s) in [("paper", Scenario::paper()), ("3-D", space)] {
        let (predicted, simulated) = predicted_and_simulated(&s);
        println!("{name}: steered path deviation RMS predicted {predicted:.3} mm, simulated {simulated:.3} mm");
        assert!(
            predicted > 0.8 * simulated && predicted < 1.5 * simulated,
            "{name}: {predicted} against {simulated}"
        );
    }
}
