//! The planner's per-form optimum on the paper's scenario against the independent reference
//! planner (`needle_e2e::reference`): each form's optimum must be the global one.

use needle_e2e::reference::compare::{run_suite, Ask};
use needle_e2e::reference::{solve_form, Effort};
use planner_core::model::scenario::Workspace;
use planner_core::{plan, Form, Scenario};

fn paper() -> Vec<(String, Scenario)> {
    vec![("paper".to_string(), Scenario::paper())]
}

#[test]
fn every_form_of_the_paper_is_globally_optimal() {
    let sum = run_suite(paper(), Effort(1.0), Ask::AllForms);
    assert_eq!(sum.forms, 10);
    assert_eq!(sum.feasible, 9, "every form but L is feasible");
    assert!(sum.mismatches.is_empty(), "{}", sum.mismatches.join("\n"));
}

#[test]
fn every_form_planned_alone_is_globally_optimal() {
    let sum = run_suite(paper(), Effort(1.0), Ask::EachForm);
    assert!(sum.mismatches.is_empty(), "{}", sum.mismatches.join("\n"));
}

#[test]
fn paper_scenario_in_space_is_globally_optimal() {
    let mut s = Scenario::paper();
    s.options.workspace = Workspace::Space;
    let sum = run_suite(
        vec![("paper in space".into(), s)],
        Effort(1.0),
        Ask::AllForms,
    );
    assert!(sum.mismatches.is_empty(), "{}", sum.mismatches.join("\n"));
}

/// The planner's and the reference's lengths give the paper's differences to the same digits.
#[test]
fn planner_and_reference_agree_on_the_papers_lengths() {
    let s = Scenario::paper();
    let report = plan(&s).unwrap();
    for word in ["R", "RL", "LRL"] {
        let f = Form::parse(word).unwrap();
        let planner = report.forms.iter().find(|o| o.form == f).unwrap();
        let reference = solve_form(&s, f, Effort(1.0)).unwrap();
        assert!(
            (f64::from(planner.length) - reference.length).abs() < 0.02,
            "{word}: planner L={} reference L={}",
            planner.length,
            reference.length
        );
    }
}
