//! Arbitrary scenarios, inside and well outside the valid ranges, through the same validation the
//! device runs: no panic, an invalid scenario is refused by `plan` with the validation's own
//! error, and every form reported feasible passes the reference's f64 re-check (end point, every
//! clearance, bounds), which shares no code with the core.

use needle_e2e::soundness;
use planner_core::model::scenario::{Obstacle, Workspace};
use planner_core::Scenario;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// A coordinate: a needle's workspace, or (`wild`) sometimes far beyond it or not a number.
fn coordinate(wild: bool) -> BoxedStrategy<f32> {
    if !wild {
        return (-60.0f32..60.0).boxed();
    }
    prop_oneof![
        8 => -60.0f32..60.0,
        1 => -3000.0f32..3000.0,
        1 => prop::sample::select(vec![f32::NAN, f32::INFINITY, 1e30, -0.0]),
    ]
    .boxed()
}

fn point(wild: bool) -> impl Strategy<Value = [f32; 3]> {
    [coordinate(wild), coordinate(wild), coordinate(wild)]
}

/// One of `sane`, or (`wild`) one of `sane` and `bad`.
fn pick(wild: bool, sane: &[f32], bad: &[f32]) -> impl Strategy<Value = f32> {
    let mut all = sane.to_vec();
    if wild {
        all.extend_from_slice(bad);
    }
    prop::sample::select(all)
}

prop_compose! {
    fn scenario(wild: bool)(
        target in point(wild),
        ahead in 40.0f32..120.0,
        obstacles in prop::collection::vec((point(wild), 1.0f32..15.0), 0..5),
        radius in pick(wild, &[20.0, 63.7, 150.0], &[-1.0, 5000.0]),
        tolerance in pick(wild, &[3e-4, 0.01, 0.1, 2.0], &[1e-9, 1e-4, 500.0]),
        weights in [
            pick(wild, &[0.5, 1.0, 3.0], &[-0.5]),
            pick(wild, &[0.0, 1.0, 4.0], &[-1.0, f32::NAN]),
            pick(wild, &[0.0, 1000.0], &[-1.0]),
            pick(wild, &[0.5, 2.0, 6.0], &[-0.5]),
        ],
        degree in if wild { 0u8..4 } else { 1u8..3 },
        plane in any::<bool>(),
        tilt in pick(wild, &[10.0, 45.0, 60.0, 89.0], &[95.0, -1.0]),
    ) -> Scenario {
        let mut s = Scenario::paper();
        s.target.position = [target[0] * 0.3, target[1] * 0.5, ahead + target[2] * 0.1];
        s.obstacles.clear();
        for (center, r) in obstacles {
            let _ = s.obstacles.push(Obstacle { center: [center[0] * 0.3, center[1] * 0.5, ahead * 0.5 + center[2] * 0.3], radius: r });
        }
        s.needle.curvature_radius = radius;
        s.target.tolerance = tolerance;
        s.weights.length = weights[0];
        s.weights.risk = weights[1];
        s.weights.penalty = weights[2];
        s.weights.control = weights[3];
        s.options.max_control_degree = degree;
        s.entry.max_tilt_deg = tilt;
        if plane {
            s.options.workspace = Workspace::PlaneYz;
            s.target.position[0] = 0.0;
            for o in s.obstacles.iter_mut() {
                o.center[0] = 0.0;
            }
        } else {
            s.options.workspace = Workspace::Space;
        }
        s
    }
}

proptest! {
    // A fixed seed: the same cases on every run and in CI (change it to search further).
    #![proptest_config(ProptestConfig {
        cases: 128,
        rng_seed: RngSeed::Fixed(20261201),
        ..ProptestConfig::default()
    })]

    #[test]
    fn wild_scenarios_are_refused_with_the_validation_error_or_planned_soundly(s in scenario(true)) {
        check_plan(&s)?;
    }

    #[test]
    fn every_reported_path_passes_an_independent_f64_check(s in scenario(false)) {
        check_plan(&s)?;
    }
}

/// The shared soundness check (`needle_e2e::soundness`), as a proptest failure.
fn check_plan(s: &Scenario) -> Result<(), TestCaseError> {
    soundness::check_plan(s).map_err(TestCaseError::fail)
}

/// Found by the planner fuzz target: with a 0.4-degree tilt bound every form's posture lay
/// 2e-5 degrees outside it, because cos of the bound rounds to within 6e-8 of 1 in f32. The
/// optimiser now measures the cone by versines (docs/protocol.md, fuzzing).
#[test]
fn a_tilt_bound_of_a_fraction_of_a_degree_is_kept() {
    use planner_core::model::scenario::{Driver, Entry, Needle, Target, Weights};
    let mut s = Scenario::paper();
    s.needle = Needle {
        curvature_radius: 63.7,
        max_arc_deg: 310.7255,
        max_line_length: 130.48225,
        length: planner_core::model::scenario::MAX_NEEDLE_LENGTH_MM,
    };
    s.entry = Entry {
        position: [0.0, 2.319713e-15, -13.882353],
        direction: [-0.69411767, -1.0, 2.319713e-15],
        max_tilt_deg: 0.40512702,
    };
    s.target = Target {
        position: [60.0, -41.251545, 139.41176],
        tolerance: 0.8255779,
    };
    s.obstacles.clear();
    s.weights = Weights {
        length: 4.3137255,
        risk: 8.627451,
        penalty: 1725.4902,
        control: 8.627451,
    };
    s.options.max_control_degree = 4;
    s.options.workspace = Workspace::Space;
    s.options.min_clearance = 4.3137255;
    s.driver = Driver {
        insert_speed: 28.247526,
        rotate_speed: 1.0290048,
        spin_rate: 19.373377,
        max_twist_deg: 1557.2809,
    };
    soundness::check_plan(&s).unwrap();
}

/// Found by the planner fuzz target: a driver inserting at 1e-30 mm/s needs more spin turns for
/// a line than a step holds, and the count overflowed (a wrapped, wrong command in a release
/// build). The driver's speeds now have physical ranges, refused by validation with the key.
#[test]
fn a_driver_too_slow_for_its_spin_is_refused() {
    use planner_core::{Field, PlanError};
    let mut s = Scenario::paper();
    s.driver.insert_speed = 1e-30;
    assert_eq!(
        planner_core::plan_scheduled(&s).err(),
        Some(PlanError::OutOfRange(Field::InsertSpeed))
    );
    s.driver.insert_speed = 1e-3;
    s.driver.spin_rate = 1e3;
    soundness::check_plan(&s).unwrap();
}

/// Found by the planner fuzz target: LRRL kept the minimum clearance (4.3137255 mm) in the
/// planner's f32 arithmetic and its own check, but fell 8e-6 mm short of it measured in f64. The
/// check now passes a clearance only by more than the scenario's resolution, and the optimiser
/// keeps twice that (docs/protocol.md, fuzzing).
#[test]
fn a_minimum_clearance_is_kept_in_exact_arithmetic() {
    use planner_core::model::scenario::{Driver, Entry, Needle, Target, Weights};
    let mut s = Scenario::paper();
    s.needle = Needle {
        curvature_radius: 63.7,
        max_arc_deg: 16.398626,
        max_line_length: 258.45892,
        length: planner_core::model::scenario::MAX_NEEDLE_LENGTH_MM,
    };
    s.entry = Entry {
        position: [14.509804, 14.509804, 14.509804],
        direction: [-0.7254902, 0.7254902, 0.7254902],
        max_tilt_deg: 77.64706,
    };
    s.target = Target {
        position: [43.52941, 60.0, 160.0],
        tolerance: 4.999998,
    };
    s.obstacles.clear();
    s.obstacles
        .push(Obstacle {
            center: [40.0, 29.062332, 103.52941],
            radius: 17.575777,
        })
        .unwrap();
    s.weights = Weights {
        length: 4.3137255,
        risk: 1.5179675,
        penalty: 1725.4902,
        control: 8.749981,
    };
    s.options.max_control_degree = 4;
    s.options.workspace = Workspace::Space;
    s.options.min_clearance = 4.3137255;
    s.driver = Driver {
        insert_speed: 28.247526,
        rotate_speed: 1553.346,
        spin_rate: 19.373377,
        max_twist_deg: 3097.9722,
    };
    soundness::check_plan(&s).unwrap();
}
