//! Shared helpers of the `lab_*` tests: the simulated lab (`hil-sim --lab`) as a process, and
//! `needle steer` against it.
#![allow(dead_code)]

#[path = "../wire_support/mod.rs"]
pub mod wire_support;

use needle_e2e::needle;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Output, Stdio};

/// A running `hil-sim --lab`; killed (by its own handle) when dropped.
pub struct Lab {
    child: Child,
    /// The tracker's address.
    pub tracker: String,
    /// The robot's address.
    pub robot: String,
    runs: BufReader<ChildStdout>,
}

impl Lab {
    /// Starts the lab of `file` on free ports, first insertion in the world of `seed`.
    pub fn start(file: &str, seed: u64, extra: &[&str]) -> Lab {
        let (child, runs, tracker, robot) = spawn(file, seed, "robot", extra);
        Lab {
            tracker,
            robot,
            child,
            runs,
        }
    }

    /// The true figures of the next insertion served (waits for its end).
    pub fn next_run(&mut self) -> Value {
        let mut line = String::new();
        self.runs.read_line(&mut line).expect("read a run");
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
    }

    /// A `needle steer` command against this lab, with `args` after the scenario.
    pub fn steer_command(&self, file: &str, args: &[&str]) -> Command {
        let mut c = needle();
        c.args([
            "steer",
            file,
            "--tracker",
            &self.tracker,
            "--robot",
            &self.robot,
        ])
        .args(args);
        c
    }

    /// Runs `needle steer FILE --json ARGS` against this lab and returns its JSON: the
    /// insertion ran (it may end any way but a failed setup), and the exit status is the one
    /// its ending has.
    pub fn steer(&self, file: &str, args: &[&str]) -> Value {
        let out: Output = self
            .steer_command(file, args)
            .arg("--json")
            .output()
            .expect("run needle steer");
        let v: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
            panic!(
                "needle steer {args:?} prints JSON ({e}): {}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
        let code = out.status.code().expect("an exit status");
        assert_eq!(v["exit_code"], code, "needle steer {args:?}: {v}");
        assert!(
            ![1, 2].contains(&code),
            "needle steer {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let expected = match v["outcome"].as_str() {
            Some("reached") => 0,
            Some("missed") => 3,
            Some("collided") => 4,
            Some("stopped") => 5,
            _ => 6,
        };
        assert_eq!(code, expected, "{v}");
        v
    }
}

impl Lab {
    /// Runs `needle steer FILE --json ARGS` against this lab whatever its ending: the exit
    /// status and the one JSON object it printed.
    pub fn steer_ending(&self, file: &str, args: &[&str]) -> (i32, Value) {
        ending(self.steer_command(file, args).arg("--json"))
    }

    /// Kills the lab now (a lab that dies mid-insertion).
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `hil-sim --lab FILE` on free ports with a `peer` (`robot`, or `board`: a driver board,
/// `--board-port`), first insertion in the world of `seed`: the process, its stdout (one JSON line
/// per insertion), the tracker's address and the peer's.
pub fn spawn(
    file: &str,
    seed: u64,
    peer: &str,
    extra: &[&str],
) -> (Child, BufReader<ChildStdout>, String, String) {
    let seed = seed.to_string();
    let peer_port = format!("--{peer}-port");
    let mut child = Command::new(wire_support::hil_sim_bin())
        .args(["--lab", file, "--tracker-port", "0", &peer_port, "0"])
        .args(["--seed", &seed])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start hil-sim --lab");
    let mut runs = BufReader::new(child.stdout.take().expect("stdout"));
    let mut line = String::new();
    runs.read_line(&mut line).expect("hil-sim prints its ports");
    let words: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(words.len(), 4, "`tracker ADDRESS {peer} ADDRESS`: {line}");
    assert_eq!((words[0], words[2]), ("tracker", peer), "{line}");
    let (tracker, address) = (words[1].to_string(), words[3].to_string());
    (child, runs, tracker, address)
}

/// Runs a `needle steer ... --json` command: its exit status and the exactly one JSON object it
/// printed on stdout.
pub fn ending(c: &mut Command) -> (i32, Value) {
    let out = c.output().expect("run needle steer");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 1, "one JSON object: {stdout}");
    let v: Value = serde_json::from_str(lines[0]).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    let code = out.status.code().expect("an exit status");
    assert_eq!(v["exit_code"], code, "{v}");
    (code, v)
}

impl Drop for Lab {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The lines of an insertion log.
pub fn log_lines(path: &std::path::Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .expect("read the insertion log")
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

/// A fresh path in the temporary directory.
pub fn temp_path(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("needle-lab-{}-{name}", std::process::id()))
}

/// `needle simulate FILE --closed-loop --runs N --seed FIRST --json --detail`: each run's record,
/// what the lab's insertions of the same seeds must end as.
pub fn simulated(file: &str, first: u64, runs: usize) -> Vec<Value> {
    simulated_with(file, first, runs, &[])
}

/// [`simulated`] with more of `needle simulate`'s flags (a world, perturbations, faults).
pub fn simulated_with(file: &str, first: u64, runs: usize, flags: &[&str]) -> Vec<Value> {
    let (first, runs) = (first.to_string(), runs.to_string());
    let mut args = vec![
        "simulate",
        file,
        "--closed-loop",
        "--runs",
        &runs,
        "--seed",
        &first,
        "--json",
        "--detail",
    ];
    args.extend_from_slice(flags);
    let v = needle_e2e::needle_json(&args);
    v["runs_detail"].as_array().expect("runs_detail").clone()
}

/// A stand-in 3D Slicer listening on a local port: every OpenIGTLink frame `needle steer
/// --slicer ADDR` sends, each decoded with its CRC checked, once the connection closes.
pub fn slicer_listener() -> (String, std::thread::JoinHandle<Vec<needle_igtl::Frame>>) {
    use needle_igtl::{Frame, FrameDecoder};
    use std::io::Read;
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let slicer = std::thread::spawn(move || {
        let (mut conn, _) = listener.accept().unwrap();
        let mut decoder: Box<FrameDecoder<8192>> = Box::default();
        let (mut frames, mut buf) = (Vec::<Frame>::new(), [0u8; 4096]);
        loop {
            let n = conn.read(&mut buf).unwrap();
            if n == 0 {
                return frames;
            }
            let mut input = &buf[..n];
            while let Some(f) = decoder.feed(&mut input) {
                frames.push(f.expect("every frame decodes, CRC checked"));
            }
        }
    });
    (address, slicer)
}
