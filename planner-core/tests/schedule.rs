//! The motor schedule: executing it on the nominal needle reproduces the plan; durations follow
//! the driver's speeds; the twist stays within its limit; bad driver settings are typed errors.

use planner_core::check::rebuild;
use planner_core::execute::nominal::{check, execute, peak_twist, sample};
use planner_core::execute::schedule::{schedule, Op, ScheduleError, MIN_SPIN_RAD_PER_MM};
use planner_core::model::scenario::{Obstacle, Workspace};
use planner_core::{plan, Field, Form, FormOutcome, PlanError, Scenario, SegmentKind, SegmentPlan};

fn space() -> Scenario {
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    s.target.position = [12.0, 8.0, 85.0];
    s.obstacles.clear();
    for (c, r) in [
        ([6.0, 4.0, 42.0], 9.0),
        ([-10.0, 14.0, 58.0], 8.0),
        ([22.0, -6.0, 62.0], 7.0),
        ([0.0, -16.0, 28.0], 10.0),
        ([14.0, 18.0, 70.0], 6.0),
    ] {
        s.obstacles
            .push(Obstacle {
                center: c,
                radius: r,
            })
            .unwrap();
    }
    s
}

fn dist(a: planner_core::model::kinematics::V3, b: planner_core::model::kinematics::V3) -> f32 {
    (a - b).norm()
}

/// Every feasible form's schedule, executed, runs through the plan's segment starts and end.
fn reproduces_every_form(scenario: &Scenario) -> usize {
    let report = plan(scenario).unwrap();
    let mut checked = 0;
    for o in report.forms.iter().filter(|o| o.feasible) {
        let s = schedule(scenario, o).unwrap();
        let geo = rebuild(scenario, o.form, &o.insertion, &o.segments);
        let planned: Vec<_> = (0..o.form.len())
            .filter(|&i| geo.lengths[i] > 0.0)
            .map(|i| geo.starts[i].p)
            .collect();
        let mut executed = Vec::new();
        let end = execute(scenario, &s, |start, _, _, _| executed.push(start.p));
        assert_eq!(planned.len(), executed.len(), "{}", o.form);
        for (a, b) in planned.iter().zip(&executed) {
            assert!(dist(*a, *b) < 1e-3, "{}: {a} vs {b}", o.form);
        }
        assert!(dist(end.p, geo.end()) < 1e-3, "{}", o.form);
        let verdict = check(scenario, &s);
        assert!(verdict.feasible, "{}: {verdict:?}", o.form);
        assert!((verdict.min_clearance - o.min_clearance).abs() < 1e-3);
        assert!(s.max_twist_deg <= scenario.driver.max_twist_deg);
        assert_eq!(peak_twist(&s), s.max_twist_deg, "{}", o.form);
        let mut points = Vec::new();
        sample(scenario, &s, 1.0, |p| points.push(p));
        assert!(points.windows(2).all(|w| dist(w[0], w[1]) <= 1.0 + 1e-4));
        checked += 1;
    }
    checked
}

#[test]
fn executing_the_schedule_reproduces_the_plan_for_every_form() {
    assert_eq!(reproduces_every_form(&Scenario::paper()), 9);
    assert!(reproduces_every_form(&space()) >= 8);
}

#[test]
fn durations_follow_the_driver_and_lines_spin_fast_enough() {
    let scenario = Scenario::paper();
    let report = plan(&scenario).unwrap();
    let d = scenario.driver;
    for o in report.forms.iter().filter(|o| o.feasible) {
        let s = schedule(&scenario, o).unwrap();
        let mut total = 0.0;
        for step in &s.steps {
            match step.op {
                Op::Rotate { angle_deg } => {
                    assert_eq!(step.duration_s, angle_deg.abs() / d.rotate_speed)
                }
                Op::Insert { length_mm } => {
                    assert_eq!(step.duration_s, length_mm / d.insert_speed)
                }
                Op::InsertSpin { length_mm, turns } => {
                    assert!(step.duration_s >= length_mm / d.insert_speed);
                    assert_eq!(turns % 2, 0, "whole turns there and back");
                    let spin = turns as f32 * 2.0 * core::f32::consts::PI;
                    assert!(spin >= MIN_SPIN_RAD_PER_MM * length_mm);
                    assert!(turns as f32 / step.duration_s <= d.spin_rate * 1.0001);
                }
                Op::InsertDuty { .. } => panic!("a plan's schedule has no duty-cycled push"),
            }
            total += step.duration_s;
        }
        assert_eq!(s.duration_s, total);
    }
}

fn outcome(word: &str, segments: &[(SegmentKind, f32, f32)]) -> FormOutcome {
    let mut o = FormOutcome::infeasible(Form::parse(word).unwrap());
    o.feasible = true;
    o.insertion.direction = [0.0, 0.0, 1.0];
    for &(kind, length, bevel_deg) in segments {
        o.segments
            .push(SegmentPlan {
                kind,
                length,
                bevel_deg,
            })
            .unwrap();
    }
    o
}

#[test]
fn rotations_go_the_long_way_rather_than_past_the_twist_limit() {
    use SegmentKind::Arc;
    let scenario = Scenario::paper();
    let o = outcome(
        "RRRR",
        &[
            (Arc, 5.0, 0.0),
            (Arc, 5.0, 170.0),
            (Arc, 5.0, 170.0),
            (Arc, 5.0, 170.0),
        ],
    );
    let s = schedule(&scenario, &o).unwrap();
    let angles: Vec<f32> = s
        .steps
        .iter()
        .filter_map(|st| match st.op {
            Op::Rotate { angle_deg } => Some(angle_deg),
            _ => None,
        })
        .collect();
    assert_eq!(angles, [170.0, 170.0, -190.0]);
    assert_eq!(s.max_twist_deg, 340.0);
    // The bevel ends where the plan puts it either way round.
    let geo = rebuild(&scenario, o.form, &o.insertion, &o.segments);
    let end = execute(&scenario, &s, |_, _, _, _| {});
    assert!(dist(end.p, geo.end()) < 1e-3);
}

#[test]
fn bad_driver_settings_and_pathless_outcomes_are_typed_errors() {
    let mut scenario = Scenario::paper();
    let report = plan(&scenario).unwrap();
    let best = report.best().unwrap().clone();
    scenario.driver.insert_speed = 0.0;
    assert_eq!(
        schedule(&scenario, &best),
        Err(ScheduleError::Driver(PlanError::NotPositive(
            Field::InsertSpeed
        )))
    );
    assert_eq!(
        scenario.validate(),
        Err(PlanError::NotPositive(Field::InsertSpeed))
    );
    scenario.driver = Default::default();
    scenario.driver.max_twist_deg = 200.0;
    assert_eq!(
        schedule(&scenario, &best),
        Err(ScheduleError::Driver(PlanError::OutOfRange(
            Field::MaxTwist
        )))
    );
    scenario.driver.max_twist_deg = f32::NAN;
    assert_eq!(
        scenario.validate(),
        Err(PlanError::NotFinite(Field::MaxTwist))
    );
    scenario.driver = Default::default();
    let none = FormOutcome::infeasible(Form::parse("RL").unwrap());
    assert_eq!(schedule(&scenario, &none), Err(ScheduleError::NoPath));
}

/// A plan keeping a fifth of the curvature in hand: its arcs have the wider radius, the schedule
/// pushes them duty-cycled at four fifths, and executing it on the nominal needle (whose duty
/// cycle bends it by that share) ends at the target clear of every obstacle. The same scenario
/// at the full curvature plans tighter arcs.
#[test]
fn a_curvature_reserve_plans_wider_arcs_pushed_duty_cycled() {
    let mut s = space();
    s.options.curvature_reserve = 0.2;
    assert!((s.planned_radius() - 63.7 / 0.8).abs() < 1e-3);
    let report = plan(&s).unwrap();
    let best = report.best().unwrap();
    let sched = schedule(&s, best).unwrap();
    let mut arcs = 0;
    for step in &sched.steps {
        match step.op {
            Op::Insert { .. } => panic!("a plain push in a reserved plan: {:?}", sched.steps),
            Op::InsertDuty { duty, .. } => {
                assert!((duty - 0.8).abs() < 1e-6, "{duty}");
                arcs += 1;
            }
            _ => {}
        }
    }
    assert!(arcs > 0, "{:?}", sched.steps);
    let verdict = check(&s, &sched);
    assert!(verdict.feasible, "{verdict:?}");
    assert!(verdict.target_error < 0.01, "{verdict:?}");
    // The reserved plan's geometry is not the full-curvature one's: the check on the needle's
    // own radius finds its end elsewhere.
    let mut full = s.clone();
    full.options.curvature_reserve = 0.0;
    let g = rebuild(&full, best.form, &best.insertion, &best.segments);
    let t = s.target.position;
    let target = planner_core::model::kinematics::V3::new(t[0], t[1], t[2]);
    let miss = dist(g.end(), target);
    assert!(miss > 1.0, "{miss}");
}

/// A reserve outside [0, 0.5] is refused with its field.
#[test]
fn a_curvature_reserve_out_of_range_is_a_typed_error() {
    for bad in [-0.1, 0.6, f32::NAN] {
        let mut s = space();
        s.options.curvature_reserve = bad;
        let e = plan(&s).unwrap_err();
        assert!(
            matches!(
                e,
                PlanError::OutOfRange(Field::CurvatureReserve)
                    | PlanError::NotFinite(Field::CurvatureReserve)
            ),
            "{bad}: {e:?}"
        );
    }
}
