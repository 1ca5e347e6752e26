//! The simulated lab in a world the controller does not know (`hil-sim --lab --world clinical`,
//! `--perturb`, `--fault`, or the scenario's `[execution]` world): `needle steer` on it ends
//! each insertion as `needle simulate --closed-loop` in the same world ends the run of the same
//! seed, bit for bit. A 5-DOF sensor's roll is left out by `needle steer --tracker-dof 5`; a
//! reading without a new image of the target carries none; a dropout is a tip flagged invalid.

mod lab_support;

use lab_support::{temp_path, wire_support, Lab};
use needle_e2e::{example, needle};
use serde_json::Value;

fn path(name: &str) -> String {
    example(name).to_str().unwrap().to_string()
}

fn simulated(file: &str, first: u64, runs: usize, flags: &[&str]) -> Vec<Value> {
    lab_support::simulated_with(file, first, runs, flags)
}

/// Steers the insertions of `file` from seed `first` on a lab started with `lab_flags`, each
/// with `steer_flags`, and compares each with the simulated run of its seed; returns the runs.
fn steers_as_simulated(
    file: &str,
    first: u64,
    expected: &[Value],
    lab_flags: &[&str],
    steer_flags: &[&str],
) -> Vec<Value> {
    let mut lab = Lab::start(file, first, lab_flags);
    for (i, sim) in expected.iter().enumerate() {
        let seed = first + i as u64;
        let seed_text = seed.to_string();
        let mut flags = vec!["--seed", &seed_text];
        flags.extend_from_slice(steer_flags);
        let steered = lab.steer(file, &flags);
        let truth = lab.next_run();
        let what = format!("{file} seed {seed} {lab_flags:?}");
        assert_eq!(sim["seed"], seed, "{what}");
        assert_eq!(truth["seed"], seed, "{what}");
        assert_eq!(truth["target_error"], sim["target_error"], "{what}");
        assert_eq!(truth["path_rms"], sim["path_rms"], "{what}");
        assert_eq!(truth["path_max"], sim["path_max"], "{what}");
        assert_eq!(truth["min_clearance"], sim["min_clearance"], "{what}");
        assert_eq!(truth["collided"], sim["collided"], "{what}");
        assert_eq!(steered["stop_reason"], sim["stop_reason"], "{what}");
        assert_eq!(
            steered["predicted_miss_mm"], sim["predicted_miss_mm"],
            "{what}"
        );
        assert_eq!(steered["steering"], sim["steering"], "{what}");
        assert_eq!(steered["robot_stopped"], true, "{what}");
        let readings = sim["steering"]["readings"].as_u64().unwrap();
        assert_eq!(truth["pieces"], readings, "{what}: one reading a piece");
    }
    expected.to_vec()
}

/// The clinical world (5-DOF, bias, registration, layers and punctures, a pushed target imaged
/// at 20 Hz 50 ms late, 30 ms of latency, dropouts), `needle steer` told the sensor is 5-DOF and
/// the simulator's gap for tracking lost: every insertion as `needle simulate --world clinical`.
#[test]
fn clinical_paper_insertions_steer_as_simulated() {
    let file = path("paper");
    let expected = simulated(&file, 1, 10, &["--world", "clinical"]);
    let steer = ["--tracker-dof", "5", "--steer", "tracking_lost_after_mm=10"];
    let runs = steers_as_simulated(&file, 1, &expected, &["--world", "clinical"], &steer);
    let dropped: u64 = runs
        .iter()
        .map(|r| r["steering"]["no_fix"].as_u64().unwrap())
        .sum();
    assert!(dropped > 0, "the dropouts reached the controller");
    assert!(runs.iter().any(|r| r["stop_reason"].is_null()));
}

#[test]
fn clinical_space_insertions_steer_as_simulated() {
    let file = path("space");
    let expected = simulated(&file, 1, 3, &["--world", "clinical"]);
    let steer = ["--tracker-dof", "5", "--steer", "tracking_lost_after_mm=10"];
    steers_as_simulated(&file, 1, &expected, &["--world", "clinical"], &steer);
}

/// With the lab's own interlock (`needle steer` stops after 2 mm without a pose), the clinical
/// world's 2 mm dropouts stop most insertions "tracking lost", as the simulation told the same
/// gap does: the robot holds, then stops.
#[test]
fn the_lab_interlock_stops_as_the_simulation_told_it() {
    let file = path("paper");
    let flags = ["--world", "clinical", "--steer", "tracking_lost_after_mm=2"];
    let expected = simulated(&file, 1, 4, &flags);
    let runs = steers_as_simulated(
        &file,
        1,
        &expected,
        &["--world", "clinical"],
        &["--tracker-dof", "5"],
    );
    assert!(runs.iter().any(|r| r["stop_reason"] == "tracking_lost"));
}

/// `--perturb` and `--fault` make the lab's world as they make `needle simulate`'s (here one
/// effect at a time and an outlier fault); the scenario's `[execution]` world is the lab's
/// when no flag says otherwise.
#[test]
fn perturb_fault_and_the_scenario_world_are_the_simulations() {
    let file = path("paper");
    let world = [
        "--perturb",
        "target_push_mm=2",
        "--perturb",
        "layers=3",
        "--perturb",
        "target_imaging_hz=5",
        "--fault",
        "outlier_rate=0.05",
        "--fault",
        "outlier_mm=3",
    ];
    let expected = simulated(&file, 5, 2, &world);
    steers_as_simulated(&file, 5, &expected, &world, &[]);

    let text = std::fs::read_to_string(&file).unwrap();
    let clinical = temp_path("clinical-world.toml");
    std::fs::write(
        &clinical,
        needle_e2e::with_execution(&text, "world = \"clinical\"\npuncture_mm = 2"),
    )
    .unwrap();
    let clinical = clinical.to_str().unwrap().to_string();
    let expected = simulated(&clinical, 2, 2, &[]);
    let steer = ["--tracker-dof", "5", "--steer", "tracking_lost_after_mm=10"];
    steers_as_simulated(&clinical, 2, &expected, &[], &steer);
    // `--world default` replaces the file's world, as it does for the simulation.
    let expected = simulated(&clinical, 2, 1, &["--world", "default"]);
    steers_as_simulated(&clinical, 2, &expected, &["--world", "default"], &[]);
    let _ = std::fs::remove_file(clinical);
}

/// A tracker streaming at 500 Hz in the clinical world: the copies of a used target, as those
/// of a used tip pose, are no new image, so the insertion is still the simulated one.
#[test]
fn a_stream_in_the_clinical_world_steers_as_simulated() {
    let file = path("paper");
    let expected = simulated(&file, 4, 1, &["--world", "clinical"]);
    let lab = [
        "--world",
        "clinical",
        "--stream-rate",
        "500",
        "--rate",
        "100",
        "--report-delay-ms",
        "3",
    ];
    let steer = ["--tracker-dof", "5", "--steer", "tracking_lost_after_mm=10"];
    steers_as_simulated(&file, 4, &expected, &lab, &steer);
}

/// `hil-sim --lab` with the output of its first line or its error.
fn lab_fails(extra: &[&str]) -> String {
    let out = std::process::Command::new(wire_support::hil_sim_bin())
        .args(["--lab", &path("paper"), "--tracker-port", "0"])
        .args(["--robot-port", "0"])
        .args(extra)
        .output()
        .expect("run hil-sim --lab");
    assert_eq!(out.status.code(), Some(1), "{extra:?} is refused");
    assert!(out.stdout.is_empty(), "nothing served: {extra:?}");
    String::from_utf8(out.stderr).unwrap()
}

/// `needle simulate`'s error for `flags`.
fn simulate_error(flags: &[&str]) -> String {
    let out = needle()
        .args(["simulate", &path("paper"), "--closed-loop", "--runs", "1"])
        .args(flags)
        .output()
        .expect("run needle simulate");
    assert!(!out.status.success());
    let text = String::from_utf8(out.stderr).unwrap();
    text.trim().trim_start_matches("error: ").to_string()
}

/// A bad world, key or value is refused with `needle simulate`'s own message; a fault the lab
/// cannot serve is refused saying why.
#[test]
fn bad_worlds_are_refused_as_the_simulation_refuses_them() {
    for flags in [
        &["--world", "mars"][..],
        &["--perturb", "layers=9"],
        &["--perturb", "tracker_dof=4"],
        &["--perturb", "no_such_key=1"],
        &["--fault", "dropout_rate=2"],
    ] {
        let expected = simulate_error(flags);
        let said = lab_fails(flags);
        assert!(said.starts_with("hil-sim: "), "{said}");
        assert!(said.contains(&expected), "{flags:?}: {said} / {expected}");
    }
    assert!(lab_fails(&["--world", "mars"]).contains("unknown world `mars`"));
    let said = lab_fails(&["--fault", "repeat_rate=0.1"]);
    assert!(said.contains("repeat_rate = 0.1"), "{said}");
    assert!(said.contains("does not serve"), "{said}");
}
