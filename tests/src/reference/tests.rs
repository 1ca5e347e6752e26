//! Unit tests of the reference planner: closed forms, the paper's figures, self-consistency.

use super::complete::{arc_arc, arc_line, line_arc};
use super::frame::V3;
use super::problem::{Cand, Problem};
use super::random::random_scenario;
use super::*;
use needle_sim::random::{seeded, Draw};
use planner_core::check::check;
use planner_core::model::form::catalogue;
use planner_core::model::scenario::Workspace;
use planner_core::{Insertion, SegmentPlan};

fn form(word: &str) -> Form {
    Form::parse(word).unwrap()
}

fn solve(s: &Scenario, word: &str) -> Option<RefSolution> {
    solve_form(s, form(word), Effort(1.0))
}

#[test]
fn single_arc_has_the_closed_form_length() {
    let mut rng = seeded(11);
    for plane in [true, false] {
        for _ in 0..6 {
            let mut s = Scenario::paper();
            s.obstacles.clear();
            s.options.workspace = if plane {
                Workspace::PlaneYz
            } else {
                Workspace::Space
            };
            let x = if plane { 0.0 } else { rng.range(-20.0, 20.0) };
            s.target.position = [
                x as f32,
                rng.range(-30.0, 30.0) as f32,
                rng.range(40.0, 110.0) as f32,
            ];
            let t = V3::from_f32(s.target.position).norm();
            let rho = f64::from(s.needle.curvature_radius);
            let expect = rho * 2.0 * (t / (2.0 * rho)).asin();
            let sol = solve(&s, "R").expect("an arc reaches the target");
            assert!(
                (sol.length - expect).abs() < 1e-6,
                "{} vs {expect}",
                sol.length
            );
            // No obstacles: F = L + 2 N.
            assert!((sol.objective - expect - 2.0).abs() < 1e-6);
        }
    }
}

#[test]
fn reproduces_the_papers_figures() {
    let s = Scenario::paper();
    let table: Vec<(Form, Option<RefSolution>)> = catalogue()
        .into_iter()
        .filter(|f| f.len() <= 3)
        .map(|f| (f, solve_form(&s, f, Effort(1.0))))
        .collect();
    let get = |w: &str| {
        table
            .iter()
            .find(|(f, _)| *f == form(w))
            .and_then(|(_, r)| r.clone())
    };
    let best_of = |n: usize| {
        table
            .iter()
            .filter(|(f, r)| f.len() == n && r.is_some())
            .min_by(|a, b| {
                let (x, y) = (a.1.as_ref().unwrap(), b.1.as_ref().unwrap());
                x.objective.total_cmp(&y.objective)
            })
            .map(|(f, _)| f.to_string())
            .unwrap()
    };
    let r = get("R").unwrap();
    assert!((r.length - 99.94).abs() < 0.005, "L(R) = {}", r.length);
    assert!(get("L").is_none(), "the straight line hits an obstacle");
    assert_eq!(best_of(1), "R");
    assert_eq!(best_of(2), "RL");
    assert_eq!(best_of(3), "LRL");
    let (rl, lrl) = (get("RL").unwrap(), get("LRL").unwrap());
    let overall = table
        .iter()
        .filter_map(|(_, r)| r.as_ref())
        .min_by(|a, b| a.objective.total_cmp(&b.objective))
        .unwrap();
    assert_eq!(overall.form, form("RL"));
    assert!(
        (r.length - rl.length - 8.11).abs() <= 0.05,
        "{}",
        r.length - rl.length
    );
    assert!(
        (rl.length - lrl.length - 0.66).abs() <= 0.05,
        "{}",
        rl.length - lrl.length
    );
}

fn as_plans(sol: &RefSolution) -> (Insertion, Vec<SegmentPlan>) {
    let insertion = Insertion {
        theta1_deg: sol.theta1_deg as f32,
        theta2_deg: sol.theta2_deg as f32,
        ..Insertion::default()
    };
    let segs = sol
        .segments
        .iter()
        .map(|s| SegmentPlan {
            kind: s.kind,
            length: s.length as f32,
            bevel_deg: s.bevel_deg as f32,
        })
        .collect();
    (insertion, segs)
}

/// The reference's paths, rebuilt from their reported numbers by the reference and by
/// planner-core's own independent check, end on the target clear of every obstacle: the two
/// implementations agree on the model's conventions.
#[test]
fn solutions_are_consistent_with_planner_core_conventions() {
    let mut scenarios = vec![Scenario::paper()];
    for seed in 0..3 {
        scenarios.push(random_scenario(seed, true));
    }
    scenarios.push(random_scenario(0, false));
    // Only long looping paths (about 330 mm, arcs of 145 mm on one circle) reach this target.
    scenarios.push(random_scenario(102, true));
    for s in &scenarios {
        for f in s.options.selected_forms().iter() {
            let Some(sol) = solve_form(s, f, Effort(0.5)) else {
                continue;
            };
            let ev = evaluate_solution(s, &sol);
            assert!(
                ev.target_error < 1e-6,
                "{sol}: end error {}",
                ev.target_error
            );
            assert!((ev.objective - sol.objective).abs() < 1e-9);
            assert!(is_feasible(s, &ev));
            if s.options.workspace == Workspace::PlaneYz {
                assert_eq!(sol.theta2_deg, 0.0);
                for seg in sol.segments.iter().filter(|g| g.kind == SegmentKind::Arc) {
                    let b = seg.bevel_deg.abs();
                    assert!(b < 1e-9 || (b - 180.0).abs() < 1e-9, "{sol}");
                }
            }
            let (ins, segs) = as_plans(&sol);
            let v = check(s, f, &ins, &segs);
            assert!(
                v.target_error < 1e-3,
                "{sol}: planner-core sees end error {}",
                v.target_error
            );
            assert!(
                (f64::from(v.min_clearance) - sol.min_clearance).abs() < 1e-3,
                "{sol}: planner-core sees clearance {}",
                v.min_clearance
            );
        }
    }
}

/// In space the plane's paths are still available, so no form can be worse there.
#[test]
fn space_optimum_is_no_worse_than_the_plane_optimum() {
    let plane = Scenario::paper();
    let mut space = plane.clone();
    space.options.workspace = Workspace::Space;
    for w in ["R", "RL", "LR", "RR", "LRL"] {
        let p = solve(&plane, w).unwrap();
        let s = solve(&space, w).unwrap();
        assert!(
            s.objective <= p.objective + 1e-6,
            "{w}: space {s} plane {p}"
        );
    }
}

/// More search does not find anything better: the default effort has converged.
#[test]
fn more_effort_finds_nothing_better() {
    for (seed, plane) in [(1, true), (2, true), (4, false)] {
        let s = random_scenario(seed, plane);
        for w in ["RL", "LRL", "RRL"] {
            let a = solve(&s, w).map(|r| r.objective);
            let b = solve_form(&s, form(w), Effort(3.0)).map(|r| r.objective);
            match (a, b) {
                (Some(a), Some(b)) => assert!(a <= b + 1e-5, "seed {seed} {w}: {a} then {b}"),
                (a, b) => assert_eq!(a.is_some(), b.is_some(), "seed {seed} {w}"),
            }
        }
    }
}

/// Every closed-form completion ends exactly on the target, from random frames.
#[test]
fn completions_end_on_the_target() {
    let mut rng = seeded(5);
    let mut pb = Problem::new(&Scenario::paper());
    let mut out = Vec::new();
    let mut count = 0;
    for i in 0..3000 {
        pb.plane = i % 2 == 0;
        pb.target = V3::new(
            if pb.plane {
                0.0
            } else {
                rng.range(-60.0, 60.0)
            },
            rng.range(-80.0, 80.0),
            rng.range(-20.0, 150.0),
        );
        let t1 = rng.range(-1.0, 1.0);
        let t2 = if pb.plane { 0.0 } else { rng.range(-1.0, 1.0) };
        let base = Cand::new(t1, t2);
        let f = pb.first_frame(t1, t2);
        let roll = if pb.plane {
            if rng.unit() < 0.5 {
                0.0
            } else {
                core::f64::consts::PI
            }
        } else {
            rng.range(-3.2, 3.2)
        };
        out.clear();
        arc_line(&pb, &f, &base, 2, &mut out);
        line_arc(&pb, &f, &base, 2, &mut out);
        arc_arc(&pb, &f, roll, &base, (2, 2), &mut out);
        for c in &out {
            if c.segs().iter().any(|s| s.length < 0.0) {
                continue; // a negative root: rejected by the bounds later
            }
            let (frames, n) = c.frames(&pb);
            let err = (frames[n].p - pb.target).norm();
            assert!(err < 1e-8, "{c:?} misses by {err}");
            count += 1;
        }
    }
    assert!(count > 3000, "only {count} completions");
}
