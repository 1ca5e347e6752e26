//! Every kind of bad input gets its typed error (and never a panic).

use planner_core::model::scenario::{Obstacle, Workspace, CURVATURE_RADIUS_RANGE_MM};
use planner_core::{plan, plan_scheduled, Field, Form, PlanError, Scenario, SolveStatus};

fn err(s: &Scenario) -> PlanError {
    plan(s).unwrap_err()
}

#[test]
fn non_finite_numbers() {
    let mut s = Scenario::paper();
    s.needle.curvature_radius = f32::NAN;
    assert_eq!(err(&s), PlanError::NotFinite(Field::CurvatureRadius));
    let mut s = Scenario::paper();
    s.target.position[2] = f32::INFINITY;
    assert_eq!(err(&s), PlanError::NotFinite(Field::TargetPosition));
    let mut s = Scenario::paper();
    s.obstacles[1].center[0] = f32::NAN;
    assert_eq!(err(&s), PlanError::NotFinite(Field::ObstacleCenter(1)));
    let mut s = Scenario::paper();
    s.weights.risk = f32::NEG_INFINITY;
    assert_eq!(err(&s), PlanError::NotFinite(Field::WeightRisk));
    let mut s = Scenario::paper();
    s.entry.direction[1] = f32::NAN;
    assert_eq!(err(&s), PlanError::NotFinite(Field::EntryDirection));
}

#[test]
fn non_positive_sizes() {
    let mut s = Scenario::paper();
    s.needle.curvature_radius = 0.0;
    assert_eq!(err(&s), PlanError::NotPositive(Field::CurvatureRadius));
    let mut s = Scenario::paper();
    s.obstacles[2].radius = -1.0;
    assert_eq!(err(&s), PlanError::NotPositive(Field::ObstacleRadius(2)));
    let mut s = Scenario::paper();
    s.target.tolerance = 0.0;
    assert_eq!(err(&s), PlanError::NotPositive(Field::TargetTolerance));
}

#[test]
fn out_of_range_settings() {
    let mut s = Scenario::paper();
    s.entry.max_tilt_deg = 95.0;
    assert_eq!(err(&s), PlanError::OutOfRange(Field::MaxTilt));
    let mut s = Scenario::paper();
    s.weights.control = -1.0;
    assert_eq!(err(&s), PlanError::OutOfRange(Field::WeightControl));
    let mut s = Scenario::paper();
    s.options.min_clearance = -0.5;
    assert_eq!(err(&s), PlanError::OutOfRange(Field::MinClearance));
    let mut s = Scenario::paper();
    s.entry.direction = [0.0; 3];
    assert_eq!(err(&s), PlanError::ZeroDirection);
}

#[test]
fn control_degree_and_form_selection() {
    let mut s = Scenario::paper();
    s.options.max_control_degree = 0;
    assert!(matches!(
        err(&s),
        PlanError::ControlDegreeOutOfRange { requested: 0, .. }
    ));
    s.options.max_control_degree = 9;
    assert!(matches!(
        err(&s),
        PlanError::ControlDegreeOutOfRange {
            requested: 9,
            max: 4
        }
    ));
    s.options.max_control_degree = 2;
    s.options.forms.insert(Form::parse("LRL").unwrap());
    assert_eq!(err(&s), PlanError::NoForms);
}

#[test]
fn entry_or_target_inside_an_obstacle() {
    let mut s = Scenario::paper();
    s.obstacles[0].center = [0.0, 0.0, 5.0];
    assert_eq!(err(&s), PlanError::EntryInsideObstacle(0));
    let mut s = Scenario::paper();
    s.obstacles[2].center = [0.0, 3.0, 88.0];
    assert_eq!(err(&s), PlanError::TargetInsideObstacle(2));
    let mut s = Scenario::paper();
    s.target.position = s.entry.position;
    assert_eq!(err(&s), PlanError::TargetAtEntry);
}

#[test]
fn plane_mode_needs_a_planar_scenario() {
    let mut s = Scenario::paper();
    s.target.position[0] = 3.0;
    assert_eq!(err(&s), PlanError::NotInPlane(Field::TargetPosition));
    let mut s = Scenario::paper();
    s.entry.direction = [0.2, 0.0, 1.0];
    assert_eq!(err(&s), PlanError::NotInPlane(Field::EntryDirection));
    s.options.workspace = Workspace::Space;
    assert!(plan(&s).is_ok());
}

#[test]
fn an_enclosed_target_gives_a_report_without_a_best_form() {
    let mut s = Scenario::paper();
    s.obstacles.clear();
    // A ring of circles around the target, touching each other, leaves no way in.
    for k in 0..16 {
        let a = k as f32 * core::f32::consts::TAU / 16.0;
        s.obstacles
            .push(Obstacle {
                center: [0.0, 15.0 * a.sin(), 90.0 + 15.0 * a.cos()],
                radius: 4.0,
            })
            .unwrap();
    }
    // Not an error: the report has no best, and every form says it found no feasible path.
    let report = plan(&s).unwrap();
    assert_eq!(report.best, None);
    assert!(report.best().is_none());
    assert!(!report.forms.is_empty());
    assert!(report
        .forms
        .iter()
        .all(|o| !o.feasible && o.status == SolveStatus::Infeasible));
    let planned = plan_scheduled(&s).unwrap();
    assert_eq!(planned.schedule, None);
}

#[test]
fn messages_name_the_input_and_what_is_allowed() {
    let mut s = Scenario::paper();
    s.weights.penalty = -1.0;
    assert_eq!(
        err(&s).to_string(),
        "weights.penalty is out of range: allowed is 0 or more"
    );
    let mut s = Scenario::paper();
    s.entry.max_tilt_deg = 90.0;
    assert!(
        err(&s).to_string().contains("0 to 89 degrees"),
        "{}",
        err(&s)
    );
    let mut s = Scenario::paper();
    s.target.tolerance = 90.0;
    assert_eq!(err(&s), PlanError::TargetAtEntry);
    assert!(err(&s).to_string().contains("within target.tolerance"));
}

#[test]
fn scenarios_beyond_a_needle_workspace_are_refused() {
    let mut s = Scenario::paper();
    s.obstacles.clear();
    s.target.position = [0.0, 0.0, 1e12];
    assert_eq!(err(&s), PlanError::OutOfRange(Field::TargetPosition));
    s.target.position = [0.0, 0.0, 999.0];
    // A target farther than the needle reaches is refused naming the needle's length.
    assert_eq!(err(&s), PlanError::OutOfRange(Field::NeedleLength));
    assert!(err(&s).to_string().contains("needle.length"), "{}", err(&s));
    s.needle.length = 1000.0;
    assert_eq!(s.validate(), Ok(()));
    s.needle.length = 6000.0;
    assert_eq!(err(&s), PlanError::OutOfRange(Field::NeedleLength));
    s.needle.length = f32::NAN;
    assert_eq!(err(&s), PlanError::NotFinite(Field::NeedleLength));
    let mut s = Scenario::paper();
    s.obstacles[2].center[1] = -1001.0;
    assert_eq!(err(&s), PlanError::OutOfRange(Field::ObstacleCenter(2)));
    let mut s = Scenario::paper();
    s.needle.curvature_radius = 1e6;
    assert_eq!(err(&s), PlanError::OutOfRange(Field::CurvatureRadius));
}

#[test]
fn an_arc_radius_no_bevel_tip_needle_bends_with_is_refused_naming_the_key_and_range() {
    let (least, most) = CURVATURE_RADIUS_RANGE_MM;
    // The paper's 63.7 mm typed in metres, a radius just under the least, one just over the most.
    for radius in [0.0637, least * 0.99, most * 1.01] {
        let mut s = Scenario::paper();
        s.needle.curvature_radius = radius;
        assert_eq!(
            err(&s),
            PlanError::OutOfRange(Field::CurvatureRadius),
            "{radius}"
        );
        let message = err(&s).to_string();
        assert!(
            message.starts_with("needle.curvature_radius is out of range: allowed is ")
                && message.contains(&format!("{least} to {most} mm")),
            "{message}"
        );
    }
    // Both ends are accepted.
    for radius in [least, most] {
        let mut s = Scenario::paper();
        s.needle.curvature_radius = radius;
        assert_eq!(s.validate(), Ok(()), "{radius}");
    }
}

#[test]
fn a_tolerance_below_f32_resolution_is_refused_and_a_fine_one_still_plans_the_optimum() {
    let mut s = Scenario::paper();
    s.target.tolerance = 1e-9;
    match err(&s) {
        PlanError::ToleranceTooFine { least_nm } => assert!((100..1000).contains(&least_nm)),
        other => panic!("{other:?}"),
    }
    // The finest accepted tolerance still finds the paper's optimum (RL, F = 96.22).
    let least = 4.0 * s.resolution();
    s.target.tolerance = least * 1.01;
    let report = plan(&s).unwrap();
    let best = report.best().unwrap();
    assert_eq!(best.form.word().as_str(), "RL");
    assert!((best.objective - 96.222).abs() < 0.01, "{}", best.objective);
    assert!(best.target_error <= s.target.tolerance);
}
