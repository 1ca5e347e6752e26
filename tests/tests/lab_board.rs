//! `needle steer` with a driver board instead of a robot (simulated): `hil-sim --lab
//! --board-port` serves the simulated device with the bench's stages in real time and a
//! free-running tracker over the world, which takes each piece the board finished. After
//! `needle motion arm` and `home`, `needle steer --tcp BOARD` (no `--robot`) has the board plan,
//! steer and move the paper's insertion (at the bench's 10 mm/s, so it takes seconds); the host
//! relays poses sampled after each piece ended.
//! The insertion ends as the host's simulation of the same board ends (`needle_sim::driven_loop`
//! with the in-process controller), bit for bit; Ctrl-C stops the board where it is.

mod lab_support;

use lab_support::{ending, log_lines, slicer_listener, spawn, temp_path};
use needle_e2e::{example, needle};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};

/// A running `hil-sim --lab --board-port`, killed when dropped.
struct BoardLab {
    child: Child,
    tracker: String,
    board: String,
    runs: BufReader<ChildStdout>,
}

impl BoardLab {
    fn start(file: &str, seed: u64, flags: &[&str]) -> BoardLab {
        let mut extra = vec!["--real-time", "--tracker-rate", "200"];
        extra.extend_from_slice(flags);
        let (child, runs, tracker, board) = spawn(file, seed, "board", &extra);
        BoardLab {
            tracker,
            board,
            child,
            runs,
        }
    }

    fn motion(&self, what: &str) -> Value {
        let out = needle()
            .args(["motion", what, "--tcp", &self.board, "--json"])
            .output()
            .expect("needle motion");
        assert!(
            out.status.success(),
            "needle motion {what}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("a status")
    }

    fn steer(&self, file: &str, extra: &[&str]) -> (i32, Value) {
        let mut c = needle();
        c.args([
            "steer",
            file,
            "--tracker",
            &self.tracker,
            "--tcp",
            &self.board,
        ])
        .args(["--tilt-set", "--json"])
        .args(extra);
        ending(&mut c)
    }

    fn next_run(&mut self) -> Value {
        let mut line = String::new();
        self.runs.read_line(&mut line).expect("read a run");
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
    }
}

impl Drop for BoardLab {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The paper's scenario with the bench's fastest insertion (10 mm/s), so that a real-time
/// insertion takes seconds: a file of its own.
fn fast_paper(name: &str) -> String {
    let text = std::fs::read_to_string(example("paper")).unwrap();
    let path = temp_path(name);
    std::fs::write(&path, format!("{text}\n[driver]\ninsert_speed = 10.0\n")).unwrap();
    path.to_str().unwrap().to_string()
}

/// The host's simulation of the same board: `file` planned as `needle steer` plans it, the
/// world of `seed` on the board's pieces, the in-process controller.
fn host_simulation(file: &str, seed: u64) -> needle_sim::ClosedRun {
    let file = std::path::PathBuf::from(file);
    let request = needle_simulate::request::Request {
        steer: vec!["tracking_lost_after_mm=2".into()],
        ..Default::default()
    };
    let setup = needle_simulate::closed_loop_setup(&file, seed, &request).expect("set up");
    let mut here =
        needle_sim::in_process(&setup.scenario, &setup.prepared.schedule, &setup.config).unwrap();
    let world = needle_sim::Conditions {
        perturbation: &setup.perturbation,
        effects: &setup.effects,
        faults: &setup.faults,
    };
    let schedule = &setup.prepared.schedule;
    needle_sim::driven_loop(
        &setup.scenario,
        &setup.planned,
        schedule,
        &world,
        &mut here,
        seed,
        1.0,
    )
    .unwrap()
}

#[test]
fn the_board_steers_the_papers_insertion_from_relayed_poses() {
    let file = fast_paper("board-paper.toml");
    let mut lab = BoardLab::start(&file, 3, &[]);
    // Nothing moves before an explicit arm and homing.
    let (code, refused) = lab.steer(&file, &[]);
    assert_eq!(code, 5, "{refused}");
    assert_eq!(refused["stop_reason"], "board_faulted", "{refused}");
    lab.motion("arm");
    let homed = lab.motion("home");
    assert_eq!(homed["homed"], true, "{homed}");
    let log = temp_path("board-steer.jsonl");
    let (address, slicer) = slicer_listener();
    let (code, v) = lab.steer(
        &file,
        &["--log", log.to_str().unwrap(), "--slicer", &address],
    );
    assert_eq!((code, &v["outcome"]), (0, &Value::from("reached")), "{v}");
    let truth = lab.next_run();
    let expected = host_simulation(&file, 3);
    assert_eq!(
        truth["target_error"].as_f64().map(|e| e as f32),
        Some(expected.run.target_error),
        "{truth}"
    );
    assert_eq!(truth["pieces"], expected.run.steps.len(), "{truth}");
    let steering: needle_sim::ClosedRun = expected;
    assert_eq!(v["steering"]["readings"], steering.stats.readings, "{v}");
    assert_eq!(v["steering"]["replans"], steering.stats.replans, "{v}");
    let lines = log_lines(&log);
    assert!(
        lines.iter().any(|l| l["event"] == "board_drive"),
        "{lines:?}"
    );
    board_estimates_are_shown_and_logged(&lines, &slicer.join().unwrap(), &steering);
    let _ = std::fs::remove_file(log);
}

/// Slicer sees the board's estimated tip at every reading and each continuation the board
/// planned, the log has each estimate, and the last is where the insertion ended.
fn board_estimates_are_shown_and_logged(
    lines: &[Value],
    frames: &[needle_igtl::Frame],
    steering: &needle_sim::ClosedRun,
) {
    let named = |name: &str| frames.iter().filter(|f| f.info.device_name == name).count();
    let readings = steering.stats.readings as usize;
    assert_eq!(named("NeedleTipEstimate"), readings);
    let replaced = lines
        .iter()
        .filter(|l| l["event"] == "reading")
        .filter(|l| l["reply"]["command"].get("Replace").is_some())
        .count();
    assert!(replaced > 0, "the board replanned");
    assert_eq!(named("NeedleContinuation"), replaced);
    let estimates: Vec<&Value> = lines
        .iter()
        .filter(|l| l["event"] == "reading")
        .map(|l| &l["estimate"])
        .collect();
    assert_eq!(estimates.len(), readings);
    let last: Vec<f32> = serde_json::from_value(estimates[readings - 1]["position"].clone())
        .expect("the last estimate's position");
    let tip = steering.run.points.last().expect("the true tip path");
    let off = (0..3)
        .map(|i| (last[i] - tip[i]).powi(2))
        .sum::<f32>()
        .sqrt();
    assert!(
        off < 1.0,
        "the last estimate {last:?} is {off} mm from {tip:?}"
    );
}

/// The registration sent by the tracker stream (`--registration-name`, poses in the tracker's
/// frame, turned 90 degrees and moved): the board moves nothing before it arrives, every
/// relayed reading is mapped by it, and the insertion ends as the host simulates it.
#[test]
fn a_streamed_registration_maps_the_boards_readings() {
    let file = fast_paper("board-registered.toml");
    let reg = temp_path("board-registration.json");
    std::fs::write(
        &reg,
        r#"{"rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "translation_mm": [100, -50, 25]}"#,
    )
    .unwrap();
    let reg = reg.to_str().unwrap();
    let name = "ReferenceToScenario";
    let mut lab = BoardLab::start(
        &file,
        3,
        &["--registration", reg, "--registration-name", name],
    );
    lab.motion("arm");
    lab.motion("home");
    let log = temp_path("board-registered.jsonl");
    let log_flag = ["--log", log.to_str().unwrap()];
    let (code, v) = lab.steer(
        &file,
        &[&log_flag[..], &["--registration-name", name]].concat(),
    );
    assert_eq!((code, &v["outcome"]), (0, &Value::from("reached")), "{v}");
    let truth = lab.next_run();
    let expected = host_simulation(&file, 3);
    let error = truth["target_error"].as_f64().unwrap() as f32;
    assert!(
        (error - expected.run.target_error).abs() < 1e-3,
        "{error} vs the host's {}",
        expected.run.target_error
    );
    let events: Vec<String> = log_lines(&log)
        .iter()
        .map(|l| l["event"].as_str().unwrap_or("").to_string())
        .collect();
    let at = |e: &str| events.iter().position(|x| x == e);
    assert!(
        at("registration").is_some() && at("registration") < at("board_drive"),
        "{events:?}"
    );
    let _ = std::fs::remove_file(log);
}

/// Ctrl-C during a board-driven insertion: the board is told to stop, the insertion ends
/// `stopped` (`interrupted`, exit 5), and the stage stands where it stopped, short of the plan.
#[test]
fn ctrl_c_stops_the_board_mid_insertion() {
    let file = fast_paper("board-ctrl-c.toml");
    let lab = BoardLab::start(&file, 4, &[]);
    lab.motion("arm");
    lab.motion("home");
    let log = temp_path("board-ctrl-c.jsonl");
    let _ = std::fs::remove_file(&log);
    let child = needle()
        .args([
            "steer",
            &file,
            "--tracker",
            &lab.tracker,
            "--tcp",
            &lab.board,
        ])
        .args(["--tilt-set", "--json", "--log", log.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Under way: a few readings answered (planning may take seconds on a loaded machine).
    let start = std::time::Instant::now();
    while log_lines_now(&log) < 5 {
        assert!(start.elapsed().as_secs() < 120, "no readings");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(5), "{v} {err}");
    assert_eq!(
        (&v["outcome"], &v["stop_reason"]),
        (&Value::from("stopped"), &Value::from("interrupted")),
        "{v}"
    );
    assert_eq!(v["robot_stopped"], true, "{v}");
    assert!(
        err.contains("interrupted: the board was told to stop"),
        "{err}"
    );
    let s = lab.motion("status");
    assert_eq!(
        (&s["state"], &s["moves_left"]),
        (&Value::from("armed"), &Value::from(0)),
        "{s}"
    );
    let depth = s["insertion_mm"].as_f64().unwrap();
    assert!(depth > 1.0 && depth < 80.0, "stopped mid-insertion: {s}");
}

/// Readings in the insertion log so far.
fn log_lines_now(path: &std::path::Path) -> usize {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter(|l| l.contains("\"reading\""))
        .count()
}
