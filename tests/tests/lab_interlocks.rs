//! The interlocks of `needle steer`, each triggered on the simulated lab: the tracker going
//! quiet, the robot going quiet, poses flagged invalid, Ctrl-C. Each ends with the robot told to
//! stop within the configured time and the insertion log complete; and the latency from a pose
//! to the robot's command over more than 1000 readings.

mod lab_support;

use lab_support::{log_lines, temp_path, Lab};
use needle_e2e::example;
use serde_json::Value;
use std::process::Stdio;
use std::time::{Duration, Instant};

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

fn commands(lines: &[Value]) -> Vec<String> {
    lines
        .iter()
        .filter(|l| l["event"] == "command")
        .map(|l| l["text"].as_str().unwrap().to_string())
        .collect()
}

fn time_of(lines: &[Value], pred: impl Fn(&Value) -> bool) -> f64 {
    lines
        .iter()
        .rev()
        .find(|l| pred(l))
        .and_then(|l| l["t_ms"].as_f64())
        .expect("the log has the line")
}

/// The tracker goes quiet after 10 poses: after the tracking timeout the robot is told hold,
/// then stop; the log ends with the stop.
#[test]
fn tracking_lost_holds_then_stops_the_robot() {
    let file = paper();
    let log = temp_path("tracking.jsonl");
    let mut lab = Lab::start(&file, 2, &["--tracker-silent-after", "10"]);
    let v = lab.steer(
        &file,
        &[
            "--tracking-timeout-ms",
            "300",
            "--log",
            log.to_str().unwrap(),
        ],
    );
    assert_eq!(v["stop_reason"], "tracking_lost");
    assert_eq!(v["robot_stopped"], true);
    assert_eq!(v["steering"]["readings"], 10);
    let truth = lab.next_run();
    assert_eq!(truth["end"], "stopped");
    assert_eq!(
        truth["pieces"], 11,
        "the robot did one piece more, unseen, and stopped"
    );
    let lines = log_lines(&log);
    let cmds = commands(&lines);
    assert_eq!(cmds[cmds.len() - 2..], ["hold", "stop"]);
    let last_reading = time_of(&lines, |l| l["event"] == "reading");
    let hold = time_of(&lines, |l| l["text"] == "hold");
    let waited = hold - last_reading;
    assert!(
        (300.0..800.0).contains(&waited),
        "hold {waited} ms after the last pose"
    );
    assert_eq!(lines.last().unwrap()["event"], "stop");
    assert_eq!(lines.last().unwrap()["stop_reason"], "tracking_lost");
    let _ = std::fs::remove_file(log);
}

/// The robot stops reporting after 10 pieces: after the robot timeout it is told stop (which
/// the simulated robot still obeys), and the log ends with the stop.
#[test]
fn a_robot_that_does_not_answer_is_stopped() {
    let file = paper();
    let log = temp_path("robot.jsonl");
    let mut lab = Lab::start(&file, 2, &["--robot-silent-after", "10"]);
    let started = Instant::now();
    let v = lab.steer(
        &file,
        &["--robot-timeout-ms", "300", "--log", log.to_str().unwrap()],
    );
    assert!(started.elapsed() < Duration::from_secs(10));
    assert_eq!(v["stop_reason"], "robot_not_answering");
    assert_eq!(v["robot_stopped"], false, "a silent robot confirms nothing");
    assert_eq!(lab.next_run()["end"], "stopped", "the robot got the stop");
    let lines = log_lines(&log);
    assert_eq!(commands(&lines).last().unwrap(), "stop");
    let last_reading = time_of(&lines, |l| l["event"] == "reading");
    let stop = time_of(&lines, |l| l["text"] == "stop");
    assert!((300.0..800.0).contains(&(stop - last_reading)));
    assert_eq!(lines.last().unwrap()["stop_reason"], "robot_not_answering");
    let _ = std::fs::remove_file(log);
}

/// Every 7th pose is flagged invalid (by v3 metadata, then by a tip STATUS, alternately): none
/// is used, the controller sees each as a reading without a fix.
#[test]
fn poses_flagged_invalid_are_not_used() {
    let file = paper();
    let log = temp_path("invalid.jsonl");
    let mut lab = Lab::start(&file, 5, &["--invalid-every", "7"]);
    let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    let readings = v["steering"]["readings"].as_u64().unwrap();
    assert!(readings >= 14, "both kinds of flag were sent");
    assert_eq!(v["invalid_poses"], readings / 7);
    assert_eq!(v["steering"]["no_fix"], readings / 7);
    assert_eq!(lab.next_run()["end"], "stopped");
    let lines = log_lines(&log);
    let without_pose = lines
        .iter()
        .filter(|l| l["event"] == "reading" && l["measurement"]["pose"].is_null())
        .count() as u64;
    assert_eq!(without_pose, readings / 7);
    let _ = std::fs::remove_file(log);
}

/// Ctrl-C (SIGINT) mid-insertion: the robot is told stop before `needle steer` exits, and the
/// log ends with the stop.
#[test]
fn sigint_stops_the_robot_before_exit() {
    let file = paper();
    let log = temp_path("sigint.jsonl");
    // 40 pieces a second: the insertion takes over 3 s.
    let mut lab = Lab::start(&file, 2, &["--rate", "40"]);
    let child = lab
        .steer_command(&file, &["--json", "--log", log.to_str().unwrap()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("start needle steer");
    std::thread::sleep(Duration::from_millis(800));
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("send SIGINT");
    assert!(status.success());
    let out = child.wait_with_output().expect("needle steer ends");
    assert_eq!(
        out.status.code(),
        Some(5),
        "an interrupted insertion is stopped"
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("the outcome is printed");
    assert_eq!(v["stop_reason"], "interrupted");
    assert_eq!(v["robot_stopped"], true);
    let truth = lab.next_run();
    assert_eq!(truth["end"], "stopped");
    assert!(
        truth["pieces"].as_u64().unwrap() < 100,
        "stopped mid-insertion"
    );
    let lines = log_lines(&log);
    assert_eq!(commands(&lines).last().unwrap(), "stop");
    assert_eq!(lines.last().unwrap()["stop_reason"], "interrupted");
    let _ = std::fs::remove_file(log);
}

/// Pose received to robot command sent, over more than 1000 readings of paper insertions on the
/// lab (each reading's `latency_ms` in the log): the median and the largest are printed; the
/// largest stays under a 40 Hz tracker's period (25 ms).
#[test]
fn latency_from_pose_to_command_over_a_thousand_readings() {
    let file = paper();
    let lab = Lab::start(&file, 1, &[]);
    let mut all = Vec::new();
    let mut seed = 0;
    while all.len() < 1000 {
        seed += 1;
        let log = temp_path(&format!("latency-{seed}.jsonl"));
        let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
        let interlocks = [
            "tracking_lost",
            "robot_not_answering",
            "robot_disconnected",
            "tracker_disconnected",
            "robot_stopped",
        ];
        let reason = v["stop_reason"].as_str().unwrap_or("");
        assert!(!interlocks.contains(&reason), "no interlock: {v}");
        for l in log_lines(&log) {
            if l["event"] == "reading" {
                all.push(l["latency_ms"].as_f64().expect("each reading's latency"));
            }
        }
        let _ = std::fs::remove_file(log);
    }
    all.sort_by(f64::total_cmp);
    let (median, max) = (all[all.len() / 2], all[all.len() - 1]);
    println!(
        "latency pose -> command over {} readings: median {median:.3} ms, max {max:.3} ms",
        all.len()
    );
    assert!(median > 0.0);
    assert!(max <= 25.0, "max {max} ms");
}

/// Insertion without a usable pose: with every pose flagged invalid, the controller stops with
/// `tracking_lost` once the robot has pushed 2 mm without a fix (the lab's default
/// `tracking_lost_after_mm`, told to the controller when the scenario does not set it), and the
/// robot is told hold, then stop.
#[test]
fn insertion_without_a_pose_stops_after_the_set_length() {
    let file = paper();
    let log = temp_path("no-pose.jsonl");
    let mut lab = Lab::start(&file, 2, &["--invalid-every", "1"]);
    let v = lab.steer(
        &file,
        &[
            "--steer",
            "tracking_lost_after_mm=2",
            "--log",
            log.to_str().unwrap(),
        ],
    );
    let sent: Vec<String> = log_lines(&log)
        .iter()
        .filter(|l| l["event"] == "command")
        .map(|l| l["text"].as_str().unwrap_or_default().to_string())
        .collect();
    let last_two: Vec<&str> = sent
        .iter()
        .rev()
        .take(2)
        .rev()
        .map(String::as_str)
        .collect();
    assert_eq!(last_two, ["hold", "stop"], "{sent:?}");
    assert_eq!(v["stop_reason"], "tracking_lost");
    assert_eq!(v["robot_stopped"], true);
    let readings = v["steering"]["readings"].as_u64().unwrap();
    assert_eq!(v["invalid_poses"], readings);
    let truth = lab.next_run();
    assert_eq!(truth["end"], "stopped");
    let pieces = truth["pieces"].as_u64().unwrap();
    assert!(
        (2..=4).contains(&pieces),
        "stopped after about 2 mm: {pieces} pieces"
    );
}

/// The robot reports 5 mm more depth than it inserted (after 10 pieces): progress its commands
/// cannot give stops it, and the log says why.
#[test]
fn a_robot_whose_progress_disagrees_is_stopped() {
    let file = paper();
    let log = temp_path("disagrees.jsonl");
    let mut lab = Lab::start(&file, 2, &["--robot-misreport-after", "10"]);
    let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    assert_eq!(v["stop_reason"], "robot_disagrees");
    assert_eq!(v["robot_stopped"], true);
    assert_eq!(v["steering"]["readings"], 10);
    let truth = lab.next_run();
    assert_eq!(
        (truth["end"].as_str(), truth["pieces"].as_u64()),
        (Some("stopped"), Some(11))
    );
    let lines = log_lines(&log);
    let why = lines
        .iter()
        .find(|l| l["event"] == "robot_disagrees")
        .unwrap();
    assert!(why["why"].as_str().unwrap().contains("jumped"), "{why}");
    assert_eq!(commands(&lines).last().unwrap(), "stop");
    assert_eq!(lines.last().unwrap()["stop_reason"], "robot_disagrees");
    let _ = std::fs::remove_file(log);
}
