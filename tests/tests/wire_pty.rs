//! `needle send` through hil-sim over a real pseudo-terminal (and TCP): the same output as
//! `needle plan`, bit for bit, apart from the timing figures.

mod wire_support;

use needle_e2e::{example, needle_bin};
use serde_json::Value;
use std::time::{Duration, Instant};
use wire_support::{run_needle, without_timing, SimProcess};

fn json_without_stats(text: &str) -> Value {
    let mut v: Value = serde_json::from_str(text).expect("JSON");
    let stats = v.as_object_mut().unwrap().remove("stats").expect("stats");
    // Effort figures come from the device's report and must match; only the time may differ.
    assert!(stats["iterations"].is_u64() && stats["evaluations"].is_u64());
    v["effort"] = serde_json::json!([stats["iterations"], stats["evaluations"]]);
    v
}

fn assert_send_equals_plan(sim: &SimProcess, file: &str, extra: &[&str]) {
    let port = sim.address.as_str();
    for json in [true, false] {
        let mut local = vec!["plan", file];
        let mut remote = vec!["send", file, "--port", port, "--timeout", "10"];
        local.extend_from_slice(extra);
        remote.extend_from_slice(extra);
        if json {
            local.push("--json");
            remote.push("--json");
        }
        let (ok_l, out_l, err_l) = run_needle(&local);
        let (ok_r, out_r, err_r) = run_needle(&remote);
        assert_eq!(ok_l, ok_r, "exit status differs: {err_l} / {err_r}");
        assert_eq!(err_l, err_r);
        // A plan with no feasible form prints its JSON too, and exits 1.
        if json && !out_l.is_empty() {
            assert_eq!(json_without_stats(&out_l), json_without_stats(&out_r));
            // Bit for bit: numbers print identically because they are the same f32 values.
            let strip = |s: &str| s.split("\"stats\"").next().unwrap().to_string();
            assert_eq!(strip(&out_l), strip(&out_r));
        } else {
            assert_eq!(without_timing(&out_l), without_timing(&out_r));
        }
    }
}

#[test]
fn send_over_a_pty_prints_what_plan_prints() {
    let sim = SimProcess::start(&["--baud", "115200"]);
    assert!(sim.address.starts_with("/dev/"), "{}", sim.address);
    let paper = example("paper");
    let space = example("space");
    assert_send_equals_plan(&sim, paper.to_str().unwrap(), &[]);
    assert_send_equals_plan(&sim, space.to_str().unwrap(), &[]);
    // Restricted forms and the planner's error path travel the same way.
    assert_send_equals_plan(&sim, paper.to_str().unwrap(), &["--forms", "L"]);
}

#[test]
fn the_paper_plan_is_feasible_over_the_wire() {
    let sim = SimProcess::start(&[]);
    let paper = example("paper");
    let (ok, out, err) = run_needle(&[
        "send",
        paper.to_str().unwrap(),
        "--port",
        &sim.address,
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["best"]["feasible"], true);
    assert_eq!(v["forms"].as_array().unwrap().len(), 10);
}

#[test]
fn info_and_ping_over_tcp() {
    let sim = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let (ok, out, err) = run_needle(&["info", "--tcp", &sim.address, "--json"]);
    assert!(ok, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["protocol"], planner_core::wire::PROTOCOL_VERSION);
    assert_eq!(v["name"], "hil-sim");
    assert_eq!(v["max_obstacles"], planner_core::DEVICE_MAX_OBSTACLES);
    assert_eq!(v["max_control_degree"], planner_core::MAX_CONTROL_DEGREE);
    let (ok, out, err) = run_needle(&["ping", "--tcp", &sim.address, "--count", "3"]);
    assert!(ok, "{err}");
    assert_eq!(
        out.lines()
            .filter(|l| l.starts_with("pong from hil-sim"))
            .count(),
        3
    );
}

#[test]
fn a_silent_device_gives_a_clear_error_not_a_hang() {
    // Accepts the connection and never answers.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let _keep = std::thread::spawn(move || {
        let conns: Vec<_> = listener.incoming().take(1).collect();
        std::thread::sleep(Duration::from_secs(30));
        drop(conns);
    });
    // Build `needle` first (when this test is the first to run it): only the ping is timed.
    needle_bin();
    let start = Instant::now();
    let (ok, _, err) = run_needle(&["ping", "--tcp", &addr, "--timeout", "0.2", "--retries", "2"]);
    assert!(!ok);
    assert!(err.contains("did not answer the hello"), "{err}");
    assert!(err.contains("gave up after 0.20 s of silence"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(10));
    let (ok, _, err) = run_needle(&["info", "--port", "/dev/no-such-port"]);
    assert!(!ok);
    assert!(err.contains("cannot open serial port"), "{err}");
}
