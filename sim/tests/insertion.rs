//! The insertion simulator: no perturbation reproduces the plan; each perturbation alone moves
//! the tip the way its physics says; a seed repeats bit for bit; bad input is a typed error.

use needle_sim::{open_loop, PerturbError, Perturbation, Planned, Run, World};
use planner_core::execute::nominal;
use planner_core::execute::schedule::{schedule, Op, Schedule};
use planner_core::model::scenario::Workspace;
use planner_core::{plan, Form, FormOutcome, Scenario};
use std::ops::ControlFlow;

/// The paper's obstacles as spheres and a target off the plane: a 3-D plan that rolls its bevel.
fn space() -> Scenario {
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    s.target.position = [9.0, 6.0, 86.0];
    s
}

fn feasible(scenario: &Scenario) -> Vec<FormOutcome> {
    let report = plan(scenario).unwrap();
    report
        .forms
        .iter()
        .filter(|o| o.feasible)
        .cloned()
        .collect()
}

fn form(scenario: &Scenario, word: &str) -> (FormOutcome, Schedule) {
    let f = Form::parse(word).unwrap();
    let o = feasible(scenario)
        .into_iter()
        .find(|o| o.form == f)
        .unwrap();
    let s = schedule(scenario, &o).unwrap();
    (o, s)
}

fn only(key: &str, value: f32) -> Perturbation {
    let mut p = Perturbation::none();
    p.set(key, value).unwrap();
    p
}

fn run(scenario: &Scenario, word: &str, p: &Perturbation, seed: u64) -> Run {
    let (o, s) = form(scenario, word);
    open_loop(scenario, &Planned::of(scenario, &o), &s, p, seed).unwrap()
}

fn end(r: &Run) -> [f32; 3] {
    *r.points.last().unwrap()
}

#[test]
fn no_perturbation_follows_every_plan() {
    let rolls = |o: &FormOutcome| o.segments.iter().any(|g| g.bevel_deg.abs() % 180.0 > 1.0);
    assert!(
        feasible(&space()).iter().any(rolls),
        "the 3-D plans roll the bevel"
    );
    for scenario in [Scenario::paper(), space()] {
        for o in feasible(&scenario) {
            let s = schedule(&scenario, &o).unwrap();
            let planned = Planned::of(&scenario, &o);
            let r = open_loop(&scenario, &planned, &s, &Perturbation::none(), 3).unwrap();
            let nominal_end = nominal::execute(&scenario, &s, |_, _, _, _| {}).p;
            let e = end(&r);
            let miss =
                (nominal_end - planner_core::model::kinematics::V3::new(e[0], e[1], e[2])).norm();
            assert!(miss < 1e-3, "{}: end {miss}", o.form);
            assert!(r.path_max < 1e-3, "{}: deviation {}", o.form, r.path_max);
            assert!((r.target_error - o.target_error).abs() < 1e-3, "{}", o.form);
            assert!(!r.collided);
            assert!(
                (r.min_clearance - o.min_clearance).abs() < 0.05,
                "{}",
                o.form
            );
            assert_eq!(r.steps, s.steps.to_vec());
            for w in r.points.windows(2) {
                let d: f32 = (0..3)
                    .map(|k| (w[1][k] - w[0][k]).powi(2))
                    .sum::<f32>()
                    .sqrt();
                assert!(d <= 1.0 + 1e-4, "{}: points {d} apart", o.form);
            }
        }
    }
}

/// The signed turn of the path's end heading in the plane (y-z), from the entry's heading.
fn turn_of(r: &Run) -> f32 {
    let n = r.points.len();
    let h = |a: [f32; 3], b: [f32; 3]| (b[1] - a[1]).atan2(b[2] - a[2]);
    h(r.points[n - 2], r.points[n - 1]) - h(r.points[0], r.points[1])
}

#[test]
fn stiffer_tissue_ends_short_of_the_turn() {
    let scenario = Scenario::paper();
    let planned = turn_of(&run(&scenario, "R", &Perturbation::none(), 0));
    let mut seen = [false; 2];
    for seed in 0..12 {
        let r = run(&scenario, "R", &only("curvature_spread", 0.1), seed);
        let f = r.drawn.curvature_factor;
        let turn = turn_of(&r);
        // A smaller factor (stiffer tissue, a larger radius) turns less, and the other way.
        assert_eq!(
            turn.abs() < planned.abs(),
            f < 1.0,
            "seed {seed}: factor {f}"
        );
        assert!(r.path_max > 0.1, "seed {seed}");
        seen[usize::from(f < 1.0)] = true;
    }
    assert_eq!(seen, [true, true]);
}

#[test]
fn a_torsional_lag_turns_the_bend_plane() {
    let scenario = Scenario::paper();
    let lag = 0.2;
    let r = run(&scenario, "LRR", &only("torsion_lag_deg_per_mm", lag), 1);
    let none = run(&scenario, "LRR", &Perturbation::none(), 1);
    // The shaft has play of lag * depth either side: LRR's spun line leaves the tip lag * d past
    // the base (on the side of the spin's first turn, +), so the first rotation (+180 at depth d)
    // turns the tip by 180 - 2 lag d; every rotation turns it less than the base, by at most that.
    let mut depth = 0.0;
    let mut rotations = 0;
    for (step, draw) in r.steps.iter().zip(&r.drawn.steps) {
        match step.op {
            Op::Rotate { angle_deg } => {
                let short = angle_deg.abs() - draw.tip_rotation_deg.abs();
                assert!(
                    short > 0.1 && short <= 2.0 * lag * depth + 1e-3,
                    "{draw:?} at {depth}"
                );
                if rotations == 0 {
                    let want = angle_deg - 2.0 * lag * depth;
                    assert!(
                        (draw.tip_rotation_deg - want).abs() < 1e-3,
                        "{draw:?} vs {want}"
                    );
                }
                rotations += 1;
            }
            op => depth += op.inserted_mm(),
        }
    }
    assert!(rotations >= 1);
    // The plan stays in the y-z plane; the lagged bevel bends the path out of it.
    assert!(end(&none)[0].abs() < 1e-4);
    assert!(end(&r)[0].abs() > 0.5, "end x {}", end(&r)[0]);
    assert!(r.path_max > 0.5);
    // Before the first rotation nothing moved.
    assert_eq!(r.points[..30], none.points[..30]);
}

#[test]
fn the_in_plane_deviation_sees_only_what_stays_in_the_plane() {
    let scenario = Scenario::paper();
    // A curvature error keeps the path in the plan's plane: both deviations agree.
    let r = run(&scenario, "R", &only("curvature_spread", 0.1), 2);
    let (rms, max) = (r.path_rms_in_plane.unwrap(), r.path_max_in_plane.unwrap());
    assert!(r.path_rms > 0.1);
    assert!((rms - r.path_rms).abs() < 1e-4 && (max - r.path_max).abs() < 1e-4);
    // A torsional lag rolls LRR's bend planes out of the plane: the view across it sees little.
    let r = run(&scenario, "LRR", &only("torsion_lag_deg_per_mm", 0.2), 2);
    let rms = r.path_rms_in_plane.unwrap();
    assert!(
        r.path_rms > 0.5 && rms < 0.1 * r.path_rms,
        "{rms} vs {}",
        r.path_rms
    );
    // Never more than the 3-D deviation; none in a 3-D scenario.
    let r = run(&scenario, "RL", &Perturbation::default(), 4);
    assert!(r.path_rms_in_plane.unwrap() <= r.path_rms + 1e-6);
    assert!(r.path_max_in_plane.unwrap() <= r.path_max + 1e-6);
    let r = run(&space(), "RL", &Perturbation::default(), 4);
    assert_eq!((r.path_rms_in_plane, r.path_max_in_plane), (None, None));
}

#[test]
fn a_target_shift_moves_the_imaged_target_and_nothing_else() {
    let scenario = Scenario::paper();
    let (o, s) = form(&scenario, "RL");
    let p = only("target_shift_mm", 2.0);
    let mut world = World::new(&scenario, &s.posture, &p, 5).unwrap();
    let shift = world.drawn().target_shift_mm;
    let t = scenario.target.position;
    let mut imaged = Vec::new();
    for step in &s.steps {
        world.execute(step, |m| {
            imaged.push(m.target);
            ControlFlow::Continue(())
        });
    }
    for m in &imaged {
        for k in 0..3 {
            assert!((m[k] - (t[k] + shift[k])).abs() < 1e-5);
        }
    }
    let r = open_loop(&scenario, &Planned::of(&scenario, &o), &s, &p, 5).unwrap();
    let size = shift.iter().map(|x| x * x).sum::<f32>().sqrt();
    assert!(size > 0.5);
    assert!(r.path_max < 1e-3, "the path does not move");
    assert!((r.target_error - size).abs() < 0.01);
}

#[test]
fn the_tracker_is_noisy_but_leaves_the_path_alone() {
    let scenario = Scenario::paper();
    let (o, s) = form(&scenario, "RL");
    let mut p = only("tracker_position_mm", 0.5);
    p.set("measure_every_mm", 0.5).unwrap();
    let mut world = World::new(&scenario, &s.posture, &p, 9).unwrap();
    let (mut n, mut sq) = (0usize, 0.0f32);
    for step in &s.steps {
        let before = world.points().len();
        world.execute(step, |m| {
            n += 1;
            let _ = m;
            ControlFlow::Continue(())
        });
        assert!(world.points().len() > before);
    }
    let m = world.measure();
    for k in 0..3 {
        let e = m.position[k] - world.tip().p[k];
        sq += e * e;
    }
    // About two measurements a millimetre, over about 92 mm.
    assert!((170..=200).contains(&n), "{n} measurements");
    assert!(sq > 0.0);
    let quiet = open_loop(
        &scenario,
        &Planned::of(&scenario, &o),
        &s,
        &Perturbation::none(),
        9,
    )
    .unwrap();
    assert!(world.points().len() > quiet.points.len());
    let noisy = open_loop(&scenario, &Planned::of(&scenario, &o), &s, &p, 9).unwrap();
    assert!(noisy.path_max < 1e-3);
}

#[test]
fn a_controller_can_break_a_step_off() {
    let scenario = Scenario::paper();
    let (_, s) = form(&scenario, "R");
    let mut world = World::new(&scenario, &s.posture, &Perturbation::default(), 2).unwrap();
    let done = world.execute(&s.steps[0], |m| {
        if m.depth_mm >= 10.0 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    assert!(done.interrupted);
    assert!((done.inserted_mm - 10.0).abs() < 1.0, "{done:?}");
    assert!(
        matches!(world.executed()[0].op, Op::Insert { length_mm } if length_mm == done.inserted_mm)
    );
}

/// A step broken off is recorded as what the driver did of it: its share of the push and of the
/// time, a spin's turns finished to an even number, not the whole step's; a step done whole is
/// recorded as planned.
#[test]
fn a_step_broken_off_records_the_time_and_turns_it_took() {
    let scenario = Scenario::paper();
    let (_, s) = form(&scenario, "LRR");
    let spin = s.steps[0];
    let Op::InsertSpin { length_mm, turns } = spin.op else {
        panic!("LRR starts with a spun line: {:?}", spin.op);
    };
    let mut world = World::new(&scenario, &s.posture, &Perturbation::default(), 2).unwrap();
    let done = world.execute(&spin, |m| {
        if m.depth_mm >= length_mm / 4.0 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    assert!(done.interrupted);
    let share = done.inserted_mm / length_mm;
    assert!((0.2..0.35).contains(&share), "{share}");
    let part = world.executed()[0];
    let Op::InsertSpin { turns: turned, .. } = part.op else {
        panic!("{:?}", part.op);
    };
    // The spin finishes the pair of turns it is in: even, at or above its share of the turns.
    let whole = (turns as f32 * share).ceil() as u32;
    assert_eq!(turned, whole + whole % 2);
    assert!(turned < turns / 2, "{turned} of {turns}");
    // Its time: the share of the push, or those turns at the step's spin rate when longer.
    let spun = spin.duration_s * turned as f32 / turns as f32;
    assert_eq!(
        part.duration_s,
        (spin.duration_s * share).max(spun),
        "{part:?}"
    );
    assert!(part.duration_s < 0.4 * spin.duration_s);
    // The arc after the rotation, done whole, is recorded exactly as planned.
    for step in &s.steps[1..3] {
        world.execute(step, |_| ControlFlow::Continue(()));
    }
    assert!(matches!(s.steps[2].op, Op::Insert { .. }));
    assert_eq!(world.executed()[2], s.steps[2]);
}

#[test]
fn a_seed_repeats_bit_for_bit() {
    let p = Perturbation::default();
    for scenario in [Scenario::paper(), space()] {
        let a = run(&scenario, "RL", &p, 42);
        let b = run(&scenario, "RL", &p, 42);
        let bits = |r: &Run| -> Vec<u32> {
            let mut v: Vec<u32> = r.points.iter().flatten().map(|x| x.to_bits()).collect();
            v.extend([
                r.target_error.to_bits(),
                r.path_rms.to_bits(),
                r.min_clearance.to_bits(),
            ]);
            v
        };
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a, b);
        let c = run(&scenario, "RL", &p, 43);
        assert_ne!(bits(&a), bits(&c));
    }
}

#[test]
fn bad_perturbations_are_typed_errors() {
    let scenario = Scenario::paper();
    let (_, s) = form(&scenario, "R");
    let mut p = Perturbation {
        curvature_spread: -0.1,
        ..Perturbation::default()
    };
    let e = World::new(&scenario, &s.posture, &p, 0).err().unwrap();
    assert!(
        matches!(
            e,
            PerturbError::OutOfRange {
                key: "curvature_spread",
                ..
            }
        ),
        "{e}"
    );
    p = Perturbation::default();
    p.measure_every_mm = 0.0;
    assert!(World::new(&scenario, &s.posture, &p, 0).is_err());
    p.measure_every_mm = f32::INFINITY;
    assert!(World::new(&scenario, &s.posture, &p, 0).is_err());
}

/// A duty-cycled push executed without perturbation ends where its curvature says (an arc of
/// radius r / duty in the bevel's plane, as the nominal model has it); with the default
/// perturbation it strays both ways, by its curvature error and its drift.
#[test]
fn a_duty_cycled_push_bends_by_its_share_of_the_curvature() {
    use planner_core::execute::nominal::execute_from;
    use planner_core::execute::schedule::duty_step;
    use planner_core::SegmentKind;
    let scenario = Scenario::paper();
    let (_, s) = form(&scenario, "R");
    let r = scenario.needle.curvature_radius;
    for duty in [0.0, 0.25, 0.5, 1.0] {
        let step = duty_step(&scenario.driver, 40.0, duty);
        let mut world = World::new(&scenario, &s.posture, &Perturbation::none(), 1).unwrap();
        let start = world.tip();
        world.execute(&step, |_| ControlFlow::Continue(()));
        let nominal = execute_from(start, &[step], r, |_, _, _, _| {});
        let expected = if duty > 0.0 {
            start.advanced(SegmentKind::Arc, 40.0, r / duty)
        } else {
            start.advanced(SegmentKind::Line, 40.0, r)
        };
        assert!((world.tip().p - expected.p).norm() < 1e-3, "duty {duty}");
        assert!((nominal.p - expected.p).norm() < 1e-4, "duty {duty}");
        // The bend is towards the bevel and grows with the duty.
        let side = (expected.p - start.p).dot(&start.e2());
        assert!(
            (side - r / duty.max(1e-9) * (1.0 - (40.0 * duty / r).cos())).abs() < 1e-3
                || duty == 0.0
        );
    }
    let step = duty_step(&scenario.driver, 40.0, 0.5);
    let ends: Vec<_> = (0..50)
        .map(|seed| {
            let mut w = World::new(&scenario, &s.posture, &Perturbation::default(), seed).unwrap();
            w.execute(&step, |_| ControlFlow::Continue(()));
            (w.tip().p, w.drawn().steps[0])
        })
        .collect();
    assert!(ends
        .iter()
        .all(|(_, d)| d.drift != [0.0; 2] && d.segment_factor != 1.0));
    let spread = ends
        .iter()
        .map(|(p, _)| (p - ends[0].0).norm())
        .fold(0.0f32, f32::max);
    assert!(spread > 0.1, "{spread}");
}
