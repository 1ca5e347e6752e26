//! The controller's dead band on bevel turns: on the paper's insertion, closed loop in the
//! default world, it commands no turn under the band (without one, each replan turns the bevel
//! by tenths of a degree), at most 30 turns per insertion (median), and lands as close.

use needle_sim::{closed_loop, in_process, Perturbation, Planned, TrackerFaults};
use planner_core::execute::schedule::{schedule, Op};
use planner_core::steer::SteerConfig;
use planner_core::{plan, Scenario};

/// Median turns per insertion, turns under 2 degrees in all, mean target error (mm).
fn steered(config: &SteerConfig) -> (usize, usize, f32) {
    let s = Scenario::paper();
    let best = plan(&s).unwrap().best().unwrap().clone();
    let sched = schedule(&s, &best).unwrap();
    let planned = Planned::of(&s, &best);
    let (mut turns, mut small, mut error) = (Vec::new(), 0, 0.0);
    for seed in 0..12 {
        let mut controller = in_process(&s, &sched, config).unwrap();
        let p = Perturbation::default();
        let r = closed_loop(
            &s,
            &planned,
            &sched,
            &p,
            &TrackerFaults::default(),
            &mut controller,
            seed,
        )
        .unwrap();
        let angles: Vec<f32> = r
            .run
            .steps
            .iter()
            .filter_map(|st| match st.op {
                Op::Rotate { angle_deg } => Some(angle_deg),
                _ => None,
            })
            .collect();
        small += angles.iter().filter(|a| a.abs() < 2.0).count();
        turns.push(angles.len());
        error += r.run.target_error / 12.0;
    }
    turns.sort_unstable();
    (turns[turns.len() / 2], small, error)
}

#[test]
fn the_dead_band_cuts_the_turns_not_the_accuracy() {
    let banded = steered(&SteerConfig::DEFAULT);
    let unbanded = steered(&SteerConfig {
        rotation_dead_band_deg: 0.0,
        ..SteerConfig::DEFAULT
    });
    println!("turns per insertion (median), turns under 2 degrees, mean error: with {banded:?}, without {unbanded:?}");
    assert!(banded.0 <= 30, "{banded:?} against {unbanded:?}");
    assert_eq!(banded.1, 0, "{banded:?} against {unbanded:?}");
    assert!(unbanded.1 > 20, "{banded:?} against {unbanded:?}");
    assert!(
        banded.2 < unbanded.2 + 0.05 && banded.2 <= 0.3,
        "{banded:?} against {unbanded:?}"
    );
}
