use super::*;
use crate::model::form::Form;
use crate::model::scenario::{Obstacle, Scenario, Workspace};
use crate::optim::problem::MAX_VARS;

/// Keeps every seed and near miss it is offered; refuses seeds at or above `bound`.
struct Collected {
    bound: f32,
    offered: Vec<(f32, Vars)>,
    near_misses: Vec<(f32, Option<Vars>)>,
}

impl Collected {
    fn new(bound: f32) -> Self {
        Collected {
            bound,
            offered: Vec::new(),
            near_misses: Vec::new(),
        }
    }
}

impl SeedSink for Collected {
    fn bound(&self) -> f32 {
        self.bound
    }
    fn offer(&mut self, objective: f32, x: &Vars) {
        self.offered.push((objective, *x));
    }
    fn near_miss(&mut self, min_clearance: f32, x: &dyn Fn() -> Option<Vars>) {
        self.near_misses.push((min_clearance, x()));
    }
}

/// The paper's scenario (entry at the origin along z, target 90 mm ahead) with `obstacles`.
fn paper_with(obstacles: &[([f32; 3], f32)]) -> Scenario {
    let mut s = Scenario::paper();
    s.obstacles.clear();
    for &(center, radius) in obstacles {
        s.obstacles.push(Obstacle { center, radius }).unwrap();
    }
    s
}

/// Every side assignment of `word`'s arcs swept in the plane turned by `psi`, each with its
/// own problem (as the per-form solve sweeps them).
fn sweep_all(s: &Scenario, word: &str, psi: f32, sink: &mut Collected) -> u32 {
    let form = Form::parse(word).unwrap();
    (0..1u8 << form.arc_count())
        .map(|sides| sweep(&Problem::new(s, form, sides), psi, sides, 0, sink))
        .sum()
}

#[test]
fn a_line_seed_runs_straight_along_the_chord() {
    let s = paper_with(&[]);
    let p = Problem::new(&s, Form::parse("L").unwrap(), 0);
    let mut sink = Collected::new(f32::INFINITY);
    assert_eq!(sweep(&p, 0.0, 0, 0, &mut sink), 1);
    // F = a1 L + a4 N = 90 + 2 with nothing to be near.
    assert_eq!(sink.offered.len(), 1);
    let (objective, x) = sink.offered[0];
    assert_eq!(objective, 92.0);
    assert_eq!(x[0], 0.0, "no tilt");
    assert!((p.lengths(&x)[0] - 90.0).abs() < 1e-4);
}

#[test]
fn a_single_arc_seed_is_the_short_way_round() {
    // The arc through entry and target spans a chord of 90 mm: 2 r asin(45 / r) long; the
    // long way round turns more than the needle's 180 degrees and is refused.
    let s = paper_with(&[]);
    let r = s.needle.curvature_radius;
    let expected = 2.0 * r * crate::fmath::asin(45.0 / r);
    let mut sink = Collected::new(f32::INFINITY);
    sweep_all(&s, "R", 0.0, &mut sink);
    assert_eq!(sink.offered.len(), 2, "one per side");
    for (objective, _) in &sink.offered {
        assert!((objective - (expected + 2.0)).abs() < 1e-3, "{objective}");
    }
}

/// The distance from the end of the path `x` of `p` to the target (mm).
fn miss(p: &Problem, x: &Vars) -> f32 {
    let end = p.geometry(x).end();
    let t = p.scenario.target.position;
    crate::fmath::sqrt((end.x - t[0]).powi(2) + (end.y - t[1]).powi(2) + (end.z - t[2]).powi(2))
}

#[test]
fn every_seed_ends_on_the_target_and_scores_as_the_problem_does() {
    let plane = Scenario::paper();
    let mut space = Scenario::paper();
    space.options.workspace = Workspace::Space;
    let mut seeds = 0;
    for (s, psi) in [(&plane, 0.0), (&space, 0.7)] {
        for word in ["R", "RL", "LR", "RR", "RLR", "LRL", "RRL"] {
            let form = Form::parse(word).unwrap();
            for sides in 0..1u8 << form.arc_count() {
                let p = Problem::new(s, form, sides);
                let mut sink = Collected::new(f32::INFINITY);
                sweep(&p, psi, sides, 0, &mut sink);
                for (objective, x) in &sink.offered {
                    assert!(miss(&p, x) < 1e-3, "{word}: {x:?} ends off the target");
                    let value = p.value(x);
                    assert!(
                        (value.objective - objective).abs() < 1e-4 * objective,
                        "{word}: swept {objective}, problem {}",
                        value.objective
                    );
                }
                seeds += sink.offered.len();
            }
        }
    }
    assert!(seeds > 100, "only {seeds} seeds");
}

#[test]
fn a_blocked_sweep_offers_nothing() {
    // A sphere on the chord: the only line cuts 10 mm into it.
    let s = paper_with(&[([0.0, 0.0, 45.0], 10.0)]);
    let mut sink = Collected::new(f32::INFINITY);
    assert_eq!(sweep_all(&s, "L", 0.0, &mut sink), 1);
    assert!(sink.offered.is_empty() && sink.near_misses.is_empty());
}

#[test]
fn a_line_cutting_an_obstacle_by_less_than_a_near_miss_is_handed_on() {
    // The sphere's centre is 8 mm off the chord and its radius 10: the line cuts 2 mm in.
    let s = paper_with(&[([0.0, 8.0, 45.0], 10.0)]);
    let mut sink = Collected::new(f32::INFINITY);
    sweep_all(&s, "L", 0.0, &mut sink);
    assert!(sink.offered.is_empty());
    assert_eq!(sink.near_misses.len(), 1);
    let (min_clearance, x) = sink.near_misses[0];
    assert_eq!(min_clearance, -2.0);
    let x = x.expect("the line's variables");
    assert_eq!(x[..2], [0.0, 90.0 / s.needle.curvature_radius]);
    assert!(x[2..MAX_VARS].iter().all(|v| *v == 0.0));
}

#[test]
fn a_sink_whose_bound_no_path_beats_gets_nothing() {
    // No path is shorter than the 90 mm to the target: a bound of a1 * 90 + a4 N refuses all.
    let s = Scenario::paper();
    for (word, bound) in [("RL", 94.0), ("LRL", 96.0)] {
        let mut sink = Collected::new(bound);
        assert_eq!(sweep_all(&s, word, 0.0, &mut sink), 0, "{word}");
        assert!(sink.offered.is_empty() && sink.near_misses.is_empty());
    }
}
