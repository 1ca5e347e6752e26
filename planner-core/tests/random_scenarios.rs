//! Property tests on random scenarios: planning never panics, every plan reported feasible passes
//! the independent check, and the same scenario gives the same plan twice.

use planner_core::check::check;
use planner_core::model::scenario::{Obstacle, Workspace};
use planner_core::{plan, PlanError, Scenario};
use proptest::prelude::*;

fn scenario(plane: bool, target: [f32; 3], obstacles: &[([f32; 3], f32)]) -> Scenario {
    let mut s = Scenario::paper();
    s.options.workspace = if plane {
        Workspace::PlaneYz
    } else {
        Workspace::Space
    };
    s.options.max_control_degree = 3;
    s.target.position = if plane {
        [0.0, target[1], target[2]]
    } else {
        target
    };
    s.obstacles.clear();
    for &(mut c, r) in obstacles {
        if plane {
            c[0] = 0.0;
        }
        s.obstacles
            .push(Obstacle {
                center: c,
                radius: r,
            })
            .unwrap();
    }
    s
}

fn obstacle() -> impl Strategy<Value = ([f32; 3], f32)> {
    (
        (-30.0f32..30.0, -30.0f32..30.0, 15.0f32..75.0),
        2.0f32..12.0,
    )
        .prop_map(|((x, y, z), r)| ([x, y, z], r))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]
    #[test]
    fn plans_are_checked_and_repeatable(
        plane in any::<bool>(),
        target in (-25.0f32..25.0, -25.0f32..25.0, 60.0f32..100.0),
        obstacles in proptest::collection::vec(obstacle(), 1..6),
    ) {
        let s = scenario(plane, [target.0, target.1, target.2], &obstacles);
        let first = plan(&s);
        let again = plan(&s);
        prop_assert_eq!(format!("{first:?}"), format!("{again:?}"));
        match first {
            Ok(report) => {
                let feasible = report.forms.iter().filter(|o| o.feasible);
                prop_assert_eq!(report.best().is_some(), feasible.clone().count() > 0);
                for o in feasible {
                    let v = check(&s, o.form, &o.insertion, &o.segments);
                    prop_assert!(v.feasible && v.target_error <= s.target.tolerance && v.min_clearance > 0.0);
                    let best = report.best().unwrap();
                    prop_assert!(best.feasible && o.objective >= best.objective);
                }
            }
            Err(e) => prop_assert!(matches!(
                e,
                PlanError::EntryInsideObstacle(_) | PlanError::TargetInsideObstacle(_)
            ), "{:?}", e),
        }
    }
}
