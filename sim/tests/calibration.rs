//! The defaults stay calibrated against the seed paper's experiment as docs/simulation.md records
//! it: open loop on its scenario, the pooled RMS deviation of R, RL and LRR lies in the paper's
//! range (0.5-1.5 mm), R and RL each do, and the largest error grows with the control degree.
//! LRR alone does not: its 3-D RMS deviation (docs/simulation.md) is above 1.5 mm, mostly
//! out of the plane; seen in the plane, as the paper's 2-D comparison of its paths does, all
//! three lie in range. The guard keeps each of those statements true, the miss included, so a
//! change to the model that moves any of them must update the docs. A few hundred runs (the
//! 1000-run figures are in the docs).

use needle_sim::{open_loop, Perturbation, Planned};
use planner_core::execute::schedule::schedule;
use planner_core::{plan, Form, Scenario};

/// Over the runs: RMS of the run RMS, mean of each run's largest deviation, and RMS of the
/// in-plane run RMS.
fn figures(word: &str, runs: u64) -> (f64, f64, f64) {
    let scenario = Scenario::paper();
    let f = Form::parse(word).unwrap();
    let report = plan(&scenario).unwrap();
    let o = report.forms.iter().find(|o| o.form == f).unwrap();
    let s = schedule(&scenario, o).unwrap();
    let planned = Planned::of(&scenario, o);
    let p = Perturbation::default();
    let (mut sq, mut max, mut sq_in) = (0.0, 0.0, 0.0);
    for seed in 1..=runs {
        let r = open_loop(&scenario, &planned, &s, &p, seed).unwrap();
        sq += f64::from(r.path_rms).powi(2);
        max += f64::from(r.path_max);
        sq_in += f64::from(r.path_rms_in_plane.unwrap()).powi(2);
    }
    let n = runs as f64;
    ((sq / n).sqrt(), max / n, (sq_in / n).sqrt())
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
    // The documented miss: LRR's 3-D RMS above the paper's range (not by much).
    assert!((1.5..=2.0).contains(&lrr.0), "LRR: RMS {}", lrr.0);
    // In the plane all three lie in range.
    for (w, f) in [("R", r), ("RL", rl), ("LRR", lrr)] {
        assert!((0.5..=1.5).contains(&f.2), "{w}: in-plane RMS {}", f.2);
    }
}
