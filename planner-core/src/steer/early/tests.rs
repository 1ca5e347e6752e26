//! Tests of the turn made early.

use super::super::aimed::tests::{off_course, open_space};
use super::*;
use crate::execute::schedule::Op;
use crate::model::kinematics::V3;
use crate::model::scenario::{Obstacle, Workspace};

/// Told the tissue changes ahead, a replan turns early although the plan's share still
/// reaches: the full curvature first, then a spun line. Told nothing, it keeps the share.
#[test]
fn a_replan_told_of_layers_turns_early() {
    let scenario = open_space();
    let pushes = |input: &ReplanInput| -> std::vec::Vec<f32> {
        let (found, _, _) = super::super::replan::replan(input, &[]);
        let found = found.expect("a continuation");
        assert!(
            found.prediction.target_error < 1e-3,
            "{:?}",
            found.prediction
        );
        found
            .steps
            .iter()
            .filter_map(|s| match s.op {
                Op::InsertDuty { duty, .. } => Some(duty),
                _ => None,
            })
            .collect()
    };
    let told = ReplanInput {
        turn_early: true,
        ..off_course(&scenario, 0.8)
    };
    assert_eq!(pushes(&told), [1.0, 0.0]);
    let untold = ReplanInput {
        turn_early: false,
        ..told
    };
    assert!(
        pushes(&untold).iter().all(|&d| d <= 0.8),
        "{:?}",
        pushes(&untold)
    );
}

/// The early turn keeps a wider margin than a continuation that must be taken: with a
/// sphere beside its path, at a margin the turn spent first keeps but the early turn does
/// not, only the first is found, and only by a replan not told to turn early.
#[test]
fn the_early_turn_keeps_a_wider_margin() {
    let mut scenario = open_space();
    let beside = Obstacle {
        center: [-2.0, 0.0, 70.0],
        radius: 1.0,
    };
    scenario.obstacles.push(beside).unwrap();
    let floor = scenario.options.min_clearance;
    let probe = ReplanInput {
        margin: 1e-3,
        ..off_course(&scenario, 0.8)
    };
    let clearance = front_loaded(&probe, &(0, 0))
        .expect("a continuation")
        .prediction
        .min_clearance;
    assert!(clearance > floor + 0.5, "{clearance}");
    let margin = (clearance - floor) / (0.5 * (1.0 + EARLY_TURN_MARGIN));
    let input = ReplanInput { margin, ..probe };
    assert!(front_loaded(&input, &(0, 0)).is_some());
    assert!(turned_early(&input, &(0, 0)).is_none());
    // A replan told to turn early tries that alone; refused, the next reading's replan
    // tries the rest, which the narrower margin lets through.
    let replan = super::super::replan::replan;
    let early_only = ReplanInput {
        turn_early: true,
        ..input
    };
    assert!(replan(&early_only, &[]).0.is_none());
    let the_rest = ReplanInput {
        turn_early: false,
        ..input
    };
    assert!(replan(&the_rest, &[]).0.is_some());
}

/// With a sphere on the whole turn's line (10 mm to turn over 40 mm), the early turn makes
/// part of it: an arc at the full curvature, then the arc through the target at less than
/// the plan's share, which reaches the target and keeps the wider margin; never an arc that
/// needs more than the plan's share, and nothing for a plan keeping nothing in hand.
#[test]
fn the_early_turn_makes_part_of_the_turn_near_an_obstacle() {
    let open = open_space();
    let probe = ReplanInput {
        target: V3::new(10.0, 0.0, 90.0),
        margin: 1e-3,
        ..off_course(&open, 0.8)
    };
    // A sphere touching the whole turn's line half way along it.
    let whole = front_loaded(&probe, &(0, 0)).expect("the whole turn");
    let ops: std::vec::Vec<Op> = whole.steps.iter().map(|s| s.op).collect();
    let [_, Op::InsertDuty { length_mm: arc, .. }, _] = ops[..] else {
        panic!("{ops:?}")
    };
    let r = open.needle.curvature_radius;
    let phi = arc / r;
    let turned = V3::new(
        r * (1.0 - crate::fmath::cos(phi)),
        0.0,
        50.0 + r * crate::fmath::sin(phi),
    );
    let on_line = 0.5 * (turned + probe.target);
    let beside = Obstacle {
        center: [on_line.x + 1.2, 0.0, on_line.z],
        radius: 1.0,
    };
    let mut scenario = open.clone();
    scenario.obstacles.push(beside).unwrap();
    let input = ReplanInput {
        scenario: &scenario,
        margin: 0.3,
        ..probe
    };
    assert!(front_loaded(&input, &(0, 0)).is_none());
    let found = turned_early(&input, &(0, 0)).expect("part of the turn");
    assert!(
        found.prediction.target_error < 1e-3,
        "{:?}",
        found.prediction
    );
    let floor = scenario.options.min_clearance;
    let clearance = found.prediction.min_clearance;
    assert!(clearance >= floor + EARLY_TURN_MARGIN * 0.3, "{clearance}");
    let pushes: std::vec::Vec<(f32, f32)> = found
        .steps
        .iter()
        .filter_map(|s| match s.op {
            Op::InsertDuty { length_mm, duty } => Some((length_mm, duty)),
            _ => None,
        })
        .collect();
    let [(part, full), (_, then)] = pushes[..] else {
        panic!("{pushes:?}")
    };
    assert_eq!(full, 1.0);
    assert!(
        part < arc && then > 0.0 && then <= 0.8 + DUTY_SLACK,
        "{pushes:?}"
    );
    // The plan keeping less in hand than that arc needs: no share passes.
    let tight = ReplanInput {
        arc_duty: 0.5 * then,
        ..input
    };
    let tight_found = turned_early(&tight, &(0, 0));
    assert!(tight_found.is_none(), "{:?}", tight_found.map(|f| f.steps));
    let no_reserve = ReplanInput {
        arc_duty: 1.0,
        ..input
    };
    assert!(turned_early(&no_reserve, &(0, 0)).is_none());
}

/// Part of the turn, then the arc: the arc ends on the target and the shares run from the
/// whole turn (a line after it) to none (the one arc through the target).
#[test]
fn part_of_the_turn_then_the_arc_ends_on_the_target() {
    let scenario = open_space();
    let input = ReplanInput {
        target: V3::new(10.0, 0.0, 90.0),
        ..off_course(&scenario, 0.8)
    };
    let turn = Turn::of(&input).expect("reachable");
    let r = input.radius;
    let mut last_duty = 0.0f32;
    for k in (1..TURN_SHARES).rev() {
        let share = k as f32 / TURN_SHARES as f32;
        let (arc, then) = part_then_arc(&input, &turn, share).expect("reachable");
        let phi = arc / r;
        let (sin, cos) = crate::fmath::sincos(phi);
        let start = V3::new(r * (1.0 - cos), 0.0, 50.0 + r * sin);
        // The second arc, of radius r / duty, bending on towards +x.
        let (r2, psi) = (r / then.duty, then.length * then.duty / r);
        let centre = start + V3::new(r2 * cos, 0.0, -r2 * sin);
        let angle = phi + psi;
        let end = centre
            + V3::new(
                -r2 * crate::fmath::cos(angle),
                0.0,
                r2 * crate::fmath::sin(angle),
            );
        assert!((end - input.target).norm() < 1e-3, "{share}: {end:?}");
        // Less of the turn made first leaves more for the arc after it.
        assert!(then.duty > last_duty, "{share}: {then:?}");
        last_duty = then.duty;
    }
}

/// The screen measures what the check measures: on the ideal arcs, a share's clearance from
/// spheres (in 3-D) and from cylinders (in the paper's plane) is the prediction's to two
/// hundredths of a millimetre, for every share.
#[test]
fn the_screen_measures_the_clearance_the_check_does() {
    for workspace in [Workspace::Space, Workspace::PlaneYz] {
        let mut scenario = open_space();
        scenario.options.workspace = workspace;
        for c in [
            [0.0f32, 3.0, 60.0],
            [1.0, 6.0, 75.0],
            [-1.0, 2.0, 70.0],
            [0.5, 9.0, 85.0],
        ] {
            let beside = Obstacle {
                center: c,
                radius: 0.5,
            };
            scenario.obstacles.push(beside).unwrap();
        }
        let input = ReplanInput {
            target: V3::new(0.0, 10.0, 90.0),
            margin: -100.0,
            ..off_course(&scenario, 0.8)
        };
        let turn = Turn::of(&input).expect("reachable");
        for k in 1..TURN_SHARES {
            let share = k as f32 / TURN_SHARES as f32;
            let (arc, then) = part_then_arc(&input, &turn, share).expect("reachable");
            let screened = screened_clearance(&input, &turn, arc, then);
            let checked = share_of_turn(&input, &turn, arc, then, &(0, 0))
                .expect("no floor")
                .prediction
                .min_clearance;
            assert!(
                (screened - checked).abs() < 0.02,
                "{workspace:?} {share}: {screened} {checked}"
            );
        }
        // The whole turn: its arc, then the line.
        let (arc, line) = whole_turn(&input, &turn);
        let screened = screened_clearance(&input, &turn, arc, line);
        let checked = front_loaded(&input, &(0, 0))
            .expect("no floor")
            .prediction
            .min_clearance;
        assert!(
            (screened - checked).abs() < 0.02,
            "{workspace:?} whole: {screened} {checked}"
        );
    }
}
