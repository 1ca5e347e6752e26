//! `needle steer --tcp`: the controller on a device (hil-sim over TCP) instead of in-process,
//! on the simulated lab: the same insertions as in-process, and a device that dies mid-insertion
//! stops the robot.

mod lab_support;

use lab_support::wire_support::SimProcess;
use lab_support::{log_lines, temp_path, Lab};
use needle_e2e::{example, needle_json};
use serde_json::Value;
use std::process::Stdio;
use std::time::Duration;

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

/// Three paper insertions steered on the device end as `needle simulate --closed-loop` does.
#[test]
fn a_device_steers_the_lab_as_in_process() {
    let file = paper();
    let sim = needle_json(&[
        "simulate",
        &file,
        "--closed-loop",
        "--runs",
        "3",
        "--seed",
        "7",
        "--json",
        "--detail",
    ]);
    let device = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let mut lab = Lab::start(&file, 7, &[]);
    for (i, expected) in sim["runs_detail"].as_array().unwrap().iter().enumerate() {
        let v = lab.steer(&file, &["--tcp", &device.address]);
        let truth = lab.next_run();
        assert_eq!(truth["seed"], 7 + i as u64);
        assert_eq!(truth["target_error"], expected["target_error"], "run {i}");
        assert_eq!(v["stop_reason"], expected["stop_reason"], "run {i}");
        assert_eq!(v["predicted_miss_mm"], expected["predicted_miss_mm"]);
        assert_eq!(v["steering"], expected["steering"], "run {i}");
        assert_eq!(v["robot_stopped"], true);
    }
}

/// The device is killed mid-insertion: the robot is told stop, the outcome says why, and the log
/// ends with the stop.
#[test]
fn a_device_that_dies_stops_the_robot() {
    let file = paper();
    let log = temp_path("device.jsonl");
    let mut device = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let mut lab = Lab::start(&file, 2, &["--rate", "40"]);
    let child = lab
        .steer_command(
            &file,
            &["--tcp", &device.address, "--timeout", "0.5", "--json"],
        )
        .args(["--log", log.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("start needle steer");
    std::thread::sleep(Duration::from_millis(1000));
    device.kill();
    let out = child.wait_with_output().expect("needle steer ends");
    let v: Value = serde_json::from_slice(&out.stdout).expect("the outcome is printed");
    assert_eq!(v["stop_reason"], "device_not_answering");
    assert_eq!(v["robot_stopped"], true);
    let truth = lab.next_run();
    assert_eq!(truth["end"], "stopped");
    assert!(
        truth["pieces"].as_u64().unwrap() < 100,
        "stopped mid-insertion"
    );
    let lines = log_lines(&log);
    assert!(lines.iter().any(|l| l["event"] == "controller_failed"));
    assert_eq!(lines.last().unwrap()["stop_reason"], "device_not_answering");
    let _ = std::fs::remove_file(log);
}
