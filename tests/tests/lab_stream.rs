//! A tracker streaming at 1 kHz with bursts (`hil-sim --lab --stream-rate 1000 --stream-burst
//! 20`), against a robot paced at 50 pieces a second, each report 3 ms after its pose:
//! `needle steer` uses the newest pose, counts
//! the ones superseded and the copies of a sample already used, does not lag, and steers as
//! `needle simulate --closed-loop` does for the seed (the stream repeats each piece's sample with
//! its timestamp, so a copy is never taken for a new measurement). Its own binary: the stream
//! loads the machine for the few seconds it lasts.

mod lab_support;

use lab_support::{log_lines, simulated, temp_path, Lab};
use needle_e2e::example;

#[test]
fn a_1khz_stream_with_bursts_steers_as_simulated_without_backlog() {
    let file = example("paper").to_str().unwrap().to_string();
    let expected = simulated(&file, 3, 1)[0].clone();
    let log = temp_path("stream.jsonl");
    // The robot's report 3 ms after its pose: the stream's copies of it arrive first.
    let stream = [
        "--stream-rate",
        "1000",
        "--stream-burst",
        "20",
        "--rate",
        "50",
        "--report-delay-ms",
        "3",
    ];
    let mut lab = Lab::start(&file, 3, &stream);
    let started = std::time::Instant::now();
    let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
    let elapsed = started.elapsed();
    let truth = lab.next_run();
    assert_eq!(v["stop_reason"], expected["stop_reason"], "{v}");
    assert_eq!(truth["target_error"], expected["target_error"]);
    assert_eq!(v["steering"], expected["steering"]);
    assert_eq!(v["robot_stopped"], true);
    // Over 2 s at 1 kHz: thousands of copies of used poses, none used twice; copies of each new
    // pose before its report superseded.
    let pieces = truth["pieces"].as_u64().unwrap();
    assert!(
        elapsed.as_secs_f64() > pieces as f64 / 50.0 * 0.9,
        "{elapsed:?}"
    );
    let repeated = v["repeated_poses"].as_u64().unwrap();
    let superseded = v["superseded_poses"].as_u64().unwrap();
    assert!(repeated > 1000, "{v}");
    assert!(superseded > pieces / 2, "{v}");
    assert_eq!(v["rejected_frames"], 0);
    // No lag: every pose reached the robot's command within a 40 Hz period.
    let max = v["latency_ms"]["max"].as_f64().unwrap();
    assert!(max <= 25.0, "latency max {max} ms");
    let lines = log_lines(&log);
    let stop = lines.last().unwrap();
    assert_eq!(stop["event"], "stop");
    assert_eq!(stop["superseded_poses"], v["superseded_poses"]);
    assert_eq!(stop["repeated_poses"], v["repeated_poses"]);
    let per_reading: u64 = lines
        .iter()
        .filter(|l| l["event"] == "reading")
        .map(|l| {
            l["superseded_poses"]
                .as_u64()
                .expect("each reading's count")
        })
        .sum();
    assert!(per_reading > 0 && per_reading <= superseded);
    let _ = std::fs::remove_file(log);
}
