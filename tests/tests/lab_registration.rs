//! The registration as a `TRANSFORM` from the tracker stream (`needle steer --registration-name
//! ReferenceToScenario`): used from the first one received, with the file's direction (tracker
//! to scenario); steering does not start without it; a later different one is refused (counted,
//! logged, the first kept).

mod lab_support;

use lab_support::{log_lines, temp_path, Lab};
use needle_e2e::example;
use serde_json::Value;

const NAME: &str = "ReferenceToScenario";

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

/// Seed 3's simulated run.
fn simulated(file: &str) -> Value {
    lab_support::simulated(file, 3, 1)[0].clone()
}

/// A tracker turned 90 degrees about z and moved, as in lab_steer's file test.
fn registration_file(name: &str) -> std::path::PathBuf {
    let path = temp_path(name);
    std::fs::write(
        &path,
        r#"{"rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "translation_mm": [100, -50, 25]}"#,
    )
    .unwrap();
    path
}

fn commands(lines: &[Value]) -> Vec<&str> {
    lines
        .iter()
        .filter(|l| l["event"] == "command")
        .map(|l| l["text"].as_str().unwrap())
        .collect()
}

fn close(a: &Value, b: &Value) -> bool {
    (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() < 1e-3
}

/// The lab sends the registration by the stream (and the poses in the tracker's frame): steered
/// as simulated; the log has the registration before the first command. Then the same
/// registration moved 5 mm after piece 20: refused on every pose after it, the insertion still
/// steered as simulated.
#[test]
fn the_streamed_registration_is_used_and_a_later_different_one_refused() {
    let file = paper();
    let expected = simulated(&file);
    let reg = registration_file("streamed.json");
    let reg = reg.to_str().unwrap();
    let log = temp_path("streamed.jsonl");
    let mut lab = Lab::start(
        &file,
        3,
        &["--registration", reg, "--registration-name", NAME],
    );
    let v = lab.steer(
        &file,
        &["--registration-name", NAME, "--log", log.to_str().unwrap()],
    );
    let truth = lab.next_run();
    assert_eq!(v["stop_reason"], expected["stop_reason"]);
    assert!(close(&truth["target_error"], &expected["target_error"]));
    assert_eq!(v["steering"]["readings"], expected["steering"]["readings"]);
    assert_eq!(v["registrations_refused"], 0);
    let lines = log_lines(&log);
    let at = |event: &str| lines.iter().position(|l| l["event"] == event).unwrap();
    assert!(at("registration") < at("command"));
    let got = &lines[at("registration")];
    assert_eq!(got["name"], NAME);
    assert_eq!(
        got["translation_mm"],
        serde_json::json!([100.0, -50.0, 25.0])
    );
    drop(lab);

    let changing = [
        "--registration",
        reg,
        "--registration-name",
        NAME,
        "--registration-change-after",
        "20",
    ];
    let mut lab = Lab::start(&file, 3, &changing);
    let v = lab.steer(
        &file,
        &["--registration-name", NAME, "--log", log.to_str().unwrap()],
    );
    let truth = lab.next_run();
    assert!(close(&truth["target_error"], &expected["target_error"]));
    let pieces = truth["pieces"].as_u64().unwrap();
    assert_eq!(v["registrations_refused"], pieces - 20, "{v}");
    let lines = log_lines(&log);
    let refused: Vec<&Value> = lines
        .iter()
        .filter(|l| l["event"] == "registration_refused")
        .collect();
    assert!(!refused.is_empty());
    assert_eq!(refused[0]["translation_mm"][0], 105.0);
    let _ = std::fs::remove_file(log);
}

/// `--registration-name` and no such TRANSFORM: after the timeout, no step list went out (the
/// robot was only told stop), the exit status is 5 (stopped) with a clear message, and the JSON
/// and the log say `no_registration`.
#[test]
fn steering_does_not_start_without_the_registration() {
    let file = paper();
    let reg = registration_file("unsent.json");
    let log = temp_path("unsent.jsonl");
    let lab = Lab::start(&file, 3, &["--registration", reg.to_str().unwrap()]);
    let started = std::time::Instant::now();
    let out = lab
        .steer_command(
            &file,
            &[
                "--registration-name",
                NAME,
                "--registration-timeout-ms",
                "300",
                "--json",
                "--log",
                log.to_str().unwrap(),
            ],
        )
        .output()
        .unwrap();
    assert!(started.elapsed().as_millis() >= 300);
    assert_eq!(out.status.code(), Some(5), "stopped by an interlock");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no registration TRANSFORM named ReferenceToScenario"),
        "{err}"
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["stop_reason"], "no_registration");
    assert_eq!(v["steering"]["readings"], 0);
    assert_eq!(v["robot_stopped"], true);
    let lines = log_lines(&log);
    assert_eq!(commands(&lines), ["stop"]);
    assert!(lines.iter().any(|l| l["event"] == "no_registration"));
    assert_eq!(lines.last().unwrap()["stop_reason"], "no_registration");
    let _ = std::fs::remove_file(log);
}
