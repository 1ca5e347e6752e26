//! A fixed insertion heading (`entry.max_tilt_deg = 0`: a template or a guide) plans: the
//! examples with only that key changed, and one sphere on the entry-target line
//! (tests/data/fixed_heading/). Every plan passes the f64 reference's re-check; with F = L in 3-D
//! (risk and control weights 0, N <= 4) the paths are as short as published sampling-based
//! planners' best.

use needle_e2e::soundness::check_plan;
use needle_e2e::workspace;
use planner_core::model::scenario::Workspace;
use planner_core::{plan, Scenario};

fn fixed(name: &str) -> Scenario {
    let path = workspace().join(format!("tests/data/fixed_heading/{name}.toml"));
    let mut s = needle_scenario::load_scenario(&path).expect("scenario");
    // The optimiser at the needle's full curvature, as the f64 reference and the published
    // planners bend it (a file silent on it keeps a steering reserve).
    s.options.curvature_reserve = 0.0;
    s
}

/// The best plan's length (mm) and its insertion tilt (degrees) for `s`; panics with the
/// scenario's name when no form is feasible.
fn best_length_and_tilt(name: &str, s: &Scenario) -> (f32, f32) {
    let report = plan(s).expect("a valid scenario");
    let best = report
        .best()
        .unwrap_or_else(|| panic!("{name}: no plan with the heading fixed"));
    (best.length, best.insertion.tilt_deg)
}

#[test]
fn each_scenario_plans_on_the_axis_with_the_default_weights() {
    for name in ["paper", "space", "spheres32", "sphere"] {
        let s = fixed(name);
        assert_eq!(s.entry.max_tilt_deg, 0.0);
        check_plan(&s).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (_, tilt) = best_length_and_tilt(name, &s);
        assert_eq!(tilt, 0.0, "{name}: the path leaves the entry off its axis");
    }
}

/// Best lengths with F = L of the UNC planners (Fu et al., RCS*, ICRA 2022) after 1 s, which
/// insert along a fixed heading: paper, space and spheres32 (the single sphere is below).
const PUBLISHED_MM: [(&str, f32); 3] = [("paper", 90.97), ("space", 88.33), ("spheres32", 97.62)];

fn shortest_in_space(mut s: Scenario) -> Scenario {
    s.options.workspace = Workspace::Space;
    s.options.max_control_degree = 4;
    s.weights.risk = 0.0;
    s.weights.control = 0.0;
    s
}

#[test]
fn with_f_equal_to_length_the_paths_are_as_short_as_a_sampling_planners() {
    for (name, published) in PUBLISHED_MM {
        let s = shortest_in_space(fixed(name));
        check_plan(&s).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (length, _) = best_length_and_tilt(name, &s);
        assert!(
            length <= 1.01 * published,
            "{name}: {length} mm, published {published} mm"
        );
    }
}

#[test]
fn around_one_sphere_the_path_is_within_a_percent_of_the_straight_line_bound() {
    // No path from the entry to the target at 90 mm passes the 6 mm sphere at 50 mm shorter than
    // the two straight lines through the sphere's rim: sqrt(50² + 6²) + sqrt(40² + 6²).
    let bound = (50.0f32.hypot(6.0)) + (40.0f32.hypot(6.0));
    let s = shortest_in_space(fixed("sphere"));
    check_plan(&s).unwrap_or_else(|e| panic!("sphere: {e}"));
    let (length, _) = best_length_and_tilt("sphere", &s);
    assert!(
        length >= bound && length <= 1.01 * bound,
        "{length} mm, bound {bound} mm"
    );
}
