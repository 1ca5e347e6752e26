//! The closed loop's spread predicted before the insertion (`planner_core::steer::apriori`)
//! against the steered simulation on generated scenarios nobody tuned on
//! (`needle_scenario::unseen`, seeds 101–110, the plans `needle benchmark` steers: a
//! curvature reserve of 0.2): the RMS distance of the steered path from the plan, predicted and
//! simulated, per scenario and over them. A first-order spread describes the runs that keep the
//! planned way around the obstacles; a run the controller takes round another way (a replan may
//! change the form) is counted apart, and must stay rare.

use needle_scenario::unseen::unseen_scenario;
use needle_sim::{closed_loop, in_process, Perturbation, Planned, TrackerFaults};
use needle_simulate::prepare_keeping_reserve;
use planner_core::model::kinematics::V3;
use planner_core::steer::apriori::propagate_steered;
use planner_core::steer::SteerConfig;

const RUNS: u64 = 60;

/// A run whose path strays this far from the plan has gone round another way (the runs that
/// keep the route stay within 4 mm of it on these scenarios; the one that did not, 12 mm).
const ROUTE_CHANGED_MM: f32 = 5.0;

#[test]
fn on_generated_scenarios_the_predicted_closed_loop_spread_holds() {
    let p = Perturbation::default();
    let config = SteerConfig::DEFAULT;
    let (mut predicted_sq, mut simulated_sq, mut n) = (0.0f64, 0.0f64, 0);
    let (mut other_ways, mut runs) = (0u32, 0u32);
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
        let (mut squares, mut kept) = (0.0f64, 0u32);
        for k in 0..RUNS {
            let mut ctl = in_process(&s, sched, &config).unwrap();
            let f = TrackerFaults::default();
            let r = closed_loop(&s, &planned, sched, &p, &f, &mut ctl, 7000 + k).unwrap();
            runs += 1;
            if r.run.path_max > ROUTE_CHANGED_MM {
                other_ways += 1;
                continue;
            }
            squares += f64::from(r.run.path_rms * r.run.path_rms);
            kept += 1;
        }
        let simulated = (squares / f64::from(kept.max(1))).sqrt();
        println!(
            "seed {seed} {}: predicted {predicted:.3} mm, simulated {simulated:.3} mm ({} of {RUNS} runs went round another way)",
            prepared.outcome.form,
            RUNS - u64::from(kept)
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
    println!(
        "{n} scenarios: predicted {predicted:.3} mm, simulated {simulated:.3} mm; \
         {other_ways} of {runs} runs went round another way"
    );
    assert!(
        other_ways * 50 <= runs,
        "{other_ways} of {runs} runs changed route"
    );
    assert!(n >= 6, "{n} scenarios planned");
    // Since the steering spends the reserve on the turn first (a full-curvature turn, then a
    // line) the steered path strays farther from the plan than the first-order spread, which
    // models the constant arc, predicts: 0.513 against 0.643 mm here (0.598 before). A known
    // gap, in docs/journal/2026-12-05.md ("Layers"), until the prediction models that turn.
    assert!(predicted > 0.75 * simulated && predicted < 1.6 * simulated);
}
