//! The whole insertion is commanded: the posture (the tilt about the entry and the starting
//! roll) is the robot's first command, before any step list; the robot reports absolute rolls
//! (the posture's, up to whole turns, plus the rotations since); a robot that starts at another
//! roll turns to the posture's and steers as simulated; a fixed guide refuses a tilted posture
//! and steering stops naming it, while a plan with the heading fixed steers through the guide.

mod lab_support;

use lab_support::{log_lines, simulated, temp_path, Lab};
use needle_e2e::{example, workspace};

fn path(name: &str) -> String {
    example(name).to_str().unwrap().to_string()
}

fn commands(lines: &[serde_json::Value]) -> Vec<String> {
    lines
        .iter()
        .filter(|l| l["event"] == "command")
        .map(|l| l["text"].as_str().unwrap().to_string())
        .collect()
}

/// The posture goes out first, with the plan's angles as the log's plan line has them, and the
/// robot's answer is logged before the three clock exchanges (`hold`) and the step list.
#[test]
fn the_posture_is_the_first_command() {
    let file = path("paper");
    let log = temp_path("posture.jsonl");
    let lab = Lab::start(&file, 1, &[]);
    let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    assert_eq!(v["outcome"], "reached", "{v}");
    let lines = log_lines(&log);
    let posture = &lines[0]["posture"];
    let sent = commands(&lines);
    let angle = |key: &str| posture[key].as_f64().unwrap() as f32;
    let want = format!(
        "posture theta1_deg={} theta2_deg={} roll_deg={}",
        angle("theta1_deg"),
        angle("theta2_deg"),
        angle("roll_deg")
    );
    assert_eq!(sent[0], want);
    assert_eq!(
        posture["roll_deg"], 180.0,
        "paper starts rolled half a turn"
    );
    // Then the clock exchanges, then the step list.
    assert_eq!(sent[1..4], ["hold", "hold", "hold"], "{sent:?}");
    assert!(sent[4].starts_with("steps count="), "{sent:?}");
    let events: Vec<&str> = lines.iter().map(|l| l["event"].as_str().unwrap()).collect();
    let set = events.iter().position(|e| *e == "posture_set").unwrap();
    let steps = lines
        .iter()
        .position(|l| l["text"].as_str().is_some_and(|t| t.starts_with("steps")))
        .unwrap();
    assert!(set < steps, "{events:?}");
    let _ = std::fs::remove_file(log);
}

/// A robot whose base starts at another absolute roll turns to the posture's by the shorter
/// way (400 deg: to 540 for paper's 180, 294.2 for space's -65.8) and reports absolute rolls
/// from there: the insertions end as simulated, bit for bit.
#[test]
fn a_robot_starting_at_another_roll_steers_as_simulated() {
    for (name, start, runs) in [
        ("paper", "400", 4),
        ("space", "400", 2),
        ("paper", "-250", 2),
    ] {
        let file = path(name);
        let log = temp_path(&format!("roll-{name}-{start}.jsonl"));
        let expected = simulated(&file, 1, runs);
        let mut lab = Lab::start(&file, 1, &["--robot-start-roll", start]);
        for (i, sim) in expected.iter().enumerate() {
            let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
            let truth = lab.next_run();
            let what = format!("{name} from {start} deg, seed {}", i + 1);
            assert_eq!(truth["target_error"], sim["target_error"], "{what}");
            assert_eq!(v["stop_reason"], sim["stop_reason"], "{what}");
            assert_eq!(v["steering"], sim["steering"], "{what}");
            let lines = log_lines(&log);
            let set = lines.iter().find(|l| l["event"] == "posture_set").unwrap();
            let roll = lines[0]["posture"]["roll_deg"].as_f64().unwrap();
            let base = set["base_deg"].as_f64().unwrap();
            let start: f64 = start.parse().unwrap();
            assert!((base - roll).rem_euclid(360.0) < 1e-6, "{what}: {set}");
            assert!((base - start).abs() <= 180.0, "{what}: the shorter way");
        }
        let _ = std::fs::remove_file(log);
    }
}

/// A fixed guide cannot tilt: paper's plan (tilted 28.7 deg) stops before anything moved,
/// naming the posture, exit status 5; the robot heard only the posture and the stop.
#[test]
fn a_fixed_guide_refuses_a_tilted_posture() {
    let file = path("paper");
    let log = temp_path("guide.jsonl");
    let mut lab = Lab::start(&file, 1, &["--robot-fixed-guide"]);
    let (code, v) = lab.steer_ending(&file, &["--log", log.to_str().unwrap()]);
    assert_eq!(code, 5, "{v}");
    assert_eq!(
        (v["outcome"].as_str(), v["stop_reason"].as_str()),
        (Some("stopped"), Some("posture_refused"))
    );
    let why = v["why"].as_str().unwrap();
    assert!(why.contains("tilted 28.67 deg"), "{why}");
    assert!(why.contains("rolled 180 deg"), "{why}");
    assert!(why.contains("max_tilt_deg = 0"), "{why}");
    let lines = log_lines(&log);
    let sent = commands(&lines);
    assert_eq!(sent.len(), 2, "{sent:?}");
    assert!(
        sent[0].starts_with("posture ") && sent[1] == "stop",
        "{sent:?}"
    );
    let truth = lab.next_run();
    assert_eq!(
        (truth["end"].as_str(), truth["pieces"].as_u64()),
        (Some("stopped"), Some(0))
    );
    assert_eq!(v["robot_stopped"], true);
    let _ = std::fs::remove_file(log);
}

/// The same guide takes a posture without tilt: paper planned with its heading fixed
/// (`entry.max_tilt_deg = 0`) steers through it as simulated.
#[test]
fn a_fixed_guide_steers_a_plan_with_the_heading_fixed() {
    let file = workspace()
        .join("tests/data/fixed_heading/paper.toml")
        .to_str()
        .unwrap()
        .to_string();
    let expected = simulated(&file, 1, 2);
    let mut lab = Lab::start(&file, 1, &["--robot-fixed-guide"]);
    for sim in &expected {
        let v = lab.steer(&file, &[]);
        let truth = lab.next_run();
        assert_ne!(v["stop_reason"], "posture_refused", "{v}");
        assert_eq!(truth["target_error"], sim["target_error"], "{v}");
        assert_eq!(v["steering"], sim["steering"], "{v}");
    }
}
