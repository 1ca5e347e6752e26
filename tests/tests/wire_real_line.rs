//! `needle send` (default flags) through the `hil-sim` binary over real transports, TCP and a
//! pty, on a noisy line (1 % of bytes flipped and 1 % dropped in each direction; bursts of 20
//! corrupted bytes), and a device that vanishes or restarts mid-plan. Short in the normal suite;
//! the long run (`--ignored`) prints the figures quoted in docs/protocol.md.

mod wire_support;

use needle_e2e::{example, needle_bin};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use wire_support::{run_needle, SimProcess};

/// `needle plan --json` of the paper without its timing.
fn expected() -> String {
    let (ok, out, err) = run_needle(&["plan", example("paper").to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    without_stats(&out)
}

fn without_stats(json: &str) -> String {
    json.split("\"stats\"").next().unwrap_or("").to_string()
}

/// How a run of sends went.
#[derive(Default)]
struct Tally {
    exact: usize,
    wrong: usize,
    failed: Vec<String>,
    times: Vec<Duration>,
}

impl Tally {
    fn median(&self) -> Duration {
        let mut t = self.times.clone();
        t.sort();
        t.get(t.len() / 2).copied().unwrap_or_default()
    }

    fn line(&self, what: &str) -> String {
        let n = self.exact + self.wrong + self.failed.len();
        let mut t = self.times.clone();
        t.sort();
        let pct = |p: usize| t.get((t.len() * p / 100).min(t.len().saturating_sub(1)));
        format!(
            "{what}: {} of {n} exact, {} wrong, {} failed; send time median {:.0} ms, \
             90th percentile {:.0} ms, max {:.0} ms",
            self.exact,
            self.wrong,
            self.failed.len(),
            self.median().as_secs_f64() * 1e3,
            pct(90).map_or(0.0, |d| d.as_secs_f64() * 1e3),
            t.last().map_or(0.0, |d| d.as_secs_f64() * 1e3),
        )
    }
}

/// `sends` sends of the paper with default flags through a hil-sim started with `sim_args`.
fn run(sim_args: &[&str], sends: usize, expected: &str) -> Tally {
    let sim = SimProcess::start(sim_args);
    let flag = if sim_args.contains(&"--tcp") {
        "--tcp"
    } else {
        "--port"
    };
    let paper = example("paper");
    let mut tally = Tally::default();
    for _ in 0..sends {
        let start = Instant::now();
        let (ok, out, err) = run_needle(&[
            "send",
            paper.to_str().unwrap(),
            flag,
            &sim.address,
            "--json",
        ]);
        tally.times.push(start.elapsed());
        assert!(!err.contains("panicked"), "{err}");
        if !ok {
            assert!(err.contains("planning on the device failed"), "{err}");
            tally.failed.push(err);
        } else if without_stats(&out) == expected {
            tally.exact += 1;
        } else {
            tally.wrong += 1;
        }
    }
    tally
}

const NOISY: [&str; 6] = ["--flip-rate", "0.01", "--drop-rate", "0.01", "--seed", "11"];
const BURSTS: [&str; 6] = ["--burst-rate", "0.002", "--burst-len", "20", "--seed", "5"];

fn with<'a>(transport: &[&'a str], faults: &[&'a str]) -> Vec<&'a str> {
    transport.iter().chain(faults).copied().collect()
}

const TCP: [&str; 2] = ["--tcp", "127.0.0.1:0"];

#[test]
fn noisy_lines_over_tcp_and_a_pty_deliver_the_exact_plan() {
    let expected = expected();
    for (what, args, sends) in [
        ("tcp 1 %/1 %", with(&TCP, &NOISY), 10),
        ("pty 1 %/1 %", with(&[], &NOISY), 10),
        ("tcp bursts", with(&TCP, &BURSTS), 5),
        ("pty bursts", with(&[], &BURSTS), 5),
    ] {
        let t = run(&args, sends, &expected);
        println!("{}", t.line(what));
        assert_eq!(t.wrong, 0, "{what}: a wrong plan was accepted");
        // One failure in a short run is the most the long run's figures allow for.
        assert!(t.exact + 1 >= sends, "{}: {:?}", t.line(what), t.failed);
    }
}

/// 500 sends: the figures of docs/protocol.md
/// (`cargo test --release -p needle-e2e --test wire_real_line -- --ignored --nocapture`).
#[test]
#[ignore = "long: 500 sends, about two minutes"]
fn five_hundred_sends_over_real_transports() {
    let expected = expected();
    let quiet = [
        "--flip-rate",
        "0.001",
        "--drop-rate",
        "0.001",
        "--seed",
        "11",
    ];
    let both: Vec<&str> = NOISY.iter().chain(&BURSTS[..4]).copied().collect();
    for (what, args, sends, at_least) in [
        ("tcp 1 %/1 %", with(&TCP, &NOISY), 200, 198),
        ("pty 1 %/1 %", with(&[], &NOISY), 50, 49),
        ("tcp 0.1 %/0.1 %", with(&TCP, &quiet), 50, 50),
        ("tcp bursts", with(&TCP, &BURSTS), 50, 49),
        ("pty bursts", with(&[], &BURSTS), 50, 49),
        ("tcp 1 %/1 % and bursts", with(&TCP, &both), 100, 97),
    ] {
        let t = run(&args, sends, &expected);
        println!("{}", t.line(what));
        for f in &t.failed {
            println!("  failed: {}", f.trim());
        }
        assert_eq!(t.wrong, 0, "{what}");
        assert!(t.exact >= at_least, "{}", t.line(what));
    }
}

/// A free TCP port on the loopback (free when asked; hil-sim binds it right after).
fn free_port() -> String {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    l.local_addr().unwrap().to_string()
}

/// Starts `needle send` of the paper against `addr` with `extra` flags.
fn start_send(addr: &str, extra: &[&str]) -> std::process::Child {
    let paper = example("paper");
    Command::new(needle_bin())
        .args(["send", paper.to_str().unwrap(), "--tcp", addr, "--json"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start needle")
}

/// Waits for `child` at most `limit`; (success, stdout, stderr), or `None` if it hangs.
fn finish_within(child: std::process::Child, limit: Duration) -> Option<(bool, String, String)> {
    let (tx, rx) = std::sync::mpsc::channel();
    let id = child.id();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(limit) {
        Ok(Ok(out)) => Some((
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )),
        _ => {
            // Hung: end it by its own id so the test run does not.
            let _ = Command::new("kill").arg(id.to_string()).status();
            None
        }
    }
}

/// hil-sim slow enough (2400 baud: a plan takes seconds) to be killed mid-plan.
const SLOW: [&str; 2] = ["--baud", "2400"];

#[test]
fn a_device_that_vanishes_mid_plan_ends_the_send_with_a_clear_error() {
    needle_bin();
    let addr = free_port();
    let mut sim = SimProcess::start(&with(&["--tcp", &addr], &SLOW));
    let send = start_send(&sim.address, &["--timeout", "1", "--deadline", "20"]);
    std::thread::sleep(Duration::from_millis(1500));
    sim.kill();
    let (ok, _, err) = finish_within(send, Duration::from_secs(40)).expect("send hung");
    assert!(!ok);
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("planning on the device failed"), "{err}");
    assert!(err.contains("the link failed during the"), "{err}");
    assert!(
        err.contains(&format!("did not come back on tcp {addr}")),
        "{err}"
    );
}

#[test]
fn a_device_that_restarts_mid_plan_completes_the_plan() {
    let expected = expected();
    let addr = free_port();
    let mut first = SimProcess::start(&with(&["--tcp", &addr], &SLOW));
    let send = start_send(&first.address, &["--timeout", "2", "--deadline", "30"]);
    std::thread::sleep(Duration::from_millis(1500));
    first.kill();
    // As a watchdog reset looks: the same address, a device that knows nothing of the plan.
    let _second = SimProcess::start(&["--tcp", &addr]);
    let (ok, out, err) = finish_within(send, Duration::from_secs(50)).expect("send hung");
    assert!(ok, "{err}");
    assert_eq!(without_stats(&out), expected);
}
