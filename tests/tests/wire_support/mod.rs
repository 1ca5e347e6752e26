//! Shared helpers of the `wire_*` tests: the hil-sim binary, a running simulator, and the
//! in-process device as a `needle` transport.
#![allow(dead_code)]

use needle_e2e::{needle_bin, workspace};
use needle_link::Transport;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

/// The hil-sim binary of the same profile as `needle` (built on first use).
pub fn hil_sim_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let needle = needle_bin();
        let dir = needle.parent().expect("binary dir");
        let profile = match dir.file_name().and_then(|n| n.to_str()) {
            Some("debug") | None => "dev".to_string(),
            Some(other) => other.to_string(),
        };
        let status = Command::new(env!("CARGO"))
            .args([
                "build",
                "--quiet",
                "-p",
                "hil-sim",
                "--bin",
                "hil-sim",
                "--profile",
            ])
            .arg(&profile)
            .current_dir(workspace())
            .status()
            .expect("run cargo build");
        assert!(status.success(), "building hil-sim failed");
        dir.join("hil-sim")
    })
}

/// A running hil-sim process; killed (by its own handle) when dropped.
pub struct SimProcess {
    child: Child,
    /// The /dev/pts path or TCP address it printed.
    pub address: String,
}

impl SimProcess {
    /// Starts hil-sim with `args` and reads the address it prints.
    pub fn start(args: &[&str]) -> SimProcess {
        let mut child = Command::new(hil_sim_bin())
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start hil-sim");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("hil-sim prints its address");
        SimProcess {
            child,
            address: line.trim().to_string(),
        }
    }
}

impl SimProcess {
    /// Kills it now (the device vanishes).
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The in-process simulated device as a transport of the `needle` client.
pub struct Sim(pub hil_sim::InProcess);

impl Transport for Sim {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.0.write(bytes);
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], _timeout: Duration) -> std::io::Result<usize> {
        // Silence is known at once in-process: a timeout costs no time.
        Ok(self.0.read(buf))
    }
}

/// `needle` with arguments; (status success, stdout, stderr).
pub fn run_needle(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(needle_bin())
        .args(args)
        .output()
        .expect("run needle");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A table with its timing figure blanked (the only thing `send` may print differently).
pub fn without_timing(table: &str) -> String {
    table
        .lines()
        .map(|l| match l.strip_prefix("planned in ") {
            Some(rest) => format!(
                "planned in _ us{}",
                rest.split_once(" us").map(|x| x.1).unwrap_or("")
            ),
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A line that flips 1 % and drops 1 % of the bytes, the fault pattern of `seed`.
pub fn noisy(seed: u64) -> hil_sim::LineConfig {
    hil_sim::LineConfig {
        flip_rate: 0.01,
        drop_rate: 0.01,
        seed,
        ..hil_sim::LineConfig::default()
    }
}
