//! The plan's predicted execution risk, end to end: `[execution]` and
//! `planner.max_collision_probability` in a scenario file, what `needle plan` reports, and the
//! prediction against the simulator (open loop, 2000 runs a plan) on the two examples and on
//! generated scenarios nobody tuned on: the simulated collision rate within a factor 2 of the
//! predicted one (or within a percentage point where both are under 2 %), the same for the 95th
//! percentile of the miss.

use needle_e2e::{
    example, needle, needle_fails_with, needle_json, with_bound, with_execution, TempScenario,
};
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Within a factor 2, or a percentage point where both are under 2 %.
fn agree(predicted: f64, simulated: f64) -> bool {
    (predicted < 0.02 && simulated < 0.02 && (predicted - simulated).abs() <= 0.01)
        || (predicted <= 2.0 * simulated && simulated <= 2.0 * predicted)
}

/// An example with a bound (and an `[execution]` table) added: open loop.
fn bounded(name: &str, bound: f64) -> TempScenario {
    let text = std::fs::read_to_string(example(name)).unwrap();
    let text = with_bound(&text, &bound.to_string());
    let text = if text.contains("mode = ") {
        text
    } else {
        with_execution(&text, "mode = \"open_loop\"")
    };
    TempScenario::new(&text)
}

#[test]
fn a_bounded_plan_reports_its_prediction_and_keeps_the_bound() {
    let file = bounded("paper", 0.01);
    let path = file.0.to_string_lossy().into_owned();
    let v = needle_json(&["plan", &path, "--json"]);
    let e = &v["execution"];
    assert_eq!(e["mode"], "open_loop");
    assert_eq!(e["within_bound"], true);
    assert!((f(&e["max_collision_probability"]) - 0.01).abs() < 1e-9);
    assert!(e["rounds"].as_u64().unwrap() >= 1);
    assert!(e["margins"].as_array().unwrap().iter().any(|m| f(m) > 0.0));
    assert!(f(&v["best"]["collision_probability"]) <= 0.01);
    assert!(f(&v["best"]["target_error_p95"]) > 0.5);
    for form in v["forms"].as_array().unwrap() {
        let p = &form["collision_probability"];
        assert_eq!(form["feasible"] == true, !p.is_null(), "{form}");
    }
    // Opted out of the bound, the prediction is still written, and the bound is null.
    let plain = needle_json(&["plan", &example("paper").to_string_lossy(), "--json"]);
    assert!(plain["execution"]["max_collision_probability"].is_null());
    assert!(f(&plain["best"]["collision_probability"]) > 0.01);
    let paper = needle()
        .args(["plan", &example("paper").to_string_lossy()])
        .output()
        .unwrap();
    let paper = String::from_utf8_lossy(&paper.stdout);
    assert!(
        paper.contains("unbounded: planner.max_collision_probability = \"off\""),
        "{paper}"
    );
    // The safe plan is no shorter than the unbounded one, and its table says the bound holds.
    assert!(f(&v["best"]["length"]) >= f(&plain["best"]["length"]));
    let table = needle().args(["plan", &path]).output().unwrap();
    let text = String::from_utf8_lossy(&table.stdout);
    assert!(table.status.success());
    assert!(
        text.contains("bound 0.01: the best form is within it"),
        "{text}"
    );
}

#[test]
fn a_bound_no_plan_meets_is_a_clear_failure() {
    let text = std::fs::read_to_string(example("paper")).unwrap();
    // A world ten times as wild as the defaults: no path keeps one in ten thousand.
    let wild = with_execution(
        &with_bound(&text, "0.0001"),
        "curvature_spread = 0.3\nentry_direction_deg = 5",
    );
    needle_fails_with(
        &wild,
        &["plan", "{}"],
        "no plan keeps the predicted collision probability within 0.0001",
    );
    let bad = with_bound(&text, "1.5");
    needle_fails_with(
        &bad,
        &["plan", "{}"],
        "planner.max_collision_probability = 1.5",
    );
    let unknown = with_execution(&text, "wobble = 1");
    needle_fails_with(&unknown, &["plan", "{}"], "unknown perturbation `wobble`");
}

/// `needle simulate` on a bounded example: its open-loop collision rate and miss against what
/// `needle plan` predicted.
fn simulated_against_predicted(name: &str) {
    let file = bounded(name, 0.05);
    let path = file.0.to_string_lossy().into_owned();
    let plan = needle_json(&["plan", &path, "--json"]);
    let predicted = f(&plan["best"]["collision_probability"]);
    let p95 = f(&plan["best"]["target_error_p95"]);
    assert!(predicted <= 0.05);
    let sim = needle_json(&["simulate", &path, "--runs", "2000", "--json"]);
    let rate = f(&sim["summary"]["collisions"]) / 2000.0;
    let simulated_p95 = f(&sim["summary"]["target_error"]["p95"]);
    println!("{name}: collision predicted {predicted:.4}, simulated {rate:.4}; p95 {p95:.2} / {simulated_p95:.2}");
    assert!(agree(predicted, rate), "{name}: {predicted} against {rate}");
    assert!(
        (p95 / simulated_p95 - 1.0).abs() < 0.1,
        "{name}: p95 {p95} against {simulated_p95}"
    );
}

#[test]
fn on_the_examples_the_prediction_matches_the_simulation() {
    simulated_against_predicted("paper");
    simulated_against_predicted("space");
}

/// Generated scenarios (`needle benchmark`), open loop, under a 5 % bound: each scenario's
/// simulated collision rate and miss against the prediction, and the refusals at most 10 %.
fn generated(scenarios: &str) {
    let v = needle_json(&[
        "benchmark",
        "--scenarios",
        scenarios,
        "--runs",
        "2000",
        "--seed",
        "101",
        "--open-loop-only",
        "--max-collision-probability",
        "0.05",
        "--json",
    ]);
    let rows = v["scenarios"].as_array().unwrap();
    for r in rows {
        let (o, p) = (&r["open_loop"], &r["predicted"]);
        let predicted = f(&p["collision_probability"]);
        let rate = f(&o["hit_percent"]) / 100.0;
        assert!(predicted <= 0.05, "{r}");
        assert!(
            agree(predicted, rate),
            "seed {}: {predicted} against {rate}",
            r["seed"]
        );
        let ratio = f(&p["target_error_p95"]) / f(&o["p95_target_error"]);
        assert!(
            (ratio - 1.0).abs() < 0.1,
            "seed {}: p95 ratio {ratio}",
            r["seed"]
        );
        assert!(r["closed_loop"].is_null());
        assert!(
            f(&r["plan_length"]) >= f(&p["unbounded_length"]) - 0.5,
            "{r}"
        );
    }
    let refused = v["unplanned"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|u| {
            u["reason"]
                .as_str()
                .unwrap()
                .contains("collision probability")
        })
        .count();
    assert!(
        refused * 10 <= rows.len() + refused,
        "{refused} refused for the bound"
    );
}

#[test]
fn on_generated_scenarios_the_prediction_matches_the_simulation() {
    generated("4");
}

/// The 20 generated scenarios of docs/journal/2026-12-04.md, "Predicted against simulated (open
/// loop)" (about 10 s in release).
#[test]
#[ignore]
fn extended_generated_scenarios() {
    generated("20");
}
