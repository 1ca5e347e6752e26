//! How `needle steer` ends, each way on the simulated lab (`hil-sim --lab`), and what it says:
//! the exit status (0 reached, 3 missed, 4 collided as the robot sensed it, 5 stopped by an
//! interlock or a refusal, 6 the link broken) and, with `--json`, exactly one JSON object naming
//! the ending, whatever it is.

mod lab_support;

use lab_support::{ending, log_lines, temp_path, Lab};
use needle_e2e::{example, needle};
use serde_json::Value;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::{Duration, Instant};

fn paper() -> String {
    example("paper").to_str().unwrap().to_string()
}

fn reason(v: &Value) -> (&str, &str) {
    (
        v["outcome"].as_str().unwrap_or("?"),
        v["stop_reason"].as_str().unwrap_or("null"),
    )
}

#[test]
fn reached_exits_0_and_missed_exits_3() {
    let file = paper();
    let lab = Lab::start(&file, 1, &[]);
    // The first insertion that reaches (the steering's defaults may change which seed does).
    let reached = (0..5)
        .map(|_| lab.steer_ending(&file, &[]))
        .find(|(_, v)| v["outcome"] == "reached")
        .expect("one of five insertions reaches");
    let (code, v) = reached;
    assert_eq!((code, reason(&v)), (0, ("reached", "null")), "{v}");
    // A reach tolerance no estimate meets: the steps run out and the verdict is a miss.
    let (code, v) = lab.steer_ending(&file, &["--steer", "reach_tolerance_mm=0.001"]);
    assert_eq!((code, reason(&v)), (3, ("missed", "missed")), "{v}");
}

/// An interlock: the robot's progress cannot come from its commands.
#[test]
fn an_interlock_exits_5() {
    let file = paper();
    let lab = Lab::start(&file, 2, &["--robot-misreport-after", "10"]);
    let (code, v) = lab.steer_ending(&file, &[]);
    assert_eq!(
        (code, reason(&v)),
        (5, ("stopped", "robot_disagrees")),
        "{v}"
    );
}

/// The robot's contact sensor fires: the insertion ends `collided`, exit status 4, the robot
/// already stopped and nothing more commanded; the log says so.
#[test]
fn a_collision_the_robot_senses_exits_4() {
    let file = paper();
    let mut lab = Lab::start(&file, 2, &["--robot-collides-after", "12"]);
    let log = temp_path("collided.jsonl");
    let (code, v) = lab.steer_ending(&file, &["--log", log.to_str().unwrap()]);
    assert_eq!(
        (code, reason(&v)),
        (4, ("collided", "robot_sensed_collision")),
        "{v}"
    );
    assert_eq!(v["robot_stopped"], true, "{v}");
    let truth = lab.next_run();
    assert_eq!(
        (truth["end"].as_str(), truth["pieces"].as_u64()),
        (Some("collided"), Some(13))
    );
    let lines = log_lines(&log);
    let sensed: Vec<_> = lines
        .iter()
        .filter(|l| l["event"] == "robot_sensed_collision")
        .collect();
    assert_eq!(sensed.len(), 1, "{lines:?}");
    assert!(sensed[0]["depth_mm"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_file(log);
}

/// The lab's world holds an obstacle the plan does not know of (a circle of 2 mm on the
/// paper's planned path, halfway): the true tip enters it, the robot senses it, and `needle
/// steer` ends `collided` with exit status 4, as the lab's truth says.
#[test]
fn an_obstacle_the_plan_did_not_know_ends_collided() {
    let paper_text = std::fs::read_to_string(paper()).unwrap();
    let lab_file = temp_path("unknown-obstacle.toml");
    let extra = "\n[[obstacles]]\ncenter = [0.0, 6.47, 44.48]\nradius = 2.0\n";
    let at = paper_text
        .find("[weights]")
        .expect("paper.toml has [weights]");
    let text = format!("{}{extra}\n{}", &paper_text[..at], &paper_text[at..]);
    std::fs::write(&lab_file, text).unwrap();
    let mut lab = Lab::start(lab_file.to_str().unwrap(), 1, &[]);
    let (code, v) = lab.steer_ending(&paper(), &[]);
    let truth = lab.next_run();
    assert_eq!(truth["collided"], true, "{truth}");
    assert_eq!(truth["end"], "collided", "{truth}");
    assert_eq!(
        (code, reason(&v)),
        (4, ("collided", "robot_sensed_collision")),
        "{v}"
    );
    let _ = std::fs::remove_file(lab_file);
}

/// The lab dies mid-insertion: the link is broken.
#[test]
fn a_killed_lab_exits_6() {
    let file = paper();
    // 40 pieces a second: the insertion takes over 3 s.
    let mut lab = Lab::start(&file, 2, &["--rate", "40"]);
    let child = lab
        .steer_command(&file, &["--json"])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("start needle steer");
    std::thread::sleep(Duration::from_millis(700));
    lab.kill();
    let out = child.wait_with_output().expect("needle steer ends");
    let v: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(out.status.code(), Some(6), "{v}");
    assert_eq!(v["outcome"], "link_broken");
    let r = v["stop_reason"].as_str().unwrap();
    assert!(
        ["robot_disconnected", "tracker_disconnected"].contains(&r),
        "{v}"
    );
}

/// A robot that accepts the connection and reads every command but never answers, beside a
/// tracker that (lock-step, its robot never moving) then sends nothing: the robot is named,
/// not the tracker, although the tracking timeout is the shorter.
#[test]
fn a_silent_robot_is_not_answering_even_when_the_tracker_goes_quiet() {
    let file = paper();
    let lab = Lab::start(&file, 1, &[]);
    let robot = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = robot.local_addr().unwrap().to_string();
    let listening = std::thread::spawn(move || {
        let (mut conn, _) = robot.accept().unwrap();
        let mut sink = Vec::new();
        let _ = conn.read_to_end(&mut sink);
        sink
    });
    let started = Instant::now();
    let (code, v) = ending(needle().args([
        "steer",
        &file,
        "--tracker",
        &lab.tracker,
        "--robot",
        &address,
        "--json",
        "--tracking-timeout-ms",
        "300",
        "--robot-timeout-ms",
        "1000",
    ]));
    assert!(started.elapsed() < Duration::from_secs(20));
    assert_eq!(
        (code, reason(&v)),
        (6, ("link_broken", "robot_not_answering")),
        "{v}"
    );
    assert_eq!(v["robot_stopped"], false);
    let heard = String::from_utf8_lossy(&listening.join().unwrap()).to_string();
    assert!(heard.contains("stop"), "the robot was told to stop");
}

/// A tracker that sends text, not OpenIGTLink (an NMEA-like serial stream forwarded to the
/// port): said so, not "tracking lost".
#[test]
fn a_tracker_that_is_not_openigtlink_says_so() {
    let file = paper();
    let lab = Lab::start(&file, 1, &[]);
    // The lab's robot moves only with a client on its tracker.
    let _watcher = TcpStream::connect(&lab.tracker).unwrap();
    let tracker = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = tracker.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        let (mut conn, _) = tracker.accept().unwrap();
        let line = b"$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n";
        while conn.write_all(line).is_ok() {
            std::thread::sleep(Duration::from_millis(10));
        }
    });
    let (code, v) = ending(needle().args([
        "steer",
        &file,
        "--tracker",
        &address,
        "--robot",
        &lab.robot,
        "--json",
        "--tracking-timeout-ms",
        "300",
    ]));
    assert_eq!(
        (code, reason(&v)),
        (6, ("link_broken", "tracker_not_openigtlink")),
        "{v}"
    );
    assert_eq!(v["robot_stopped"], true, "the lab's robot took the stop");
}

/// A robot that answers in text, not OpenIGTLink: said so.
#[test]
fn a_robot_that_is_not_openigtlink_says_so() {
    let file = paper();
    let lab = Lab::start(&file, 1, &[]);
    let robot = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = robot.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        let (mut conn, _) = robot.accept().unwrap();
        let mut buf = [0u8; 4096];
        while matches!(conn.read(&mut buf), Ok(n) if n > 0) {
            let _ = conn.write_all(b"OK\r\n");
        }
    });
    let (code, v) = ending(needle().args([
        "steer",
        &file,
        "--tracker",
        &lab.tracker,
        "--robot",
        &address,
        "--json",
        "--robot-timeout-ms",
        "500",
    ]));
    assert_eq!(
        (code, reason(&v)),
        (6, ("link_broken", "robot_not_openigtlink")),
        "{v}"
    );
}

/// Nothing listens: one JSON object names the side that could not be reached, exit status 6;
/// a setup that fails (a scenario that does not exist) is 1, in JSON too.
#[test]
fn a_refused_connection_prints_one_json_object() {
    let file = paper();
    let free = || {
        TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .to_string()
    };
    let (nowhere, nowhere_else) = (free(), free());
    let (code, v) = ending(needle().args([
        "steer",
        &file,
        "--tracker",
        &nowhere,
        "--robot",
        &nowhere_else,
        "--json",
    ]));
    assert_eq!(
        (code, reason(&v)),
        (6, ("link_broken", "tracker_unreachable")),
        "{v}"
    );
    assert_eq!(v["form"], "RL", "planned before connecting");
    assert!(v["error"].as_str().unwrap().contains(&nowhere), "{v}");
    let lab = Lab::start(&file, 1, &[]);
    let (code, v) = ending(needle().args([
        "steer",
        &file,
        "--tracker",
        &lab.tracker,
        "--robot",
        &nowhere_else,
        "--json",
    ]));
    assert_eq!(
        (code, reason(&v)),
        (6, ("link_broken", "robot_unreachable")),
        "{v}"
    );
    let (code, v) = ending(needle().args([
        "steer",
        "no-such-scenario.toml",
        "--tracker",
        &lab.tracker,
        "--robot",
        &lab.robot,
        "--json",
    ]));
    assert_eq!(
        (code, reason(&v)),
        (1, ("not_started", "setup_failed")),
        "{v}"
    );
    assert_eq!(v["form"], Value::Null);
}
