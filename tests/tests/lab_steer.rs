//! `needle steer` end to end on the simulated lab (`hil-sim --lab`, lock-step): every insertion
//! ends as `needle simulate --closed-loop` ends the run of the same seed, bit for bit (the true
//! target error from the lab, the stop reason, predicted miss and counters from `needle steer`).

mod lab_support;

use lab_support::{log_lines, temp_path, Lab};
use needle_e2e::{example, needle_json};
use serde_json::Value;

fn path(name: &str) -> String {
    example(name).to_str().unwrap().to_string()
}

/// `needle simulate FILE --closed-loop --runs N --seed FIRST --json --detail`: each run's record.
fn simulated(file: &str, first: u64, runs: usize) -> Vec<Value> {
    let (first, runs) = (first.to_string(), runs.to_string());
    let v = needle_json(&[
        "simulate",
        file,
        "--closed-loop",
        "--runs",
        &runs,
        "--seed",
        &first,
        "--json",
        "--detail",
    ]);
    v["runs_detail"].as_array().expect("runs_detail").clone()
}

/// Steers `runs` insertions of `file` from seed `first` on one lab and compares each with the
/// simulation of its seed.
fn steers_as_simulated(name: &str, first: u64, runs: usize) {
    let file = path(name);
    let expected = simulated(&file, first, runs);
    let mut lab = Lab::start(&file, first, &[]);
    let mut reached = 0;
    for (i, sim) in expected.iter().enumerate() {
        let seed = first + i as u64;
        let steered = lab.steer(&file, &["--seed", &seed.to_string()]);
        let truth = lab.next_run();
        let what = format!("{name} seed {seed}");
        assert_eq!(sim["seed"], seed, "{what}");
        assert_eq!(truth["seed"], seed, "{what}");
        assert_eq!(truth["target_error"], sim["target_error"], "{what}");
        assert_eq!(truth["path_rms"], sim["path_rms"], "{what}");
        assert_eq!(truth["min_clearance"], sim["min_clearance"], "{what}");
        assert_eq!(steered["stop_reason"], sim["stop_reason"], "{what}");
        assert_eq!(
            steered["predicted_miss_mm"], sim["predicted_miss_mm"],
            "{what}"
        );
        assert_eq!(steered["steering"], sim["steering"], "{what}");
        assert_eq!(steered["robot_stopped"], true, "{what}");
        assert_eq!(truth["end"], "stopped", "{what}");
        let readings = sim["steering"]["readings"].as_u64().unwrap();
        assert_eq!(truth["pieces"], readings, "{what}: one reading a piece");
        assert_eq!(steered["latency_ms"]["readings"], readings, "{what}");
        reached += usize::from(sim["stop_reason"].is_null());
    }
    assert!(reached > 0, "{name}: some insertions reach the target");
}

#[test]
fn twenty_paper_insertions_steer_as_simulated() {
    steers_as_simulated("paper", 1, 20);
}

#[test]
fn space_insertions_steer_as_simulated() {
    steers_as_simulated("space", 1, 5);
}

/// The insertion log holds the plan, every reading with its command, and the stop last.
#[test]
fn the_insertion_log_is_complete() {
    let file = path("paper");
    let log = temp_path("complete.jsonl");
    let lab = Lab::start(&file, 4, &[]);
    let steered = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    let lines = log_lines(&log);
    assert_eq!(lines[0]["event"], "plan");
    let first_steps = lines[0]["steps"].as_array().unwrap();
    assert!(first_steps[0].as_str().unwrap().starts_with("steps count="));
    let readings = lines.iter().filter(|l| l["event"] == "reading").count();
    assert_eq!(
        readings as u64,
        steered["steering"]["readings"].as_u64().unwrap()
    );
    let last = lines.last().unwrap();
    assert_eq!(last["event"], "stop");
    assert_eq!(last["stop_reason"], steered["stop_reason"]);
    assert_eq!(last["robot_stopped"], true);
    let last_command = lines
        .iter()
        .rev()
        .find(|l| l["event"] == "command")
        .unwrap();
    assert_eq!(last_command["text"], "stop");
    for l in &lines {
        assert!(l["t_ms"].as_f64().is_some(), "every line is timed: {l}");
    }
    let _ = std::fs::remove_file(log);
}
