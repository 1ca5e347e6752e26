//! `needle steer --tcp`: the controller on a device (hil-sim over TCP) instead of in-process,
//! on the simulated lab: the same insertions as in-process, and a device that dies mid-insertion
//! stops the robot.

mod firmware_support;
mod lab_support;

use lab_support::wire_support::SimProcess;
use lab_support::{log_lines, slicer_listener, temp_path, Lab};
use needle_e2e::{example, needle_json};
use serde_json::Value;
use std::process::Stdio;
use std::time::Duration;

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

/// `runs` insertions of `name` (an example) from seed 7 steered on the device at `address` end
/// as `needle simulate --closed-loop` ends them.
fn device_steers_the_lab_as_in_process(address: &str, name: &str, runs: usize) {
    let file = example(name).to_str().unwrap().to_string();
    let sim = needle_json(&[
        "simulate",
        &file,
        "--closed-loop",
        "--runs",
        &runs.to_string(),
        "--seed",
        "7",
        "--json",
        "--detail",
    ]);
    let mut lab = Lab::start(&file, 7, &[]);
    for (i, expected) in sim["runs_detail"].as_array().unwrap().iter().enumerate() {
        let v = lab.steer(&file, &["--tcp", address]);
        let truth = lab.next_run();
        assert_eq!(truth["seed"], 7 + i as u64);
        assert_eq!(truth["target_error"], expected["target_error"], "run {i}");
        assert_eq!(v["stop_reason"], expected["stop_reason"], "run {i}");
        assert_eq!(v["predicted_miss_mm"], expected["predicted_miss_mm"]);
        // A device's `repeated` also counts the link's resends of a reading whose answer was
        // late (answered again, not applied), as in tests/tests/steer_device.rs.
        let mut steering = v["steering"].clone();
        let mut expected_steering = expected["steering"].clone();
        steering["repeated"] = Value::Null;
        expected_steering["repeated"] = Value::Null;
        assert_eq!(steering, expected_steering, "run {i}");
        assert_eq!(v["robot_stopped"], true);
    }
}

/// Twenty paper and five space insertions steered on hil-sim over TCP.
#[test]
fn hil_sim_steers_the_lab_as_in_process() {
    let device = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    device_steers_the_lab_as_in_process(&device.address, "paper", 20);
    device_steers_the_lab_as_in_process(&device.address, "space", 5);
}

/// The estimated tips Slicer is sent, one per reading: from a device they are the in-process
/// controller's, bit for bit (the device reports them in its steering status).
#[test]
fn slicer_sees_the_devices_estimates_as_in_process() {
    let file = paper();
    let device = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let estimates = |flags: &[&str]| {
        let lab = Lab::start(&file, 7, &[]);
        let (address, slicer) = slicer_listener();
        let v = lab.steer(&file, &[flags, &["--slicer", &address]].concat());
        let frames = slicer.join().unwrap();
        let drawn: Vec<_> = frames
            .into_iter()
            .filter(|f| f.info.device_name == "NeedleTipEstimate")
            .map(|f| format!("{:?}", f.message))
            .collect();
        assert_eq!(
            drawn.len() as u64,
            v["steering"]["readings"].as_u64().unwrap()
        );
        drawn
    };
    let in_process = estimates(&[]);
    assert!(in_process.len() > 50, "{}", in_process.len());
    assert_eq!(estimates(&["--tcp", &device.address]), in_process);
}

/// One paper insertion steered on the firmware in QEMU (each emulated reading costs about a
/// million instructions).
#[test]
fn the_firmware_in_qemu_steers_the_lab_as_in_process() {
    if !firmware_support::emulator_ready("the_firmware_in_qemu_steers_the_lab_as_in_process") {
        return;
    }
    let image = firmware_support::build_firmware("mps2-an386", "mps2-an386");
    let mut qemu = firmware_support::Qemu::start("mps2-an386", &image);
    device_steers_the_lab_as_in_process(&qemu.addr, "paper", 1);
    assert!(qemu.running(), "the firmware stopped QEMU (a fault)");
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
