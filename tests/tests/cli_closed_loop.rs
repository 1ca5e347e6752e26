//! `needle simulate --closed-loop` end to end: how steered runs end (reached or missed), the
//! bevel rotations they report, and a bounded plan kept off a device.

use needle_e2e::{example, needle_json};
use serde_json::Value;

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

/// A one-arc plan leaves the controller no authority: runs that end off the target say so
/// (`missed`, with the controller's predicted miss beyond the reach tolerance) instead of
/// counting as reached because their steps ran out.
#[test]
fn a_run_that_ends_off_the_target_is_missed() {
    let v = needle_json(&[
        "simulate",
        &paper(),
        "--form",
        "R",
        "--runs",
        "10",
        "--seed",
        "3",
        "--closed-loop",
        "--json",
        "--detail",
    ]);
    let runs = v["runs_detail"].as_array().unwrap();
    let missed: Vec<&Value> = runs
        .iter()
        .filter(|r| r["stop_reason"] == "missed")
        .collect();
    assert!(!missed.is_empty(), "an R plan closed loop misses some runs");
    assert_eq!(v["summary"]["stops"]["missed"], missed.len());
    for r in runs {
        let predicted = r["predicted_miss_mm"].as_f64();
        match r["stop_reason"].as_str() {
            None => assert!(predicted.unwrap() <= 1.0),
            Some("missed") => {
                assert!(predicted.is_none_or(|p| p > 1.0), "{r}");
                assert!(r["target_error"].as_f64().unwrap() > 0.0);
            }
            Some(_) => {}
        }
    }
}

/// Each steered run reports its bevel rotations, and the summary's figures are those of the
/// runs: the median count, the most, the smallest turn of any.
#[test]
fn rotations_are_reported_per_run_and_summarised() {
    let v = needle_json(&[
        "simulate",
        &paper(),
        "--runs",
        "9",
        "--seed",
        "3",
        "--closed-loop",
        "--json",
        "--detail",
    ]);
    let runs = v["runs_detail"].as_array().unwrap();
    let mut counts: Vec<u64> = Vec::new();
    let mut smallest = f64::INFINITY;
    for r in runs {
        let turns: Vec<f64> = r["steps"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["op"] == "rotate")
            .map(|s| s["angle_deg"].as_f64().unwrap().abs())
            .filter(|a| *a > 0.0)
            .collect();
        assert_eq!(
            r["rotations"]["count"].as_u64().unwrap(),
            turns.len() as u64
        );
        let total: f64 = turns.iter().sum();
        let reported = r["rotations"]["total_deg"].as_f64().unwrap();
        assert!(
            (reported - total).abs() <= 1e-3 * total.max(1.0),
            "{reported} {total}"
        );
        counts.push(turns.len() as u64);
        smallest = turns.iter().copied().fold(smallest, f64::min);
    }
    counts.sort_unstable();
    let s = &v["summary"]["rotations"];
    assert!(
        counts[4] > 0,
        "a steered paper insertion turns the bevel: {counts:?}"
    );
    assert_eq!(s["median_per_run"].as_u64().unwrap(), counts[4]);
    assert_eq!(s["max_per_run"].as_u64().unwrap(), counts[8]);
    assert!((s["smallest_deg"].as_f64().unwrap() - smallest).abs() < 1e-4);
}
