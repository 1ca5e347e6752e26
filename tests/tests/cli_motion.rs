//! `needle motion` against `hil-sim --axes` (simulated motors in real time, over TCP): refused
//! before arming and homing, homes to the switch, refuses a tilted plan until the guide is said
//! to be set, turns the shaft to the plan's roll and moves the plan to its insertion, keeps
//! the watchdog fed while it waits, stops the moves on Ctrl-C, and the e-stop latches until
//! cleared.

mod wire_support;

use needle_e2e::{example, needle_bin};
use serde_json::Value;
use std::process::{Command, Stdio};
use std::time::Duration;
use wire_support::{run_needle, SimProcess};

fn free_port() -> String {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    l.local_addr().unwrap().to_string()
}

/// `needle motion ACTION [extra] --tcp ADDR --json`: (success, status JSON, stderr).
fn motion(addr: &str, action: &str, extra: &[&str]) -> (bool, Value, String) {
    let mut args = vec!["motion", action];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--tcp", addr, "--json"]);
    let (ok, out, err) = run_needle(&args);
    let status = serde_json::from_str(out.trim()).unwrap_or(Value::Null);
    (ok, status, err)
}

fn paper_inserted_mm() -> f64 {
    let (ok, out, err) = run_needle(&["plan", example("paper").to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let plan: Value = serde_json::from_str(&out).unwrap();
    plan["best"]["schedule"]["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["length_mm"].as_f64().unwrap_or(0.0))
        .sum()
}

#[test]
fn needle_motion_homes_moves_stops_and_estops_the_simulated_axes() {
    needle_bin();
    let sim = SimProcess::start(&["--axes", "--tcp", &free_port()]);
    let addr = sim.address.clone();
    let paper = example("paper");
    let paper = paper.to_str().unwrap();

    let (ok, s, _) = motion(&addr, "status", &[]);
    assert!(ok);
    assert_eq!(
        (s["state"].as_str(), s["homed"].as_bool()),
        (Some("disarmed"), Some(false))
    );
    let (ok, _, err) = motion(&addr, "move", &[paper, "--tilt-set"]);
    assert!(
        !ok && err.contains("refused `move`") && err.contains("disarmed"),
        "{err}"
    );
    assert!(motion(&addr, "arm", &[]).0);
    let (ok, _, err) = motion(&addr, "move", &[paper, "--tilt-set"]);
    assert!(!ok && err.contains("home"), "{err}");

    // Homing waits for the switch (the stage starts 5 mm out at 2 mm/s).
    let (ok, s, err) = motion(&addr, "home", &[]);
    assert!(ok, "{err}");
    assert_eq!(
        (s["state"].as_str(), s["homed"].as_bool()),
        (Some("armed"), Some(true))
    );
    assert_eq!(s["insertion_mm"].as_f64(), Some(0.0));

    // The paper's plan tilts the needle 28.67 deg: refused until the guide is said to be set,
    // and nothing moves.
    let (ok, _, err) = motion(&addr, "move", &[paper]);
    assert!(
        !ok && err.contains("tilts the needle 28.67 deg") && err.contains("--tilt-set"),
        "{err}"
    );
    let (_, s, _) = motion(&addr, "status", &[]);
    assert_eq!(
        (s["insertion_mm"].as_f64(), s["rotation_deg"].as_f64()),
        (Some(0.0), Some(0.0))
    );

    // Ctrl-C mid-move: the board stops and drops the moves; the command fails.
    let child = Command::new(needle_bin())
        .args([
            "motion",
            "move",
            paper,
            "--tilt-set",
            "--tcp",
            &addr,
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(3));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("interrupted"),
        "{err}"
    );
    let s: Value = serde_json::from_slice(&out.stdout).expect("the status after the stop");
    let at = s["insertion_mm"].as_f64().unwrap();
    assert_eq!(
        (s["state"].as_str(), s["moves_left"].as_u64()),
        (Some("armed"), Some(0))
    );
    assert!(at > 1.0 && at < 20.0, "{s}");
    let (_, later, _) = motion(&addr, "status", &[]);
    assert_eq!(
        later["insertion_mm"].as_f64(),
        Some(at),
        "stopped means stopped"
    );

    // Home again (a few mm), then the paper's plan, about 37 s of simulated motors: the command feeds the watchdog all along.
    assert!(motion(&addr, "home", &[]).0);
    let (ok, s, err) = motion(&addr, "move", &[paper, "--tilt-set"]);
    assert!(ok, "{err}");
    // The shaft turns to the posture's roll (180 deg) first; the plan's line spins whole turns.
    assert!(err.contains("bevel roll 180 deg: the shaft turns"), "{err}");
    let roll = s["rotation_deg"].as_f64().unwrap();
    assert!(((roll - 180.0) / 360.0).fract().abs() < 1e-3, "{s}");
    assert_eq!(s["state"].as_str(), Some("armed"));
    assert!(s["last_fault"].is_null(), "{s}");
    let inserted = s["insertion_mm"].as_f64().unwrap();
    assert!(
        (inserted - paper_inserted_mm()).abs() <= 1.0 / 1600.0 + 1e-4,
        "{inserted} mm"
    );

    estop_latches_until_cleared(&addr);
}

/// The e-stop latches through a reset and an arm until cleared.
fn estop_latches_until_cleared(addr: &str) {
    let (ok, s, _) = motion(addr, "estop", &[]);
    assert!(ok);
    assert_eq!(s["state"].as_str(), Some("faulted"));
    assert_eq!(s["last_fault"]["cause"].as_str(), Some("e-stop"), "{s}");
    for action in ["reset", "arm"] {
        let (ok, _, err) = motion(addr, action, &[]);
        assert!(!ok && err.contains("e-stop"), "{action}: {err}");
    }
    let (ok, s, err) = motion(addr, "clear-fault", &[]);
    assert!(ok, "{err}");
    assert_eq!(
        (s["state"].as_str(), s["homed"].as_bool()),
        (Some("disarmed"), Some(false))
    );
}

#[test]
fn needle_motion_says_what_is_wrong_with_its_arguments_and_devices_without_axes() {
    needle_bin();
    // `move` without a scenario, a scenario for another action: clap or the command refuses.
    let (ok, _, err) = run_needle(&["motion", "move", "--tcp", "127.0.0.1:9"]);
    assert!(!ok && err.contains("SCENARIO"), "{err}");
    let paper = example("paper");
    let (ok, _, err) = run_needle(&[
        "motion",
        "arm",
        paper.to_str().unwrap(),
        "--tcp",
        "127.0.0.1:9",
    ]);
    assert!(
        !ok && err.contains("only `needle motion move` takes a scenario"),
        "{err}"
    );
    let (ok, _, err) = run_needle(&["motion", "arm", "--tilt-set", "--tcp", "127.0.0.1:9"]);
    assert!(
        !ok && err.contains("only `needle motion move` takes --tilt-set"),
        "{err}"
    );
    // A device without axes says so.
    let sim = SimProcess::start(&["--tcp", &free_port()]);
    let (ok, _, err) = motion(&sim.address, "status", &[]);
    assert!(!ok && err.contains("drives no axes"), "{err}");
}
