//! `needle steer` against the simulated lab in real time (`hil-sim --lab --real-time`): a
//! free-running tracker sampling the tip (each sample stamped when taken) and a robot whose
//! pieces take their share of the plan's durations (sped up). A reading uses a pose sampled
//! after its piece ended, so an insertion still ends as `needle simulate --closed-loop` ends the
//! run of its seed, bit for bit, also with a tracker whose poses lag the robot by 100 ms; and
//! the program's reaction (pose received to command sent) over 1000 readings; bad frames in the
//! free-running stream are read past.
//!
//! The tests take turns: they time the program, and two labs and two steering programs at once
//! on two cores would time the machine instead.

mod lab_support;

use lab_support::{log_lines, simulated, temp_path, Lab};
use needle_e2e::example;
use serde_json::Value;
use std::sync::Mutex;

static TURN: Mutex<()> = Mutex::new(());

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

/// Steers `runs` paper insertions from seed 1 on a real-time lab with `extra` flags: each ends
/// as simulated, bit for bit, and every reading used a pose sampled once its piece had ended.
/// Gives each insertion's JSON and reading lines.
fn steers_as_simulated(runs: usize, extra: &[&str]) -> Vec<(Value, Vec<Value>)> {
    let file = paper();
    let expected = simulated(&file, 1, runs);
    let mut flags = vec!["--real-time"];
    flags.extend_from_slice(extra);
    let mut lab = Lab::start(&file, 1, &flags);
    let mut out = Vec::new();
    for (i, sim) in expected.iter().enumerate() {
        let log = temp_path(&format!("real-time-{i}.jsonl"));
        let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
        let truth = lab.next_run();
        let what = format!("seed {} with {extra:?}", i + 1);
        assert_eq!(truth["target_error"], sim["target_error"], "{what}");
        assert_eq!(truth["path_rms"], sim["path_rms"], "{what}");
        assert_eq!(v["stop_reason"], sim["stop_reason"], "{what}");
        assert_eq!(v["steering"], sim["steering"], "{what}");
        let readings: Vec<Value> = log_lines(&log)
            .into_iter()
            .filter(|l| l["event"] == "reading")
            .collect();
        for r in &readings {
            let sampled = r["pose_sampled_s"].as_f64().expect("stamped poses");
            let ended = r["piece_ended_s"].as_f64().expect("stamped reports");
            assert!(
                sampled >= ended,
                "{what}: a pose sampled before its piece ended: {r}"
            );
        }
        let _ = std::fs::remove_file(log);
        out.push((v, readings));
    }
    out
}

/// A free-running 40 Hz tracker, the pieces at a twentieth of their durations.
#[test]
fn real_time_insertions_steer_as_simulated() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let runs = steers_as_simulated(3, &["--tracker-rate", "40", "--time-scale", "0.05"]);
    for (v, _) in &runs {
        assert_eq!(v["clock_offset_applied"], false, "one clock: {v}");
    }
}

/// A free-running tracker that sends a bad frame before every fifth sample: each is rejected and
/// counted, none costs a reading, and the insertion ends as simulated.
#[test]
fn bad_frames_in_a_free_running_stream_are_read_past() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let extra = [
        "--tracker-rate",
        "40",
        "--time-scale",
        "0.05",
        "--bad-frames-every",
        "5",
    ];
    let runs = steers_as_simulated(1, &extra);
    let (v, _) = &runs[0];
    let rejected = v["rejected_frames"].as_u64().unwrap();
    let ignored = v["ignored_frames"].as_u64().unwrap();
    // Four of the five kinds are rejected, the fifth (a name one letter off) ignored.
    assert!(rejected >= 4 && ignored >= 1, "{v}");
    assert!(rejected <= 4 * ignored + 4, "the kinds in turn: {v}");
}

/// A robot whose clock runs 300 ms behind the tracker's (and this machine's): its piece ends
/// are stamped early, so poses sampled before a piece truly ended (a 200 Hz tracker samples a
/// few during each piece) look fresh by the stamps. The
/// `hold`/`holding` exchanges at the start prove it behind and move its stamps forward: every
/// reading still uses a pose sampled after its piece ended, and the insertion ends as simulated.
/// (Judged here by the simulation's end alone: the log's stamps are the robot's own.)
#[test]
fn a_robot_clock_behind_is_found_and_corrected() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let file = paper();
    let expected = simulated(&file, 1, 2);
    let extra = [
        "--real-time",
        "--tracker-rate",
        "200",
        "--time-scale",
        "0.05",
        "--robot-clock-offset-ms",
        "-300",
    ];
    let mut lab = Lab::start(&file, 1, &extra);
    for (i, sim) in expected.iter().enumerate() {
        let log = temp_path(&format!("robot-behind-{i}.jsonl"));
        let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
        let truth = lab.next_run();
        assert_eq!(
            truth["target_error"],
            sim["target_error"],
            "seed {}: {v}",
            i + 1
        );
        assert_eq!(v["steering"], sim["steering"], "seed {}", i + 1);
        assert_eq!(v["clock_offset_applied"], true, "{v}");
        let clock = log_lines(&log)
            .into_iter()
            .find(|l| l["event"] == "robot_clock")
            .expect("a robot_clock line");
        let (lo, hi) = (
            clock["offset_ms_at_least"].as_f64().unwrap(),
            clock["offset_ms_at_most"].as_f64().unwrap(),
        );
        assert!(
            lo > 250.0 && lo <= 300.0 && (300.0..350.0).contains(&hi),
            "{clock}"
        );
        let _ = std::fs::remove_file(log);
    }
}

/// The tracker's poses lag the robot by 100 ms: poses sampled before the piece ended keep
/// arriving after the report and are not used (counted stale); the reading waits for one
/// sampled after, at least 100 ms old when used, and the insertion ends as simulated.
#[test]
fn a_tracker_lagging_100_ms_is_waited_for() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let extra = [
        "--tracker-rate",
        "200",
        "--time-scale",
        "0",
        "--tracker-lag-ms",
        "100",
    ];
    let runs = steers_as_simulated(1, &extra);
    let (v, readings) = &runs[0];
    assert!(v["stale_poses"].as_u64().unwrap() > 0, "{v}");
    for r in readings {
        let age = r["pose_age_ms"].as_f64().unwrap();
        let waited = r["waited_ms"].as_f64().unwrap();
        assert!(age >= 100.0, "{r}");
        // Nearly the lag: the report is read a little after the piece ended, later still on a
        // loaded machine (93 ms was seen with both cores busy), so only a fresh pose's wait is
        // asserted, not its length to the millisecond.
        assert!(waited >= 50.0, "{r}");
    }
    println!(
        "lagging tracker: pose age {}, waited {}",
        v["pose_age_ms"], v["waited_ms"]
    );
}

/// The program's reaction, from a fresh pose (or the report, when the pose came first) to the
/// robot's command, over more than 1000 readings on the real-time lab at 40 Hz: median at most
/// 5 ms, largest at most 25 ms (a 40 Hz tracker's period); the pose's age is printed beside it.
#[test]
fn reaction_over_a_thousand_real_time_readings() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let file = paper();
    let lab = Lab::start(
        &file,
        1,
        &[
            "--real-time",
            "--tracker-rate",
            "40",
            "--time-scale",
            "0.02",
        ],
    );
    let (mut reactions, mut ages) = (Vec::new(), Vec::new());
    let mut i = 0;
    while reactions.len() < 1000 {
        i += 1;
        let log = temp_path(&format!("reaction-{i}.jsonl"));
        let v = lab.steer(&file, &["--log", log.to_str().unwrap()]);
        assert!(
            ["reached", "missed"].contains(&v["outcome"].as_str().unwrap()),
            "{v}"
        );
        for l in log_lines(&log).iter().filter(|l| l["event"] == "reading") {
            reactions.push(l["reaction_ms"].as_f64().unwrap());
            ages.push(l["pose_age_ms"].as_f64().unwrap());
        }
        let _ = std::fs::remove_file(log);
    }
    for v in [&mut reactions, &mut ages] {
        v.sort_by(f64::total_cmp);
    }
    let (n, mid) = (reactions.len(), reactions.len() / 2);
    println!(
        "real-time lab, 40 Hz, over {n} readings: reaction median {:.3} ms, max {:.3} ms; \
         pose age median {:.3} ms, max {:.3} ms",
        reactions[mid],
        reactions[n - 1],
        ages[mid],
        ages[n - 1]
    );
    assert!(reactions[mid] <= 5.0, "median {}", reactions[mid]);
    assert!(reactions[n - 1] <= 25.0, "max {}", reactions[n - 1]);
}
