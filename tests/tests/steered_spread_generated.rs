//! The closed loop's spread predicted before the insertion (`planner_core::steer::apriori`)
//! against the steered simulation on generated scenarios nobody tuned on
//! (`needle_cli::scenario::unseen`, seeds 101–110, the plans `needle benchmark` steers: a
//! curvature reserve of 0.2): the RMS distance of the steered path from the plan, predicted and
//! simulated, per scenario and over them.

use needle_cli::scenario::unseen::unseen_scenario;
use needle_cli::simulate::prepare_keeping_reserve;
use needle_sim::{closed_loop, in_process, Perturbation, Planned, TrackerFaults};
use planner_core::model::kinematics::V3;
use planner_core::steer::apriori::propagate_steered;
use planner_core::steer::SteerConfig;

const RUNS: u64 = 60;

#[test]
fn on_generated_scenarios_the_predicted_closed_loop_spread_holds() {
    let p = Perturbation::default();
    let config = SteerConfig::DEFAULT;
    let (mut predicted_sq, mut simulated_sq, mut n) = (0.0f64, 0.0f64, 0);
    for seed in 101..=110u64 {
        let mut s = unseen_scenario(seed);
        s.options.curvature_reserve = 0.2;
        let Ok((s, prepared)) = prepare_keeping_reserve(&s, None) else {
            continue; // no path: counted by the benchmark, nothing to compare here
        };
        let sched = &prepared.schedule;
        let (mut sum, mut points, mut last): (f32, u32, Option<V3>) = (0.0, 0, None);
        propagate_steered(&s, sched, &p, &config.noise, 1.0, |t| {
            if let Some(prev) = last {
                let d = t.planned - prev;
                if d.norm() > 1e-6 {
                    let along = d / d.norm();
                    sum += t.covariance.trace() - (along.transpose() * t.covariance * along)[0];
                    points += 1;
                }
            }
            last = Some(t.planned);
        });
        let predicted = f64::from(sum / points.max(1) as f32).sqrt();
        let planned = Planned::of(&s, &prepared.outcome);
        let mut squares = 0.0f64;
        for k in 0..RUNS {
            let mut ctl = in_process(&s, sched, &config).unwrap();
            let f = TrackerFaults::default();
            let r = closed_loop(&s, &planned, sched, &p, &f, &mut ctl, 7000 + k).unwrap();
            squares += f64::from(r.run.path_rms * r.run.path_rms);
        }
        let simulated = (squares / RUNS as f64).sqrt();
        println!(
            "seed {seed} {}: predicted {predicted:.3} mm, simulated {simulated:.3} mm",
            prepared.outcome.form
        );
        predicted_sq += predicted * predicted;
        simulated_sq += simulated * simulated;
        n += 1;
        assert!(
            predicted > 0.5 * simulated && predicted < 2.0 * simulated,
            "seed {seed}: {predicted} against {simulated}"
        );
    }
    let (predicted, simulated) = (
        (predicted_sq / n as f64).sqrt(),
        (simulated_sq / n as f64).sqrt(),
    );
    println!("{n} scenarios: predicted {predicted:.3} mm, simulated {simulated:.3} mm");
    assert!(n >= 6, "{n} scenarios planned");
    assert!(predicted > 0.8 * simulated && predicted < 1.6 * simulated);
}
