//! The defaults stay calibrated against the seed paper's experiment (docs/execution.md): open
//! loop on its scenario, the pooled RMS deviation of R, RL and LRR lies in the paper's range and
//! the largest error grows with the control degree. A few hundred runs (the 1000-run figures are
//! in the docs).

use hil_sim::insertion::{open_loop, Perturbation, Planned};
use planner_core::execute::schedule::schedule;
use planner_core::{plan, Form, Scenario};

/// RMS over runs of the run RMS, and the mean of each run's largest deviation.
fn figures(word: &str, runs: u64) -> (f64, f64) {
    let scenario = Scenario::paper();
    let f = Form::parse(word).unwrap();
    let report = plan(&scenario).unwrap();
    let o = report.forms.iter().find(|o| o.form == f).unwrap();
    let s = schedule(&scenario, o).unwrap();
    let planned = Planned::of(&scenario, o);
    let p = Perturbation::default();
    let (mut sq, mut max) = (0.0, 0.0);
    for seed in 1..=runs {
        let r = open_loop(&scenario, &planned, &s, &p, seed).unwrap();
        sq += f64::from(r.path_rms).powi(2);
        max += f64::from(r.path_max);
    }
    ((sq / runs as f64).sqrt(), max / runs as f64)
}

#[test]
fn defaults_reproduce_the_papers_experiment() {
    let [r, rl, lrr] = ["R", "RL", "LRR"].map(|w| figures(w, 400));
    let pooled = ((r.0.powi(2) + rl.0.powi(2) + lrr.0.powi(2)) / 3.0).sqrt();
    assert!((0.5..=1.5).contains(&pooled), "pooled RMS {pooled}");
    for (w, f) in [("R", r), ("RL", rl)] {
        assert!((0.5..=1.5).contains(&f.0), "{w}: RMS {}", f.0);
    }
    assert!(r.1 < rl.1 && rl.1 < lrr.1, "max {r:?} {rl:?} {lrr:?}");
}
